//! The interface between a generic FMI wrapper (the FMI 2.0 one: [`crate::fmi2`]) and one
//! model ("core"). The core knows nothing of FMI: no C types, no state machine, no logging.
//! Errors are plain messages that the wrapper logs together with the function name. The FMI
//! functions named below are the FMI 2.0 ones the wrapper maps onto each method.

use std::path::Path;

use super::variables::{ModelInfo, Variable};

/// One simulation model as seen by the FMI wrapper ([`crate::fmi2::instance::Instance`]).
///
/// Contract, beyond the method docs:
/// * Outputs must be functions of the internal state and parameters only (no direct
///   feedthrough from inputs): `modelDescription.xml` declares `dependencies=""` for them.
/// * `get_real` must give consistent values from Initialization Mode on, i.e. after
///   [`FmuCore::enter_initialization`]: outputs and calculated parameters are computed from
///   the current parameters and inputs, and values set in Initialization Mode are seen.
/// * Every method that returns `Err` leaves `self` as it was before the call.
/// * A panic is caught by the wrapper and puts the instance into the FMI error state.
pub trait FmuCore: Clone + Send + 'static {
    /// Model-level data of `modelDescription.xml`; must not depend on the instance.
    fn model_info() -> ModelInfo;

    /// Creates an instance with its start values; `resource_dir` is the FMU's resources
    /// folder when the importer gave one (`fmi2Instantiate`, section 2.1.6).
    fn instantiate(resource_dir: Option<&Path>) -> Result<Self, String>;

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
    /// the initial state is computed; stepping follows.
    fn exit_initialization(&mut self) -> Result<(), String>;

    /// Integrates from the internal time over `step` seconds (`step > 0`, finite) with the
    /// inputs held. On `Err` the core must leave itself at the start of the step (usable);
    /// the wrapper returns `fmi2Discard` and logs the reason.
    fn do_step(&mut self, step: f64) -> Result<(), String>;

    /// The internal time: the end of the last successful step.
    fn time(&self) -> f64;

    /// The complete dynamic state as bytes (everything `deserialize_state` needs beyond what
    /// `instantiate` gives), for `fmi2SerializeFMUstate`.
    fn serialize_state(&self) -> Vec<u8>;

    /// Rebuilds a core from [`FmuCore::serialize_state`] bytes; `self` is the instance that
    /// asks (for data that is not serialized, such as resources). Must reject malformed
    /// bytes with a message, never panic. A restored core must replay bit for bit.
    fn deserialize_state(&self, bytes: &[u8]) -> Result<Self, String>;
}
