//! The FMI 3.0 instance (standard sections 2.3, 3.2 and 4.2): the generic
//! [`Instance`](crate::fmi_common::instance::Instance) of [`fmi_common`](crate::fmi_common)
//! with what FMI 3.0 brings to it ([`Fmi3`]: its status, state table, logger, names, messages
//! and FMU-state format) and its own calls: `fmi3Instantiate…`, `fmi3EnterInitializationMode`
//! with the experiment, Event and Step Mode, the step, the Model Exchange calls that check the
//! state vector FMI 3.0's way and directional derivatives (`fmi3SetTime`, the event indicators
//! and `fmi3CompletedIntegratorStep` are the generic instance's). Which call is allowed in which
//! state is the table of [`super::state_machine`]. The `extern "C"` layer
//! ([`super::functions`]) only converts pointers and catches panics.
//!
//! Error policy: that of the generic instance; core failures of `fmi3DoStep` are
//! `fmi3Discard` (state Step Discarded). A panic puts the instance into the error state, where
//! only `fmi3Reset`, `fmi3SetFMUState`, `fmi3FreeInstance`, the getters (for debugging) and the
//! FMU-state functions are allowed.

use std::path::PathBuf;

use super::Fmi3;
use super::logging::{Callback, Logger};
use super::model_description::{Model, instantiation_token, with_time};
use super::state_machine::{Experiment, Phase, allowed};
use super::types::{Fmi3Status, InstanceKind, fmi3Boolean};
use crate::fmi_common::instance::{self, Masks, Names, Version, Wording, optional};
use crate::fmi_common::logging::Status;
use crate::fmi_common::model_api::{FmuCore, ModelStructure};
use crate::fmi_common::shell::same_time;
use crate::fmi_common::variables::{Causality, ModelInfo, Variable};

use Phase::*;

/// One FMI 3.0 instance around a core `M`.
pub type Instance<M> = instance::Instance<Fmi3, M>;

/// Whether a Co-Simulation importer uses Event Mode (`eventModeUsed`; always for Model
/// Exchange).
#[derive(Debug, Clone, Copy)]
pub struct EventModeUsed(pub bool);

impl Version for Fmi3 {
    type Status = Fmi3Status;
    type Boolean = fmi3Boolean;
    type Sink = Callback;
    type Options = EventModeUsed;

    const NAMES: Names = Names {
        set_debug_logging: "fmi3SetDebugLogging",
        exit_initialization_mode: "fmi3ExitInitializationMode",
        terminate: "fmi3Terminate",
        reset: "fmi3Reset",
        free_instance: "fmi3FreeInstance",
        get_values: "fmi3GetFloat64",
        set_values: "fmi3SetFloat64",
        get_fmu_state: "fmi3GetFMUState",
        set_fmu_state: "fmi3SetFMUState",
        deserialize_fmu_state: "fmi3DeserializeFMUState",
        serialized_size: "fmi3SerializedFMUStateSize",
        value_references: "valueReferences",
        values: "values",
        fmu_state: "FMUState",
        value_type: "Float64",
        set_time: "fmi3SetTime",
        set_continuous_states: "fmi3SetContinuousStates",
        get_event_indicators: "fmi3GetEventIndicators",
        completed_integrator_step: "fmi3CompletedIntegratorStep",
        get_directional_derivative: "fmi3GetDirectionalDerivative",
        continuous_states: "continuousStates",
        unknowns: "unknowns or knowns",
        knowns: "unknowns or knowns",
        seed: "seed",
        sensitivity: "sensitivity",
    };
    const MASKS: Masks = Masks {
        terminate: allowed::TERMINATE,
        get_values: allowed::GET_VALUES,
        set_values: allowed::SET_VALUES,
        set_time: allowed::SET_TIME,
        get_event_indicators: allowed::GET_MODEL_EQUATIONS,
        completed_integrator_step: allowed::COMPLETED_INTEGRATOR_STEP,
    };
    const WORDING: Wording = Wording {
        wrong_interface: "a function of {}, but this instance was created for {}",
        token_mismatch: "instantiationToken {} given by the importer does not match the FMU's {}",
        token_changed: "the instantiationToken is now {} instead of {}",
        foreign_state: "the state belongs to instantiationToken {}, this instance has {}",
        no_event_indicators: "nEventIndicators = {}, but the FMU has none",
    };

    /// The core's table with the independent variable `time`, and the instantiationToken of
    /// its description.
    fn variables_and_token(
        info: &ModelInfo,
        variables: Vec<Variable>,
        structure: &ModelStructure,
    ) -> Result<(Vec<Variable>, String), String> {
        let variables = with_time(variables);
        let token = instantiation_token(&Model {
            info,
            vars: &variables,
            structure,
        })?;
        Ok((variables, token))
    }

    /// Step Mode (Co-Simulation without Event Mode) or Event Mode.
    fn after_initialization(kind: InstanceKind, event_mode: EventModeUsed) -> Phase {
        match kind {
            InstanceKind::CoSimulation if !event_mode.0 => StepMode,
            _ => EventMode,
        }
    }
}

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

impl<M: FmuCore> Instance<M> {
    /// `fmi3InstantiateModelExchange` / `fmi3InstantiateCoSimulation` (section 2.3.1):
    /// creates the core from the resources and checks the importer's token against the one
    /// computed for this core. Errors are logged and give `None`.
    pub fn create(request: Request, logger: Logger) -> Option<Self> {
        let func = match request.interface {
            InstanceKind::ModelExchange => "fmi3InstantiateModelExchange",
            InstanceKind::CoSimulation => "fmi3InstantiateCoSimulation",
        };
        let resource_dir = request
            .resource_path
            .filter(|p| !p.is_empty())
            .map(PathBuf::from);
        let resource_dir = if request.name.trim().is_empty() {
            Err("instanceName is empty".into())
        } else if let Some(dir) = resource_dir.as_ref().filter(|d| !d.is_absolute()) {
            Err(format!(
                "resourcePath {} is not an absolute path (section 2.3.1)",
                dir.display()
            ))
        } else {
            Ok(resource_dir)
        };
        let generic = instance::Request {
            func,
            kind: request.interface,
            token: request.token,
            resource_dir,
            options: EventModeUsed(request.event_mode_used),
        };
        let instance = Self::instantiate(generic, logger)?;
        instance.trace(|| {
            format!(
                "{func}: {} instance {:?} created",
                request.interface.name(),
                request.name
            )
        });
        Some(instance)
    }

    /// `fmi3EnterInitializationMode` (section 2.3.2), with the experiment.
    pub fn enter_initialization_mode(&mut self, e: Experiment) -> Status {
        const F: &str = "fmi3EnterInitializationMode";
        self.trace(|| {
            format!(
                "{F}(tolerance={}, startTime={:?}, stopTime={})",
                optional(e.tolerance),
                e.start_time,
                optional(e.stop_time)
            )
        });
        if let Err(s) = self
            .require(F, allowed::ENTER_INITIALIZATION_MODE)
            .and_then(|()| self.check_experiment(F, &e))
        {
            return s;
        }
        self.initialize(F, e)
    }

    /// `fmi3EnterEventMode` (section 2.3.5): from Continuous-Time Mode, or from Step Mode when
    /// the importer asked for Event Mode. This FMU has no events of its own.
    pub fn enter_event_mode(&mut self) -> Status {
        const F: &str = "fmi3EnterEventMode";
        self.trace(|| F.into());
        if let Err(s) = self.require(F, allowed::ENTER_EVENT_MODE) {
            return s;
        }
        if self.kind == InstanceKind::CoSimulation && !self.options.0 {
            return self.error(
                F,
                "the instance was created with eventModeUsed = false (section 4.2.2)",
            );
        }
        self.phase = EventMode;
        Status::Ok
    }

    /// `fmi3UpdateDiscreteStates` (section 3.2.3): no discrete states, no time events; the
    /// flags are all false.
    pub fn update_discrete_states(&mut self) -> Status {
        const F: &str = "fmi3UpdateDiscreteStates";
        self.trace(|| F.into());
        self.require(F, allowed::UPDATE_DISCRETE_STATES)
            .err()
            .unwrap_or(Status::Ok)
    }

    /// `fmi3EnterStepMode` (section 4.2.2): from Event Mode, Co-Simulation only.
    pub fn enter_step_mode(&mut self) -> Status {
        let (cs, mask) = (Some(InstanceKind::CoSimulation), allowed::ENTER_STEP_MODE);
        self.move_to("fmi3EnterStepMode", cs, mask, StepMode)
    }

    /// What `fmi3DoStep` returns beyond its status (section 4.2.2).
    pub fn do_step(&mut self, tc: f64, h: f64) -> (Status, f64) {
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
            Ok(()) => (Status::Ok, self.core.time()),
            Err(msg) => {
                self.phase = StepDiscarded;
                let t = self.core.time();
                self.log(Status::Discard, format_args!("{F}: step from t = {tc:?} over {h:?} s discarded: {msg}; the FMU stays at t = {t:?} (lastSuccessfulTime); restore a state with fmi3SetFMUState, or terminate"),
                );
                (Status::Discard, t)
            }
        }
    }

    /// Checks that an array of `n` elements has one per continuous state.
    fn check_states(&self, func: &str, what: &str, n: usize) -> Result<(), Status> {
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
    pub fn number_of(&self, func: &str, what: usize) -> Result<usize, Status> {
        self.require_of(func, InstanceKind::ModelExchange, allowed::GET_NUMBER_OF)
            .map(|()| what)
    }

    /// `fmi3EnterContinuousTimeMode` (section 3.2.2).
    pub fn enter_continuous_time_mode(&mut self) -> Status {
        let (f, mask) = (
            "fmi3EnterContinuousTimeMode",
            allowed::ENTER_CONTINUOUS_TIME_MODE,
        );
        self.move_to(
            f,
            Some(InstanceKind::ModelExchange),
            mask,
            ContinuousTimeMode,
        )
    }

    /// `fmi3SetContinuousStates` (section 3.2.1); a NaN is refused with its state named.
    pub fn set_continuous_states(&mut self, x: &[f64]) -> Status {
        const F: &str = "fmi3SetContinuousStates";
        if let Err(s) = self
            .require_of(
                F,
                InstanceKind::ModelExchange,
                allowed::SET_CONTINUOUS_STATES,
            )
            .and_then(|()| self.check_states(F, "nContinuousStates", x.len()))
        {
            return s;
        }
        if let Some(k) = x.iter().position(|v| v.is_nan()) {
            let vr = self.structure.derivatives[k].state;
            let name = self.find(vr).map_or("", |v| v.name.as_str());
            return self.error(F, format_args!("continuousStates[{k}] ({name}) is NaN"));
        }
        self.core_call(F, |core| core.set_continuous_states(x))
    }

    /// `fmi3GetContinuousStates` (section 3.2.1).
    pub fn get_continuous_states(&mut self, x: &mut [f64]) -> Status {
        self.state_vector("fmi3GetContinuousStates", x, M::continuous_states)
    }

    /// `fmi3GetContinuousStateDerivatives` (section 3.2.1).
    pub fn get_derivatives(&mut self, dx: &mut [f64]) -> Status {
        self.state_vector("fmi3GetContinuousStateDerivatives", dx, M::derivatives)
    }

    /// `fmi3GetNominalsOfContinuousStates` (section 3.2.1).
    pub fn get_nominals(&mut self, nominals: &mut [f64]) -> Status {
        self.state_vector("fmi3GetNominalsOfContinuousStates", nominals, |m, out| {
            m.nominals(out)
        })
    }

    /// `fmi3GetContinuousStates`, `fmi3GetContinuousStateDerivatives` and
    /// `fmi3GetNominalsOfContinuousStates` (`func`, section 3.2.1): one value per state from
    /// `call`. Where the model cannot be evaluated (a state outside its domain), the
    /// derivatives give `fmi3Discard` (the importer may retry with a smaller step).
    fn state_vector(
        &mut self,
        func: &str,
        out: &mut [f64],
        call: fn(&mut M, &mut [f64]) -> Result<(), String>,
    ) -> Status {
        if let Err(s) = self
            .require_of(
                func,
                InstanceKind::ModelExchange,
                allowed::GET_MODEL_EQUATIONS,
            )
            .and_then(|()| self.check_states(func, "nContinuousStates", out.len()))
        {
            return s;
        }
        match call(&mut self.core, out) {
            Ok(()) => Status::Ok,
            Err(msg) if func == "fmi3GetContinuousStateDerivatives" => {
                self.log(Status::Discard, format_args!("{func}: {msg}"));
                Status::Discard
            }
            Err(msg) => self.error(func, msg),
        }
    }

    /// `fmi3GetDirectionalDerivative` (section 2.3.8): ∂unknowns/∂knowns · seed, with state
    /// derivatives and outputs as unknowns, states and inputs as knowns.
    pub fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        sensitivity: &mut [f64],
    ) -> Status {
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
        let is_known = |vr: &u32| {
            self.is_state(*vr)
                || self
                    .find(*vr)
                    .is_some_and(|v| v.causality == Causality::Input)
        };
        let name = |vr: u32| {
            self.find(vr)
                .map_or(String::new(), |v| format!(" ({})", v.name))
        };
        if let Some(&vr) = unknowns.iter().find(|vr| !self.is_unknown(**vr)) {
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
        self.core_call(F, |core| {
            core.directional_derivative(unknowns, knowns, seed, sensitivity)
        })
    }
}
