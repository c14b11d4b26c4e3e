//! Logging through the importer's `fmi3LogMessageCallback` (FMI 3.0 standard, sections 2.3.1
//! and 2.4.5, `fmi3SetDebugLogging`), as the sink of the shared
//! [`Logger`](crate::fmi_common::logging::Logger): the message is a plain string (FMI 3.0 has
//! no printf format).

use std::ffi::CStr;

use super::types::{Fmi3Status, fmi3InstanceEnvironment, fmi3LogMessageCallback};
use crate::fmi_common::logging::{self, LOG_CALLS, LogSink, Status};

/// The categories the shell logs with, `(name, description)`, listed in `<LogCategories>`
/// before the model's own; the status names are those the standard suggests (section 2.4.5).
pub const SHELL_CATEGORIES: [(&str, &str); 5] = [
    (LOG_CALLS, "Each FMI 3.0 call with its arguments (debug)"),
    ("logStatusWarning", "Calls that returned fmi3Warning"),
    ("logStatusDiscard", "Calls that returned fmi3Discard"),
    ("logStatusError", "Calls that returned fmi3Error"),
    ("logStatusFatal", "Calls that returned fmi3Fatal"),
];

/// The importer's callback and the environment it is given back.
pub struct Callback {
    callback: fmi3LogMessageCallback,
    environment: fmi3InstanceEnvironment,
}

/// The logger of an FMI 3.0 instance.
pub type Logger = logging::Logger<Callback>;

/// A logger through `callback`, which gets `environment` back.
pub fn logger(
    callback: fmi3LogMessageCallback,
    environment: fmi3InstanceEnvironment,
    debug_on: bool,
) -> Logger {
    Logger::new(
        Callback {
            callback,
            environment,
        },
        debug_on,
    )
}

impl LogSink for Callback {
    fn connected(&self) -> bool {
        self.callback.is_some()
    }

    fn send(&self, status: Status, category: &CStr, message: &CStr) {
        let Some(callback) = self.callback else {
            return;
        };
        // SAFETY: the importer promised a callback valid for the instance's lifetime
        // (section 2.3.1); both strings are NUL-terminated and outlive the call.
        unsafe {
            callback(
                self.environment,
                Fmi3Status::from(status),
                category.as_ptr(),
                message.as_ptr(),
            );
        }
    }
}
