//! The state machines of FMI 2.0, Co-Simulation (standard section 4.2.4) and Model Exchange
//! (section 3.2.3), as one table laid out like the Modelica Reference FMUs' `MASK_fmi2…`: one
//! bit per state ([`Phase::bit`]), and for each function the mask of the states it may be
//! called in ([`allowed`]). The instance checks every call against it (and that a function of
//! one interface is not called on an instance of the other); which variables `fmi2SetReal` may
//! set in a state is [`States::set_rule`].

use crate::fmi_common::model_api::InstanceKind;
pub use crate::fmi_common::state_machine::{Experiment, Mask, States, names};

/// The states of the two state machines this FMU can be in.
/// `stepInProgress` and `stepCanceled` are unreachable: `fmi2DoStep` is synchronous.
/// The discriminant is the state's byte in a serialized FMU state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Phase {
    Instantiated = 0,
    InitializationMode = 1,
    /// slaveInitialized / stepComplete
    StepComplete = 2,
    /// after `fmi2DoStep` returned `fmi2Discard`
    StepFailed = 3,
    Terminated = 4,
    Error = 5,
    /// Model Exchange
    EventMode = 6,
    /// Model Exchange
    ContinuousTimeMode = 7,
}

impl Phase {
    pub fn from_u8(b: u8) -> Option<Phase> {
        Phase::ALL.get(usize::from(b)).copied()
    }

    /// Whether an instance of `kind` can be in this state.
    pub fn belongs_to(self, kind: InstanceKind) -> bool {
        match self {
            Phase::StepComplete | Phase::StepFailed => kind == InstanceKind::CoSimulation,
            Phase::EventMode | Phase::ContinuousTimeMode => kind == InstanceKind::ModelExchange,
            _ => true,
        }
    }

    /// The state's bit in a [`Mask`].
    pub const fn bit(self) -> Mask {
        1 << self as u8
    }
}

impl States for Phase {
    const ALL: &'static [Phase] = &[
        Phase::Instantiated,
        Phase::InitializationMode,
        Phase::StepComplete,
        Phase::StepFailed,
        Phase::Terminated,
        Phase::Error,
        Phase::EventMode,
        Phase::ContinuousTimeMode,
    ];

    const INSTANTIATED: Phase = Phase::Instantiated;
    const INITIALIZATION_MODE: Phase = Phase::InitializationMode;
    const TERMINATED: Phase = Phase::Terminated;
    const ERROR: Phase = Phase::Error;
    const INPUTS_AND_TUNABLE_PARAMETERS: Mask = Phase::StepComplete.bit() | Phase::EventMode.bit();
    const CONTINUOUS_INPUTS: Mask = Phase::ContinuousTimeMode.bit();

    fn name(self) -> &'static str {
        match self {
            Phase::Instantiated => "instantiated",
            Phase::InitializationMode => "initializationMode",
            Phase::StepComplete => "stepComplete",
            Phase::StepFailed => "stepFailed",
            Phase::Terminated => "terminated",
            Phase::Error => "error",
            Phase::EventMode => "eventMode",
            Phase::ContinuousTimeMode => "continuousTimeMode",
        }
    }
}

/// The states each function may be called in (sections 3.2.3 and 4.2.4). Allowed in every
/// state, and so not checked: `fmi2SetDebugLogging`, `fmi2Reset`, `fmi2FreeInstance` and the
/// FMU-state functions (`fmi2GetFMUstate` … `fmi2DeSerializeFMUstate`). Functions this FMU
/// does not offer (input and output derivatives) fail in every state.
///
/// `fmi2ExitInitializationMode` is allowed in Initialization Mode only, in both versions: the generic
/// instance checks it.
pub mod allowed {
    use super::Mask;
    use super::Phase::*;

    const INSTANTIATED: Mask = Instantiated.bit();
    const INITIALIZATION_MODE: Mask = InitializationMode.bit();
    const STEP_COMPLETE: Mask = StepComplete.bit();
    const STEP_FAILED: Mask = StepFailed.bit();
    const TERMINATED: Mask = Terminated.bit();
    const ERROR: Mask = Error.bit();
    const EVENT_MODE: Mask = EventMode.bit();
    const CONTINUOUS_TIME_MODE: Mask = ContinuousTimeMode.bit();

    pub const SETUP_EXPERIMENT: Mask = INSTANTIATED;
    pub const ENTER_INITIALIZATION_MODE: Mask = INSTANTIATED;
    pub const TERMINATE: Mask = STEP_COMPLETE | STEP_FAILED | EVENT_MODE | CONTINUOUS_TIME_MODE;
    /// `fmi2Get{Real,Integer,Boolean,String}`; in stepFailed and error for debugging only.
    pub const GET_VALUES: Mask = INITIALIZATION_MODE
        | STEP_COMPLETE
        | STEP_FAILED
        | TERMINATED
        | ERROR
        | EVENT_MODE
        | CONTINUOUS_TIME_MODE;
    /// `fmi2Set{Real,Integer,Boolean,String}`; which variables depends on the state
    /// (`States::set_rule`).
    pub const SET_VALUES: Mask =
        INSTANTIATED | INITIALIZATION_MODE | STEP_COMPLETE | EVENT_MODE | CONTINUOUS_TIME_MODE;
    /// `fmi2GetDirectionalDerivative`, both interfaces.
    pub const GET_DIRECTIONAL_DERIVATIVE: Mask = INITIALIZATION_MODE
        | EVENT_MODE
        | CONTINUOUS_TIME_MODE
        | STEP_COMPLETE
        | STEP_FAILED
        | TERMINATED
        | ERROR;

    // Model Exchange (section 3.2.3)
    pub const ENTER_EVENT_MODE: Mask = EVENT_MODE | CONTINUOUS_TIME_MODE;
    pub const NEW_DISCRETE_STATES: Mask = EVENT_MODE;
    pub const ENTER_CONTINUOUS_TIME_MODE: Mask = EVENT_MODE;
    pub const COMPLETED_INTEGRATOR_STEP: Mask = CONTINUOUS_TIME_MODE;
    pub const SET_TIME: Mask = EVENT_MODE | CONTINUOUS_TIME_MODE;
    pub const SET_CONTINUOUS_STATES: Mask = CONTINUOUS_TIME_MODE;
    /// `fmi2GetEventIndicators` and `fmi2GetContinuousStates`.
    pub const GET_STATES: Mask =
        INITIALIZATION_MODE | EVENT_MODE | CONTINUOUS_TIME_MODE | TERMINATED | ERROR;
    pub const GET_DERIVATIVES: Mask = EVENT_MODE | CONTINUOUS_TIME_MODE | TERMINATED | ERROR;
    pub const GET_NOMINALS: Mask =
        INSTANTIATED | EVENT_MODE | CONTINUOUS_TIME_MODE | TERMINATED | ERROR;

    // Co-Simulation (section 4.2.4)
    pub const DO_STEP: Mask = STEP_COMPLETE;
    /// `fmi2Get{,Real,Integer,Boolean,String}Status`.
    pub const GET_STATUS: Mask = STEP_COMPLETE | STEP_FAILED | TERMINATED;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phases_round_trip_through_their_byte_and_bit() {
        for (i, p) in Phase::ALL.iter().copied().enumerate() {
            assert_eq!(Phase::from_u8(p as u8), Some(p));
            assert_eq!(p.bit(), 1 << i);
        }
        assert_eq!(Phase::from_u8(8), None);
        assert_eq!(
            names::<Phase>(allowed::TERMINATE | Phase::Instantiated.bit()),
            "instantiated, stepComplete, stepFailed, eventMode, continuousTimeMode"
        );
    }
}
