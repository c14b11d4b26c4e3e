//! The FMI 2.0 logger of the fuzz targets: variadic, as an importer written in C declares it
//! (`fmi2CallbackLogger`), which Rust defines only with the nightly feature `c_variadic` (each
//! FMI 2.0 target enables it). The replay on stable Rust (tests/fuzz_replay.rs) passes a logger
//! declared with fixed arguments instead.

use std::ffi::{CStr, c_char, c_void};

use crate::fmi2_sequence::{Logger, read_log};
use hasel_fmu::fmi2::types::fmi2Status;

pub const LOGGER: Logger = Some(logger);

unsafe extern "C" fn logger(
    _env: *mut c_void,
    name: *const c_char,
    _status: fmi2Status,
    category: *const c_char,
    message: *const c_char,
    mut args: ...
) {
    // the FMU logs through the format "%s" with one string argument
    let text = if !message.is_null() && unsafe { CStr::from_ptr(message) } == c"%s" {
        unsafe { args.next_arg::<*const c_char>() }
    } else {
        std::ptr::null()
    };
    read_log(name, category, message, text);
}
