//! The statuses the shells return and the logger they send messages through, whatever the FMI
//! version (FMI 2.0 sections 2.1.3 and 2.1.5, FMI 3.0 sections 2.2.3 and 2.3.1). A version
//! maps [`Status`] to its C enumeration (`From<Status>`) and hands the messages to its
//! importer's callback ([`LogSink`]).
//!
//! Rules: the category is never NULL and is the one of the message's status; messages with
//! status OK are debug logging (call traces) and go out only when debug logging is on for
//! their category; all other statuses go out whenever the importer gave a callback.

use std::ffi::{CStr, CString};

use super::shell::{DebugLogging, c_string};

/// The status of a call, as both versions define it: `fmi2Status` and `fmi3Status` are this C
/// enumeration (FMI 2.0's `fmi2Pending`, 5, never occurs: steps are synchronous).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    Ok = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
}

/// The category of call traces (debug logging).
pub const LOG_CALLS: &str = "logCalls";

impl Status {
    /// The log category of messages of this status (names from FMI 2.0 section 2.2.4,
    /// FMI 3.0 section 2.4.5), in the order of the statuses.
    pub fn category(self) -> &'static CStr {
        match self {
            Status::Ok => c"logCalls",
            Status::Warning => c"logStatusWarning",
            Status::Discard => c"logStatusDiscard",
            Status::Error => c"logStatusError",
            Status::Fatal => c"logStatusFatal",
        }
    }
}

/// The importer's logging callback of one version.
pub trait LogSink {
    /// Whether the importer gave a callback.
    fn connected(&self) -> bool;
    /// Hands one message to the callback (if any).
    fn send(&self, status: Status, category: &CStr, message: &CStr);
}

/// The instance's logger: the importer's callback and the debug-logging settings.
pub struct Logger<S> {
    sink: S,
    debug: DebugLogging,
}

impl<S: LogSink> Logger<S> {
    pub fn new(sink: S, debug_on: bool) -> Self {
        Logger {
            sink,
            debug: DebugLogging::new(debug_on),
        }
    }

    /// `fmi2SetDebugLogging` / `fmi3SetDebugLogging`: switches debug logging for the given
    /// categories (all when the list is empty). Returns the first unknown category name as the
    /// error.
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
        self.sink.connected() && self.debug.enabled(LOG_CALLS)
    }

    /// Logs `message` with `status`, under the category of that status.
    pub fn log(&self, status: Status, message: &str) {
        if !self.sink.connected() || (status == Status::Ok && !self.debug_enabled()) {
            return;
        }
        let text: CString = c_string(message);
        self.sink.send(status, status.category(), &text);
    }
}
