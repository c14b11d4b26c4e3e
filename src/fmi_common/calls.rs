//! The bodies of the C functions that FMI 2.0 and 3.0 define alike, generic over the version
//! `V` and the core `M` of an [`Instance`]: running a call on an instance behind its C pointer
//! with panics caught, freeing it, and the six FMU-state functions (get, set, free, size, serialize, deserialize:
//! FMI 2.0 section 2.1.8, FMI 3.0 section 2.3.6). Each version's `extern "C"` functions pass
//! their own name, pointers and status type.
//!
//! Safety of all functions here: the caller is an importer of the version and keeps the
//! standard's pointer and calling-sequence rules: `c` is NULL or an `Instance<V, M>` made
//! by this FMU and not yet freed, FMU states come from this FMU, arrays hold the given number
//! of elements, and one instance is not used by two threads at once.
#![allow(clippy::missing_safety_doc)]

use std::ffi::{c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::ptr::null_mut;

use super::fmu_state::{Format, Snapshot};
use super::instance::{Instance, Version};
use super::logging::Status;
use super::model_api::FmuCore;
use super::shell::{in_slice, opt_str, out_slice, panic_message};

/// The FMU state of an instance of `V` around `M`.
type State<V, M> = Snapshot<M, <V as Format>::Phase>;

/// Runs `f` on the instance behind `c`, catching panics. A NULL instance gives the error
/// status without a log message, there being no logger to send it to.
pub unsafe fn with_instance<V: Version, M: FmuCore>(
    c: *mut c_void,
    func: &str,
    f: impl FnOnce(&mut Instance<V, M>) -> Status,
) -> V::Status {
    if c.is_null() {
        return Status::Error.into();
    }
    // SAFETY: `c` is an `Instance<V, M>` (caller contract) used by one thread.
    let inst = unsafe { &mut *c.cast::<Instance<V, M>>() };
    let status = match catch_unwind(AssertUnwindSafe(|| f(&mut *inst))) {
        Ok(status) => status,
        Err(payload) => {
            let message = panic_message(&*payload);
            catch_unwind(AssertUnwindSafe(|| inst.panicked(func, &message)))
                .unwrap_or(Status::Fatal)
        }
    };
    status.into()
}

/// `fmi2FreeInstance` / `fmi3FreeInstance`: a NULL instance is ignored.
pub unsafe fn free_instance<V: Version, M: FmuCore>(c: *mut c_void) {
    if !c.is_null() {
        // SAFETY: `c` is an `Instance<V, M>` (caller contract), not used after this call.
        let instance = unsafe { Box::from_raw(c.cast::<Instance<V, M>>()) };
        let _ = catch_unwind(AssertUnwindSafe(move || drop(instance)));
    }
}

/// The calls of one instance method without arguments (`call`, of function `func`).
pub unsafe fn simple<V: Version, M: FmuCore>(
    c: *mut c_void,
    func: &str,
    call: fn(&mut Instance<V, M>) -> Status,
) -> V::Status {
    unsafe { with_instance::<V, M>(c, func, call) }
}

/// `fmi2SetDebugLogging` / `fmi3SetDebugLogging` with the `n` category names `categories`.
pub unsafe fn set_debug_logging<V: Version, M: FmuCore>(
    c: *mut c_void,
    on: bool,
    n: usize,
    categories: *const *const c_char,
) -> V::Status {
    let func = V::NAMES.set_debug_logging;
    unsafe {
        with_instance::<V, M>(c, func, |inst| {
            let Some(pointers) = in_slice(categories, n) else {
                return inst.null_argument(func, "categories");
            };
            let mut names = Vec::with_capacity(n);
            for &p in pointers {
                let Some(name) = opt_str(p) else {
                    return inst.null_argument(func, "categories[i]");
                };
                names.push(name.into_owned());
            }
            inst.set_debug_logging(on, &names)
        })
    }
}

/// A getter or setter (`func`) of `nvr` references `vr` and the values `values` (`None`
/// where NULL although some are needed): `call` with both, or the NULL argument named.
unsafe fn with_values<V: Version, M: FmuCore, T>(
    c: *mut c_void,
    func: &str,
    (vr, nvr): (*const u32, usize),
    values: Option<T>,
    call: fn(&mut Instance<V, M>, &[u32], T) -> Status,
) -> V::Status {
    unsafe {
        with_instance::<V, M>(c, func, |inst| match (in_slice(vr, nvr), values) {
            (Some(vrs), Some(values)) => call(inst, vrs, values),
            (None, _) => inst.null_argument(func, V::NAMES.value_references),
            (_, None) => inst.null_argument(func, V::NAMES.values),
        })
    }
}

/// `fmi2GetReal` / `fmi3GetFloat64`: `nvr` references, `n_values` values.
pub unsafe fn get_values<V: Version, M: FmuCore>(
    c: *mut c_void,
    vr: (*const u32, usize),
    (values, n_values): (*mut f64, usize),
) -> V::Status {
    let values = unsafe { out_slice(values, n_values) };
    unsafe {
        with_values(
            c,
            V::NAMES.get_values,
            vr,
            values,
            Instance::<V, M>::get_values,
        )
    }
}

/// `fmi2SetReal` / `fmi3SetFloat64`: `nvr` references, `n_values` values.
pub unsafe fn set_values<V: Version, M: FmuCore>(
    c: *mut c_void,
    vr: (*const u32, usize),
    (values, n_values): (*const f64, usize),
) -> V::Status {
    let values = unsafe { in_slice(values, n_values) };
    unsafe {
        with_values(
            c,
            V::NAMES.set_values,
            vr,
            values,
            Instance::<V, M>::set_values,
        )
    }
}

/// The getters and setters of the types this FMU has no variables of (`func`, named
/// `fmiXGet<type>` / `fmiXSet<type>`); `values` is the value array, of whichever type.
pub unsafe fn no_variables<V: Version, M: FmuCore>(
    c: *mut c_void,
    func: &str,
    (vr, nvr): (*const u32, usize),
    values: *const c_void,
) -> V::Status {
    const PREFIX: usize = "fmiXGet".len();
    let setter = func.get(PREFIX - 3..PREFIX) == Some("Set");
    let type_name = func.get(PREFIX..).unwrap_or(func);
    let n = &V::NAMES;
    unsafe {
        with_instance::<V, M>(c, func, |inst| match in_slice(vr, nvr) {
            None => inst.null_argument(func, n.value_references),
            Some(_) if nvr > 0 && values.is_null() => inst.null_argument(func, n.values),
            Some(vrs) => inst.no_variables_of_type(func, type_name, setter, vrs),
        })
    }
}

/// Functions of interfaces or capabilities (`what`) this FMU does not offer.
pub unsafe fn not_offered<V: Version, M: FmuCore>(
    c: *mut c_void,
    func: &str,
    what: &str,
) -> V::Status {
    unsafe { with_instance::<V, M>(c, func, |inst| inst.not_offered(func, what)) }
}

/// Puts `snapshot` where `*state` points: a new state where it is NULL, else into the state
/// there, which is one of this FMU's to be reused (FMI 2.0 section 2.1.8). Replaced by a new
/// one, the importer's only handle of it would be lost (a leak the fuzzer found after a
/// deserialization into a held handle). `state` is not NULL.
unsafe fn store<V: Version, M: FmuCore>(state: *mut *mut c_void, snapshot: State<V, M>) {
    unsafe {
        if (*state).is_null() {
            *state = Box::into_raw(Box::new(snapshot)).cast();
        } else {
            *(*state).cast::<State<V, M>>() = snapshot;
        }
    }
}

/// `fmi2GetFMUstate` / `fmi3GetFMUState`: a new state, or the one in `*state` overwritten.
pub unsafe fn get_fmu_state<V: Version, M: FmuCore>(
    c: *mut c_void,
    func: &str,
    state: *mut *mut c_void,
) -> V::Status {
    unsafe {
        with_instance::<V, M>(c, func, |inst| {
            if state.is_null() {
                return inst.null_argument(func, V::NAMES.fmu_state);
            }
            store::<V, M>(state, inst.snapshot());
            Status::Ok
        })
    }
}

/// `fmi2SetFMUstate` / `fmi3SetFMUState`.
pub unsafe fn set_fmu_state<V: Version, M: FmuCore>(
    c: *mut c_void,
    func: &str,
    state: *mut c_void,
) -> V::Status {
    unsafe {
        with_instance::<V, M>(c, func, |inst| match state.cast::<State<V, M>>().as_ref() {
            Some(snapshot) => inst.restore(snapshot),
            None => inst.null_argument(func, V::NAMES.fmu_state),
        })
    }
}

/// `fmi2FreeFMUstate` / `fmi3FreeFMUState`: a NULL pointer is ignored.
pub unsafe fn free_fmu_state<V: Version, M: FmuCore>(
    c: *mut c_void,
    func: &str,
    state: *mut *mut c_void,
) -> V::Status {
    unsafe {
        with_instance::<V, M>(c, func, |_| {
            if !state.is_null() && !(*state).is_null() {
                drop(Box::from_raw((*state).cast::<State<V, M>>()));
                *state = null_mut();
            }
            Status::Ok
        })
    }
}

/// `fmi2SerializedFMUstateSize` / `fmi3SerializedFMUStateSize`.
pub unsafe fn serialized_fmu_state_size<V: Version, M: FmuCore>(
    c: *mut c_void,
    func: &str,
    state: *mut c_void,
    size: *mut usize,
) -> V::Status {
    unsafe {
        with_instance::<V, M>(c, func, |inst| {
            match (state.cast::<State<V, M>>().as_ref(), size.is_null()) {
                (Some(snapshot), false) => {
                    *size = V::to_bytes(snapshot).len();
                    Status::Ok
                }
                (None, _) => inst.null_argument(func, V::NAMES.fmu_state),
                (_, true) => inst.null_argument(func, "size"),
            }
        })
    }
}

/// `fmi2SerializeFMUstate` / `fmi3SerializeFMUState`, into a buffer of `size` bytes.
pub unsafe fn serialize_fmu_state<V: Version, M: FmuCore>(
    c: *mut c_void,
    func: &str,
    state: *mut c_void,
    bytes: *mut u8,
    size: usize,
) -> V::Status {
    unsafe {
        with_instance::<V, M>(c, func, |inst| {
            let Some(snapshot) = state.cast::<State<V, M>>().as_ref() else {
                return inst.null_argument(func, V::NAMES.fmu_state);
            };
            let data = V::to_bytes(snapshot);
            if size < data.len() {
                let needs = data.len();
                return inst.error(
                    func,
                    format_args!(
                        "buffer of {size} bytes is too small, the state needs {needs} ({})",
                        V::NAMES.serialized_size
                    ),
                );
            }
            let Some(out) = out_slice(bytes, data.len()) else {
                return inst.null_argument(func, "serializedState");
            };
            out.copy_from_slice(&data);
            Status::Ok
        })
    }
}

/// `fmi2DeSerializeFMUstate` / `fmi3DeserializeFMUState`: a state from `size` bytes, new or
/// into the one in `*state`.
pub unsafe fn deserialize_fmu_state<V: Version, M: FmuCore>(
    c: *mut c_void,
    func: &str,
    bytes: *const u8,
    size: usize,
    state: *mut *mut c_void,
) -> V::Status {
    unsafe {
        with_instance::<V, M>(c, func, |inst| {
            let Some(data) = in_slice(bytes, size) else {
                return inst.null_argument(func, "serializedState");
            };
            if state.is_null() {
                return inst.null_argument(func, V::NAMES.fmu_state);
            }
            match inst.deserialize(data) {
                Ok(snapshot) => {
                    store::<V, M>(state, snapshot);
                    Status::Ok
                }
                Err(status) => status,
            }
        })
    }
}
