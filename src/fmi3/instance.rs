//! The generic FMI 3.0 instance: the state transitions, argument checks and logging of the
//! standard (sections 2.3, 3.2 and 4.2) around one [`FmuCore`], in safe Rust; which call is
//! allowed in which state is the table of [`super::state_machine`]. The `extern "C"` layer in
//! [`super::exports`] only converts pointers and catches panics.
//!
//! Error policy: a call in a state the table does not allow, or with invalid arguments,
//! returns `fmi3Error` with a log message naming the function and the offending state,
//! reference or value, and changes nothing. Core failures are reported the same way (the core
//! contract keeps the core unchanged on `Err`), except in `fmi3DoStep`, where they are
//! `fmi3Discard` (state Step Discarded). A panic puts the instance into the error state, where
//! only `fmi3Reset`, `fmi3SetFMUState`, `fmi3FreeInstance`, the getters (for debugging) and the
//! FMU-state functions are allowed.

use std::path::PathBuf;

use super::fmu_state::Snapshot;
use super::logging::Logger;
use super::model_description::{Model, instantiation_token, log_categories, with_time};
use super::state_machine::{self, Experiment, Mask, Phase, States, allowed};
use super::types::{Fmi3Status, InstanceKind};
use crate::fmi_common::calls::ShellInstance;
use crate::fmi_common::model_api::{FmuCore, ModelStructure};
use crate::fmi_common::shell::same_time;
use crate::fmi_common::values;
use crate::fmi_common::variables::{Causality, Variable};

use Phase::*;

/// What `fmi3Instantiate…` is asked for beyond the logger.
pub struct Request<'a> {
    pub interface: InstanceKind,
    pub name: &'a str,
    pub token: &'a str,
    /// `resourcePath`: the FMU's `resources` folder, an absolute path (section 2.3.1).
    pub resource_path: Option<&'a str>,
    /// Co-Simulation: whether the importer uses Event Mode (`eventModeUsed`).
    pub event_mode_used: bool,
}

/// One FMU instance: the shell state around a core `M`.
pub struct Instance<M: FmuCore> {
    token: String,
    interface: InstanceKind,
    event_mode_used: bool,
    resource_dir: Option<PathBuf>,
    logger: Logger,
    /// Names of all log categories of `modelDescription.xml`.
    categories: Vec<String>,
    phase: Phase,
    experiment: Option<Experiment>,
    core: M,
    /// The FMI 3.0 variables (with `time`), sorted by value reference for lookups.
    variables: Vec<Variable>,
    /// The continuous states and the dependencies.
    structure: ModelStructure,
}

/// A fresh core with its sorted variable table and token.
struct Built<M> {
    core: M,
    variables: Vec<Variable>,
    token: String,
}

fn build<M: FmuCore>(
    kind: InstanceKind,
    resource_dir: Option<&std::path::Path>,
) -> Result<Built<M>, String> {
    let core = M::instantiate(kind, resource_dir)?;
    let mut variables = with_time(core.variables());
    let token = instantiation_token(&Model {
        info: &M::model_info(),
        vars: &variables,
        structure: &M::model_structure(),
    })?;
    variables.sort_by_key(|v| v.value_reference);
    Ok(Built {
        core,
        variables,
        token,
    })
}

/// An optional number for messages: the value, or "undefined".
fn optional(x: Option<f64>) -> String {
    x.map_or("undefined".into(), |x| format!("{x:?}"))
}

impl<M: FmuCore> Instance<M> {
    /// `fmi3InstantiateModelExchange` / `fmi3InstantiateCoSimulation` (section 2.3.1):
    /// creates the core from the resources and checks the importer's token against the one
    /// computed for this core. Errors are logged and give `None`.
    pub fn instantiate(request: Request, logger: Logger) -> Option<Self> {
        let func = match request.interface {
            InstanceKind::ModelExchange => "fmi3InstantiateModelExchange",
            InstanceKind::CoSimulation => "fmi3InstantiateCoSimulation",
        };
        let fail = |msg: String| {
            logger.log(Fmi3Status::Error, &format!("{func}: {msg}"));
            None
        };
        if request.name.trim().is_empty() {
            return fail("instanceName is empty".into());
        }
        let resource_dir = request
            .resource_path
            .filter(|p| !p.is_empty())
            .map(PathBuf::from);
        if let Some(dir) = resource_dir.as_ref().filter(|d| !d.is_absolute()) {
            return fail(format!(
                "resourcePath {} is not an absolute path (section 2.3.1)",
                dir.display()
            ));
        }
        let built = match build::<M>(request.interface, resource_dir.as_deref()) {
            Ok(b) => b,
            Err(e) => return fail(format!("cannot create the model: {e}")),
        };
        if built.token != request.token {
            return fail(format!(
                "instantiationToken {} given by the importer does not match the FMU's {}",
                request.token, built.token
            ));
        }
        let categories = log_categories(&M::model_info())
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        let instance = Instance {
            token: built.token,
            interface: request.interface,
            event_mode_used: request.event_mode_used,
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
            format!(
                "{func}: {} instance {:?} created",
                request.interface.name(),
                request.name
            )
        });
        Some(instance)
    }

    /// The state-machine state.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Logs an error message of `func` and returns `fmi3Error`.
    pub fn error(&self, func: &str, msg: impl std::fmt::Display) -> Fmi3Status {
        self.logger
            .log(Fmi3Status::Error, &format!("{func}: {msg}"));
        Fmi3Status::Error
    }

    /// Debug-logs a call trace; the message is built only when debug logging is on.
    fn trace(&self, msg: impl FnOnce() -> String) {
        if self.logger.debug_enabled() {
            self.logger.log(Fmi3Status::Ok, &msg());
        }
    }

    /// Checks the state table: `func` may be called in the states of `mask`.
    fn require(&self, func: &str, mask: Mask) -> Result<(), Fmi3Status> {
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

    /// Checks that the instance is of `interface`, for the functions of one interface only.
    fn require_interface(&self, func: &str, interface: InstanceKind) -> Result<(), Fmi3Status> {
        if self.interface == interface {
            return Ok(());
        }
        Err(self.error(
            func,
            format_args!(
                "a function of {}, but this instance was created for {}",
                interface.name(),
                self.interface.name()
            ),
        ))
    }

    /// Logs that `func` was called with a NULL `argument`.
    pub fn null_argument(&self, func: &str, argument: &str) -> Fmi3Status {
        self.error(func, format_args!("argument {argument} is NULL"))
    }

    /// For functions of capabilities this FMU does not declare.
    pub fn not_offered(&self, func: &str, what: &str) -> Fmi3Status {
        self.error(
            func,
            format_args!("{what} is not offered by this FMU (see modelDescription.xml)"),
        )
    }

    /// `fmi3SetDebugLogging` (section 2.3.1); an empty `categories` means all categories.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[String]) -> Fmi3Status {
        match self
            .logger
            .set_debug_logging(on, categories, &self.categories)
        {
            Ok(()) => Fmi3Status::Ok,
            Err(bad) => self.error(
                "fmi3SetDebugLogging",
                format_args!(
                    "unknown log category {bad:?} (known: {})",
                    self.categories.join(", ")
                ),
            ),
        }
    }

    /// `fmi3EnterInitializationMode` (section 2.3.2), with the experiment.
    pub fn enter_initialization_mode(&mut self, e: Experiment) -> Fmi3Status {
        const F: &str = "fmi3EnterInitializationMode";
        self.trace(|| {
            format!(
                "{F}(tolerance={}, startTime={:?}, stopTime={})",
                optional(e.tolerance),
                e.start_time,
                optional(e.stop_time)
            )
        });
        if let Err(s) = self.require(F, allowed::ENTER_INITIALIZATION_MODE) {
            return s;
        }
        let start = e.start_time;
        if !start.is_finite() {
            return self.error(F, format_args!("startTime = {start:?} is not finite"));
        }
        if let Some(stop) = e.stop_time.filter(|s| !(s.is_finite() && *s >= start)) {
            return self.error(
                F,
                format_args!("stopTime = {stop:?} is not a finite time >= startTime = {start:?}"),
            );
        }
        if let Some(tol) = e.tolerance.filter(|t| !(t.is_finite() && *t > 0.0)) {
            return self.error(
                F,
                format_args!("tolerance = {tol:?} is not a finite positive number"),
            );
        }
        match self
            .core
            .enter_initialization(start, e.stop_time, e.tolerance)
        {
            Ok(()) => {
                self.experiment = Some(e);
                self.phase = InitializationMode;
                Fmi3Status::Ok
            }
            Err(msg) => self.error(F, msg),
        }
    }

    /// `fmi3ExitInitializationMode` (section 2.3.2): on to Step Mode (Co-Simulation without
    /// Event Mode) or Event Mode.
    pub fn exit_initialization_mode(&mut self) -> Fmi3Status {
        const F: &str = "fmi3ExitInitializationMode";
        self.trace(|| F.into());
        if let Err(s) = self.require(F, allowed::EXIT_INITIALIZATION_MODE) {
            return s;
        }
        match self.core.exit_initialization() {
            Ok(()) => {
                self.phase = match self.interface {
                    InstanceKind::CoSimulation if !self.event_mode_used => StepMode,
                    _ => EventMode,
                };
                Fmi3Status::Ok
            }
            Err(msg) => self.error(F, msg),
        }
    }

    /// `fmi3EnterEventMode` (section 2.3.5): from Continuous-Time Mode, or from Step Mode when
    /// the importer asked for Event Mode. This FMU has no events of its own.
    pub fn enter_event_mode(&mut self) -> Fmi3Status {
        const F: &str = "fmi3EnterEventMode";
        self.trace(|| F.into());
        if let Err(s) = self.require(F, allowed::ENTER_EVENT_MODE) {
            return s;
        }
        if self.interface == InstanceKind::CoSimulation && !self.event_mode_used {
            return self.error(
                F,
                "the instance was created with eventModeUsed = false (section 4.2.2)",
            );
        }
        self.phase = EventMode;
        Fmi3Status::Ok
    }

    /// `fmi3UpdateDiscreteStates` (section 3.2.3): no discrete states, no time events; the
    /// flags are all false.
    pub fn update_discrete_states(&mut self) -> Fmi3Status {
        const F: &str = "fmi3UpdateDiscreteStates";
        self.trace(|| F.into());
        self.require(F, allowed::UPDATE_DISCRETE_STATES)
            .err()
            .unwrap_or(Fmi3Status::Ok)
    }

    /// `fmi3EnterStepMode` (section 4.2.2): from Event Mode, Co-Simulation only.
    pub fn enter_step_mode(&mut self) -> Fmi3Status {
        const F: &str = "fmi3EnterStepMode";
        self.trace(|| F.into());
        if let Err(s) = self
            .require_interface(F, InstanceKind::CoSimulation)
            .and_then(|()| self.require(F, allowed::ENTER_STEP_MODE))
        {
            return s;
        }
        self.phase = StepMode;
        Fmi3Status::Ok
    }

    /// `fmi3Terminate` (section 2.3.4); a second call is an error.
    pub fn terminate(&mut self) -> Fmi3Status {
        const F: &str = "fmi3Terminate";
        self.trace(|| F.into());
        if let Err(s) = self.require(F, allowed::TERMINATE) {
            return s;
        }
        self.phase = Terminated;
        Fmi3Status::Ok
    }

    /// `fmi3Reset` (section 2.3.4): back to Instantiated with the start values, by creating
    /// the core anew from the same resources.
    pub fn reset(&mut self) -> Fmi3Status {
        const F: &str = "fmi3Reset";
        self.trace(|| F.into());
        let built = match build::<M>(self.interface, self.resource_dir.as_deref()) {
            Ok(b) => b,
            Err(e) => {
                self.phase = Error;
                return self.error(F, format_args!("cannot create the model again: {e}"));
            }
        };
        if built.token != self.token {
            self.phase = Error;
            return self.error(
                F,
                format_args!(
                    "the resources changed: the instantiationToken is now {} instead of {}",
                    built.token, self.token
                ),
            );
        }
        self.core = built.core;
        self.variables = built.variables;
        self.experiment = None;
        self.phase = Instantiated;
        Fmi3Status::Ok
    }

    /// The variable with value reference `vr`.
    fn find(&self, vr: u32) -> Option<&Variable> {
        values::find(&self.variables, vr)
    }

    /// Checks that `n_values` values go with `n_refs` scalar references (section 2.3.3:
    /// `nValues` counts the elements of all variables; every variable here is a scalar).
    fn check_sizes(&self, func: &str, n_refs: usize, n_values: usize) -> Result<(), Fmi3Status> {
        if n_refs == n_values {
            return Ok(());
        }
        Err(self.error(
            func,
            format_args!(
                "nValues = {n_values}, but the {n_refs} value references are scalars and need {n_refs} values"
            ),
        ))
    }

    /// `fmi3GetFloat64` (section 2.3.3).
    pub fn get_float64(&mut self, vrs: &[u32], values: &mut [f64]) -> Fmi3Status {
        const F: &str = "fmi3GetFloat64";
        if let Err(s) = self
            .require(F, allowed::GET_VALUES)
            .and_then(|()| self.check_sizes(F, vrs.len(), values.len()))
        {
            return s;
        }
        match values::get(&mut self.core, &self.variables, vrs, values) {
            Ok(()) => Fmi3Status::Ok,
            Err(msg) => self.error(F, msg),
        }
    }

    /// `fmi3SetFloat64` (section 2.3.3). All references are checked before any value is set;
    /// values are then set in order, and a value the core rejects stops there.
    pub fn set_float64(&mut self, vrs: &[u32], values: &[f64]) -> Fmi3Status {
        const F: &str = "fmi3SetFloat64";
        if let Err(s) = self
            .require(F, allowed::SET_VALUES)
            .and_then(|()| self.check_sizes(F, vrs.len(), values.len()))
        {
            return s;
        }
        let logger = &self.logger;
        let trace = |name: &str, value: f64| {
            if logger.debug_enabled() {
                logger.log(Fmi3Status::Ok, &format!("{F}: {name} = {value:?}"));
            }
        };
        let rule = (self.phase.set_rule(), self.phase.name());
        match values::set(&mut self.core, &self.variables, rule, (vrs, values), trace) {
            Ok(()) => Fmi3Status::Ok,
            Err(msg) => self.error(F, msg),
        }
    }

    /// `fmi3Get/Set{Float32,Int8,…,Binary,Clock}` (`func`, of variables of `type_name`): this
    /// FMU has Float64 variables only, so any value reference is unknown for these types.
    pub fn no_variables_of_type(
        &self,
        func: &str,
        type_name: &str,
        setter: bool,
        vrs: &[u32],
    ) -> Fmi3Status {
        let mask = if setter {
            allowed::SET_VALUES
        } else {
            allowed::GET_VALUES
        };
        if let Err(s) = self.require(func, mask) {
            return s;
        }
        match values::no_variables_of_type(&self.variables, type_name, "Float64", vrs) {
            None => Fmi3Status::Ok,
            Some(msg) => self.error(func, msg),
        }
    }

    /// What `fmi3DoStep` returns beyond its status (section 4.2.2).
    pub fn do_step(&mut self, tc: f64, h: f64) -> (Fmi3Status, f64) {
        const F: &str = "fmi3DoStep";
        self.trace(|| {
            format!("{F}(currentCommunicationPoint={tc:?}, communicationStepSize={h:?})")
        });
        let t = self.core.time();
        if let Err(s) = self.require(F, allowed::DO_STEP) {
            return (s, t);
        }
        if !(h.is_finite() && h > 0.0) {
            let msg = format!("communicationStepSize = {h:?} must be finite and > 0");
            return (self.error(F, msg), t);
        }
        if !(tc.is_finite() && same_time(t, tc, h)) {
            let msg = format!(
                "currentCommunicationPoint = {tc:?} does not match the FMU's time {t:?} (difference {:?})",
                tc - t
            );
            return (self.error(F, msg), t);
        }
        if let Some(stop) = self.experiment.and_then(|e| e.stop_time)
            && t + h > stop
            && !same_time(t + h, stop, h)
        {
            let msg = format!("step to {:?} goes past stopTime = {stop:?}", t + h);
            return (self.error(F, msg), t);
        }
        match self.core.do_step(h) {
            Ok(()) => (Fmi3Status::Ok, self.core.time()),
            Err(msg) => {
                self.phase = StepDiscarded;
                let t = self.core.time();
                self.logger.log(
                    Fmi3Status::Discard,
                    &format!("{F}: step from t = {tc:?} over {h:?} s discarded: {msg}; the FMU stays at t = {t:?} (lastSuccessfulTime); restore a state with fmi3SetFMUState, or terminate"),
                );
                (Fmi3Status::Discard, t)
            }
        }
    }

    /// The number of continuous states (`fmi3GetNumberOfContinuousStates`, section 3.2.1).
    pub fn number_of_states(&self) -> usize {
        self.structure.derivatives.len()
    }

    /// The checks of a Model Exchange call: the instance's kind and the state table.
    fn require_me(&self, func: &str, mask: Mask) -> Result<(), Fmi3Status> {
        self.require_interface(func, InstanceKind::ModelExchange)
            .and_then(|()| self.require(func, mask))
    }

    /// Checks that an array of `n` elements has one per continuous state.
    fn check_states(&self, func: &str, what: &str, n: usize) -> Result<(), Fmi3Status> {
        let nx = self.number_of_states();
        if n == nx {
            return Ok(());
        }
        Err(self.error(
            func,
            format_args!(
                "{what} = {n}, but the FMU has {nx} continuous states (modelDescription.xml)"
            ),
        ))
    }

    /// `fmi3GetNumberOfContinuousStates` / `fmi3GetNumberOfEventIndicators` (`func`).
    pub fn number_of(&self, func: &str, what: usize) -> Result<usize, Fmi3Status> {
        self.require_me(func, allowed::GET_NUMBER_OF).map(|()| what)
    }

    /// `fmi3EnterContinuousTimeMode` (section 3.2.2).
    pub fn enter_continuous_time_mode(&mut self) -> Fmi3Status {
        const F: &str = "fmi3EnterContinuousTimeMode";
        self.trace(|| F.into());
        if let Err(s) = self.require_me(F, allowed::ENTER_CONTINUOUS_TIME_MODE) {
            return s;
        }
        self.phase = ContinuousTimeMode;
        Fmi3Status::Ok
    }

    /// `fmi3CompletedIntegratorStep` (section 3.2.2): no step events, no termination.
    pub fn completed_integrator_step(&mut self) -> Fmi3Status {
        const F: &str = "fmi3CompletedIntegratorStep";
        self.require_me(F, allowed::COMPLETED_INTEGRATOR_STEP)
            .err()
            .unwrap_or(Fmi3Status::Ok)
    }

    /// `fmi3SetTime` (section 3.2.1).
    pub fn set_time(&mut self, time: f64) -> Fmi3Status {
        const F: &str = "fmi3SetTime";
        if let Err(s) = self.require_me(F, allowed::SET_TIME) {
            return s;
        }
        if !time.is_finite() {
            return self.error(F, format_args!("time = {time:?} is not finite"));
        }
        match self.core.set_time(time) {
            Ok(()) => Fmi3Status::Ok,
            Err(msg) => self.error(F, format_args!("time = {time:?}: {msg}")),
        }
    }

    /// `fmi3SetContinuousStates` (section 3.2.1); a NaN is refused with its state named.
    pub fn set_continuous_states(&mut self, x: &[f64]) -> Fmi3Status {
        const F: &str = "fmi3SetContinuousStates";
        if let Err(s) = self
            .require_me(F, allowed::SET_CONTINUOUS_STATES)
            .and_then(|()| self.check_states(F, "nContinuousStates", x.len()))
        {
            return s;
        }
        if let Some(k) = x.iter().position(|v| v.is_nan()) {
            let vr = self.structure.derivatives[k].state;
            let name = self.find(vr).map_or("", |v| v.name.as_str());
            return self.error(F, format_args!("continuousStates[{k}] ({name}) is NaN"));
        }
        match self.core.set_continuous_states(x) {
            Ok(()) => Fmi3Status::Ok,
            Err(msg) => self.error(F, msg),
        }
    }

    /// `fmi3GetContinuousStates`, `fmi3GetContinuousStateDerivatives` and
    /// `fmi3GetNominalsOfContinuousStates` (`func`, section 3.2.1): one value per state from
    /// `call`. Where the model cannot be evaluated (a state outside its domain), the
    /// derivatives give `fmi3Discard` (the importer may retry with a smaller step).
    pub fn state_vector(
        &mut self,
        func: &str,
        out: &mut [f64],
        call: fn(&mut M, &mut [f64]) -> Result<(), String>,
    ) -> Fmi3Status {
        if let Err(s) = self
            .require_me(func, allowed::GET_MODEL_EQUATIONS)
            .and_then(|()| self.check_states(func, "nContinuousStates", out.len()))
        {
            return s;
        }
        match call(&mut self.core, out) {
            Ok(()) => Fmi3Status::Ok,
            Err(msg) if func == "fmi3GetContinuousStateDerivatives" => {
                self.logger
                    .log(Fmi3Status::Discard, &format!("{func}: {msg}"));
                Fmi3Status::Discard
            }
            Err(msg) => self.error(func, msg),
        }
    }

    /// `fmi3GetEventIndicators` (section 3.2.1): the FMU has none.
    pub fn event_indicators(&self, n: usize) -> Fmi3Status {
        const F: &str = "fmi3GetEventIndicators";
        if let Err(s) = self.require_me(F, allowed::GET_MODEL_EQUATIONS) {
            return s;
        }
        if n != 0 {
            return self.error(
                F,
                format_args!("nEventIndicators = {n}, but the FMU has none"),
            );
        }
        Fmi3Status::Ok
    }

    /// `fmi3GetDirectionalDerivative` (section 2.3.8): ∂unknowns/∂knowns · seed, with state
    /// derivatives and outputs as unknowns, states and inputs as knowns.
    pub fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        sensitivity: &mut [f64],
    ) -> Fmi3Status {
        const F: &str = "fmi3GetDirectionalDerivative";
        if let Err(s) = self.require(F, allowed::DIRECTIONAL_DERIVATIVE) {
            return s;
        }
        let sizes = [
            ("nSeed", seed.len(), "nKnowns", knowns.len()),
            (
                "nSensitivity",
                sensitivity.len(),
                "nUnknowns",
                unknowns.len(),
            ),
        ];
        if let Some((a, n, b, m)) = sizes.into_iter().find(|(_, n, _, m)| n != m) {
            return self.error(F, format_args!("{a} = {n} must equal {b} = {m}"));
        }
        let s = &self.structure;
        let is_unknown = |vr: &u32| {
            s.derivatives.iter().any(|d| d.derivative == *vr)
                || s.outputs.iter().any(|o| o.output == *vr)
        };
        let is_known = |vr: &u32| {
            s.derivatives.iter().any(|d| d.state == *vr)
                || self
                    .find(*vr)
                    .is_some_and(|v| v.causality == Causality::Input)
        };
        let name = |vr: u32| {
            self.find(vr)
                .map_or(String::new(), |v| format!(" ({})", v.name))
        };
        if let Some(&vr) = unknowns.iter().find(|vr| !is_unknown(vr)) {
            let msg = format!(
                "unknowns: value reference {vr}{} is neither a state derivative nor an output",
                name(vr)
            );
            return self.error(F, msg);
        }
        if let Some(&vr) = knowns.iter().find(|vr| !is_known(vr)) {
            let msg = format!(
                "knowns: value reference {vr}{} is neither a continuous state nor an input",
                name(vr)
            );
            return self.error(F, msg);
        }
        if let Some(k) = seed.iter().position(|x| !x.is_finite()) {
            return self.error(F, format_args!("seed[{k}] = {:?} is not finite", seed[k]));
        }
        match self
            .core
            .directional_derivative(unknowns, knowns, seed, sensitivity)
        {
            Ok(()) => Fmi3Status::Ok,
            Err(msg) => self.error(F, msg),
        }
    }
}

impl<M: FmuCore> ShellInstance for Instance<M> {
    type Status = Fmi3Status;
    type Snapshot = Snapshot<M>;
    const OK: Fmi3Status = Fmi3Status::Ok;
    const ERROR: Fmi3Status = Fmi3Status::Error;
    const FATAL: Fmi3Status = Fmi3Status::Fatal;
    const FMU_STATE: &'static str = "FMUState";
    const SIZE_FUNCTION: &'static str = "fmi3SerializedFMUStateSize";

    fn fail(&self, func: &str, msg: std::fmt::Arguments) -> Fmi3Status {
        self.error(func, msg)
    }
    fn panicked(&mut self, func: &str, message: &str) -> Fmi3Status {
        self.phase = Error;
        self.error(func, format_args!("internal error (panic: {message}); the instance is now in the error state: call fmi3Reset, fmi3SetFMUState or fmi3FreeInstance"))
    }
    fn snapshot(&self) -> Snapshot<M> {
        self.trace(|| {
            format!(
                "fmi3GetFMUState at t = {:?} in state {}",
                self.core.time(),
                self.phase.name()
            )
        });
        Snapshot {
            token: self.token.clone(),
            kind: self.interface,
            phase: self.phase,
            experiment: self.experiment,
            core: self.core.clone(),
        }
    }
    fn restore(&mut self, state: &Snapshot<M>) -> Fmi3Status {
        const F: &str = "fmi3SetFMUState";
        if state.token != self.token {
            return self.error(
                F,
                format_args!(
                    "the state belongs to instantiationToken {}, this instance has {}",
                    state.token, self.token
                ),
            );
        }
        if state.kind != self.interface {
            return self.error(
                F,
                format_args!(
                    "the state is of a {} instance, this one is {}",
                    state.kind.name(),
                    self.interface.name()
                ),
            );
        }
        self.core = state.core.clone();
        self.phase = state.phase;
        self.experiment = state.experiment;
        self.trace(|| {
            format!(
                "{F}: back at t = {:?} in state {}",
                self.core.time(),
                self.phase.name()
            )
        });
        Fmi3Status::Ok
    }
    fn serialize(state: &Snapshot<M>) -> Vec<u8> {
        state.to_bytes()
    }
    fn deserialize(&self, bytes: &[u8]) -> Result<Snapshot<M>, Fmi3Status> {
        Snapshot::from_bytes(bytes, &self.token, self.interface, &self.core)
            .map_err(|e| self.error("fmi3DeserializeFMUState", e))
    }
}
