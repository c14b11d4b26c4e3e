//! The C types of the FMI 2.0 headers `fmi2TypesPlatform.h` and `fmi2FunctionTypes.h`
//! (FMI 2.0 standard, section 2.1.2), declared for Rust.
//!
//! Enumerations received *from* the importer (`fmi2Type`, `fmi2StatusKind`) are plain
//! `c_int`s with named constants, because a foreign value outside the Rust enum's range would
//! be undefined behaviour; `fmi2Status` is only ever produced by the FMU, so it is a Rust enum.
#![allow(non_camel_case_types)]

use std::ffi::{c_char, c_int, c_void};

use crate::fmi_common::logging::Status;

/// Opaque pointer to an FMU instance (`void*`).
pub type fmi2Component = *mut c_void;
/// Opaque pointer the importer passes in and gets back unchanged in callbacks.
pub type fmi2ComponentEnvironment = *mut c_void;
/// Opaque pointer to a saved FMU state.
pub type fmi2FMUstate = *mut c_void;
pub type fmi2ValueReference = u32;
pub type fmi2Real = f64;
pub type fmi2Integer = i32;
/// `int` in C: 0 is false, anything else true.
pub type fmi2Boolean = i32;
pub type fmi2Char = c_char;
pub type fmi2String = *const fmi2Char;
pub type fmi2Byte = c_char;

pub const FMI2_TRUE: fmi2Boolean = 1;
pub const FMI2_FALSE: fmi2Boolean = 0;

/// `fmi2TypesPlatform` as returned by `fmi2GetTypesPlatform` (section 2.1.4).
pub const TYPES_PLATFORM: &std::ffi::CStr = c"default";
/// `fmi2Version` as returned by `fmi2GetVersion` (section 2.1.4).
pub const VERSION: &std::ffi::CStr = c"2.0";

/// `fmi2Status` (section 2.1.3): the statuses both versions share, less `fmi2Pending`, which
/// this FMU never returns.
pub type Fmi2Status = Status;

/// The C name of the status enumeration.
pub type fmi2Status = Fmi2Status;

/// `fmi2Type` (section 2.1.5): which interface `fmi2Instantiate` is asked for.
pub type fmi2Type = c_int;
pub const FMI2_MODEL_EXCHANGE: fmi2Type = 0;
pub const FMI2_CO_SIMULATION: fmi2Type = 1;

/// `fmi2StatusKind` (section 4.2.3): what `fmi2Get*Status` is asked about.
pub type fmi2StatusKind = c_int;
pub const FMI2_DO_STEP_STATUS: fmi2StatusKind = 0;
pub const FMI2_PENDING_STATUS: fmi2StatusKind = 1;
pub const FMI2_LAST_SUCCESSFUL_TIME: fmi2StatusKind = 2;
pub const FMI2_TERMINATED: fmi2StatusKind = 3;

/// `fmi2CallbackLogger`: printf-style, variadic.
pub type fmi2CallbackLogger = Option<
    unsafe extern "C" fn(
        component_environment: fmi2ComponentEnvironment,
        instance_name: fmi2String,
        status: fmi2Status,
        category: fmi2String,
        message: fmi2String,
        ...
    ),
>;
/// `fmi2CallbackAllocateMemory` (unused: the FMU declares `canNotUseMemoryManagementFunctions`).
pub type fmi2CallbackAllocateMemory =
    Option<unsafe extern "C" fn(nobj: usize, size: usize) -> *mut c_void>;
/// `fmi2CallbackFreeMemory` (unused, see above).
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(obj: *mut c_void)>;
/// `fmi2StepFinished` (unused: `fmi2DoStep` is synchronous and never returns `fmi2Pending`).
pub type fmi2StepFinished = Option<
    unsafe extern "C" fn(component_environment: fmi2ComponentEnvironment, status: fmi2Status),
>;

/// `fmi2CallbackFunctions` (section 2.1.5). Copied by `fmi2Instantiate`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct fmi2CallbackFunctions {
    pub logger: fmi2CallbackLogger,
    pub allocate_memory: fmi2CallbackAllocateMemory,
    pub free_memory: fmi2CallbackFreeMemory,
    pub step_finished: fmi2StepFinished,
    pub component_environment: fmi2ComponentEnvironment,
}

/// `fmi2EventInfo` (section 3.2.2), filled by `fmi2NewDiscreteStates`.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct fmi2EventInfo {
    pub new_discrete_states_needed: fmi2Boolean,
    pub terminate_simulation: fmi2Boolean,
    pub nominals_of_continuous_states_changed: fmi2Boolean,
    pub values_of_continuous_states_changed: fmi2Boolean,
    pub next_event_time_defined: fmi2Boolean,
    pub next_event_time: fmi2Real,
}
