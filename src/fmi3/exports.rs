//! The bodies of the C functions of `fmi3Functions.h` (FMI 3.0 standard, sections 2.3, 3.2, 4.2
//! and 5.2) that FMI 3.0 has of its own: instantiation, `fmi3EnterInitializationMode`,
//! `fmi3UpdateDiscreteStates`, the step and the counts of states and event indicators. The
//! functions [`export_fmi3!`](crate::export_fmi3) generates ([`super::functions`]) call them, or
//! the bodies both versions share in [`calls`](crate::fmi_common::calls).
//!
//! Each function checks its pointers, converts them to slices and strings, and calls the safe
//! [`Instance`] method inside `catch_unwind`; nothing unwinds across the C boundary. A caught
//! panic is logged and gives `fmi3Error` (the instance goes to the error state; other
//! instances are unaffected because no state is shared). A NULL instance gives `fmi3Error`
//! without a log message, there being no logger to send it to.
//!
//! Safety of all functions here: the caller is an FMI 3.0 importer and keeps the pointer and
//! calling-sequence rules of the standard: `c` is NULL or an instance returned by
//! `fmi3Instantiate…` of this FMU and not yet freed, arrays hold the given number of elements,
//! strings are NUL-terminated, FMU states come from this FMU, and one instance is not used by
//! two threads at once.
#![allow(clippy::missing_safety_doc)]

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::ptr::null_mut;

use super::Fmi3;
use super::instance::{Instance, Request};
use super::logging::logger;
use super::state_machine::Experiment;
use super::types::*;
use crate::fmi_common::calls::with_instance;
use crate::fmi_common::logging::Status;
use crate::fmi_common::model_api::FmuCore;
use crate::fmi_common::shell::{opt_str, panic_message};

/// The strings and flags of `fmi3Instantiate…`, as received.
pub struct CRequest {
    pub interface: InstanceKind,
    pub name: fmi3String,
    pub token: fmi3String,
    pub resource_path: fmi3String,
    pub logging_on: fmi3Boolean,
    pub event_mode_used: fmi3Boolean,
    pub environment: fmi3InstanceEnvironment,
    pub log_message: fmi3LogMessageCallback,
}

pub unsafe fn instantiate<M: FmuCore>(r: CRequest) -> fmi3Instance {
    let (name, token, resources) =
        unsafe { (opt_str(r.name), opt_str(r.token), opt_str(r.resource_path)) };
    let logger = || logger(r.log_message, r.environment, r.logging_on != FMI3_FALSE);
    let (Some(name), Some(token)) = (name.as_deref(), token.as_deref()) else {
        logger().log(
            Status::Error,
            "fmi3Instantiate: instanceName or instantiationToken is NULL",
        );
        return null_mut();
    };
    let request = Request {
        interface: r.interface,
        name,
        token,
        resource_path: resources.as_deref(),
        event_mode_used: r.event_mode_used != FMI3_FALSE,
    };
    match catch_unwind(AssertUnwindSafe(|| {
        Instance::<M>::create(request, logger())
    })) {
        Ok(Some(instance)) => Box::into_raw(Box::new(instance)).cast(),
        Ok(None) => null_mut(),
        Err(payload) => {
            let msg = format!(
                "fmi3Instantiate: internal error (panic: {})",
                panic_message(&*payload)
            );
            logger().log(Status::Error, &msg);
            null_mut()
        }
    }
}

/// `fmi3InstantiateScheduledExecution`, which is not offered: no instance, and the reason
/// logged.
pub unsafe fn instantiate_not_offered(
    func: &str,
    what: &str,
    environment: fmi3InstanceEnvironment,
    log_message: fmi3LogMessageCallback,
) -> fmi3Instance {
    let _ = catch_unwind(|| {
        logger(log_message, environment, false).log(
            Status::Error,
            &format!("{func}: {what} is not offered by this FMU (see modelDescription.xml)"),
        )
    });
    null_mut()
}

pub unsafe fn enter_initialization_mode<M: FmuCore>(
    c: fmi3Instance,
    tolerance_defined: fmi3Boolean,
    tolerance: f64,
    start_time: f64,
    stop_time_defined: fmi3Boolean,
    stop_time: f64,
) -> Fmi3Status {
    let experiment = Experiment {
        start_time,
        stop_time: (stop_time_defined != FMI3_FALSE).then_some(stop_time),
        tolerance: (tolerance_defined != FMI3_FALSE).then_some(tolerance),
    };
    unsafe {
        with_instance::<Fmi3, M>(c, "fmi3EnterInitializationMode", |inst| {
            inst.enter_initialization_mode(experiment)
        })
    }
}

/// Writes `value` to each output flag that is not NULL; a NULL one is an error.
unsafe fn set_flags<M: FmuCore>(
    inst: &Instance<M>,
    func: &str,
    flags: &[(&str, *mut fmi3Boolean)],
    value: fmi3Boolean,
) -> Result<(), Status> {
    if let Some((name, _)) = flags.iter().find(|(_, p)| p.is_null()) {
        return Err(inst.null_argument(func, name));
    }
    for (_, p) in flags {
        unsafe { **p = value };
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
pub unsafe fn update_discrete_states<M: FmuCore>(
    c: fmi3Instance,
    discrete_states_need_update: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
    nominals_changed: *mut fmi3Boolean,
    values_changed: *mut fmi3Boolean,
    next_event_time_defined: *mut fmi3Boolean,
    next_event_time: *mut f64,
) -> Fmi3Status {
    const F: &str = "fmi3UpdateDiscreteStates";
    unsafe {
        with_instance::<Fmi3, M>(c, F, |inst| {
            if next_event_time.is_null() {
                return inst.null_argument(F, "nextEventTime");
            }
            let flags = [
                ("discreteStatesNeedUpdate", discrete_states_need_update),
                ("terminateSimulation", terminate_simulation),
                ("nominalsOfContinuousStatesChanged", nominals_changed),
                ("valuesOfContinuousStatesChanged", values_changed),
                ("nextEventTimeDefined", next_event_time_defined),
            ];
            let status = inst.update_discrete_states();
            if status == Status::Ok
                && let Err(s) = set_flags(inst, F, &flags, FMI3_FALSE)
            {
                return s;
            }
            status
        })
    }
}

#[allow(clippy::too_many_arguments)]
pub unsafe fn do_step<M: FmuCore>(
    c: fmi3Instance,
    tc: f64,
    h: f64,
    event_handling_needed: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
    early_return: *mut fmi3Boolean,
    last_successful_time: *mut f64,
) -> Fmi3Status {
    const F: &str = "fmi3DoStep";
    unsafe {
        with_instance::<Fmi3, M>(c, F, |inst| {
            let flags = [
                ("eventHandlingNeeded", event_handling_needed),
                ("terminateSimulation", terminate_simulation),
                ("earlyReturn", early_return),
            ];
            if last_successful_time.is_null() {
                return inst.null_argument(F, "lastSuccessfulTime");
            }
            if let Err(s) = set_flags(inst, F, &flags, FMI3_FALSE) {
                return s;
            }
            let (status, t) = inst.do_step(tc, h);
            *last_successful_time = t;
            status
        })
    }
}

/// `fmi3GetNumberOfContinuousStates` and `fmi3GetNumberOfEventIndicators` (`func`): `count`
/// gives the number.
pub unsafe fn get_number_of<M: FmuCore>(
    c: fmi3Instance,
    func: &'static str,
    n: *mut usize,
    count: fn(&Instance<M>) -> usize,
) -> Fmi3Status {
    unsafe {
        with_instance::<Fmi3, M>(c, func, |inst| {
            if n.is_null() {
                return inst.null_argument(func, "the output argument");
            }
            match inst.number_of(func, count(inst)) {
                Ok(value) => {
                    *n = value;
                    Status::Ok
                }
                Err(s) => s,
            }
        })
    }
}

/// The C string returned by `fmi3GetVersion`.
pub fn version() -> *const std::ffi::c_char {
    VERSION.as_ptr()
}
