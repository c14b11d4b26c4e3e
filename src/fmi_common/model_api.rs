//! The interface between a generic FMI wrapper ([`crate::fmi2`] or [`crate::fmi3`]) and one
//! model ("core"). The core knows nothing of FMI: no C types, no state machine, no logging.
//! Errors are plain messages that the wrapper logs together with the function name. The FMI
//! functions named below are the FMI 2.0 ones the wrapper maps onto each method (FMI 3.0 has
//! their counterparts); the methods are the same for both versions, Co-Simulation and Model
//! Exchange.

use std::path::Path;

use super::variables::{ModelInfo, Variable};

/// The interface an instance is created for, fixed for its life.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InstanceKind {
    /// The importer integrates: it sets time and states and asks for derivatives.
    ModelExchange,
    /// The core integrates over each communication step.
    CoSimulation,
}

impl InstanceKind {
    /// The interface's name in the standard, for messages.
    pub fn name(self) -> &'static str {
        match self {
            InstanceKind::ModelExchange => "Model Exchange",
            InstanceKind::CoSimulation => "Co-Simulation",
        }
    }
}

/// One continuous state of the model's state vector and what its derivative depends on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StateDerivative {
    /// Value reference of the state.
    pub state: u32,
    /// Value reference of its derivative (a variable whose `derivative` is `state`).
    pub derivative: u32,
    /// Value references of the states and inputs the derivative can depend on, ascending.
    pub dependencies: Vec<u32>,
}

/// One output and what it can depend on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutputDependency {
    pub output: u32,
    /// Value references of the states and inputs the output can depend on, ascending.
    pub dependencies: Vec<u32>,
}

/// The model's structure (FMI's `<ModelStructure>` before any FMI version's format): the
/// continuous states in the order of the state vector and the dependencies of their
/// derivatives and of the outputs. A dependency is listed if some parameter values can make
/// it nonzero, so the lists hold for every instance.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModelStructure {
    pub derivatives: Vec<StateDerivative>,
    pub outputs: Vec<OutputDependency>,
}

/// One simulation model as seen by the generic FMI instance ([`super::instance::Instance`]).
///
/// Contract, beyond the method docs:
/// * An output depends on what [`ModelStructure::outputs`] lists for it (states, inputs), a
///   state derivative on what [`ModelStructure::derivatives`] lists; `modelDescription.xml`
///   declares exactly that.
/// * `get_real` must give consistent values from Initialization Mode on, i.e. after
///   [`FmuCore::enter_initialization`]: outputs and calculated parameters are computed from
///   the current parameters and inputs, and values set in Initialization Mode are seen.
/// * Every method that returns `Err` leaves `self` as it was before the call.
/// * A panic is caught by the wrapper and puts the instance into the FMI error state.
pub trait FmuCore: Clone + Send + 'static {
    /// Model-level data of `modelDescription.xml`; must not depend on the instance.
    fn model_info() -> ModelInfo;

    /// The continuous states and the dependencies; must not depend on the instance. Every
    /// value reference in it is one of [`FmuCore::variables`].
    fn model_structure() -> ModelStructure;

    /// Creates an instance of `kind` with its start values; `resource_dir` is the FMU's
    /// resources folder when the importer gave one (`fmi2Instantiate`, section 2.1.6).
    fn instantiate(kind: InstanceKind, resource_dir: Option<&Path>) -> Result<Self, String>;

    /// The variable table with this instance's start values (the start values can come from
    /// `resources/`, so it is per instance). The GUID is computed from it, and the wrapper
    /// calls it only at instantiation and reset.
    fn variables(&self) -> Vec<Variable>;

    /// The current value of the Real variable `vr` (the wrapper has checked that it exists).
    fn get_real(&mut self, vr: u32) -> Result<f64, String>;

    /// Sets the Real variable `vr`. The wrapper has checked that it exists and that the
    /// causality/variability/state rules of section 4.2.4 allow setting it now; the core
    /// validates the value (NaN, range) and names the variable and the value in the message.
    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), String>;

    /// Start of Initialization Mode (`fmi2EnterInitializationMode`) with the experiment of
    /// `fmi2SetupExperiment`: the core sets its time to `start_time`.
    fn enter_initialization(
        &mut self,
        start_time: f64,
        stop_time: Option<f64>,
        tolerance: Option<f64>,
    ) -> Result<(), String>;

    /// End of Initialization Mode (`fmi2ExitInitializationMode`): the parameters are final,
    /// the initial state is computed; stepping (Co-Simulation) or the importer's integration
    /// (Model Exchange) follows. A configuration the instance's kind cannot run is refused
    /// here, with the reason.
    fn exit_initialization(&mut self) -> Result<(), String>;

    /// Integrates from the internal time over `step` seconds (`step > 0`, finite) with the
    /// inputs held. On `Err` the core must leave itself at the start of the step (usable);
    /// the wrapper returns `fmi2Discard` and logs the reason.
    fn do_step(&mut self, step: f64) -> Result<(), String>;

    /// The internal time: the end of the last successful step, or the time last set in Model
    /// Exchange.
    fn time(&self) -> f64;

    /// Model Exchange, after initialization: the time of the next evaluations (`fmi2SetTime`;
    /// finite, checked by the wrapper).
    fn set_time(&mut self, time: f64) -> Result<(), String>;

    /// The continuous states, in the order of [`ModelStructure::derivatives`], into `x` (of
    /// that length): from Initialization Mode on (`fmi2GetContinuousStates`).
    fn continuous_states(&mut self, x: &mut [f64]) -> Result<(), String>;

    /// Model Exchange, after initialization: sets the continuous states (`fmi2SetContinuous
    /// States`); the core rejects values it cannot evaluate (not finite) with a message.
    fn set_continuous_states(&mut self, x: &[f64]) -> Result<(), String>;

    /// The state derivatives at the current time, states and inputs, in state order
    /// (`fmi2GetDerivatives`); `Err` where the model cannot be evaluated there.
    fn derivatives(&mut self, dx: &mut [f64]) -> Result<(), String>;

    /// The nominal value of each continuous state, its typical magnitude, in state order
    /// (`fmi2GetNominalsOfContinuousStates`); from the current parameters.
    fn nominals(&self, nominal: &mut [f64]) -> Result<(), String>;

    /// The directional derivative `Σ_j ∂unknown_i/∂known_j · seed_j` of state derivatives or
    /// outputs (`unknowns`) in the direction `seed` of states or inputs (`knowns`), at the
    /// current states and inputs, into `result` (`fmi2GetDirectionalDerivative`). The wrapper
    /// has checked that the references are of those kinds and the lengths agree.
    fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        result: &mut [f64],
    ) -> Result<(), String>;

    /// The complete dynamic state as bytes (everything `deserialize_state` needs beyond what
    /// `instantiate` gives), for `fmi2SerializeFMUstate`.
    fn serialize_state(&self) -> Vec<u8>;

    /// Rebuilds a core from [`FmuCore::serialize_state`] bytes; `self` is the instance that
    /// asks (for data that is not serialized, such as resources). Must reject malformed
    /// bytes with a message, never panic. A restored core must replay bit for bit.
    fn deserialize_state(&self, bytes: &[u8]) -> Result<Self, String>;
}
