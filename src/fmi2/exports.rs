//! The `extern "C"` layer: the 44 functions of `fmi2Functions.h` (FMI 2.0 standard, sections
//! 2.1, 3.2 and 4.2), generated for one core by [`export_fmi2!`](crate::export_fmi2).
//!
//! Each function checks its pointers, converts them to slices and strings, and calls the safe
//! [`Instance`] method inside `catch_unwind`; nothing unwinds across the C boundary. A caught
//! panic is logged and gives `fmi2Error` (the instance goes to the error state; other
//! instances are unaffected because no state is shared). A NULL component gives `fmi2Error`
//! without a log message, there being no logger to send it to.
//!
//! Safety of all functions here: the caller is an FMI 2.0 importer and keeps the pointer and
//! calling-sequence rules of the standard: `c` is NULL or an instance returned by
//! `fmi2Instantiate` of this FMU and not yet freed, arrays hold `nvr` elements, strings are
//! NUL-terminated, FMU states come from this FMU, and one instance is not used by two
//! threads at once.
#![allow(clippy::missing_safety_doc)]

use std::ffi::{CStr, c_char, c_void};
use std::panic::catch_unwind;
use std::ptr::null_mut;

use super::Fmi2;
use super::instance::Instance;
use super::logging::logger;
use super::types::*;
use crate::fmi_common::calls::with_instance;
use crate::fmi_common::logging::Status;
use crate::fmi_common::model_api::{FmuCore, InstanceKind};
use crate::fmi_common::shell::{in_slice, opt_str, out_slice, panic_message};

pub unsafe fn instantiate<M: FmuCore>(
    instance_name: fmi2String,
    fmu_type: fmi2Type,
    guid: fmi2String,
    resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    if functions.is_null() {
        return null_mut();
    }
    let callbacks = unsafe { *functions };
    let (name, guid, resources) = unsafe {
        (
            opt_str(instance_name),
            opt_str(guid),
            opt_str(resource_location),
        )
    };
    let fail = |msg: &str| {
        logger(callbacks, name.as_deref().unwrap_or(""), false)
            .log(Status::Error, &format!("fmi2Instantiate: {msg}"));
        null_mut()
    };
    let kind = match fmu_type {
        FMI2_MODEL_EXCHANGE => InstanceKind::ModelExchange,
        FMI2_CO_SIMULATION => InstanceKind::CoSimulation,
        _ => {
            return fail(&format!(
                "fmuType = {fmu_type} is neither fmi2ModelExchange (0) nor fmi2CoSimulation (1)"
            ));
        }
    };
    let (Some(name), Some(guid)) = (name.as_deref(), guid.as_deref()) else {
        return fail("instanceName or fmuGUID is NULL");
    };
    match catch_unwind(|| {
        Instance::<M>::create(
            name,
            kind,
            guid,
            resources.as_deref(),
            callbacks,
            logging_on != FMI2_FALSE,
        )
    }) {
        Ok(Some(instance)) => Box::into_raw(Box::new(instance)).cast(),
        Ok(None) => null_mut(),
        Err(payload) => fail(&format!(
            "internal error (panic: {})",
            panic_message(&*payload)
        )),
    }
}

pub unsafe fn setup_experiment<M: FmuCore>(
    c: fmi2Component,
    tolerance_defined: fmi2Boolean,
    tolerance: f64,
    start_time: f64,
    stop_time_defined: fmi2Boolean,
    stop_time: f64,
) -> Fmi2Status {
    let tolerance = (tolerance_defined != FMI2_FALSE).then_some(tolerance);
    let stop_time = (stop_time_defined != FMI2_FALSE).then_some(stop_time);
    unsafe {
        with_instance::<Fmi2, M>(c, "fmi2SetupExperiment", |inst| {
            inst.setup_experiment(tolerance, start_time, stop_time)
        })
    }
}

pub unsafe fn get_directional_derivative<M: FmuCore>(
    c: fmi2Component,
    unknown: *const fmi2ValueReference,
    n_unknown: usize,
    known: *const fmi2ValueReference,
    n_known: usize,
    dv_known: *const f64,
    dv_unknown: *mut f64,
) -> Fmi2Status {
    const F: &str = "fmi2GetDirectionalDerivative";
    unsafe {
        with_instance::<Fmi2, M>(c, F, |inst| {
            match (
                in_slice(unknown, n_unknown),
                in_slice(known, n_known),
                in_slice(dv_known, n_known),
                out_slice(dv_unknown, n_unknown),
            ) {
                (Some(u), Some(k), Some(dk), Some(du)) => {
                    inst.get_directional_derivative(u, k, dk, du)
                }
                (None, ..) => inst.null_argument(F, "vUnknown_ref"),
                (_, None, ..) => inst.null_argument(F, "vKnown_ref"),
                (_, _, None, _) => inst.null_argument(F, "dvKnown"),
                (.., None) => inst.null_argument(F, "dvUnknown"),
            }
        })
    }
}

pub unsafe fn new_discrete_states<M: FmuCore>(
    c: fmi2Component,
    event_info: *mut fmi2EventInfo,
) -> Fmi2Status {
    const F: &str = "fmi2NewDiscreteStates";
    unsafe {
        with_instance::<Fmi2, M>(c, F, |inst| {
            let Some(out) = event_info.as_mut() else {
                return inst.null_argument(F, "fmi2eventInfo");
            };
            match inst.new_discrete_states() {
                Ok(info) => {
                    *out = fmi2EventInfo {
                        new_discrete_states_needed: info.new_discrete_states_needed.into(),
                        terminate_simulation: info.terminate_simulation.into(),
                        nominals_of_continuous_states_changed: info
                            .nominals_of_continuous_states_changed
                            .into(),
                        values_of_continuous_states_changed: info
                            .values_of_continuous_states_changed
                            .into(),
                        next_event_time_defined: info.next_event_time.is_some().into(),
                        next_event_time: info.next_event_time.unwrap_or(0.0),
                    };
                    Status::Ok
                }
                Err(status) => status,
            }
        })
    }
}

pub unsafe fn completed_integrator_step<M: FmuCore>(
    c: fmi2Component,
    enter_event_mode: *mut fmi2Boolean,
    terminate_simulation: *mut fmi2Boolean,
) -> Fmi2Status {
    const F: &str = "fmi2CompletedIntegratorStep";
    unsafe {
        with_instance::<Fmi2, M>(c, F, |inst| {
            match (enter_event_mode.as_mut(), terminate_simulation.as_mut()) {
                (Some(event), Some(terminate)) => match inst.completed_integrator_step() {
                    Ok((e, t)) => {
                        (*event, *terminate) = (e.into(), t.into());
                        Status::Ok
                    }
                    Err(status) => status,
                },
                (None, _) => inst.null_argument(F, "enterEventMode"),
                (_, None) => inst.null_argument(F, "terminateSimulation"),
            }
        })
    }
}

pub unsafe fn set_time<M: FmuCore>(c: fmi2Component, time: f64) -> Fmi2Status {
    unsafe { with_instance::<Fmi2, M>(c, "fmi2SetTime", |inst| inst.set_time(time)) }
}

pub unsafe fn set_continuous_states<M: FmuCore>(
    c: fmi2Component,
    x: *const f64,
    nx: usize,
) -> Fmi2Status {
    const F: &str = "fmi2SetContinuousStates";
    unsafe {
        with_instance::<Fmi2, M>(c, F, |inst| match in_slice(x, nx) {
            Some(x) => inst.set_continuous_states(x),
            None => inst.null_argument(F, "x"),
        })
    }
}

/// The functions that fill an array of the `nx` continuous states (`func`, its array argument
/// named `argument`): states, derivatives, nominals.
pub unsafe fn get_state_vector<M: FmuCore>(
    c: fmi2Component,
    func: &'static str,
    argument: &'static str,
    out: *mut f64,
    nx: usize,
    get: fn(&mut Instance<M>, &mut [f64]) -> Status,
) -> Fmi2Status {
    unsafe {
        with_instance::<Fmi2, M>(c, func, |inst| match out_slice(out, nx) {
            Some(out) => get(inst, out),
            None => inst.null_argument(func, argument),
        })
    }
}

pub unsafe fn get_event_indicators<M: FmuCore>(
    c: fmi2Component,
    indicators: *mut f64,
    ni: usize,
) -> Fmi2Status {
    const F: &str = "fmi2GetEventIndicators";
    unsafe {
        with_instance::<Fmi2, M>(c, F, |inst| match out_slice(indicators, ni) {
            Some(_) => inst.get_event_indicators(ni),
            None => inst.null_argument(F, "eventIndicators"),
        })
    }
}

pub unsafe fn do_step<M: FmuCore>(
    c: fmi2Component,
    tc: f64,
    h: f64,
    no_set_fmu_state_prior: fmi2Boolean,
) -> Fmi2Status {
    unsafe {
        with_instance::<Fmi2, M>(c, "fmi2DoStep", |inst| {
            inst.do_step(tc, h, no_set_fmu_state_prior != FMI2_FALSE)
        })
    }
}

/// `fmi2GetStatus`, `fmi2GetIntegerStatus`, `fmi2GetStringStatus` (`func`): no value is ever
/// delivered, so `value` may point to any type.
pub unsafe fn get_valueless_status<M: FmuCore>(
    c: fmi2Component,
    func: &'static str,
    kind: fmi2StatusKind,
    value: *mut c_void,
) -> Fmi2Status {
    unsafe {
        with_instance::<Fmi2, M>(c, func, |inst| {
            if value.is_null() {
                return inst.null_argument(func, "value");
            }
            inst.get_valueless_status(func, kind)
        })
    }
}

pub unsafe fn get_real_status<M: FmuCore>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut f64,
) -> Fmi2Status {
    const F: &str = "fmi2GetRealStatus";
    unsafe {
        with_instance::<Fmi2, M>(c, F, |inst| match value.as_mut() {
            Some(v) => inst.get_real_status(kind, v),
            None => inst.null_argument(F, "value"),
        })
    }
}

pub unsafe fn get_boolean_status<M: FmuCore>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> Fmi2Status {
    const F: &str = "fmi2GetBooleanStatus";
    unsafe {
        with_instance::<Fmi2, M>(c, F, |inst| match value.as_mut() {
            Some(v) => {
                let mut b = false;
                let status = inst.get_boolean_status(kind, &mut b);
                if status == Status::Ok {
                    *v = fmi2Boolean::from(b);
                }
                status
            }
            None => inst.null_argument(F, "value"),
        })
    }
}

/// The C string returned by `fmi2GetTypesPlatform`/`fmi2GetVersion`.
pub fn static_c_str(s: &'static CStr) -> *const c_char {
    s.as_ptr()
}

/// Exports the 44 functions of `fmi2Functions.h` for the core type `$core` (an
/// [`FmuCore`](crate::fmi_common::model_api::FmuCore)). Invoke exactly once per shared
/// library, at item level of a module of its own (it imports the C types there):
/// `mod fmi2_functions { hasel_fmu::export_fmi2!(super::MyCore); }` (inside this crate:
/// `crate::export_fmi2!`).
#[macro_export]
macro_rules! export_fmi2 {
    ($core:ty) => {
        $crate::__fmi2_functions!([#[unsafe(no_mangle)]] $core);
    };
}

/// The functions of [`export_fmi2!`]; the bracketed attributes go on each function (tests
/// pass none, to get the C-ABI functions without exported symbol names). Each function hands
/// its arguments to the function of [`exports`](crate::fmi2::exports) of the same name.
#[doc(hidden)]
#[macro_export]
macro_rules! __fmi2_functions {
    ([$($attr:tt)*] $core:ty) => {
        use $crate::fmi2::exports as shell;
        use $crate::fmi2::Fmi2;
        use $crate::fmi2::instance::Instance;
        use $crate::fmi2::types::*;
        use $crate::fmi_common::calls as common;

        // Inquire platform and version number of the header files (section 2.1.4)

        $($attr)* #[allow(non_snake_case)]
        pub extern "C" fn fmi2GetTypesPlatform() -> *const ::std::ffi::c_char {
            shell::static_c_str(TYPES_PLATFORM)
        }

        $($attr)* #[allow(non_snake_case)]
        pub extern "C" fn fmi2GetVersion() -> *const ::std::ffi::c_char {
            shell::static_c_str(VERSION)
        }

        // Creation and destruction of instances, debug logging (sections 2.1.5, 2.1.6)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetDebugLogging(
            c: fmi2Component,
            logging_on: fmi2Boolean,
            n_categories: usize,
            categories: *const fmi2String,
        ) -> fmi2Status {
            unsafe { common::set_debug_logging::<Fmi2, $core>(c, logging_on != FMI2_FALSE, n_categories, categories) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Instantiate(
            name: fmi2String,
            fmu_type: fmi2Type,
            guid: fmi2String,
            resources: fmi2String,
            functions: *const fmi2CallbackFunctions,
            _visible: fmi2Boolean, // no user interface to show (section 2.1.6)
            logging_on: fmi2Boolean,
        ) -> fmi2Component {
            unsafe {
                shell::instantiate::<$core>(name, fmu_type, guid, resources, functions, logging_on)
            }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
            unsafe { common::free_instance::<Fmi2, $core>(c) }
        }

        // Initialization, termination and reset (section 2.1.6)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetupExperiment(
            c: fmi2Component,
            tol_defined: fmi2Boolean,
            tol: fmi2Real,
            start: fmi2Real,
            stop_defined: fmi2Boolean,
            stop: fmi2Real,
        ) -> fmi2Status {
            unsafe {
                shell::setup_experiment::<$core>(c, tol_defined, tol, start, stop_defined, stop)
            }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2EnterInitializationMode", Instance::enter_initialization_mode) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2ExitInitializationMode", Instance::exit_initialization_mode) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2Terminate", Instance::terminate) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2Reset", Instance::reset) }
        }

        // Getting and setting variable values (section 2.1.7); Real variables only

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetReal(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *mut fmi2Real,
        ) -> fmi2Status {
            unsafe { common::get_values::<Fmi2, $core>(c, (vr, nvr), (value, nvr)) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetInteger(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *mut fmi2Integer,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2GetInteger", (vr, nvr), value.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetBoolean(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *mut fmi2Boolean,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2GetBoolean", (vr, nvr), value.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetString(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *mut fmi2String,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2GetString", (vr, nvr), value.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetReal(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *const fmi2Real,
        ) -> fmi2Status {
            unsafe { common::set_values::<Fmi2, $core>(c, (vr, nvr), (value, nvr)) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetInteger(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *const fmi2Integer,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2SetInteger", (vr, nvr), value.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetBoolean(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *const fmi2Boolean,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2SetBoolean", (vr, nvr), value.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetString(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            nvr: usize,
            value: *const fmi2String,
        ) -> fmi2Status {
            unsafe { common::no_variables::<Fmi2, $core>(c, "fmi2SetString", (vr, nvr), value.cast()) }
        }

        // FMU states (section 2.1.8)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetFMUstate(
            c: fmi2Component,
            state: *mut fmi2FMUstate,
        ) -> fmi2Status {
            unsafe { common::get_fmu_state::<Fmi2, $core>(c, "fmi2GetFMUstate", state) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetFMUstate(
            c: fmi2Component,
            state: fmi2FMUstate,
        ) -> fmi2Status {
            unsafe { common::set_fmu_state::<Fmi2, $core>(c, "fmi2SetFMUstate", state) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2FreeFMUstate(
            c: fmi2Component,
            state: *mut fmi2FMUstate,
        ) -> fmi2Status {
            unsafe { common::free_fmu_state::<Fmi2, $core>(c, "fmi2FreeFMUstate", state) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
            c: fmi2Component,
            state: fmi2FMUstate,
            size: *mut usize,
        ) -> fmi2Status {
            unsafe { common::serialized_fmu_state_size::<Fmi2, $core>(c, "fmi2SerializedFMUstateSize", state, size) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SerializeFMUstate(
            c: fmi2Component,
            state: fmi2FMUstate,
            bytes: *mut fmi2Byte,
            size: usize,
        ) -> fmi2Status {
            unsafe { common::serialize_fmu_state::<Fmi2, $core>(c, "fmi2SerializeFMUstate", state, bytes.cast(), size) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
            c: fmi2Component,
            bytes: *const fmi2Byte,
            size: usize,
            state: *mut fmi2FMUstate,
        ) -> fmi2Status {
            unsafe { common::deserialize_fmu_state::<Fmi2, $core>(c, "fmi2DeSerializeFMUstate", bytes.cast(), size, state) }
        }

        // Directional derivatives (section 2.1.9)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
            c: fmi2Component,
            v_unknown_ref: *const fmi2ValueReference,
            n_unknown: usize,
            v_known_ref: *const fmi2ValueReference,
            n_known: usize,
            dv_known: *const fmi2Real,
            dv_unknown: *mut fmi2Real,
        ) -> fmi2Status {
            unsafe {
                shell::get_directional_derivative::<$core>(
                    c,
                    v_unknown_ref,
                    n_unknown,
                    v_known_ref,
                    n_known,
                    dv_known,
                    dv_unknown,
                )
            }
        }

        // Model Exchange (section 3.2)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2EnterEventMode(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2EnterEventMode", Instance::enter_event_mode) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2NewDiscreteStates(
            c: fmi2Component,
            event_info: *mut fmi2EventInfo,
        ) -> fmi2Status {
            unsafe { shell::new_discrete_states::<$core>(c, event_info) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2EnterContinuousTimeMode", Instance::enter_continuous_time_mode) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
            c: fmi2Component,
            _no_set_fmu_state_prior_to_current_point: fmi2Boolean,
            enter_event_mode: *mut fmi2Boolean,
            terminate_simulation: *mut fmi2Boolean,
        ) -> fmi2Status {
            unsafe {
                shell::completed_integrator_step::<$core>(
                    c,
                    enter_event_mode,
                    terminate_simulation,
                )
            }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status {
            unsafe { shell::set_time::<$core>(c, time) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetContinuousStates(
            c: fmi2Component,
            x: *const fmi2Real,
            nx: usize,
        ) -> fmi2Status {
            unsafe { shell::set_continuous_states::<$core>(c, x, nx) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetDerivatives(
            c: fmi2Component,
            derivatives: *mut fmi2Real,
            nx: usize,
        ) -> fmi2Status {
            unsafe {
                shell::get_state_vector::<$core>(
                    c,
                    "fmi2GetDerivatives",
                    "derivatives",
                    derivatives,
                    nx,
                    |inst, out| inst.get_derivatives(out),
                )
            }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetEventIndicators(
            c: fmi2Component,
            event_indicators: *mut fmi2Real,
            ni: usize,
        ) -> fmi2Status {
            unsafe { shell::get_event_indicators::<$core>(c, event_indicators, ni) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetContinuousStates(
            c: fmi2Component,
            x: *mut fmi2Real,
            nx: usize,
        ) -> fmi2Status {
            unsafe {
                shell::get_state_vector::<$core>(
                    c,
                    "fmi2GetContinuousStates",
                    "x",
                    x,
                    nx,
                    |inst, out| inst.get_continuous_states(out),
                )
            }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
            c: fmi2Component,
            x_nominal: *mut fmi2Real,
            nx: usize,
        ) -> fmi2Status {
            unsafe {
                shell::get_state_vector::<$core>(
                    c,
                    "fmi2GetNominalsOfContinuousStates",
                    "x_nominal",
                    x_nominal,
                    nx,
                    |inst, out| inst.get_nominals(out),
                )
            }
        }

        // Co-Simulation (section 4.2)

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
            c: fmi2Component,
            _vr: *const fmi2ValueReference,
            _nvr: usize,
            _order: *const fmi2Integer,
            _value: *const fmi2Real,
        ) -> fmi2Status {
            let what = "canInterpolateInputs (input derivatives)";
            unsafe { common::not_offered::<Fmi2, $core>(c, "fmi2SetRealInputDerivatives", what) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
            c: fmi2Component,
            _vr: *const fmi2ValueReference,
            _nvr: usize,
            _order: *const fmi2Integer,
            _value: *mut fmi2Real,
        ) -> fmi2Status {
            let what = "maxOutputDerivativeOrder > 0 (output derivatives)";
            unsafe { common::not_offered::<Fmi2, $core>(c, "fmi2GetRealOutputDerivatives", what) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2DoStep(
            c: fmi2Component,
            tc: fmi2Real,
            h: fmi2Real,
            no_set_prior: fmi2Boolean,
        ) -> fmi2Status {
            unsafe { shell::do_step::<$core>(c, tc, h, no_set_prior) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
            unsafe { common::simple::<Fmi2, $core>(c, "fmi2CancelStep", |inst| inst.cancel_step()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetStatus(
            c: fmi2Component,
            kind: fmi2StatusKind,
            value: *mut fmi2Status,
        ) -> fmi2Status {
            unsafe { shell::get_valueless_status::<$core>(c, "fmi2GetStatus", kind, value.cast()) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetRealStatus(
            c: fmi2Component,
            kind: fmi2StatusKind,
            value: *mut fmi2Real,
        ) -> fmi2Status {
            unsafe { shell::get_real_status::<$core>(c, kind, value) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetIntegerStatus(
            c: fmi2Component,
            kind: fmi2StatusKind,
            value: *mut fmi2Integer,
        ) -> fmi2Status {
            unsafe {
                shell::get_valueless_status::<$core>(c, "fmi2GetIntegerStatus", kind, value.cast())
            }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetBooleanStatus(
            c: fmi2Component,
            kind: fmi2StatusKind,
            value: *mut fmi2Boolean,
        ) -> fmi2Status {
            unsafe { shell::get_boolean_status::<$core>(c, kind, value) }
        }

        $($attr)* #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetStringStatus(
            c: fmi2Component,
            kind: fmi2StatusKind,
            value: *mut fmi2String,
        ) -> fmi2Status {
            unsafe {
                shell::get_valueless_status::<$core>(c, "fmi2GetStringStatus", kind, value.cast())
            }
        }
    };
}
