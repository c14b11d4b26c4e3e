//! The generic FMU instance: the state transitions, argument checks and logging of FMI 2.0
//! (standard sections 2.1, 3.2 and 4.2) around one [`FmuCore`], for Model Exchange or
//! Co-Simulation, in safe Rust; which call is allowed in which state is the table of
//! [`super::state_machine`]. The `extern "C"` layer in [`super::exports`] only converts
//! pointers and catches panics.
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
use super::state_machine::{self, Experiment, Mask, Phase, States, allowed};
use super::types::{
    FMI2_DO_STEP_STATUS, FMI2_LAST_SUCCESSFUL_TIME, FMI2_PENDING_STATUS, FMI2_TERMINATED,
    Fmi2Status, fmi2CallbackFunctions, fmi2StatusKind,
};
use super::uri::path_from_file_uri;
use crate::fmi_common::calls::ShellInstance;
use crate::fmi_common::model_api::{FmuCore, InstanceKind, ModelStructure};
use crate::fmi_common::shell::same_time;
use crate::fmi_common::values::{self, find};
use crate::fmi_common::variables::{Causality, Variable, check_variable_table};

use Phase::*;

/// One FMU instance: the wrapper state around a core `M`.
pub struct Instance<M: FmuCore> {
    kind: InstanceKind,
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
    /// The continuous states and dependencies ([`FmuCore::model_structure`]).
    structure: ModelStructure,
}

/// What `fmi2NewDiscreteStates` reports (section 3.2.2): this FMU has no events, so nothing
/// changes and no event is pending.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EventInfo {
    pub new_discrete_states_needed: bool,
    pub terminate_simulation: bool,
    pub nominals_of_continuous_states_changed: bool,
    pub values_of_continuous_states_changed: bool,
    pub next_event_time: Option<f64>,
}

/// A fresh core with its sorted variable table and GUID.
struct Built<M> {
    core: M,
    variables: Vec<Variable>,
    guid: String,
}

fn build<M: FmuCore>(kind: InstanceKind, resource_dir: Option<&Path>) -> Result<Built<M>, String> {
    let core = M::instantiate(kind, resource_dir)?;
    let variables = core.variables();
    check_variable_table(&variables).map_err(|e| format!("invalid variable table: {e}"))?;
    let guid = guid_for(&M::model_info(), &variables, &M::model_structure())?;
    let mut variables = variables;
    variables.sort_by_key(|v| v.value_reference);
    Ok(Built {
        core,
        variables,
        guid,
    })
}

/// An optional number for messages: the value, or "undefined".
fn optional(x: Option<f64>) -> String {
    x.map_or("undefined".into(), |x| format!("{x:?}"))
}

impl<M: FmuCore> Instance<M> {
    /// `fmi2Instantiate` (section 2.1.6) for `kind`: creates the core from the resources,
    /// checks the importer's GUID against the one computed for this core. Errors are logged
    /// and give `None`.
    pub fn instantiate(
        name: &str,
        kind: InstanceKind,
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
        let built = match build::<M>(kind, resource_dir.as_deref()) {
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
            kind,
            guid: built.guid,
            resource_dir,
            logger,
            categories,
            phase: Instantiated,
            experiment: None,
            core: built.core,
            variables: built.variables,
            structure: M::model_structure(),
        };
        instance.trace(|| {
            let resources = instance
                .resource_dir
                .as_ref()
                .map_or("none".into(), |d| d.display().to_string());
            format!(
                "fmi2Instantiate: {} instance of GUID {guid} created, resources: {resources}",
                kind.name()
            )
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
                state_machine::names::<Phase>(mask)
            ),
        ))
    }

    /// Checks that `func`, a function of the `kind` interface only, is called on an instance
    /// of that kind.
    fn require_interface(&self, kind: InstanceKind, func: &str) -> Result<(), Fmi2Status> {
        if self.kind == kind {
            return Ok(());
        }
        Err(self.error(
            func,
            format_args!(
                "is a {} function; this instance was instantiated for {}",
                kind.name(),
                self.kind.name()
            ),
        ))
    }

    /// [`Self::require_interface`], then the state table.
    fn require_of(&self, kind: InstanceKind, func: &str, mask: Mask) -> Result<(), Fmi2Status> {
        self.require_interface(kind, func)?;
        self.require(func, mask)
    }

    /// Logs that `func` was called with a NULL `argument`.
    pub fn null_argument(&self, func: &str, argument: &str) -> Fmi2Status {
        self.error(func, format_args!("argument {argument} is NULL"))
    }

    /// For functions of capabilities this FMU does not offer (input/output derivatives).
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

    /// `fmi2ExitInitializationMode` (section 2.1.6): on to stepComplete (Co-Simulation) or
    /// Event Mode (Model Exchange, section 3.2.3).
    pub fn exit_initialization_mode(&mut self) -> Fmi2Status {
        const F: &str = "fmi2ExitInitializationMode";
        self.trace(|| F.into());
        if let Err(s) = self.require(F, allowed::EXIT_INITIALIZATION_MODE) {
            return s;
        }
        match self.core.exit_initialization() {
            Ok(()) => {
                self.phase = match self.kind {
                    InstanceKind::ModelExchange => EventMode,
                    InstanceKind::CoSimulation => StepComplete,
                };
                Fmi2Status::Ok
            }
            Err(msg) => self.error(F, msg),
        }
    }

    /// `fmi2Terminate` (section 2.1.6); allowed in stepComplete, stepFailed, Event Mode and
    /// Continuous-Time Mode only, so a second call is an error.
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
        let built = match build::<M>(self.kind, self.resource_dir.as_deref()) {
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
        match values::get(&mut self.core, &self.variables, vrs, values) {
            Ok(()) => Fmi2Status::Ok,
            Err(msg) => self.error(F, msg),
        }
    }

    /// `fmi2SetReal` (section 2.1.7). All references are checked before any value is set;
    /// values are then set in order, and a value the core rejects stops there.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Fmi2Status {
        const F: &str = "fmi2SetReal";
        if let Err(s) = self.require(F, allowed::SET_VALUES) {
            return s;
        }
        let logger = &self.logger;
        let trace = |name: &str, value: f64| {
            if logger.debug_enabled() {
                logger.log(Fmi2Status::Ok, &format!("{F}: {name} = {value:?}"));
            }
        };
        let rule = (self.phase.set_rule(), self.phase.name());
        match values::set(&mut self.core, &self.variables, rule, (vrs, values), trace) {
            Ok(()) => Fmi2Status::Ok,
            Err(msg) => self.error(F, msg),
        }
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
        let mask = if setter {
            allowed::SET_VALUES
        } else {
            allowed::GET_VALUES
        };
        if let Err(s) = self.require(func, mask) {
            return s;
        }
        match values::no_variables_of_type(&self.variables, type_name, "", vrs) {
            None => Fmi2Status::Ok,
            Some(msg) => self.error(func, msg),
        }
    }

    /// `fmi2DoStep` (section 4.2.2): one synchronous step; `fmi2Discard` (state stepFailed)
    /// when the core rejects the step, which leaves it at the start of the step.
    pub fn do_step(&mut self, tc: f64, h: f64, no_set_fmu_state_prior: bool) -> Fmi2Status {
        const F: &str = "fmi2DoStep";
        self.trace(|| format!("{F}(currentCommunicationPoint={tc:?}, communicationStepSize={h:?}, noSetFMUStatePriorToCurrentPoint={no_set_fmu_state_prior})"));
        if let Err(s) = self.require_of(InstanceKind::CoSimulation, F, allowed::DO_STEP) {
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
        const F: &str = "fmi2CancelStep";
        if let Err(s) = self.require_interface(InstanceKind::CoSimulation, F) {
            return s;
        }
        self.error(
            F,
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
        self.require_of(InstanceKind::CoSimulation, func, allowed::GET_STATUS)
            .err()
            .unwrap_or_else(|| self.unsupported_kind(func, kind))
    }

    /// `fmi2GetRealStatus` (section 4.2.3): `fmi2LastSuccessfulTime` is the core's time,
    /// since a failed step leaves the core at its start.
    pub fn get_real_status(&self, kind: fmi2StatusKind, value: &mut f64) -> Fmi2Status {
        const F: &str = "fmi2GetRealStatus";
        if let Err(s) = self.require_of(InstanceKind::CoSimulation, F, allowed::GET_STATUS) {
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
        if let Err(s) = self.require_of(InstanceKind::CoSimulation, F, allowed::GET_STATUS) {
            return s;
        }
        if kind != FMI2_TERMINATED {
            return self.unsupported_kind(F, kind);
        }
        *value = false;
        Fmi2Status::Ok
    }

    /// The number of continuous states.
    pub fn n_states(&self) -> usize {
        self.structure.derivatives.len()
    }

    /// Checks a Model Exchange call on the state vector: interface, state, and that the
    /// importer's array holds the `nx` states of `modelDescription.xml`.
    fn require_states(&self, func: &str, mask: Mask, nx: usize) -> Result<(), Fmi2Status> {
        self.require_of(InstanceKind::ModelExchange, func, mask)?;
        let n = self.n_states();
        if nx != n {
            return Err(self.error(
                func,
                format_args!("nx = {nx}, but the FMU has {n} continuous states (<Derivatives>)"),
            ));
        }
        Ok(())
    }

    /// Runs a core call of `func` that can only fail with a message; `fmi2Error` then.
    fn core_call(
        &mut self,
        func: &str,
        f: impl FnOnce(&mut M) -> Result<(), String>,
    ) -> Fmi2Status {
        match f(&mut self.core) {
            Ok(()) => Fmi2Status::Ok,
            Err(msg) => self.error(func, msg),
        }
    }

    /// `fmi2SetTime` (section 3.2.1).
    pub fn set_time(&mut self, time: f64) -> Fmi2Status {
        const F: &str = "fmi2SetTime";
        self.trace(|| format!("{F}(time={time:?})"));
        if let Err(s) = self.require_of(InstanceKind::ModelExchange, F, allowed::SET_TIME) {
            return s;
        }
        if !time.is_finite() {
            return self.error(F, format_args!("time = {time:?} is not finite"));
        }
        self.core_call(F, |core| core.set_time(time))
    }

    /// `fmi2SetContinuousStates` (section 3.2.1).
    pub fn set_continuous_states(&mut self, x: &[f64]) -> Fmi2Status {
        const F: &str = "fmi2SetContinuousStates";
        if let Err(s) = self.require_states(F, allowed::SET_CONTINUOUS_STATES, x.len()) {
            return s;
        }
        self.core_call(F, |core| core.set_continuous_states(x))
    }

    /// `fmi2GetContinuousStates` (section 3.2.2).
    pub fn get_continuous_states(&mut self, x: &mut [f64]) -> Fmi2Status {
        const F: &str = "fmi2GetContinuousStates";
        if let Err(s) = self.require_states(F, allowed::GET_STATES, x.len()) {
            return s;
        }
        self.core_call(F, |core| core.continuous_states(x))
    }

    /// `fmi2GetDerivatives` (section 3.2.2); `fmi2Discard` where the model cannot be evaluated
    /// at the states the integrator tries (it should try a smaller step).
    pub fn get_derivatives(&mut self, dx: &mut [f64]) -> Fmi2Status {
        const F: &str = "fmi2GetDerivatives";
        if let Err(s) = self.require_states(F, allowed::GET_DERIVATIVES, dx.len()) {
            return s;
        }
        match self.core.derivatives(dx) {
            Ok(()) => Fmi2Status::Ok,
            Err(msg) => {
                let t = self.core.time();
                self.logger.log(
                    Fmi2Status::Discard,
                    &format!(
                        "{F}: the model cannot be evaluated at t = {t:?} and these states: {msg}"
                    ),
                );
                Fmi2Status::Discard
            }
        }
    }

    /// `fmi2GetNominalsOfContinuousStates` (section 3.2.2).
    pub fn get_nominals(&mut self, nominal: &mut [f64]) -> Fmi2Status {
        const F: &str = "fmi2GetNominalsOfContinuousStates";
        if let Err(s) = self.require_states(F, allowed::GET_NOMINALS, nominal.len()) {
            return s;
        }
        self.core_call(F, |core| core.nominals(nominal))
    }

    /// `fmi2GetEventIndicators` (section 3.2.2): the FMU has none (`numberOfEventIndicators`
    /// is 0), so `ni` must be 0.
    pub fn get_event_indicators(&self, ni: usize) -> Fmi2Status {
        const F: &str = "fmi2GetEventIndicators";
        if let Err(s) = self.require_of(InstanceKind::ModelExchange, F, allowed::GET_STATES) {
            return s;
        }
        if ni != 0 {
            return self.error(
                F,
                format_args!(
                    "ni = {ni}, but the FMU has no event indicators (numberOfEventIndicators = 0)"
                ),
            );
        }
        Fmi2Status::Ok
    }

    /// `fmi2EnterEventMode` (section 3.2.2).
    pub fn enter_event_mode(&mut self) -> Fmi2Status {
        const F: &str = "fmi2EnterEventMode";
        self.trace(|| F.into());
        if let Err(s) = self.require_of(InstanceKind::ModelExchange, F, allowed::ENTER_EVENT_MODE) {
            return s;
        }
        self.phase = EventMode;
        Fmi2Status::Ok
    }

    /// `fmi2NewDiscreteStates` (section 3.2.2): the model has no discrete states and no
    /// events, so one call completes the event iteration.
    pub fn new_discrete_states(&mut self) -> Result<EventInfo, Fmi2Status> {
        const F: &str = "fmi2NewDiscreteStates";
        self.trace(|| F.into());
        self.require_of(InstanceKind::ModelExchange, F, allowed::NEW_DISCRETE_STATES)?;
        Ok(EventInfo::default())
    }

    /// `fmi2EnterContinuousTimeMode` (section 3.2.2).
    pub fn enter_continuous_time_mode(&mut self) -> Fmi2Status {
        const F: &str = "fmi2EnterContinuousTimeMode";
        self.trace(|| F.into());
        if let Err(s) = self.require_of(
            InstanceKind::ModelExchange,
            F,
            allowed::ENTER_CONTINUOUS_TIME_MODE,
        ) {
            return s;
        }
        self.phase = ContinuousTimeMode;
        Fmi2Status::Ok
    }

    /// `fmi2CompletedIntegratorStep` (section 3.2.2): no step event, no termination. Returns
    /// `(enterEventMode, terminateSimulation)`.
    pub fn completed_integrator_step(&mut self) -> Result<(bool, bool), Fmi2Status> {
        const F: &str = "fmi2CompletedIntegratorStep";
        self.require_of(
            InstanceKind::ModelExchange,
            F,
            allowed::COMPLETED_INTEGRATOR_STEP,
        )?;
        Ok((false, false))
    }

    /// Whether `vr` may be an unknown of `fmi2GetDirectionalDerivative`: a state derivative or
    /// an output (section 2.1.9).
    fn is_unknown(&self, vr: u32) -> bool {
        self.structure
            .derivatives
            .iter()
            .any(|d| d.derivative == vr)
            || self.structure.outputs.iter().any(|o| o.output == vr)
    }

    /// Whether `vr` may be a known: an input, or a state outside Initialization Mode (where the
    /// states are calculated, not known).
    fn is_known(&self, vr: u32) -> bool {
        let input = find(&self.variables, vr).is_some_and(|v| v.causality == Causality::Input);
        input
            || (self.phase != InitializationMode
                && self.structure.derivatives.iter().any(|d| d.state == vr))
    }

    /// `fmi2GetDirectionalDerivative` (section 2.1.9): `dv_unknown = Σ ∂unknown/∂known ·
    /// dv_known` for state derivatives and outputs against states and inputs, analytic, at the
    /// current states and inputs; the same in Model Exchange and Co-Simulation.
    pub fn get_directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Fmi2Status {
        const F: &str = "fmi2GetDirectionalDerivative";
        if let Err(s) = self.require(F, allowed::GET_DIRECTIONAL_DERIVATIVE) {
            return s;
        }
        for &vr in unknowns {
            let Some(v) = find(&self.variables, vr) else {
                return self.unknown_reference(F, vr);
            };
            if !self.is_unknown(vr) {
                return self.error(F, format_args!("unknown {} (value reference {vr}) is neither a state derivative nor an output (section 2.1.9)", v.name));
            }
        }
        for (&vr, &seed) in knowns.iter().zip(dv_known) {
            let Some(v) = find(&self.variables, vr) else {
                return self.unknown_reference(F, vr);
            };
            if !self.is_known(vr) {
                let what = if self.phase == InitializationMode {
                    "an input (the states are calculated in Initialization Mode)"
                } else {
                    "a continuous state or an input"
                };
                return self.error(
                    F,
                    format_args!(
                        "known {} (value reference {vr}) is not {what} (section 2.1.9)",
                        v.name
                    ),
                );
            }
            if !seed.is_finite() {
                return self.error(
                    F,
                    format_args!("dvKnown for {} is {seed:?}, not finite", v.name),
                );
            }
        }
        self.core_call(F, |core| {
            core.directional_derivative(unknowns, knowns, dv_known, dv_unknown)
        })
    }
}

impl<M: FmuCore> ShellInstance for Instance<M> {
    type Status = Fmi2Status;
    type Snapshot = Snapshot<M>;
    const OK: Fmi2Status = Fmi2Status::Ok;
    const ERROR: Fmi2Status = Fmi2Status::Error;
    const FATAL: Fmi2Status = Fmi2Status::Fatal;
    const FMU_STATE: &'static str = "FMUstate";
    const SIZE_FUNCTION: &'static str = "fmi2SerializedFMUstateSize";

    fn fail(&self, func: &str, msg: std::fmt::Arguments) -> Fmi2Status {
        self.error(func, msg)
    }
    fn panicked(&mut self, func: &str, message: &str) -> Fmi2Status {
        self.phase = Error;
        self.error(func, format_args!("internal error (panic: {message}); the instance is now in the error state: call fmi2Reset, fmi2SetFMUstate or fmi2FreeInstance"))
    }
    fn snapshot(&self) -> Snapshot<M> {
        self.trace(|| {
            format!(
                "fmi2GetFMUstate at t = {:?} in state {}",
                self.core.time(),
                self.phase.name()
            )
        });
        Snapshot {
            token: self.guid.clone(),
            kind: self.kind,
            phase: self.phase,
            experiment: self.experiment,
            core: self.core.clone(),
        }
    }
    fn restore(&mut self, state: &Snapshot<M>) -> Fmi2Status {
        if state.token != self.guid {
            return self.error(
                "fmi2SetFMUstate",
                format_args!(
                    "the state belongs to GUID {}, this instance has GUID {}",
                    state.token, self.guid
                ),
            );
        }
        if state.kind != self.kind {
            return self.error(
                "fmi2SetFMUstate",
                format_args!(
                    "the state is of a {} instance, this one is {}",
                    state.kind.name(),
                    self.kind.name()
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
    fn serialize(state: &Snapshot<M>) -> Vec<u8> {
        state.to_bytes()
    }
    fn deserialize(&self, bytes: &[u8]) -> Result<Snapshot<M>, Fmi2Status> {
        Snapshot::from_bytes(bytes, &self.guid, self.kind, &self.core)
            .map_err(|e| self.error("fmi2DeSerializeFMUstate", e))
    }
}
