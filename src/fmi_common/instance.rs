//! The generic FMU instance: what the FMI 2.0 and 3.0 shells do alike around one [`FmuCore`]
//! in safe Rust: creating the core and checking the importer's token, the state machine checks
//! (a call in a state its version's table does not allow is refused), the argument checks,
//! logging, getting and setting values, initialization, termination, reset and FMU states.
//! A version ([`Version`]) brings its C status, its states and table, its logging callback,
//! its function names and the messages it words its own way, and adds its own calls in an
//! `impl` of [`Instance`] of its own (`fmi2::instance`, `fmi3::instance`).
//!
//! Error policy: a call in a state where the table does not allow it, or with invalid
//! arguments, returns [`Status::Error`] with a log message naming the function and the
//! offending state, reference or value, and changes nothing. Core failures are reported the
//! same way (the core contract keeps the core unchanged on `Err`), except in a step, where
//! they are [`Status::Discard`]. A caught panic puts the instance into the error state.

use std::fmt::{self, Display};
use std::path::{Path, PathBuf};

use super::fmu_state::{Format, Snapshot};
use super::logging::{LogSink, Logger, Status};
use super::model_api::{FmuCore, InstanceKind, ModelStructure};
use super::state_machine::{Experiment, Mask, States, names};
use super::values;
use super::variables::{ModelInfo, Variable};
use super::xml::{Dialect, log_categories};

/// The names of a version's functions and arguments the shared code writes in messages.
pub struct Names {
    pub set_debug_logging: &'static str,
    pub exit_initialization_mode: &'static str,
    pub terminate: &'static str,
    pub reset: &'static str,
    pub free_instance: &'static str,
    /// The Float64 (Real) getter and setter.
    pub get_values: &'static str,
    pub set_values: &'static str,
    pub get_fmu_state: &'static str,
    pub set_fmu_state: &'static str,
    pub deserialize_fmu_state: &'static str,
    /// The function that tells the size of a serialized FMU state.
    pub serialized_size: &'static str,
    /// The names of the value-reference and value arguments of the getters and setters.
    pub value_references: &'static str,
    pub values: &'static str,
    /// The name of an FMU-state argument in the version's headers.
    pub fmu_state: &'static str,
    /// The type of this FMU's variables in the version ("" where there is one real type).
    pub value_type: &'static str,
    /// The Model Exchange functions and the directional derivative.
    pub set_time: &'static str,
    pub set_continuous_states: &'static str,
    pub get_event_indicators: &'static str,
    pub completed_integrator_step: &'static str,
    pub get_directional_derivative: &'static str,
    /// The name of the states argument of the set-continuous-states function.
    pub continuous_states: &'static str,
    /// The names of the directional derivative's arguments, as its NULL messages say them.
    pub unknowns: &'static str,
    pub knowns: &'static str,
    pub seed: &'static str,
    pub sensitivity: &'static str,
}

/// The messages a version words its own way; each `{}` takes the next value.
pub struct Wording {
    /// A function of the interface `{}` called on an instance of `{}`.
    pub wrong_interface: &'static str,
    /// The importer's token `{}` is not the FMU's `{}`.
    pub token_mismatch: &'static str,
    /// After a reset, the token is `{}` instead of `{}`.
    pub token_changed: &'static str,
    /// An FMU state of the instance with the token `{}` given to the one with `{}`.
    pub foreign_state: &'static str,
    /// The importer asks for `{}` event indicators of an FMU that has none.
    pub no_event_indicators: &'static str,
}

/// `template` with each `{}` replaced by the next of `values`.
pub(super) fn fill(template: &str, values: [&str; 2]) -> String {
    let mut parts = template.split("{}");
    let mut out = parts.next().unwrap_or_default().to_string();
    for (value, part) in values.into_iter().zip(parts) {
        out.push_str(value);
        out.push_str(part);
    }
    out
}

/// The states each shared call may be called in (`fmiXExitInitializationMode`: Initialization
/// Mode in both versions).
pub struct Masks {
    pub terminate: Mask,
    pub get_values: Mask,
    pub set_values: Mask,
    pub set_time: Mask,
    pub get_event_indicators: Mask,
    pub completed_integrator_step: Mask,
}

/// What a version brings to the generic instance, beyond how it writes its description.
pub trait Version: Dialect + Format<Phase: States> + Sized + 'static {
    /// The version's C status enumeration.
    type Status: Copy + From<Status>;
    /// The version's C boolean.
    type Boolean: Copy + From<bool>;
    /// The importer's logging callback.
    type Sink: LogSink;
    /// What an instance holds beyond the shared state (FMI 3.0: `eventModeUsed`).
    type Options: Copy;

    const NAMES: Names;
    const MASKS: Masks;

    /// The state after `fmiXExitInitializationMode`.
    fn after_initialization(kind: InstanceKind, options: Self::Options) -> Self::Phase;
    /// The instance's variable table and token (GUID, instantiationToken) for a core's
    /// `variables`.
    fn variables_and_token(
        info: &ModelInfo,
        variables: Vec<Variable>,
        structure: &ModelStructure,
    ) -> Result<(Vec<Variable>, String), String>;
    const WORDING: Wording;
}

/// One FMU instance of version `V`: the shell state around a core `M`.
pub struct Instance<V: Version, M: FmuCore> {
    pub kind: InstanceKind,
    /// GUID (FMI 2.0) or instantiationToken (FMI 3.0).
    pub token: String,
    pub options: V::Options,
    pub resource_dir: Option<PathBuf>,
    logger: Logger<V::Sink>,
    /// Names of all log categories of `modelDescription.xml`.
    categories: Vec<String>,
    pub phase: V::Phase,
    pub experiment: Option<Experiment>,
    pub core: M,
    /// The instance's variables, sorted by value reference for lookups.
    pub variables: Vec<Variable>,
    /// The continuous states and dependencies ([`FmuCore::model_structure`]).
    pub structure: ModelStructure,
}

/// A fresh core with its sorted variable table and token.
struct Built<M> {
    core: M,
    variables: Vec<Variable>,
    token: String,
}

fn build<V: Version, M: FmuCore>(
    kind: InstanceKind,
    resource_dir: Option<&Path>,
) -> Result<Built<M>, String> {
    let core = M::instantiate(kind, resource_dir)?;
    let (mut variables, token) =
        V::variables_and_token(&M::model_info(), core.variables(), &M::model_structure())?;
    variables.sort_by_key(|v| v.value_reference);
    Ok(Built {
        core,
        variables,
        token,
    })
}

/// An optional number for messages: the value, or "undefined".
pub fn optional(x: Option<f64>) -> String {
    x.map_or("undefined".into(), |x| format!("{x:?}"))
}

/// What an importer asks `fmiXInstantiate…` for, after the version's own checks.
pub struct Request<'a, V: Version> {
    /// The instantiating function, for messages.
    pub func: &'a str,
    pub kind: InstanceKind,
    /// The importer's GUID or instantiationToken.
    pub token: &'a str,
    /// The resources folder, or the version's message why the request is refused.
    pub resource_dir: Result<Option<PathBuf>, String>,
    pub options: V::Options,
}

impl<V: Version, M: FmuCore> Instance<V, M> {
    /// Creates the core from the resources and checks the importer's token against the one
    /// computed for this core. Errors are logged and give `None`.
    pub fn instantiate(request: Request<V>, logger: Logger<V::Sink>) -> Option<Self> {
        let fail = |msg: String| {
            logger.log(Status::Error, &format!("{}: {msg}", request.func));
            None
        };
        let resource_dir = match request.resource_dir {
            Ok(dir) => dir,
            Err(e) => return fail(e),
        };
        let built = match build::<V, M>(request.kind, resource_dir.as_deref()) {
            Ok(b) => b,
            Err(e) => return fail(format!("cannot create the model: {e}")),
        };
        if built.token != request.token {
            return fail(fill(
                V::WORDING.token_mismatch,
                [request.token, &built.token],
            ));
        }
        let categories = log_categories(&V::CATEGORIES, &M::model_info())
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        Some(Instance {
            kind: request.kind,
            token: built.token,
            options: request.options,
            resource_dir,
            logger,
            categories,
            phase: V::Phase::INSTANTIATED,
            experiment: None,
            core: built.core,
            variables: built.variables,
            structure: M::model_structure(),
        })
    }
}

impl<V: Version, M: FmuCore> Instance<V, M> {
    /// Logs an error message of `func` and returns [`Status::Error`].
    pub fn error(&self, func: &str, msg: impl Display) -> Status {
        self.log(Status::Error, format_args!("{func}: {msg}"));
        Status::Error
    }

    /// Logs `msg` with `status`.
    pub fn log(&self, status: Status, msg: fmt::Arguments) {
        self.logger.log(status, &msg.to_string());
    }

    /// Debug-logs a call trace; the message is built only when debug logging is on.
    pub fn trace(&self, msg: impl FnOnce() -> String) {
        if self.logger.debug_enabled() {
            self.logger.log(Status::Ok, &msg());
        }
    }

    /// Checks the version's state table: `func` may be called in the states of `mask`.
    pub fn require(&self, func: &str, mask: Mask) -> Result<(), Status> {
        if self.phase.is_in(mask) {
            return Ok(());
        }
        Err(self.error(
            func,
            format_args!(
                "not allowed in state {} (allowed in: {})",
                self.phase.name(),
                names::<V::Phase>(mask)
            ),
        ))
    }

    /// Checks that `func`, a function of the `kind` interface only, is called on an instance
    /// of that kind.
    pub fn require_interface(&self, func: &str, kind: InstanceKind) -> Result<(), Status> {
        if self.kind == kind {
            return Ok(());
        }
        Err(self.error(
            func,
            fill(V::WORDING.wrong_interface, [kind.name(), self.kind.name()]),
        ))
    }

    /// [`Self::require_interface`], then the state table.
    pub fn require_of(&self, func: &str, kind: InstanceKind, mask: Mask) -> Result<(), Status> {
        self.require_interface(func, kind)?;
        self.require(func, mask)
    }

    /// Logs that `func` was called with a NULL `argument`.
    pub fn null_argument(&self, func: &str, argument: &str) -> Status {
        self.error(func, format_args!("argument {argument} is NULL"))
    }

    /// For functions of capabilities this FMU does not declare.
    pub fn not_offered(&self, func: &str, what: &str) -> Status {
        self.error(
            func,
            format_args!("{what} is not offered by this FMU (see modelDescription.xml)"),
        )
    }

    /// `fmiXSetDebugLogging`; an empty `categories` means all categories.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[String]) -> Status {
        match self
            .logger
            .set_debug_logging(on, categories, &self.categories)
        {
            Ok(()) => Status::Ok,
            Err(bad) => self.error(
                V::NAMES.set_debug_logging,
                format_args!(
                    "unknown log category {bad:?} (known: {})",
                    self.categories.join(", ")
                ),
            ),
        }
    }

    /// Checks the experiment an importer gives to `func`: finite start, stop (if any) not
    /// before it, tolerance (if any) positive.
    pub fn check_experiment(&self, func: &str, e: &Experiment) -> Result<(), Status> {
        let start = e.start_time;
        if !start.is_finite() {
            return Err(self.error(func, format_args!("startTime = {start:?} is not finite")));
        }
        if let Some(stop) = e.stop_time.filter(|s| !(s.is_finite() && *s >= start)) {
            return Err(self.error(
                func,
                format_args!("stopTime = {stop:?} is not a finite time >= startTime = {start:?}"),
            ));
        }
        if let Some(tol) = e.tolerance.filter(|t| !(t.is_finite() && *t > 0.0)) {
            return Err(self.error(
                func,
                format_args!("tolerance = {tol:?} is not a finite positive number"),
            ));
        }
        Ok(())
    }

    /// Initializes the core for experiment `e` (`func`, after its checks) and enters
    /// Initialization Mode.
    pub fn initialize(&mut self, func: &str, e: Experiment) -> Status {
        match self
            .core
            .enter_initialization(e.start_time, e.stop_time, e.tolerance)
        {
            Ok(()) => {
                self.experiment = Some(e);
                self.phase = V::Phase::INITIALIZATION_MODE;
                Status::Ok
            }
            Err(msg) => self.error(func, msg),
        }
    }

    /// `fmiXExitInitializationMode`: on to the state of [`Version::after_initialization`].
    pub fn exit_initialization_mode(&mut self) -> Status {
        let func = V::NAMES.exit_initialization_mode;
        self.trace(|| func.into());
        if let Err(s) = self.require(func, V::Phase::INITIALIZATION_MODE.bit()) {
            return s;
        }
        match self.core.exit_initialization() {
            Ok(()) => {
                self.phase = V::after_initialization(self.kind, self.options);
                Status::Ok
            }
            Err(msg) => self.error(func, msg),
        }
    }

    /// A call `func` that only moves the state machine to `to`, from the states of `mask`, on
    /// an instance of `interface` (if the function belongs to one).
    pub fn move_to(
        &mut self,
        func: &str,
        interface: Option<InstanceKind>,
        mask: Mask,
        to: V::Phase,
    ) -> Status {
        self.trace(|| func.into());
        let checked = match interface {
            Some(kind) => self.require_of(func, kind, mask),
            None => self.require(func, mask),
        };
        if let Err(s) = checked {
            return s;
        }
        self.phase = to;
        Status::Ok
    }

    /// `fmiXTerminate`; a second call is an error.
    pub fn terminate(&mut self) -> Status {
        let (mask, to) = (V::MASKS.terminate, V::Phase::TERMINATED);
        self.move_to(V::NAMES.terminate, None, mask, to)
    }

    /// `fmiXReset`: back to the instantiated state with the start values, by creating the
    /// core anew from the same resources.
    pub fn reset(&mut self) -> Status {
        let func = V::NAMES.reset;
        self.trace(|| func.into());
        let built = match build::<V, M>(self.kind, self.resource_dir.as_deref()) {
            Ok(b) => b,
            Err(e) => {
                self.phase = V::Phase::ERROR;
                return self.error(func, format_args!("cannot create the model again: {e}"));
            }
        };
        if built.token != self.token {
            self.phase = V::Phase::ERROR;
            let msg = fill(V::WORDING.token_changed, [&built.token, &self.token]);
            return self.error(func, format_args!("the resources changed: {msg}"));
        }
        self.core = built.core;
        self.variables = built.variables;
        self.experiment = None;
        self.phase = V::Phase::INSTANTIATED;
        Status::Ok
    }

    /// The variable with value reference `vr`.
    pub fn find(&self, vr: u32) -> Option<&Variable> {
        values::find(&self.variables, vr)
    }

    /// Checks that `func`, a getter or setter allowed in the states of `mask`, is called in
    /// one of them with `n_values` values for `n_refs` scalar references (FMI 3.0 section
    /// 2.3.3: `nValues` counts the elements of all variables; every variable here is a scalar;
    /// FMI 2.0 has one count for both).
    fn check_values(
        &self,
        func: &str,
        mask: Mask,
        (n_refs, n_values): (usize, usize),
    ) -> Result<(), Status> {
        self.require(func, mask)?;
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

    /// `fmi2GetReal` / `fmi3GetFloat64`.
    pub fn get_values(&mut self, vrs: &[u32], values: &mut [f64]) -> Status {
        let func = V::NAMES.get_values;
        let sizes = (vrs.len(), values.len());
        if let Err(s) = self.check_values(func, V::MASKS.get_values, sizes) {
            return s;
        }
        let result = values::get(&mut self.core, &self.variables, vrs, values);
        self.reported(func, result)
    }

    /// `fmi2SetReal` / `fmi3SetFloat64`. All references are checked before any value is set;
    /// values are then set in order, and a value the core rejects stops there.
    pub fn set_values(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        let func = V::NAMES.set_values;
        let sizes = (vrs.len(), values.len());
        if let Err(s) = self.check_values(func, V::MASKS.set_values, sizes) {
            return s;
        }
        let logger = &self.logger;
        let trace = |name: &str, value: f64| {
            if logger.debug_enabled() {
                logger.log(Status::Ok, &format!("{func}: {name} = {value:?}"));
            }
        };
        let rule = (self.phase.set_rule(), self.phase.name());
        let result = values::set(&mut self.core, &self.variables, rule, (vrs, values), trace);
        self.reported(func, result)
    }

    /// The getters and setters of the types (`type_name`, of function `func`) this FMU has no
    /// variables of: any value reference is unknown for them.
    pub fn no_variables_of_type(
        &self,
        func: &str,
        type_name: &str,
        setter: bool,
        vrs: &[u32],
    ) -> Status {
        let mask = if setter {
            V::MASKS.set_values
        } else {
            V::MASKS.get_values
        };
        if let Err(s) = self.require(func, mask) {
            return s;
        }
        let real_type = V::NAMES.value_type;
        match values::no_variables_of_type(&self.variables, type_name, real_type, vrs) {
            None => Status::Ok,
            Some(msg) => self.error(func, msg),
        }
    }

    /// The status of a call of `func` that can only fail with a message: an error then.
    pub fn reported(&self, func: &str, result: Result<(), String>) -> Status {
        match result {
            Ok(()) => Status::Ok,
            Err(msg) => self.error(func, msg),
        }
    }

    /// Runs a core call of `func` that can only fail with a message; an error then.
    pub fn core_call(
        &mut self,
        func: &str,
        f: impl FnOnce(&mut M) -> Result<(), String>,
    ) -> Status {
        let result = f(&mut self.core);
        self.reported(func, result)
    }

    /// The number of continuous states.
    pub fn number_of_states(&self) -> usize {
        self.structure.derivatives.len()
    }

    /// Whether `vr` may be an unknown of a directional derivative: a state derivative or an
    /// output.
    pub fn is_unknown(&self, vr: u32) -> bool {
        let s = &self.structure;
        s.derivatives.iter().any(|d| d.derivative == vr) || s.outputs.iter().any(|o| o.output == vr)
    }

    /// Whether `vr` is a continuous state.
    pub fn is_state(&self, vr: u32) -> bool {
        self.structure.derivatives.iter().any(|d| d.state == vr)
    }

    /// Logs a caught panic of `func` and puts the instance into the error state, where only
    /// reset, setting an FMU state, freeing, the getters (for debugging) and the FMU-state
    /// functions are allowed.
    pub fn panicked(&mut self, func: &str, message: &str) -> Status {
        self.phase = V::Phase::ERROR;
        let n = &V::NAMES;
        self.error(func, format_args!("internal error (panic: {message}); the instance is now in the error state: call {}, {} or {}", n.reset, n.set_fmu_state, n.free_instance))
    }

    /// The instance's FMU state now.
    pub fn snapshot(&self) -> Snapshot<M, V::Phase> {
        self.trace(|| {
            format!(
                "{} at t = {:?} in state {}",
                V::NAMES.get_fmu_state,
                self.core.time(),
                self.phase.name()
            )
        });
        Snapshot {
            token: self.token.clone(),
            kind: self.kind,
            phase: self.phase,
            experiment: self.experiment,
            core: self.core.clone(),
        }
    }

    /// Goes back to `state`, which must come from an instance of the same token and kind.
    pub fn restore(&mut self, state: &Snapshot<M, V::Phase>) -> Status {
        let func = V::NAMES.set_fmu_state;
        if state.token != self.token {
            let msg = fill(V::WORDING.foreign_state, [&state.token, &self.token]);
            return self.error(func, msg);
        }
        if state.kind != self.kind {
            return self.error(
                func,
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
                "{func}: back at t = {:?} in state {}",
                self.core.time(),
                self.phase.name()
            )
        });
        Status::Ok
    }

    /// A state from serialized bytes, or the logged error's status.
    pub fn deserialize(&self, bytes: &[u8]) -> Result<Snapshot<M, V::Phase>, Status> {
        V::from_bytes(bytes, &self.token, self.kind, &self.core)
            .map_err(|e| self.error(V::NAMES.deserialize_fmu_state, e))
    }
}
