//! The generic FMU instance: the state transitions, argument checks and logging of FMI 2.0
//! (standard sections 2.1 and 4.2) around one [`FmuCore`], in safe Rust; which call is allowed
//! in which state is the table of [`super::state_machine`]. The `extern "C"` layer in
//! [`super::exports`] only converts pointers and catches panics.
//!
//! Error policy: a call in a state where the table of section 4.2.4 does not allow it, or
//! with invalid arguments, returns `fmi2Error` with a log message naming the function and
//! the offending state, reference or value, and changes nothing. Core failures are reported
//! the same way (the core contract keeps the core unchanged on `Err`), except in `fmi2DoStep`
//! where they are `fmi2Discard` (state stepFailed). A panic puts the instance into the error
//! state, where only `fmi2Reset`, `fmi2SetFMUstate`, `fmi2FreeInstance`, the getters (for
//! debugging) and the FMU-state functions are allowed.

use std::path::{Path, PathBuf};

use super::fmu_state::Snapshot;
use super::logging::Logger;
use super::model_description::{guid_for, log_categories};
use super::state_machine::{self, Experiment, Mask, Phase, allowed, settable};
use super::types::{
    FMI2_DO_STEP_STATUS, FMI2_LAST_SUCCESSFUL_TIME, FMI2_PENDING_STATUS, FMI2_TERMINATED,
    Fmi2Status, fmi2CallbackFunctions, fmi2StatusKind,
};
use super::uri::path_from_file_uri;
use crate::fmi_common::model_api::{FmuCore, InstanceKind};
use crate::fmi_common::variables::{Variable, check_variable_table};

use Phase::*;

/// One FMU instance: the wrapper state around a core `M`.
pub struct Instance<M: FmuCore> {
    guid: String,
    resource_dir: Option<PathBuf>,
    logger: Logger,
    /// Names of all log categories of `modelDescription.xml`.
    categories: Vec<String>,
    phase: Phase,
    experiment: Option<Experiment>,
    core: M,
    /// The core's variables, sorted by value reference for lookups.
    variables: Vec<Variable>,
}

/// A fresh core with its sorted variable table and GUID.
struct Built<M> {
    core: M,
    variables: Vec<Variable>,
    guid: String,
}

fn build<M: FmuCore>(resource_dir: Option<&Path>) -> Result<Built<M>, String> {
    let core = M::instantiate(InstanceKind::CoSimulation, resource_dir)?;
    let variables = core.variables();
    check_variable_table(&variables).map_err(|e| format!("invalid variable table: {e}"))?;
    let guid = guid_for(&M::model_info(), &variables)?;
    let mut variables = variables;
    variables.sort_by_key(|v| v.value_reference);
    Ok(Built {
        core,
        variables,
        guid,
    })
}

/// The variable with value reference `vr` in a table sorted by value reference.
fn find(variables: &[Variable], vr: u32) -> Option<&Variable> {
    let i = variables
        .binary_search_by_key(&vr, |v| v.value_reference)
        .ok()?;
    Some(&variables[i])
}

/// The message of a caught panic.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(no message)".into())
}

/// An optional number for messages: the value, or "undefined".
fn optional(x: Option<f64>) -> String {
    x.map_or("undefined".into(), |x| format!("{x:?}"))
}

/// Relative tolerance for comparing `currentCommunicationPoint` with the internal time.
const TIME_RTOL: f64 = 1e-12;

/// Whether the master's time `tc` and the FMU's time `t` agree up to rounding: always within
/// 1e-12 relative, and within up to 1e-9 relative as long as that is below a thousandth of
/// the step `h` (accumulated `t += h` in the master); a skipped or repeated step never passes.
fn same_time(t: f64, tc: f64, h: f64) -> bool {
    let scale = t.abs().max(tc.abs());
    (t - tc).abs() <= (TIME_RTOL * scale).max((1e3 * TIME_RTOL * scale).min(1e-3 * h))
}

impl<M: FmuCore> Instance<M> {
    /// `fmi2Instantiate` for Co-Simulation (section 2.1.6): creates the core from the
    /// resources, checks the importer's GUID against the one computed for this core. Errors
    /// are logged and give `None`.
    pub fn instantiate(
        name: &str,
        guid: &str,
        resource_location: Option<&str>,
        callbacks: fmi2CallbackFunctions,
        logging_on: bool,
    ) -> Option<Self> {
        let logger = Logger::new(callbacks, name, logging_on);
        let fail = |msg: String| {
            logger.log(Fmi2Status::Error, &format!("fmi2Instantiate: {msg}"));
            None
        };
        if name.is_empty() {
            return fail("instanceName is empty".into());
        }
        let resource_dir = match resource_location
            .filter(|l| !l.is_empty())
            .map(path_from_file_uri)
            .transpose()
        {
            Ok(dir) => dir,
            Err(e) => return fail(e),
        };
        let built = match build::<M>(resource_dir.as_deref()) {
            Ok(b) => b,
            Err(e) => return fail(format!("cannot create the model: {e}")),
        };
        if built.guid != guid {
            return fail(format!(
                "GUID {guid} given by the importer does not match the FMU's GUID {}",
                built.guid
            ));
        }
        let categories = log_categories(&M::model_info())
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        let instance = Instance {
            guid: built.guid,
            resource_dir,
            logger,
            categories,
            phase: Instantiated,
            experiment: None,
            core: built.core,
            variables: built.variables,
        };
        instance.trace(|| {
            let resources = instance
                .resource_dir
                .as_ref()
                .map_or("none".into(), |d| d.display().to_string());
            format!("fmi2Instantiate: instance of GUID {guid} created, resources: {resources}")
        });
        Some(instance)
    }

    /// The state-machine state.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Logs an error message of `func` and returns `fmi2Error`.
    fn error(&self, func: &str, msg: impl std::fmt::Display) -> Fmi2Status {
        self.logger
            .log(Fmi2Status::Error, &format!("{func}: {msg}"));
        Fmi2Status::Error
    }

    /// Debug-logs a call trace; the message is built only when debug logging is on.
    fn trace(&self, msg: impl FnOnce() -> String) {
        if self.logger.debug_enabled() {
            self.logger.log(Fmi2Status::Ok, &msg());
        }
    }

    /// Checks the state table of section 4.2.4: `func` may be called in the states of `mask`.
    fn require(&self, func: &str, mask: Mask) -> Result<(), Fmi2Status> {
        if self.phase.is_in(mask) {
            return Ok(());
        }
        Err(self.error(
            func,
            format_args!(
                "not allowed in state {} (allowed in: {})",
                self.phase.name(),
                state_machine::names(mask)
            ),
        ))
    }

    /// Logs a caught panic of `func` and puts the instance into the error state.
    pub fn on_panic(&mut self, func: &str, message: &str) -> Fmi2Status {
        self.phase = Error;
        self.error(func, format_args!("internal error (panic: {message}); the instance is now in the error state: call fmi2Reset, fmi2SetFMUstate or fmi2FreeInstance"))
    }

    /// Logs that `func` was called with a NULL `argument`.
    pub fn null_argument(&self, func: &str, argument: &str) -> Fmi2Status {
        self.error(func, format_args!("argument {argument} is NULL"))
    }

    /// For functions of interfaces this FMU does not offer (Model Exchange, directional
    /// derivatives, input/output derivatives).
    pub fn not_offered(&self, func: &str, what: &str) -> Fmi2Status {
        self.error(
            func,
            format_args!("{what} is not offered by this FMU (see modelDescription.xml)"),
        )
    }

    /// `fmi2SetDebugLogging` (section 2.1.5); an empty `categories` means all categories.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[String]) -> Fmi2Status {
        match self
            .logger
            .set_debug_logging(on, categories, &self.categories)
        {
            Ok(()) => Fmi2Status::Ok,
            Err(bad) => self.error(
                "fmi2SetDebugLogging",
                format_args!(
                    "unknown log category {bad:?} (known: {})",
                    self.categories.join(", ")
                ),
            ),
        }
    }

    /// `fmi2SetupExperiment` (section 2.1.6).
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Fmi2Status {
        const F: &str = "fmi2SetupExperiment";
        self.trace(|| {
            format!(
                "{F}(tolerance={}, startTime={start_time:?}, stopTime={})",
                optional(tolerance),
                optional(stop_time)
            )
        });
        if let Err(s) = self.require(F, allowed::SETUP_EXPERIMENT) {
            return s;
        }
        if !start_time.is_finite() {
            return self.error(F, format_args!("startTime = {start_time:?} is not finite"));
        }
        if let Some(stop) = stop_time.filter(|s| !(s.is_finite() && *s >= start_time)) {
            return self.error(
                F,
                format_args!(
                    "stopTime = {stop:?} is not a finite time >= startTime = {start_time:?}"
                ),
            );
        }
        if let Some(tol) = tolerance.filter(|t| !(t.is_finite() && *t > 0.0)) {
            return self.error(
                F,
                format_args!("tolerance = {tol:?} is not a finite positive number"),
            );
        }
        self.experiment = Some(Experiment {
            start_time,
            stop_time,
            tolerance,
        });
        Fmi2Status::Ok
    }

    /// `fmi2EnterInitializationMode` (section 2.1.6); needs `fmi2SetupExperiment` first.
    pub fn enter_initialization_mode(&mut self) -> Fmi2Status {
        const F: &str = "fmi2EnterInitializationMode";
        self.trace(|| F.into());
        if let Err(s) = self.require(F, allowed::ENTER_INITIALIZATION_MODE) {
            return s;
        }
        let Some(e) = self.experiment else {
            return self.error(
                F,
                "fmi2SetupExperiment must be called before (section 2.1.6)",
            );
        };
        match self
            .core
            .enter_initialization(e.start_time, e.stop_time, e.tolerance)
        {
            Ok(()) => {
                self.phase = InitializationMode;
                Fmi2Status::Ok
            }
            Err(msg) => self.error(F, msg),
        }
    }

    /// `fmi2ExitInitializationMode` (section 2.1.6): on to stepComplete.
    pub fn exit_initialization_mode(&mut self) -> Fmi2Status {
        const F: &str = "fmi2ExitInitializationMode";
        self.trace(|| F.into());
        if let Err(s) = self.require(F, allowed::EXIT_INITIALIZATION_MODE) {
            return s;
        }
        match self.core.exit_initialization() {
            Ok(()) => {
                self.phase = StepComplete;
                Fmi2Status::Ok
            }
            Err(msg) => self.error(F, msg),
        }
    }

    /// `fmi2Terminate` (section 2.1.6); allowed in stepComplete and stepFailed only, so a
    /// second call is an error.
    pub fn terminate(&mut self) -> Fmi2Status {
        const F: &str = "fmi2Terminate";
        self.trace(|| F.into());
        if let Err(s) = self.require(F, allowed::TERMINATE) {
            return s;
        }
        self.phase = Terminated;
        Fmi2Status::Ok
    }

    /// `fmi2Reset` (section 2.1.6): back to the instantiated state with the start values, by
    /// creating the core anew from the same resources.
    pub fn reset(&mut self) -> Fmi2Status {
        const F: &str = "fmi2Reset";
        self.trace(|| F.into());
        let built = match build::<M>(self.resource_dir.as_deref()) {
            Ok(b) => b,
            Err(e) => {
                self.phase = Error;
                return self.error(F, format_args!("cannot create the model again: {e}"));
            }
        };
        if built.guid != self.guid {
            self.phase = Error;
            return self.error(
                F,
                format_args!(
                    "the resources changed: GUID is now {} instead of {}",
                    built.guid, self.guid
                ),
            );
        }
        self.core = built.core;
        self.variables = built.variables;
        self.experiment = None;
        self.phase = Instantiated;
        Fmi2Status::Ok
    }

    fn unknown_reference(&self, func: &str, vr: u32) -> Fmi2Status {
        self.error(func, format_args!("unknown value reference {vr}"))
    }

    /// `fmi2GetReal` (section 2.1.7).
    pub fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Fmi2Status {
        const F: &str = "fmi2GetReal";
        if let Err(s) = self.require(F, allowed::GET_VALUES) {
            return s;
        }
        for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
            let Some(v) = find(&self.variables, vr) else {
                return self.unknown_reference(F, vr);
            };
            match self.core.get_real(vr) {
                Ok(x) => *value = x,
                Err(msg) => {
                    let name = &v.name;
                    return self.error(F, format_args!("{name} (value reference {vr}): {msg}"));
                }
            }
        }
        Fmi2Status::Ok
    }

    /// `fmi2SetReal` (section 2.1.7). All references are checked before any value is set;
    /// values are then set in order, and a value the core rejects stops there.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Fmi2Status {
        const F: &str = "fmi2SetReal";
        if let Err(s) = self.require(F, allowed::SET_VALUES) {
            return s;
        }
        for &vr in vrs {
            let Some(v) = find(&self.variables, vr) else {
                return self.unknown_reference(F, vr);
            };
            if !settable(self.phase, v) {
                let initial = v.effective_initial().map_or("none", |i| i.as_str());
                return self.error(
                    F,
                    format_args!(
                        "{} (value reference {vr}, causality {}, variability {}, initial {initial}) cannot be set in state {} (FMI 2.0 section 4.2.4)",
                        v.name,
                        v.causality.as_str(),
                        v.variability.as_str(),
                        self.phase.name()
                    ),
                );
            }
        }
        for (&vr, &value) in vrs.iter().zip(values) {
            let name = &find(&self.variables, vr).expect("checked above").name;
            self.trace(|| format!("{F}: {name} = {value:?}"));
            if value.is_nan() {
                return self.error(
                    F,
                    format_args!("{name} (value reference {vr}): value is NaN"),
                );
            }
            if let Err(msg) = self.core.set_real(vr, value) {
                return self.error(
                    F,
                    format_args!("{name} (value reference {vr}) = {value:?} rejected: {msg}"),
                );
            }
        }
        Fmi2Status::Ok
    }

    /// `fmi2Get/Set{Integer,Boolean,String}`: this FMU has only Real variables, so any value
    /// reference is unknown for these types.
    pub fn no_variables_of_type(
        &self,
        func: &str,
        type_name: &str,
        setter: bool,
        vrs: &[u32],
    ) -> Fmi2Status {
        if let Err(s) = self.require(
            func,
            if setter {
                allowed::SET_VALUES
            } else {
                allowed::GET_VALUES
            },
        ) {
            return s;
        }
        match vrs.first() {
            None => Fmi2Status::Ok,
            Some(vr) => self.error(
                func,
                format_args!("unknown value reference {vr}: this FMU has no {type_name} variables"),
            ),
        }
    }

    /// `fmi2DoStep` (section 4.2.2): one synchronous step; `fmi2Discard` (state stepFailed)
    /// when the core rejects the step, which leaves it at the start of the step.
    pub fn do_step(&mut self, tc: f64, h: f64, no_set_fmu_state_prior: bool) -> Fmi2Status {
        const F: &str = "fmi2DoStep";
        self.trace(|| format!("{F}(currentCommunicationPoint={tc:?}, communicationStepSize={h:?}, noSetFMUStatePriorToCurrentPoint={no_set_fmu_state_prior})"));
        if let Err(s) = self.require(F, allowed::DO_STEP) {
            return s;
        }
        if !(h.is_finite() && h > 0.0) {
            return self.error(
                F,
                format_args!(
                    "communicationStepSize = {h:?} must be finite and > 0 (section 4.2.2)"
                ),
            );
        }
        let t = self.core.time();
        if !(tc.is_finite() && same_time(t, tc, h)) {
            return self.error(F, format_args!("currentCommunicationPoint = {tc:?} does not match the FMU's time {t:?} (difference {:?})", tc - t));
        }
        if let Some(stop) = self.experiment.and_then(|e| e.stop_time)
            && t + h > stop
            && !same_time(t + h, stop, h)
        {
            return self.error(
                F,
                format_args!(
                    "step to {:?} goes past stopTime = {stop:?} (section 2.1.6)",
                    t + h
                ),
            );
        }
        match self.core.do_step(h) {
            Ok(()) => Fmi2Status::Ok,
            Err(msg) => {
                self.phase = StepFailed;
                let t = self.core.time();
                self.logger.log(
                    Fmi2Status::Discard,
                    &format!("{F}: step from t = {tc:?} over {h:?} s discarded: {msg}; the FMU stays at t = {t:?} (fmi2LastSuccessfulTime); restore a state with fmi2SetFMUstate, or terminate"),
                );
                Fmi2Status::Discard
            }
        }
    }

    /// `fmi2CancelStep` (section 4.2.2): only for a step in progress, which never exists.
    pub fn cancel_step(&self) -> Fmi2Status {
        self.error(
            "fmi2CancelStep",
            format_args!("not allowed in state {}: fmi2DoStep is synchronous and never returns fmi2Pending, so no step is in progress", self.phase.name()),
        )
    }

    fn unsupported_kind(&self, func: &str, kind: fmi2StatusKind) -> Fmi2Status {
        let why = match kind {
            FMI2_DO_STEP_STATUS | FMI2_PENDING_STATUS => {
                "is only defined after fmi2DoStep returned fmi2Pending, which this FMU never does"
            }
            0..=3 => "is not provided by this function",
            _ => "is not a valid fmi2StatusKind",
        };
        self.error(
            func,
            format_args!("status kind {kind} {why} (section 4.2.3)"),
        )
    }

    /// `fmi2GetStatus`, `fmi2GetIntegerStatus` and `fmi2GetStringStatus` (`func`, section
    /// 4.2.3): never a value, since their kinds need a pending step (`fmi2DoStepStatus`,
    /// `fmi2PendingStatus`) and FMI 2.0 defines no Integer status.
    pub fn get_valueless_status(&self, func: &str, kind: fmi2StatusKind) -> Fmi2Status {
        self.require(func, allowed::GET_STATUS)
            .err()
            .unwrap_or_else(|| self.unsupported_kind(func, kind))
    }

    /// `fmi2GetRealStatus` (section 4.2.3): `fmi2LastSuccessfulTime` is the core's time,
    /// since a failed step leaves the core at its start.
    pub fn get_real_status(&self, kind: fmi2StatusKind, value: &mut f64) -> Fmi2Status {
        const F: &str = "fmi2GetRealStatus";
        if let Err(s) = self.require(F, allowed::GET_STATUS) {
            return s;
        }
        if kind != FMI2_LAST_SUCCESSFUL_TIME {
            return self.unsupported_kind(F, kind);
        }
        *value = self.core.time();
        Fmi2Status::Ok
    }

    /// `fmi2GetBooleanStatus` (section 4.2.3): `fmi2Terminated` is always false — a
    /// discarded step can be retried from a restored state.
    pub fn get_boolean_status(&self, kind: fmi2StatusKind, value: &mut bool) -> Fmi2Status {
        const F: &str = "fmi2GetBooleanStatus";
        if let Err(s) = self.require(F, allowed::GET_STATUS) {
            return s;
        }
        if kind != FMI2_TERMINATED {
            return self.unsupported_kind(F, kind);
        }
        *value = false;
        Fmi2Status::Ok
    }

    /// `fmi2GetFMUstate` (section 2.1.8): allowed in every state of this FMU.
    pub fn get_fmu_state(&self) -> Snapshot<M> {
        self.trace(|| {
            format!(
                "fmi2GetFMUstate at t = {:?} in state {}",
                self.core.time(),
                self.phase.name()
            )
        });
        Snapshot {
            guid: self.guid.clone(),
            phase: self.phase,
            experiment: self.experiment,
            core: self.core.clone(),
        }
    }

    /// `fmi2SetFMUstate` (section 2.1.8): restores core and state machine.
    pub fn set_fmu_state(&mut self, state: &Snapshot<M>) -> Fmi2Status {
        if state.guid != self.guid {
            return self.error(
                "fmi2SetFMUstate",
                format_args!(
                    "the state belongs to GUID {}, this instance has GUID {}",
                    state.guid, self.guid
                ),
            );
        }
        self.core = state.core.clone();
        self.phase = state.phase;
        self.experiment = state.experiment;
        self.trace(|| {
            format!(
                "fmi2SetFMUstate: back at t = {:?} in state {}",
                self.core.time(),
                self.phase.name()
            )
        });
        Fmi2Status::Ok
    }

    /// `fmi2DeSerializeFMUstate` (section 2.1.8): a state from bytes, or a logged error.
    pub fn deserialize_fmu_state(&self, bytes: &[u8]) -> Result<Snapshot<M>, Fmi2Status> {
        Snapshot::from_bytes(bytes, &self.guid, &self.core)
            .map_err(|e| self.error("fmi2DeSerializeFMUstate", e))
    }

    /// Logs an error of `func` for the caller (used by the C layer for buffer sizes).
    pub fn argument_error(&self, func: &str, msg: impl std::fmt::Display) -> Fmi2Status {
        self.error(func, msg)
    }
}
