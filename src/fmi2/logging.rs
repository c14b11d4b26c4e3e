//! Logging through the importer's `fmi2CallbackLogger` (FMI 2.0 standard, sections 2.1.5
//! and 2.1.6 `fmi2SetDebugLogging`).
//!
//! Rules: messages go out as the printf format `"%s"` with the text as its one argument, so
//! a `%` in the text is never interpreted; the category is never NULL; messages with status
//! `fmi2OK` are debug logging and go out only when debug logging is on for their category;
//! all other statuses go out whenever a logger exists.

use std::ffi::{CStr, CString};

use super::types::{Fmi2Status, fmi2CallbackFunctions};
use crate::fmi_common::shell::{DebugLogging, c_string};

/// Category of debug (OK-level) messages tracing the calls into the FMU.
const LOG_CALLS: &CStr = c"logCalls";
const LOG_CALLS_NAME: &str = "logCalls";
const LOG_WARNING: &CStr = c"logStatusWarning";
const LOG_DISCARD: &CStr = c"logStatusDiscard";
const LOG_ERROR: &CStr = c"logStatusError";
const LOG_FATAL: &CStr = c"logStatusFatal";

/// The categories the wrapper logs with, `(name, description)`, listed in
/// `<LogCategories>` before the model's own (names from section 2.2.4).
pub const WRAPPER_CATEGORIES: [(&str, &str); 5] = [
    (LOG_CALLS_NAME, "Trace of the FMI function calls (debug)"),
    ("logStatusWarning", "Messages with status fmi2Warning"),
    ("logStatusDiscard", "Messages with status fmi2Discard"),
    ("logStatusError", "Messages with status fmi2Error"),
    ("logStatusFatal", "Messages with status fmi2Fatal"),
];

/// The instance's logger: the importer's callbacks and the debug-logging settings.
pub struct Logger {
    callbacks: fmi2CallbackFunctions,
    instance_name: CString,
    debug: DebugLogging,
}

impl Logger {
    pub fn new(callbacks: fmi2CallbackFunctions, instance_name: &str, debug_on: bool) -> Self {
        Logger {
            callbacks,
            instance_name: c_string(instance_name),
            debug: DebugLogging::new(debug_on),
        }
    }

    /// `fmi2SetDebugLogging`: switches debug logging for the given categories (all when the
    /// list is empty). Returns the first unknown category name as the error.
    pub fn set_debug_logging(
        &mut self,
        on: bool,
        categories: &[String],
        known: &[String],
    ) -> Result<(), String> {
        self.debug.set(on, categories, known)
    }

    /// Whether debug logging is on; callers may skip building expensive debug messages.
    pub fn debug_enabled(&self) -> bool {
        self.callbacks.logger.is_some() && self.debug.enabled(LOG_CALLS_NAME)
    }

    /// Logs `message` with `status`, under the category of that status.
    pub fn log(&self, status: Fmi2Status, message: &str) {
        let Some(logger) = self.callbacks.logger else {
            return;
        };
        let category = match status {
            Fmi2Status::Ok | Fmi2Status::Pending => LOG_CALLS,
            Fmi2Status::Warning => LOG_WARNING,
            Fmi2Status::Discard => LOG_DISCARD,
            Fmi2Status::Error => LOG_ERROR,
            Fmi2Status::Fatal => LOG_FATAL,
        };
        if status == Fmi2Status::Ok && !self.debug_enabled() {
            return;
        }
        let text = c_string(message);
        // SAFETY: the importer promised a valid logger for the lifetime of the instance
        // (section 2.1.5); all pointers passed are valid NUL-terminated strings that outlive
        // the call, and the format "%s" consumes exactly the one string argument given.
        unsafe {
            logger(
                self.callbacks.component_environment,
                self.instance_name.as_ptr(),
                status,
                category.as_ptr(),
                c"%s".as_ptr(),
                text.as_ptr(),
            );
        }
    }
}
