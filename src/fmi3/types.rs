//! The C types of the FMI 3.0 headers `fmi3PlatformTypes.h` and `fmi3FunctionTypes.h`
//! (FMI 3.0 standard, section 2.2.2), declared for Rust.
//!
//! `fmi3Boolean` is C's `bool`; a value received from the importer is read as a byte (`u8`,
//! anything but 0 is true), because a foreign byte other than 0 or 1 in a Rust `bool` would be
//! undefined behaviour. `fmi3Status` is only ever produced by the FMU, so it is a Rust enum.
#![allow(non_camel_case_types)]

use std::ffi::{c_char, c_void};

use crate::fmi_common::logging::Status;

pub use crate::fmi_common::model_api::InstanceKind;

/// Opaque pointer to an FMU instance.
pub type fmi3Instance = *mut c_void;
/// Opaque pointer the importer passes in and gets back unchanged in callbacks.
pub type fmi3InstanceEnvironment = *mut c_void;
/// Opaque pointer to a saved FMU state.
pub type fmi3FMUState = *mut c_void;
pub type fmi3ValueReference = u32;
pub type fmi3Float32 = f32;
pub type fmi3Float64 = f64;
pub type fmi3Int8 = i8;
pub type fmi3UInt8 = u8;
pub type fmi3Int16 = i16;
pub type fmi3UInt16 = u16;
pub type fmi3Int32 = i32;
pub type fmi3UInt32 = u32;
pub type fmi3Int64 = i64;
pub type fmi3UInt64 = u64;
/// C `bool`, read as a byte (see the module documentation).
pub type fmi3Boolean = u8;
pub type fmi3Char = c_char;
pub type fmi3String = *const fmi3Char;
pub type fmi3Byte = u8;
pub type fmi3Binary = *const fmi3Byte;
/// C `bool`, like [`fmi3Boolean`].
pub type fmi3Clock = u8;

pub const FMI3_TRUE: fmi3Boolean = 1;
pub const FMI3_FALSE: fmi3Boolean = 0;

/// `fmi3Version` as returned by `fmi3GetVersion` (section 2.3.1).
pub const VERSION: &std::ffi::CStr = c"3.0";

/// `fmi3Status` (section 2.2.3): the statuses both versions share.
pub type Fmi3Status = Status;

/// The C name of the status enumeration.
pub type fmi3Status = Fmi3Status;

/// `fmi3DependencyKind` (section 2.2.10), for the signature of `fmi3GetVariableDependencies`.
pub type fmi3DependencyKind = std::ffi::c_int;
/// `fmi3IntervalQualifier` (section 2.2.9), for the signatures of the Clock functions.
pub type fmi3IntervalQualifier = std::ffi::c_int;

/// `fmi3LogMessageCallback` (section 2.3.1); unlike FMI 2.0, not variadic.
pub type fmi3LogMessageCallback = Option<
    unsafe extern "C" fn(
        instance_environment: fmi3InstanceEnvironment,
        status: fmi3Status,
        category: fmi3String,
        message: fmi3String,
    ),
>;

/// `fmi3IntermediateUpdateCallback` (section 4.2.2); never called: this FMU declares no
/// intermediate update and does not return early.
pub type fmi3IntermediateUpdateCallback = Option<
    unsafe extern "C" fn(
        instance_environment: fmi3InstanceEnvironment,
        intermediate_update_time: fmi3Float64,
        intermediate_variable_set_requested: fmi3Boolean,
        intermediate_variable_get_allowed: fmi3Boolean,
        intermediate_step_finished: fmi3Boolean,
        can_return_early: fmi3Boolean,
        early_return_requested: *mut fmi3Boolean,
        early_return_time: *mut fmi3Float64,
    ),
>;

/// `fmi3ClockUpdateCallback` (section 5.2.1), for the signature of
/// `fmi3InstantiateScheduledExecution` only.
pub type fmi3ClockUpdateCallback =
    Option<unsafe extern "C" fn(instance_environment: fmi3InstanceEnvironment)>;
/// `fmi3LockPreemptionCallback` / `fmi3UnlockPreemptionCallback`, likewise.
pub type fmi3PreemptionCallback = Option<unsafe extern "C" fn()>;
