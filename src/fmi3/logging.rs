//! Logging through the importer's `fmi3LogMessageCallback` (FMI 3.0 standard, sections 2.3.1
//! and 2.4.5, `fmi3SetDebugLogging`).
//!
//! Rules: the message is a plain string (FMI 3.0 has no printf format), the category is never
//! NULL; messages with status `fmi3OK` are debug logging and go out only when debug logging is
//! on for their category; all other statuses go out whenever a callback exists.

use std::ffi::CStr;

use super::types::{Fmi3Status, fmi3InstanceEnvironment, fmi3LogMessageCallback};
use crate::fmi_common::shell::{DebugLogging, c_string};

const LOG_CALLS: &str = "logCalls";

/// The categories the shell logs with, `(name, description)`, listed in `<LogCategories>`
/// before the model's own; the status names are those the standard suggests (section 2.4.5).
pub const SHELL_CATEGORIES: [(&str, &str); 5] = [
    (LOG_CALLS, "Each FMI 3.0 call with its arguments (debug)"),
    ("logStatusWarning", "Calls that returned fmi3Warning"),
    ("logStatusDiscard", "Calls that returned fmi3Discard"),
    ("logStatusError", "Calls that returned fmi3Error"),
    ("logStatusFatal", "Calls that returned fmi3Fatal"),
];

/// The category of a message of `status`.
fn category(status: Fmi3Status) -> &'static CStr {
    match status {
        Fmi3Status::Ok => c"logCalls",
        Fmi3Status::Warning => c"logStatusWarning",
        Fmi3Status::Discard => c"logStatusDiscard",
        Fmi3Status::Error => c"logStatusError",
        Fmi3Status::Fatal => c"logStatusFatal",
    }
}

/// The instance's logger: the importer's callback and the debug-logging settings.
pub struct Logger {
    callback: fmi3LogMessageCallback,
    environment: fmi3InstanceEnvironment,
    debug: DebugLogging,
}

impl Logger {
    pub fn new(
        callback: fmi3LogMessageCallback,
        environment: fmi3InstanceEnvironment,
        debug_on: bool,
    ) -> Self {
        Logger {
            callback,
            environment,
            debug: DebugLogging::new(debug_on),
        }
    }

    /// `fmi3SetDebugLogging`: switches debug logging for the given categories (all when the
    /// list is empty). Returns the first unknown category name as the error.
    pub fn set_debug_logging(
        &mut self,
        on: bool,
        categories: &[String],
        known: &[String],
    ) -> Result<(), String> {
        self.debug.set(on, categories, known)
    }

    /// Whether call traces go out; callers skip building them otherwise.
    pub fn debug_enabled(&self) -> bool {
        self.callback.is_some() && self.debug.enabled(LOG_CALLS)
    }

    /// Logs `message` with `status`, under the category of that status.
    pub fn log(&self, status: Fmi3Status, message: &str) {
        let Some(callback) = self.callback else {
            return;
        };
        if status == Fmi3Status::Ok && !self.debug_enabled() {
            return;
        }
        let text = c_string(message);
        // SAFETY: the importer promised a callback valid for the instance's lifetime
        // (section 2.3.1); both strings are NUL-terminated and outlive the call.
        unsafe {
            callback(
                self.environment,
                status,
                category(status).as_ptr(),
                text.as_ptr(),
            );
        }
    }
}
