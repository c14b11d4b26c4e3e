//! What the FMI 2.0 and 3.0 state machines share: the mask-table mechanism (each state a bit
//! of a [`Mask`], each function the mask of the states it may be called in), the rule of which
//! variables a setter may set in a kind of state ([`SetRule`], the footnotes of both
//! standards' tables), and the experiment an importer sets before initialization. Each version
//! names its own states and lays out its own table (`fmi2::state_machine`,
//! `fmi3::state_machine`).

use serde::{Deserialize, Serialize};

use super::variables::{Causality, Initial, Variability, Variable};

/// A set of states, one bit per state.
pub type Mask = u8;

/// The states of one version's state machine: at most eight, in the standard's order.
pub trait States: Copy + PartialEq + 'static {
    /// Every state, in the order of the standard (a state's bit is its position).
    const ALL: &'static [Self];
    /// The states both versions have: before initialization, during it, after termination,
    /// and where a caught panic or a failed reset leaves an instance.
    const INSTANTIATED: Self;
    const INITIALIZATION_MODE: Self;
    const TERMINATED: Self;
    const ERROR: Self;
    /// The states after initialization where the setters may set inputs and tunable
    /// parameters, and those where they may set continuous inputs only.
    const INPUTS_AND_TUNABLE_PARAMETERS: Mask;
    const CONTINUOUS_INPUTS: Mask;

    /// The state's name in the standard.
    fn name(self) -> &'static str;

    /// The state's bit in a [`Mask`]: its position in [`States::ALL`].
    fn bit(self) -> Mask {
        Self::ALL
            .iter()
            .position(|&s| s == self)
            .map_or(0, |i| 1 << i)
    }

    /// Whether the state is in `mask`.
    fn is_in(self, mask: Mask) -> bool {
        self.bit() & mask != 0
    }

    /// Which variables the setters may set in this state.
    fn set_rule(self) -> SetRule {
        if self == Self::INSTANTIATED {
            SetRule::StartValues
        } else if self == Self::INITIALIZATION_MODE {
            SetRule::ExactStartValues
        } else if self.is_in(Self::INPUTS_AND_TUNABLE_PARAMETERS) {
            SetRule::InputsAndTunableParameters
        } else if self.is_in(Self::CONTINUOUS_INPUTS) {
            SetRule::ContinuousInputs
        } else {
            SetRule::Nothing
        }
    }
}

/// The names of the states in `mask`, in the order of the standard, for messages.
pub fn names<S: States>(mask: Mask) -> String {
    let names: Vec<&str> = S::ALL
        .iter()
        .filter(|s| s.is_in(mask))
        .map(|s| s.name())
        .collect();
    names.join(", ")
}

/// The kinds of state that differ in what `fmi2SetReal` / `fmi3SetFloat64` may set (FMI 2.0
/// sections 3.2.3 and 4.2.4, FMI 3.0 sections 2.3.3, 3.2 and 4.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SetRule {
    /// Before initialization: inputs and variables with a start value (initial exact or approx).
    StartValues,
    /// Initialization Mode: inputs and variables with initial exact.
    ExactStartValues,
    /// Event Mode, a completed step: inputs and tunable parameters.
    InputsAndTunableParameters,
    /// Continuous-Time Mode: continuous inputs.
    ContinuousInputs,
    /// Anything else: nothing.
    Nothing,
}

/// Whether a setter may set `v` under `rule`. Constants and the independent variable never.
pub fn settable(rule: SetRule, v: &Variable) -> bool {
    let input = v.causality == Causality::Input;
    let initial = v.effective_initial();
    let tunable = v.causality == Causality::Parameter && v.variability == Variability::Tunable;
    v.variability != Variability::Constant
        && v.causality != Causality::Independent
        && match rule {
            SetRule::StartValues => {
                input || matches!(initial, Some(Initial::Exact | Initial::Approx))
            }
            SetRule::ExactStartValues => input || initial == Some(Initial::Exact),
            SetRule::InputsAndTunableParameters => input || tunable,
            SetRule::ContinuousInputs => input && v.variability == Variability::Continuous,
            SetRule::Nothing => false,
        }
}

/// The experiment an importer sets before initialization (`fmi2SetupExperiment`, FMI 2.0
/// section 2.1.6; the arguments of `fmi3EnterInitializationMode`, FMI 3.0 section 2.3.2).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Experiment {
    pub start_time: f64,
    pub stop_time: Option<f64>,
    pub tolerance: Option<f64>,
}
