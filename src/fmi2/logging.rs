//! Logging through the importer's `fmi2CallbackLogger` (FMI 2.0 standard, sections 2.1.5
//! and 2.1.6 `fmi2SetDebugLogging`), as the sink of the shared
//! [`Logger`](crate::fmi_common::logging::Logger): messages go out as the printf format
//! `"%s"` with the text as its one argument, so a `%` in the text is never interpreted.

use std::ffi::{CStr, CString};

use super::types::{Fmi2Status, fmi2CallbackFunctions};
use crate::fmi_common::logging::{self, LOG_CALLS, LogSink, Status};
use crate::fmi_common::shell::c_string;

/// The categories the wrapper logs with, `(name, description)`, listed in
/// `<LogCategories>` before the model's own (names from section 2.2.4).
pub const WRAPPER_CATEGORIES: [(&str, &str); 5] = [
    (LOG_CALLS, "Trace of the FMI function calls (debug)"),
    ("logStatusWarning", "Messages with status fmi2Warning"),
    ("logStatusDiscard", "Messages with status fmi2Discard"),
    ("logStatusError", "Messages with status fmi2Error"),
    ("logStatusFatal", "Messages with status fmi2Fatal"),
];

/// The importer's callbacks and the instance name they are given.
pub struct Callbacks {
    callbacks: fmi2CallbackFunctions,
    instance_name: CString,
}

/// The logger of an FMI 2.0 instance.
pub type Logger = logging::Logger<Callbacks>;

/// A logger through `callbacks` for the instance `instance_name`.
pub fn logger(callbacks: fmi2CallbackFunctions, instance_name: &str, debug_on: bool) -> Logger {
    let sink = Callbacks {
        callbacks,
        instance_name: c_string(instance_name),
    };
    Logger::new(sink, debug_on)
}

impl LogSink for Callbacks {
    fn connected(&self) -> bool {
        self.callbacks.logger.is_some()
    }

    fn send(&self, status: Status, category: &CStr, message: &CStr) {
        let Some(logger) = self.callbacks.logger else {
            return;
        };
        // SAFETY: the importer promised a valid logger for the lifetime of the instance
        // (section 2.1.5); all pointers passed are valid NUL-terminated strings that outlive
        // the call, and the format "%s" consumes exactly the one string argument given.
        unsafe {
            logger(
                self.callbacks.component_environment,
                self.instance_name.as_ptr(),
                Fmi2Status::from(status),
                category.as_ptr(),
                c"%s".as_ptr(),
                message.as_ptr(),
            );
        }
    }
}
