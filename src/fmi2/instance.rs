//! The FMI 2.0 instance (standard sections 2.1, 3.2 and 4.2): the generic
//! [`Instance`](crate::fmi_common::instance::Instance) of [`fmi_common`](crate::fmi_common)
//! with what FMI 2.0 brings to it ([`Fmi2`]: its status, state table, logger, names, messages
//! and FMU-state format) and its own calls: `fmi2Instantiate`, `fmi2SetupExperiment`, the
//! Co-Simulation step and status calls, the Model Exchange calls that check the state vector
//! FMI 2.0's way and directional derivatives (`fmi2SetTime`, the event indicators and
//! `fmi2CompletedIntegratorStep` are the generic instance's). Which call is allowed in which
//! state is the table of [`super::state_machine`]. The `extern "C"` layer ([`super::functions`])
//! only converts pointers and catches panics.
//!
//! Error policy: that of the generic instance; core failures of `fmi2DoStep` are
//! `fmi2Discard` (state stepFailed). A panic puts the instance into the error state, where
//! only `fmi2Reset`, `fmi2SetFMUstate`, `fmi2FreeInstance`, the getters (for debugging) and
//! the FMU-state functions are allowed.

use super::Fmi2;
use super::logging::{Callbacks, logger};
use super::model_description::guid_for;
use super::state_machine::{Experiment, Mask, Phase, allowed};
use super::types::{
    FMI2_DO_STEP_STATUS, FMI2_LAST_SUCCESSFUL_TIME, FMI2_PENDING_STATUS, FMI2_TERMINATED,
    Fmi2Status, fmi2Boolean, fmi2CallbackFunctions, fmi2StatusKind,
};
use super::uri::path_from_file_uri;
use crate::fmi_common::instance::{self, Masks, Names, Request, Version, Wording, optional};
use crate::fmi_common::logging::Status;
use crate::fmi_common::model_api::{FmuCore, InstanceKind, ModelStructure};
use crate::fmi_common::shell::same_time;
use crate::fmi_common::state_machine::States;
use crate::fmi_common::variables::{Causality, ModelInfo, Variable, check_variable_table};

use Phase::*;

/// The interface of the Model Exchange calls.
const ME: Option<InstanceKind> = Some(InstanceKind::ModelExchange);

/// One FMI 2.0 instance around a core `M`.
pub type Instance<M> = instance::Instance<Fmi2, M>;

impl Version for Fmi2 {
    type Status = Fmi2Status;
    type Boolean = fmi2Boolean;
    type Sink = Callbacks;
    type Options = ();

    const NAMES: Names = Names {
        set_debug_logging: "fmi2SetDebugLogging",
        exit_initialization_mode: "fmi2ExitInitializationMode",
        terminate: "fmi2Terminate",
        reset: "fmi2Reset",
        free_instance: "fmi2FreeInstance",
        get_values: "fmi2GetReal",
        set_values: "fmi2SetReal",
        get_fmu_state: "fmi2GetFMUstate",
        set_fmu_state: "fmi2SetFMUstate",
        deserialize_fmu_state: "fmi2DeSerializeFMUstate",
        serialized_size: "fmi2SerializedFMUstateSize",
        value_references: "vr",
        values: "value",
        fmu_state: "FMUstate",
        value_type: "",
        set_time: "fmi2SetTime",
        set_continuous_states: "fmi2SetContinuousStates",
        get_event_indicators: "fmi2GetEventIndicators",
        completed_integrator_step: "fmi2CompletedIntegratorStep",
        get_directional_derivative: "fmi2GetDirectionalDerivative",
        continuous_states: "x",
        unknowns: "vUnknown_ref",
        knowns: "vKnown_ref",
        seed: "dvKnown",
        sensitivity: "dvUnknown",
    };
    const MASKS: Masks = Masks {
        terminate: allowed::TERMINATE,
        get_values: allowed::GET_VALUES,
        set_values: allowed::SET_VALUES,
        set_time: allowed::SET_TIME,
        get_event_indicators: allowed::GET_STATES,
        completed_integrator_step: allowed::COMPLETED_INTEGRATOR_STEP,
    };
    const WORDING: Wording = Wording {
        wrong_interface: "is a {} function; this instance was instantiated for {}",
        token_mismatch: "GUID {} given by the importer does not match the FMU's GUID {}",
        token_changed: "GUID is now {} instead of {}",
        foreign_state: "the state belongs to GUID {}, this instance has GUID {}",
        no_event_indicators: "ni = {}, but the FMU has no event indicators (numberOfEventIndicators = 0)",
    };

    /// The core's table as it is, checked, and the GUID of its description.
    fn variables_and_token(
        info: &ModelInfo,
        variables: Vec<Variable>,
        structure: &ModelStructure,
    ) -> Result<(Vec<Variable>, String), String> {
        check_variable_table(&variables).map_err(|e| format!("invalid variable table: {e}"))?;
        let guid = guid_for(info, &variables, structure)?;
        Ok((variables, guid))
    }

    /// stepComplete (Co-Simulation) or Event Mode (Model Exchange, section 3.2.3).
    fn after_initialization(kind: InstanceKind, (): ()) -> Phase {
        match kind {
            InstanceKind::ModelExchange => EventMode,
            InstanceKind::CoSimulation => StepComplete,
        }
    }
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

impl<M: FmuCore> Instance<M> {
    /// `fmi2Instantiate` (section 2.1.6) for `kind`: creates the core from the resources,
    /// checks the importer's GUID against the one computed for this core. Errors are logged
    /// and give `None`.
    pub fn create(
        name: &str,
        kind: InstanceKind,
        guid: &str,
        resource_location: Option<&str>,
        callbacks: fmi2CallbackFunctions,
        logging_on: bool,
    ) -> Option<Self> {
        const F: &str = "fmi2Instantiate";
        let resource_dir = if name.is_empty() {
            Err("instanceName is empty".into())
        } else {
            resource_location
                .filter(|l| !l.is_empty())
                .map(path_from_file_uri)
                .transpose()
        };
        let request = Request {
            func: F,
            kind,
            token: guid,
            resource_dir,
            options: (),
        };
        let instance = Self::instantiate(request, logger(callbacks, name, logging_on))?;
        instance.trace(|| {
            let resources = instance
                .resource_dir
                .as_ref()
                .map_or("none".into(), |d| d.display().to_string());
            format!(
                "{F}: {} instance of GUID {guid} created, resources: {resources}",
                kind.name()
            )
        });
        Some(instance)
    }

    /// `fmi2SetupExperiment` (section 2.1.6).
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Status {
        const F: &str = "fmi2SetupExperiment";
        self.trace(|| {
            format!(
                "{F}(tolerance={}, startTime={start_time:?}, stopTime={})",
                optional(tolerance),
                optional(stop_time)
            )
        });
        let e = Experiment {
            start_time,
            stop_time,
            tolerance,
        };
        if let Err(s) = self
            .require(F, allowed::SETUP_EXPERIMENT)
            .and_then(|()| self.check_experiment(F, &e))
        {
            return s;
        }
        self.experiment = Some(e);
        Status::Ok
    }

    /// `fmi2EnterInitializationMode` (section 2.1.6); needs `fmi2SetupExperiment` first.
    pub fn enter_initialization_mode(&mut self) -> Status {
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
        self.initialize(F, e)
    }

    /// `fmi2DoStep` (section 4.2.2): one synchronous step; `fmi2Discard` (state stepFailed)
    /// when the core rejects the step, which leaves it at the start of the step.
    pub fn do_step(&mut self, tc: f64, h: f64, no_set_fmu_state_prior: bool) -> Status {
        const F: &str = "fmi2DoStep";
        self.trace(|| format!("{F}(currentCommunicationPoint={tc:?}, communicationStepSize={h:?}, noSetFMUStatePriorToCurrentPoint={no_set_fmu_state_prior})"));
        if let Err(s) = self.require_of(F, InstanceKind::CoSimulation, allowed::DO_STEP) {
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
            Ok(()) => Status::Ok,
            Err(msg) => {
                self.phase = StepFailed;
                let t = self.core.time();
                self.log(Status::Discard, format_args!("{F}: step from t = {tc:?} over {h:?} s discarded: {msg}; the FMU stays at t = {t:?} (fmi2LastSuccessfulTime); restore a state with fmi2SetFMUstate, or terminate"),
                );
                Status::Discard
            }
        }
    }

    /// `fmi2CancelStep` (section 4.2.2): only for a step in progress, which never exists.
    pub fn cancel_step(&self) -> Status {
        const F: &str = "fmi2CancelStep";
        if let Err(s) = self.require_interface(F, InstanceKind::CoSimulation) {
            return s;
        }
        self.error(
            F,
            format_args!("not allowed in state {}: fmi2DoStep is synchronous and never returns fmi2Pending, so no step is in progress", self.phase.name()),
        )
    }

    fn unsupported_kind(&self, func: &str, kind: fmi2StatusKind) -> Status {
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
    pub fn get_valueless_status(&self, func: &str, kind: fmi2StatusKind) -> Status {
        self.require_of(func, InstanceKind::CoSimulation, allowed::GET_STATUS)
            .err()
            .unwrap_or_else(|| self.unsupported_kind(func, kind))
    }

    /// `fmi2GetRealStatus` (section 4.2.3): `fmi2LastSuccessfulTime` is the core's time,
    /// since a failed step leaves the core at its start.
    pub fn get_real_status(&self, kind: fmi2StatusKind, value: &mut f64) -> Status {
        const F: &str = "fmi2GetRealStatus";
        if let Err(s) = self.require_of(F, InstanceKind::CoSimulation, allowed::GET_STATUS) {
            return s;
        }
        if kind != FMI2_LAST_SUCCESSFUL_TIME {
            return self.unsupported_kind(F, kind);
        }
        *value = self.core.time();
        Status::Ok
    }

    /// `fmi2GetBooleanStatus` (section 4.2.3): `fmi2Terminated` is always false — a
    /// discarded step can be retried from a restored state.
    pub fn get_boolean_status(&self, kind: fmi2StatusKind, value: &mut bool) -> Status {
        const F: &str = "fmi2GetBooleanStatus";
        if let Err(s) = self.require_of(F, InstanceKind::CoSimulation, allowed::GET_STATUS) {
            return s;
        }
        if kind != FMI2_TERMINATED {
            return self.unsupported_kind(F, kind);
        }
        *value = false;
        Status::Ok
    }

    /// Checks a Model Exchange call on the state vector: interface, state, and that the
    /// importer's array holds the `nx` states of `modelDescription.xml`.
    fn require_states(&self, func: &str, mask: Mask, nx: usize) -> Result<(), Status> {
        self.require_of(func, InstanceKind::ModelExchange, mask)?;
        let n = self.number_of_states();
        if nx != n {
            return Err(self.error(
                func,
                format_args!("nx = {nx}, but the FMU has {n} continuous states (<Derivatives>)"),
            ));
        }
        Ok(())
    }

    /// `fmi2SetContinuousStates` (section 3.2.1).
    pub fn set_continuous_states(&mut self, x: &[f64]) -> Status {
        const F: &str = "fmi2SetContinuousStates";
        if let Err(s) = self.require_states(F, allowed::SET_CONTINUOUS_STATES, x.len()) {
            return s;
        }
        self.core_call(F, |core| core.set_continuous_states(x))
    }

    /// `fmi2GetContinuousStates` (section 3.2.2).
    pub fn get_continuous_states(&mut self, x: &mut [f64]) -> Status {
        const F: &str = "fmi2GetContinuousStates";
        if let Err(s) = self.require_states(F, allowed::GET_STATES, x.len()) {
            return s;
        }
        self.core_call(F, |core| core.continuous_states(x))
    }

    /// `fmi2GetDerivatives` (section 3.2.2); `fmi2Discard` where the model cannot be evaluated
    /// at the states the integrator tries (it should try a smaller step).
    pub fn get_derivatives(&mut self, dx: &mut [f64]) -> Status {
        const F: &str = "fmi2GetDerivatives";
        if let Err(s) = self.require_states(F, allowed::GET_DERIVATIVES, dx.len()) {
            return s;
        }
        match self.core.derivatives(dx) {
            Ok(()) => Status::Ok,
            Err(msg) => {
                let t = self.core.time();
                self.log(
                    Status::Discard,
                    format_args!(
                        "{F}: the model cannot be evaluated at t = {t:?} and these states: {msg}"
                    ),
                );
                Status::Discard
            }
        }
    }

    /// `fmi2GetNominalsOfContinuousStates` (section 3.2.2).
    pub fn get_nominals(&mut self, nominal: &mut [f64]) -> Status {
        const F: &str = "fmi2GetNominalsOfContinuousStates";
        if let Err(s) = self.require_states(F, allowed::GET_NOMINALS, nominal.len()) {
            return s;
        }
        self.core_call(F, |core| core.nominals(nominal))
    }

    /// `fmi2EnterEventMode` (section 3.2.2).
    pub fn enter_event_mode(&mut self) -> Status {
        let mask = allowed::ENTER_EVENT_MODE;
        self.move_to("fmi2EnterEventMode", ME, mask, EventMode)
    }

    /// `fmi2NewDiscreteStates` (section 3.2.2): the model has no discrete states and no
    /// events, so one call completes the event iteration.
    pub fn new_discrete_states(&mut self) -> Result<EventInfo, Status> {
        const F: &str = "fmi2NewDiscreteStates";
        self.trace(|| F.into());
        self.require_of(F, InstanceKind::ModelExchange, allowed::NEW_DISCRETE_STATES)?;
        Ok(EventInfo::default())
    }

    /// `fmi2EnterContinuousTimeMode` (section 3.2.2).
    pub fn enter_continuous_time_mode(&mut self) -> Status {
        let (f, mask) = (
            "fmi2EnterContinuousTimeMode",
            allowed::ENTER_CONTINUOUS_TIME_MODE,
        );
        self.move_to(f, ME, mask, ContinuousTimeMode)
    }

    /// Whether `vr` may be a known: an input, or a state outside Initialization Mode (where the
    /// states are calculated, not known).
    fn is_known(&self, vr: u32) -> bool {
        let input = self
            .find(vr)
            .is_some_and(|v| v.causality == Causality::Input);
        input || (self.phase != InitializationMode && self.is_state(vr))
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
    ) -> Status {
        const F: &str = "fmi2GetDirectionalDerivative";
        if let Err(s) = self.require(F, allowed::GET_DIRECTIONAL_DERIVATIVE) {
            return s;
        }
        for &vr in unknowns {
            let Some(v) = self.find(vr) else {
                return self.error(F, format_args!("unknown value reference {vr}"));
            };
            if !self.is_unknown(vr) {
                return self.error(F, format_args!("unknown {} (value reference {vr}) is neither a state derivative nor an output (section 2.1.9)", v.name));
            }
        }
        for (&vr, &seed) in knowns.iter().zip(dv_known) {
            let Some(v) = self.find(vr) else {
                return self.error(F, format_args!("unknown value reference {vr}"));
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
