//! The bodies of the C functions that FMI 2.0 and 3.0 define alike, generic over the version
//! `V` and the core `M` of an [`Instance`]: running a call on an instance behind its C pointer
//! with panics caught, freeing it, values, the six FMU-state functions (get, set, free, size,
//! serialize, deserialize: FMI 2.0 section 2.1.8, FMI 3.0 section 2.3.6), and the Model
//! Exchange calls with the directional derivative (FMI 2.0 sections 2.1.9 and 3.2, FMI 3.0
//! sections 2.3.8 and 3.2). Each version's `extern "C"` functions pass their own pointers, and
//! where a version checks its own way, its instance's method.
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

/// `fmi2SetTime` / `fmi3SetTime`.
pub unsafe fn set_time<V: Version, M: FmuCore>(c: *mut c_void, time: f64) -> V::Status {
    unsafe { with_instance::<V, M>(c, V::NAMES.set_time, |inst| inst.set_time(time)) }
}

/// `fmi2SetContinuousStates` / `fmi3SetContinuousStates` with the `nx` states `x`; `call` is
/// the version's, which checks the states its own way.
pub unsafe fn set_continuous_states<V: Version, M: FmuCore>(
    c: *mut c_void,
    (x, nx): (*const f64, usize),
    call: fn(&mut Instance<V, M>, &[f64]) -> Status,
) -> V::Status {
    let func = V::NAMES.set_continuous_states;
    unsafe {
        with_instance::<V, M>(c, func, |inst| match in_slice(x, nx) {
            Some(x) => call(inst, x),
            None => inst.null_argument(func, V::NAMES.continuous_states),
        })
    }
}

/// The functions that fill an array of the `n` continuous states (`func`, its array argument
/// named `argument` in NULL messages): states, derivatives, nominals; `get` fills it.
pub unsafe fn get_state_vector<V: Version, M: FmuCore>(
    c: *mut c_void,
    (func, argument): (&str, &str),
    (out, n): (*mut f64, usize),
    get: impl FnOnce(&mut Instance<V, M>, &mut [f64]) -> Status,
) -> V::Status {
    unsafe {
        with_instance::<V, M>(c, func, |inst| match out_slice(out, n) {
            Some(out) => get(inst, out),
            None => inst.null_argument(func, argument),
        })
    }
}

/// `fmi2GetEventIndicators` / `fmi3GetEventIndicators` into `n` values.
pub unsafe fn get_event_indicators<V: Version, M: FmuCore>(
    c: *mut c_void,
    (indicators, n): (*mut f64, usize),
) -> V::Status {
    let func = V::NAMES.get_event_indicators;
    unsafe {
        with_instance::<V, M>(c, func, |inst| match out_slice(indicators, n) {
            Some(_) => inst.event_indicators(n),
            None => inst.null_argument(func, "eventIndicators"),
        })
    }
}

/// `fmi2CompletedIntegratorStep` / `fmi3CompletedIntegratorStep`: the two flags are written
/// only when the call succeeds.
pub unsafe fn completed_integrator_step<V: Version, M: FmuCore>(
    c: *mut c_void,
    enter_event_mode: *mut V::Boolean,
    terminate_simulation: *mut V::Boolean,
) -> V::Status {
    let func = V::NAMES.completed_integrator_step;
    unsafe {
        with_instance::<V, M>(c, func, |inst| {
            match (enter_event_mode.as_mut(), terminate_simulation.as_mut()) {
                (Some(event), Some(terminate)) => match inst.completed_integrator_step() {
                    Ok((e, t)) => {
                        (*event, *terminate) = (e.into(), t.into());
                        Status::Ok
                    }
                    Err(status) => status,
                },
                (None, _) => inst.null_argument(func, "enterEventMode"),
                (_, None) => inst.null_argument(func, "terminateSimulation"),
            }
        })
    }
}

/// The references and values of a directional derivative: `unknowns`, `knowns`, `seed` (one
/// per known) and `sensitivity` (one per unknown), each a C array and its length.
pub struct DerivativeArrays {
    pub unknowns: (*const u32, usize),
    pub knowns: (*const u32, usize),
    pub seed: (*const f64, usize),
    pub sensitivity: (*mut f64, usize),
}

/// A version's directional derivative on its instance: unknowns, knowns, seed, sensitivity.
type DerivativeCall<V, M> = fn(&mut Instance<V, M>, &[u32], &[u32], &[f64], &mut [f64]) -> Status;

/// `fmi2GetDirectionalDerivative` / `fmi3GetDirectionalDerivative`: `call` is the version's,
/// which checks the references and lengths its own way.
pub unsafe fn get_directional_derivative<V: Version, M: FmuCore>(
    c: *mut c_void,
    d: DerivativeArrays,
    call: DerivativeCall<V, M>,
) -> V::Status {
    let (func, n) = (V::NAMES.get_directional_derivative, &V::NAMES);
    unsafe {
        with_instance::<V, M>(c, func, |inst| {
            match (
                in_slice(d.unknowns.0, d.unknowns.1),
                in_slice(d.knowns.0, d.knowns.1),
                in_slice(d.seed.0, d.seed.1),
                out_slice(d.sensitivity.0, d.sensitivity.1),
            ) {
                (Some(u), Some(k), Some(s), Some(out)) => call(inst, u, k, s, out),
                (None, ..) => inst.null_argument(func, n.unknowns),
                (_, None, ..) => inst.null_argument(func, n.knowns),
                (_, _, None, _) => inst.null_argument(func, n.seed),
                (.., None) => inst.null_argument(func, n.sensitivity),
            }
        })
    }
}
