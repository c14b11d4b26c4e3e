//! The state machine of FMI 3.0 for Model Exchange and Co-Simulation (standard sections 3.2
//! and 4.2) as one table: one bit per state ([`Phase::bit`]), and for each function the mask
//! of the states it may be called in ([`allowed`]). The instance checks every call against
//! it; which variables `fmi3SetFloat64` may set in a state is [`States::set_rule`].

use serde::{Deserialize, Serialize};

use super::types::InstanceKind;
pub use crate::fmi_common::state_machine::{Experiment, Mask, States, names};

/// The states this FMU can be in. Configuration, Reconfiguration, Clock Activation and
/// Intermediate Update Mode are unreachable: the FMU has no structural parameters, no clocks
/// and never returns early. `Error` is where a caught panic leaves an instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[repr(u8)]
pub enum Phase {
    Instantiated = 0,
    InitializationMode = 1,
    EventMode = 2,
    /// Model Exchange only
    ContinuousTimeMode = 3,
    /// Co-Simulation only
    StepMode = 4,
    /// Co-Simulation, after `fmi3DoStep` returned `fmi3Discard`
    StepDiscarded = 5,
    Terminated = 6,
    Error = 7,
}

impl Phase {
    /// The state's bit in a [`Mask`].
    pub const fn bit(self) -> Mask {
        1 << self as u8
    }

    /// Whether an instance of `interface` can be in this state.
    pub fn belongs_to(self, interface: InstanceKind) -> bool {
        match self {
            Phase::ContinuousTimeMode => interface == InstanceKind::ModelExchange,
            Phase::StepMode | Phase::StepDiscarded => interface == InstanceKind::CoSimulation,
            _ => true,
        }
    }
}

impl States for Phase {
    const ALL: &'static [Phase] = &[
        Phase::Instantiated,
        Phase::InitializationMode,
        Phase::EventMode,
        Phase::ContinuousTimeMode,
        Phase::StepMode,
        Phase::StepDiscarded,
        Phase::Terminated,
        Phase::Error,
    ];

    const INSTANTIATED: Phase = Phase::Instantiated;
    const INITIALIZATION_MODE: Phase = Phase::InitializationMode;
    const TERMINATED: Phase = Phase::Terminated;
    const ERROR: Phase = Phase::Error;
    const INPUTS_AND_TUNABLE_PARAMETERS: Mask = Phase::EventMode.bit() | Phase::StepMode.bit();
    const CONTINUOUS_INPUTS: Mask = Phase::ContinuousTimeMode.bit();

    fn name(self) -> &'static str {
        match self {
            Phase::Instantiated => "Instantiated",
            Phase::InitializationMode => "Initialization Mode",
            Phase::EventMode => "Event Mode",
            Phase::ContinuousTimeMode => "Continuous-Time Mode",
            Phase::StepMode => "Step Mode",
            Phase::StepDiscarded => "Step Discarded",
            Phase::Terminated => "Terminated",
            Phase::Error => "error (after an internal error)",
        }
    }
}

/// The states each function may be called in. Allowed in every state, and so not checked:
/// `fmi3SetDebugLogging`, `fmi3Reset`, `fmi3FreeInstance` and the FMU-state functions.
/// Functions of capabilities this FMU does not declare fail in every state.
///
/// `fmi3ExitInitializationMode` is allowed in Initialization Mode only, in both versions: the generic
/// instance checks it.
pub mod allowed {
    use super::Mask;
    use super::Phase::*;

    const INSTANTIATED: Mask = Instantiated.bit();
    const INITIALIZATION_MODE: Mask = InitializationMode.bit();
    const EVENT_MODE: Mask = EventMode.bit();
    const CONTINUOUS_TIME_MODE: Mask = ContinuousTimeMode.bit();
    const STEP_MODE: Mask = StepMode.bit();
    const STEP_DISCARDED: Mask = StepDiscarded.bit();
    const TERMINATED: Mask = Terminated.bit();
    const ERROR: Mask = Error.bit();

    pub const ENTER_INITIALIZATION_MODE: Mask = INSTANTIATED;
    /// Model Exchange from Continuous-Time Mode; Co-Simulation from Step Mode when the
    /// importer asked for Event Mode (`eventModeUsed`).
    pub const ENTER_EVENT_MODE: Mask = CONTINUOUS_TIME_MODE | STEP_MODE;
    pub const TERMINATE: Mask = EVENT_MODE | CONTINUOUS_TIME_MODE | STEP_MODE | STEP_DISCARDED;
    /// `fmi3Get{Float64,…}`; in Step Discarded and error for debugging.
    pub const GET_VALUES: Mask = INITIALIZATION_MODE
        | EVENT_MODE
        | CONTINUOUS_TIME_MODE
        | STEP_MODE
        | STEP_DISCARDED
        | TERMINATED
        | ERROR;
    /// `fmi3Set{Float64,…}`; which variables depends on the state (`States::set_rule`).
    pub const SET_VALUES: Mask =
        INSTANTIATED | INITIALIZATION_MODE | EVENT_MODE | CONTINUOUS_TIME_MODE | STEP_MODE;
    pub const DIRECTIONAL_DERIVATIVE: Mask = INITIALIZATION_MODE
        | EVENT_MODE
        | CONTINUOUS_TIME_MODE
        | STEP_MODE
        | STEP_DISCARDED
        | TERMINATED;
    pub const UPDATE_DISCRETE_STATES: Mask = EVENT_MODE;
    pub const ENTER_CONTINUOUS_TIME_MODE: Mask = EVENT_MODE;
    pub const COMPLETED_INTEGRATOR_STEP: Mask = CONTINUOUS_TIME_MODE;
    pub const SET_TIME: Mask = EVENT_MODE | CONTINUOUS_TIME_MODE;
    pub const SET_CONTINUOUS_STATES: Mask = CONTINUOUS_TIME_MODE;
    /// `fmi3GetContinuousStateDerivatives`, `fmi3GetEventIndicators`,
    /// `fmi3GetContinuousStates`, `fmi3GetNominalsOfContinuousStates`.
    pub const GET_MODEL_EQUATIONS: Mask =
        INITIALIZATION_MODE | EVENT_MODE | CONTINUOUS_TIME_MODE | TERMINATED;
    /// `fmi3GetNumberOf{ContinuousStates,EventIndicators}`: fixed by the description.
    pub const GET_NUMBER_OF: Mask = !0;
    pub const ENTER_STEP_MODE: Mask = EVENT_MODE;
    pub const DO_STEP: Mask = STEP_MODE;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_phase_has_its_own_bit_and_belongs_to_its_interfaces() {
        for (i, p) in Phase::ALL.iter().copied().enumerate() {
            assert_eq!(p.bit(), 1 << i);
        }
        assert!(!Phase::StepMode.belongs_to(InstanceKind::ModelExchange));
        assert!(!Phase::ContinuousTimeMode.belongs_to(InstanceKind::CoSimulation));
        assert_eq!(
            names::<Phase>(allowed::TERMINATE),
            "Event Mode, Continuous-Time Mode, Step Mode, Step Discarded"
        );
    }
}
