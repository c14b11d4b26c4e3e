//! The bodies of the C functions of `fmi2Functions.h` (FMI 2.0 standard, sections 2.1, 3.2 and
//! 4.2) that FMI 2.0 has of its own: instantiation, `fmi2SetupExperiment`,
//! `fmi2NewDiscreteStates`, the step and the status calls. The functions
//! [`export_fmi2!`](crate::export_fmi2) generates ([`super::functions`]) call them, or the
//! bodies both versions share in [`calls`](crate::fmi_common::calls).
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
use crate::fmi_common::shell::{opt_str, panic_message};

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
