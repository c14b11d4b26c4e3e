//! The bodies of the C functions that FMI 2.0 and 3.0 define alike, generic over a version's
//! instance ([`ShellInstance`]): running a call on an instance behind its C pointer with panics
//! caught, and the six FMU-state functions (get, set, free, size, serialize, deserialize:
//! FMI 2.0 section 2.1.8, FMI 3.0 section 2.3.6). Each version's `extern "C"` functions pass
//! their own name, pointers and status type.
//!
//! Safety of all functions here: the caller is an importer of the version and keeps the
//! standard's pointer and calling-sequence rules: `c` is NULL or an instance of type `I` made
//! by this FMU and not yet freed, FMU states come from this FMU, arrays hold the given number
//! of elements, and one instance is not used by two threads at once.
#![allow(clippy::missing_safety_doc)]

use std::ffi::c_void;
use std::fmt;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::ptr::null_mut;

use super::shell::{in_slice, out_slice, panic_message};

/// What the shared bodies need of a version's instance.
pub trait ShellInstance {
    /// The version's status enumeration.
    type Status: Copy;
    /// The version's FMU state.
    type Snapshot;
    const OK: Self::Status;
    const ERROR: Self::Status;
    const FATAL: Self::Status;
    /// The name of an FMU-state argument in the version's headers.
    const FMU_STATE: &'static str;
    /// The function that tells the size of a serialized FMU state.
    const SIZE_FUNCTION: &'static str;

    /// Logs an error of `func` and gives the error status.
    fn fail(&self, func: &str, msg: fmt::Arguments) -> Self::Status;
    /// Logs a caught panic of `func` and puts the instance into the error state.
    fn panicked(&mut self, func: &str, message: &str) -> Self::Status;
    /// The instance's FMU state now.
    fn snapshot(&self) -> Self::Snapshot;
    /// Goes back to `state`.
    fn restore(&mut self, state: &Self::Snapshot) -> Self::Status;
    /// A state's serialized bytes.
    fn serialize(state: &Self::Snapshot) -> Vec<u8>;
    /// A state from serialized bytes, or the logged error's status.
    fn deserialize(&self, bytes: &[u8]) -> Result<Self::Snapshot, Self::Status>;
}

/// Runs `f` on the instance behind `c`, catching panics. A NULL instance gives the error
/// status without a log message, there being no logger to send it to.
pub unsafe fn with_instance<I: ShellInstance>(
    c: *mut c_void,
    func: &str,
    f: impl FnOnce(&mut I) -> I::Status,
) -> I::Status {
    if c.is_null() {
        return I::ERROR;
    }
    // SAFETY: `c` is an instance of type `I` (caller contract) used by one thread.
    let inst = unsafe { &mut *c.cast::<I>() };
    match catch_unwind(AssertUnwindSafe(|| f(&mut *inst))) {
        Ok(status) => status,
        Err(payload) => {
            let message = panic_message(&*payload);
            catch_unwind(AssertUnwindSafe(|| inst.panicked(func, &message))).unwrap_or(I::FATAL)
        }
    }
}

fn null_argument<I: ShellInstance>(inst: &I, func: &str, argument: &str) -> I::Status {
    inst.fail(func, format_args!("argument {argument} is NULL"))
}

/// `fmi2GetFMUstate` / `fmi3GetFMUState`: a new state, or the one in `*state` overwritten.
pub unsafe fn get_fmu_state<I: ShellInstance>(
    c: *mut c_void,
    func: &str,
    state: *mut *mut c_void,
) -> I::Status {
    unsafe {
        with_instance::<I>(c, func, |inst| {
            if state.is_null() {
                return null_argument(inst, func, I::FMU_STATE);
            }
            let snapshot = inst.snapshot();
            if (*state).is_null() {
                *state = Box::into_raw(Box::new(snapshot)).cast();
            } else {
                // a non-NULL *FMUstate is a state of this FMU to be reused
                *(*state).cast::<I::Snapshot>() = snapshot;
            }
            I::OK
        })
    }
}

/// `fmi2SetFMUstate` / `fmi3SetFMUState`.
pub unsafe fn set_fmu_state<I: ShellInstance>(
    c: *mut c_void,
    func: &str,
    state: *mut c_void,
) -> I::Status {
    unsafe {
        with_instance::<I>(c, func, |inst| match state.cast::<I::Snapshot>().as_ref() {
            Some(snapshot) => inst.restore(snapshot),
            None => null_argument(inst, func, I::FMU_STATE),
        })
    }
}

/// `fmi2FreeFMUstate` / `fmi3FreeFMUState`: a NULL pointer is ignored.
pub unsafe fn free_fmu_state<I: ShellInstance>(
    c: *mut c_void,
    func: &str,
    state: *mut *mut c_void,
) -> I::Status {
    unsafe {
        with_instance::<I>(c, func, |_| {
            if !state.is_null() && !(*state).is_null() {
                drop(Box::from_raw((*state).cast::<I::Snapshot>()));
                *state = null_mut();
            }
            I::OK
        })
    }
}

/// `fmi2SerializedFMUstateSize` / `fmi3SerializedFMUStateSize`.
pub unsafe fn serialized_fmu_state_size<I: ShellInstance>(
    c: *mut c_void,
    func: &str,
    state: *mut c_void,
    size: *mut usize,
) -> I::Status {
    unsafe {
        with_instance::<I>(c, func, |inst| {
            match (state.cast::<I::Snapshot>().as_ref(), size.is_null()) {
                (Some(snapshot), false) => {
                    *size = I::serialize(snapshot).len();
                    I::OK
                }
                (None, _) => null_argument(inst, func, I::FMU_STATE),
                (_, true) => null_argument(inst, func, "size"),
            }
        })
    }
}

/// `fmi2SerializeFMUstate` / `fmi3SerializeFMUState`, into a buffer of `size` bytes.
pub unsafe fn serialize_fmu_state<I: ShellInstance>(
    c: *mut c_void,
    func: &str,
    state: *mut c_void,
    bytes: *mut u8,
    size: usize,
) -> I::Status {
    unsafe {
        with_instance::<I>(c, func, |inst| {
            let Some(snapshot) = state.cast::<I::Snapshot>().as_ref() else {
                return null_argument(inst, func, I::FMU_STATE);
            };
            let data = I::serialize(snapshot);
            if size < data.len() {
                let needs = data.len();
                return inst.fail(
                    func,
                    format_args!(
                        "buffer of {size} bytes is too small, the state needs {needs} ({})",
                        I::SIZE_FUNCTION
                    ),
                );
            }
            let Some(out) = out_slice(bytes, data.len()) else {
                return null_argument(inst, func, "serializedState");
            };
            out.copy_from_slice(&data);
            I::OK
        })
    }
}

/// `fmi2DeSerializeFMUstate` / `fmi3DeserializeFMUState`: a new state from `size` bytes.
pub unsafe fn deserialize_fmu_state<I: ShellInstance>(
    c: *mut c_void,
    func: &str,
    bytes: *const u8,
    size: usize,
    state: *mut *mut c_void,
) -> I::Status {
    unsafe {
        with_instance::<I>(c, func, |inst| {
            let Some(data) = in_slice(bytes, size) else {
                return null_argument(inst, func, "serializedState");
            };
            if state.is_null() {
                return null_argument(inst, func, I::FMU_STATE);
            }
            match inst.deserialize(data) {
                Ok(snapshot) => {
                    *state = Box::into_raw(Box::new(snapshot)).cast();
                    I::OK
                }
                Err(status) => status,
            }
        })
    }
}
