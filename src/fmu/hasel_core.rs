//! The HaselPlatform model core: the mapping of FMI calls onto the model, parameters until
//! initialization ends, then a running simulation (Co-Simulation) or the importer's time and
//! states (Model Exchange). The generic FMI shell does every check of the standard around it;
//! the variable table says what each value reference is. One core for each FMU of the platform:
//! the full model's (HaselPlatform) and the slow model's (HaselPlatformReduced), told apart by
//! their [`FmuModel`].

use std::marker::PhantomData;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::structure::model_structure;
use super::variables::{Slot, rows_of, variables};
use super::{FmuModel, RESOURCE_PARAMS};
use crate::fmi_common::model_api::{FmuCore, InstanceKind, ModelStructure};
use crate::fmi_common::variables::{ModelInfo, Variable};
use crate::io::params_file;
use crate::model::params::{ParamDef, parameters};
use crate::model::platform::BlockState;
use crate::model::{Params, Platform, Reduction};
use crate::simulation::{DEFAULT_RTOL, Simulator, Snapshot, check_rtol};

/// Reads the packed start values from `resources/parameters.toml`, if the FMU has one.
pub fn resource_params(resource_dir: Option<&Path>) -> Result<Params, String> {
    match resource_dir
        .map(|d| d.join(RESOURCE_PARAMS))
        .filter(|p| p.exists())
    {
        Some(path) => params_file::read(&path).map_err(|e| e.to_string()),
        None => Ok(Params::default()),
    }
}

/// The parameters as a serialized state holds them: the values in table order.
pub fn saved_params(params: &Params) -> Vec<f64> {
    parameters().map(|d| (d.get)(params)).collect()
}

/// The parameters back from [`saved_params`], each validated.
pub fn restored_params(values: &[f64]) -> Result<Params, String> {
    let defs: Vec<&ParamDef> = parameters().collect();
    if values.len() != defs.len() {
        return Err(format!(
            "state holds {} parameters, this FMU has {}",
            values.len(),
            defs.len()
        ));
    }
    let mut params = Params::default();
    for (d, v) in defs.iter().zip(values) {
        params.set_param(d, *v).map_err(|e| format!("state: {e}"))?;
    }
    Ok(params)
}

/// The core of the FMU of the model `K`: parameters until initialization ends, then a run.
#[derive(Clone, Debug)]
pub struct PlatformCore<K: FmuModel> {
    model: PhantomData<K>,
    kind: InstanceKind,
    params: Params,
    rtol: f64,
    /// The importer's tolerance for the experiment (`fmi2SetupExperiment`,
    /// `fmi3EnterInitializationMode`), which takes precedence over `rtol`.
    tolerance: Option<f64>,
    u: [f64; 3],
    t_start: f64,
    run: Option<Run>,
    /// The outputs (h1, h2, h3, tip) at a Co-Simulation run's current state, computed on the
    /// first read after a step: an importer reads them one by one, and each tip coordinate
    /// needs all three heights.
    outputs: Option<[f64; 6]>,
}

/// The model after initialization.
#[derive(Clone, Debug)]
enum Run {
    /// Co-Simulation: the core integrates.
    Steps(Box<Simulator>),
    /// Model Exchange: the importer's time and states, `x` in the model's layout.
    Importer {
        model: Box<Platform>,
        t: f64,
        x: Vec<f64>,
    },
}

/// The serialized dynamic state.
#[derive(Serialize, Deserialize)]
struct State {
    model_exchange: bool,
    params: Vec<f64>,
    rtol: f64,
    tolerance: Option<f64>,
    u: [f64; 3],
    t_start: f64,
    run: Option<SavedRun>,
}

#[derive(Serialize, Deserialize)]
enum SavedRun {
    Steps(Box<Snapshot>),
    Importer { t: f64, x: Vec<f64> },
}

/// The continuous states in the order of the state vector: the table's state variables of the
/// model `reduction`, in value-reference order ([`model_structure`]).
fn table_states(reduction: Reduction) -> impl Iterator<Item = (usize, BlockState)> {
    rows_of(reduction).iter().filter_map(|r| match r.slot {
        Slot::State { actuator, state } => Some((actuator, state)),
        _ => None,
    })
}

/// An unknown of a directional derivative, resolved to the model's layout: the row of a state
/// derivative (`None` for an effect that is off: it never moves) or an output's index in
/// [`Platform::outputs`].
#[derive(Clone, Copy)]
enum Unknown {
    Derivative(Option<usize>),
    Output(usize),
}

/// A known of a directional derivative: the column of a state (`None` for an effect that is
/// off: it moves nothing) or the index of a command U_j.
#[derive(Clone, Copy)]
enum Known {
    State(Option<usize>),
    Input(usize),
}

/// The analytic Jacobians at one point, each computed on first use: A = ∂f/∂x, B = ∂f/∂U,
/// C = ∂y/∂x (column-major, the model's layout) and D = ∂y/∂U.
struct Jacobians<'m> {
    model: &'m Platform,
    x: &'m [f64],
    u: [f64; 3],
    a: Option<Vec<f64>>,
    b: Option<Vec<f64>>,
    c: Option<Vec<f64>>,
}

impl<'m> Jacobians<'m> {
    fn at(model: &'m Platform, x: &'m [f64], u: [f64; 3]) -> Self {
        Jacobians {
            model,
            x,
            u,
            a: None,
            b: None,
            c: None,
        }
    }

    fn unknown(&self, vr: u32) -> Result<Unknown, String> {
        let row = &rows_of(self.model.reduction())[vr as usize];
        match row.slot {
            Slot::Derivative { actuator, state } => Ok(Unknown::Derivative(
                self.model.state_position(actuator, state),
            )),
            Slot::Height(i) => Ok(Unknown::Output(i)),
            Slot::Tip(i) => Ok(Unknown::Output(3 + i)),
            _ => Err(format!(
                "{} is neither a state derivative nor an output",
                row.name
            )),
        }
    }

    fn known(&self, vr: u32) -> Result<Known, String> {
        let row = &rows_of(self.model.reduction())[vr as usize];
        match row.slot {
            Slot::State { actuator, state } => {
                Ok(Known::State(self.model.state_position(actuator, state)))
            }
            Slot::Input(j) => Ok(Known::Input(j)),
            _ => Err(format!("{} is neither a state nor an input", row.name)),
        }
    }

    /// ∂unknown/∂known.
    fn partial(&mut self, unknown: Unknown, known: Known) -> Result<f64, String> {
        let (model, x, u) = (self.model, self.x, self.u);
        let n = model.n_states();
        let error = |e: crate::model::ModelError| e.to_string();
        Ok(match (unknown, known) {
            (Unknown::Derivative(Some(r)), Known::State(Some(c))) => {
                let a = match &mut self.a {
                    Some(a) => a,
                    none => {
                        let mut a = vec![0.0; n * n];
                        model.jacobian(x, u, &mut a).map_err(error)?;
                        none.insert(a)
                    }
                };
                a[c * n + r]
            }
            (Unknown::Derivative(Some(r)), Known::Input(j)) => {
                let b = match &mut self.b {
                    Some(b) => b,
                    none => {
                        let mut b = vec![0.0; n * 3];
                        model.input_jacobian(x, u, &mut b).map_err(error)?;
                        none.insert(b)
                    }
                };
                b[j * n + r]
            }
            (Unknown::Output(o), Known::State(Some(c))) => {
                let jac = self.c.get_or_insert_with(|| {
                    let mut jac = vec![0.0; 6 * n];
                    model.output_jacobian(x, &mut jac);
                    jac
                });
                jac[c * 6 + o]
            }
            (Unknown::Output(o), Known::Input(j)) => model.output_input_jacobian()[o][j],
            (Unknown::Derivative(None), _) | (_, Known::State(None)) => 0.0,
        })
    }
}

impl<K: FmuModel> PlatformCore<K> {
    /// The model at the parameters `params`.
    fn model(params: Params) -> Result<Platform, String> {
        Platform::reduced(params, K::REDUCTION).map_err(|e| e.to_string())
    }

    /// The model at the current parameters and its rest state: the initial state, and what
    /// outputs show in Initialization Mode.
    fn at_rest(&self) -> Result<(Platform, Vec<f64>), String> {
        let model = Self::model(self.params.clone())?;
        let x = model.rest_state().map_err(|e| e.to_string())?;
        Ok((model, x))
    }

    fn effective_rtol(&self) -> f64 {
        self.tolerance.unwrap_or(self.rtol)
    }

    /// `f` of the model and its current state (the rest state before initialization ends).
    fn evaluate<T>(
        &self,
        f: impl FnOnce(&Platform, &[f64]) -> Result<T, String>,
    ) -> Result<T, String> {
        match &self.run {
            Some(Run::Steps(sim)) => f(sim.model(), sim.state()),
            Some(Run::Importer { model, x, .. }) => f(model, x),
            None => {
                let (model, x) = self.at_rest()?;
                f(&model, &x)
            }
        }
    }

    /// The importer's states, Model Exchange after initialization only.
    fn importer_states(&mut self) -> Result<(&Platform, &mut f64, &mut Vec<f64>), String> {
        match &mut self.run {
            Some(Run::Importer { model, t, x }) => Ok((model, t, x)),
            _ => {
                Err("only a Model Exchange instance after initialization has its states set".into())
            }
        }
    }

    /// Output `k` of [`Platform::outputs`] of a Co-Simulation run, from the cache.
    fn stepped_output(&mut self, k: usize) -> Option<f64> {
        let Some(Run::Steps(sim)) = &self.run else {
            return None;
        };
        let outputs = self
            .outputs
            .get_or_insert_with(|| sim.model().outputs(sim.state()));
        Some(outputs[k])
    }

    fn value(&self, slot: Slot, model: &Platform, x: &[f64]) -> Result<f64, String> {
        let ok = |r: Result<f64, crate::model::ModelError>| r.map_err(|e| e.to_string());
        Ok(match slot {
            Slot::Input(i) => self.u[i],
            Slot::Height(i) => model.heights(x)[i],
            Slot::Tip(i) => model.tip(x)[i],
            Slot::Param(d) => (d.get)(&self.params),
            Slot::Rtol => self.rtol,
            Slot::State { actuator, state } => {
                model.state_position(actuator, state).map_or(0.0, |k| x[k])
            }
            Slot::Derivative { actuator, state } => match model.state_position(actuator, state) {
                Some(k) => {
                    let mut dx = vec![0.0; model.n_states()];
                    model.rhs(x, self.u, &mut dx).map_err(|e| e.to_string())?;
                    dx[k]
                }
                None => 0.0,
            },
            Slot::Energy => ok(model.energy(x))?,
            Slot::SuppliedPower => ok(model.supplied_power(x, self.u))?,
            Slot::DissipatedPower => ok(model.dissipated_power_at(x, self.u))?,
        })
    }
}

impl<K: FmuModel> FmuCore for PlatformCore<K> {
    fn model_info() -> ModelInfo {
        K::model_info()
    }

    fn model_structure() -> ModelStructure {
        model_structure(K::REDUCTION)
    }

    fn instantiate(kind: InstanceKind, resource_dir: Option<&Path>) -> Result<Self, String> {
        Ok(PlatformCore {
            model: PhantomData,
            kind,
            params: resource_params(resource_dir)?,
            rtol: DEFAULT_RTOL,
            tolerance: None,
            u: [0.0; 3],
            t_start: 0.0,
            run: None,
            outputs: None,
        })
    }

    fn variables(&self) -> Vec<Variable> {
        variables(K::REDUCTION, &self.params, self.rtol)
    }

    fn get_real(&mut self, vr: u32) -> Result<f64, String> {
        let row = &rows_of(K::REDUCTION)[vr as usize];
        match row.slot {
            Slot::Input(i) => return Ok(self.u[i]),
            Slot::Param(d) => return Ok((d.get)(&self.params)),
            Slot::Rtol => return Ok(self.rtol),
            Slot::Height(i) => {
                if let Some(h) = self.stepped_output(i) {
                    return Ok(h);
                }
            }
            Slot::Tip(i) => {
                if let Some(tip) = self.stepped_output(3 + i) {
                    return Ok(tip);
                }
            }
            _ => {}
        }
        self.evaluate(|model, x| self.value(row.slot, model, x))
    }

    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), String> {
        let row = &rows_of(K::REDUCTION)[vr as usize];
        match row.slot {
            Slot::Input(i) => {
                if !value.is_finite() {
                    return Err(format!("{} = {value}: a voltage must be finite", row.name));
                }
                self.u[i] = value;
            }
            Slot::Param(d) => self.params.set_param(d, value).map_err(|e| e.to_string())?,
            Slot::Rtol => {
                check_rtol("rtol", value).map_err(|e| e.to_string())?;
                self.rtol = value;
            }
            _ => {
                return Err(format!(
                    "{} is computed by the model and cannot be set",
                    row.name
                ));
            }
        }
        Ok(())
    }

    fn enter_initialization(
        &mut self,
        start_time: f64,
        _stop: Option<f64>,
        tolerance: Option<f64>,
    ) -> Result<(), String> {
        if let Some(tol) = tolerance {
            check_rtol("tolerance", tol).map_err(|e| e.to_string())?;
        }
        self.t_start = start_time;
        self.tolerance = tolerance;
        Ok(())
    }

    fn exit_initialization(&mut self) -> Result<(), String> {
        let (model, x) = self.at_rest()?;
        self.outputs = None;
        self.run = Some(match self.kind {
            InstanceKind::CoSimulation => Run::Steps(Box::new(
                Simulator::from_state(model, self.t_start, &x, self.effective_rtol())
                    .map_err(|e| e.to_string())?,
            )),
            InstanceKind::ModelExchange => {
                let tau_d = model.params().effects.delay.tau_d;
                if tau_d > 0.0 {
                    return Err(format!(
                        "the transport delay (tau_d = {tau_d:e} s) cannot run in Model Exchange: \
                         it needs the history of the command, which only the FMU's own \
                         integrator keeps; use Co-Simulation, or set tau_d = 0"
                    ));
                }
                Run::Importer {
                    model: Box::new(model),
                    t: self.t_start,
                    x,
                }
            }
        });
        Ok(())
    }

    fn do_step(&mut self, step: f64) -> Result<(), String> {
        let Some(Run::Steps(sim)) = self.run.as_mut() else {
            return Err("the simulation has not been initialized for Co-Simulation".into());
        };
        self.outputs = None;
        let t_end = sim.t() + step;
        sim.step_held(self.u, t_end).map_err(|e| e.to_string())
    }

    fn time(&self) -> f64 {
        match &self.run {
            Some(Run::Steps(sim)) => sim.t(),
            Some(Run::Importer { t, .. }) => *t,
            None => self.t_start,
        }
    }

    fn set_time(&mut self, time: f64) -> Result<(), String> {
        *self.importer_states()?.1 = time;
        Ok(())
    }

    fn continuous_states(&mut self, out: &mut [f64]) -> Result<(), String> {
        self.evaluate(|model, x| {
            for (v, (actuator, state)) in out.iter_mut().zip(table_states(K::REDUCTION)) {
                *v = model.state_position(actuator, state).map_or(0.0, |k| x[k]);
            }
            Ok(())
        })
    }

    fn set_continuous_states(&mut self, values: &[f64]) -> Result<(), String> {
        if let Some((v, k)) = values.iter().zip(0..).find(|(v, _)| !v.is_finite()) {
            let name = &rows_of(K::REDUCTION)
                [model_structure(K::REDUCTION).derivatives[k].state as usize]
                .name;
            return Err(format!("state {name} = {v}: must be finite"));
        }
        let (model, _, x) = self.importer_states()?;
        for (&v, (actuator, state)) in values.iter().zip(table_states(K::REDUCTION)) {
            // an effect that is off keeps its state at 0
            if let Some(k) = model.state_position(actuator, state) {
                x[k] = v;
            }
        }
        Ok(())
    }

    fn derivatives(&mut self, out: &mut [f64]) -> Result<(), String> {
        let u = self.u;
        self.evaluate(|model, x| {
            let mut dx = vec![0.0; model.n_states()];
            model.rhs(x, u, &mut dx).map_err(|e| e.to_string())?;
            for (v, (actuator, state)) in out.iter_mut().zip(table_states(K::REDUCTION)) {
                *v = model.state_position(actuator, state).map_or(0.0, |k| dx[k]);
            }
            Ok(())
        })
    }

    /// The model's state scales; 1 for the state of an effect that is off (it stays 0).
    fn nominals(&self, out: &mut [f64]) -> Result<(), String> {
        let model = Self::model(self.params.clone())?;
        let scales = model.state_scales();
        for (v, (actuator, state)) in out.iter_mut().zip(table_states(K::REDUCTION)) {
            *v = model
                .state_position(actuator, state)
                .map_or(1.0, |k| scales[k]);
        }
        Ok(())
    }

    fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        result: &mut [f64],
    ) -> Result<(), String> {
        let u = self.u;
        self.evaluate(|model, x| {
            let mut jac = Jacobians::at(model, x, u);
            let rows: Vec<Unknown> = unknowns
                .iter()
                .map(|&vr| jac.unknown(vr))
                .collect::<Result<_, _>>()?;
            let mut columns = Vec::with_capacity(knowns.len());
            for (&vr, &s) in knowns.iter().zip(seed) {
                let known = jac.known(vr)?;
                if s != 0.0 {
                    columns.push((known, s));
                }
            }
            for (r, &unknown) in result.iter_mut().zip(&rows) {
                *r = 0.0;
                for &(known, s) in &columns {
                    *r += jac.partial(unknown, known)? * s;
                }
            }
            Ok(())
        })
    }

    fn serialize_state(&self) -> Vec<u8> {
        let state = State {
            model_exchange: self.kind == InstanceKind::ModelExchange,
            params: saved_params(&self.params),
            rtol: self.rtol,
            tolerance: self.tolerance,
            u: self.u,
            t_start: self.t_start,
            run: self.run.as_ref().map(|run| match run {
                Run::Steps(sim) => SavedRun::Steps(Box::new(sim.snapshot())),
                Run::Importer { t, x, .. } => SavedRun::Importer {
                    t: *t,
                    x: x.clone(),
                },
            }),
        };
        postcard::to_stdvec(&state).expect("serializing to memory cannot fail")
    }

    fn deserialize_state(&self, bytes: &[u8]) -> Result<Self, String> {
        let state: State =
            postcard::from_bytes(bytes).map_err(|e| format!("not a HaselPlatform state: {e}"))?;
        let kind = if state.model_exchange {
            InstanceKind::ModelExchange
        } else {
            InstanceKind::CoSimulation
        };
        if kind != self.kind {
            return Err(format!(
                "the state is of a {kind:?} instance, this one is {:?}",
                self.kind
            ));
        }
        let params = restored_params(&state.params)?;
        let run = match state.run {
            Some(saved) => {
                let model = Self::model(params.clone()).map_err(|e| format!("state: {e}"))?;
                Some(match saved {
                    SavedRun::Steps(snapshot) => Run::Steps(Box::new(
                        Simulator::from_snapshot(model, *snapshot)
                            .map_err(|e| format!("state: {e}"))?,
                    )),
                    SavedRun::Importer { t, x } => {
                        if x.len() != model.n_states() {
                            return Err(format!(
                                "state: {} states, the model has {}",
                                x.len(),
                                model.n_states()
                            ));
                        }
                        Run::Importer {
                            model: Box::new(model),
                            t,
                            x,
                        }
                    }
                })
            }
            None => None,
        };
        Ok(PlatformCore {
            model: PhantomData,
            kind,
            params,
            rtol: state.rtol,
            tolerance: state.tolerance,
            u: state.u,
            t_start: state.t_start,
            run,
            outputs: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmu::variables::rows;
    use crate::fmu::{FullModel, HaselCore, HaselReducedCore, SlowModel};

    /// The value reference of the variable `name` in the FMU of the model `K`.
    fn vr_in<K: FmuModel>(name: &str) -> u32 {
        rows_of(K::REDUCTION)
            .iter()
            .position(|r| r.name == name)
            .unwrap() as u32
    }

    /// The value reference of the variable `name` in HaselPlatform.
    fn vr(name: &str) -> u32 {
        vr_in::<FullModel>(name)
    }

    /// The effects with states on (with their second stages and the hysteresis' relaxation,
    /// when `other_forms`), and the coupling that links the actuators.
    fn effects_on<K: FmuModel>(core: &mut PlatformCore<K>, other_forms: bool) {
        let effects = [
            ("R3", 2e4),
            ("tau3", 0.5),
            ("k_v", 0.05),
            ("tau_v", 0.3),
            ("k_h", 0.04),
            ("theta_h", 2e-3),
            ("tau_a", 0.02),
            ("k_c", 40.0),
            ("k3", 30.0),
        ];
        for (name, value) in effects {
            core.set_real(vr(name), value).unwrap();
        }
        if other_forms {
            for (name, value) in [
                ("tau_a2", 0.005),
                ("k_v_1s", 0.02),
                ("r_h", 2.0),
                ("k_h_2mrad", 0.02),
                ("C3_300ms", 1e-9),
                ("R3_1s", 1e4),
            ] {
                core.set_real(vr(name), value).unwrap();
            }
        }
    }

    /// A core of `kind` past initialization.
    fn started(kind: InstanceKind, effects: bool) -> HaselCore {
        started_as(kind, effects)
    }

    fn started_as<K: FmuModel>(kind: InstanceKind, effects: bool) -> PlatformCore<K> {
        let mut core = PlatformCore::<K>::instantiate(kind, None).unwrap();
        if effects {
            effects_on(&mut core, false);
        }
        core.enter_initialization(0.0, None, None).unwrap();
        core.exit_initialization().unwrap();
        core
    }

    fn n_states() -> usize {
        model_structure(Reduction::Full).derivatives.len()
    }

    /// A Co-Simulation core in motion, 0.5 ms after the commands changed, and its states
    /// (in motion: the hysteresis has a kink where θ̇ = 0).
    fn simulated(effects: bool) -> (HaselCore, Vec<f64>) {
        simulated_as(effects)
    }

    fn simulated_as<K: FmuModel>(effects: bool) -> (PlatformCore<K>, Vec<f64>) {
        let mut core = started_as::<K>(InstanceKind::CoSimulation, effects);
        for (k, name) in ["U1", "U2", "U3"].iter().enumerate() {
            core.set_real(vr(name), 30.0 + 10.0 * k as f64).unwrap();
        }
        core.do_step(0.01).unwrap();
        for (name, u) in [("U1", 45.0), ("U2", -20.0), ("U3", 10.0)] {
            core.set_real(vr(name), u).unwrap();
        }
        core.do_step(5e-4).unwrap();
        let mut x = vec![0.0; model_structure(K::REDUCTION).derivatives.len()];
        core.continuous_states(&mut x).unwrap();
        (core, x)
    }

    #[test]
    fn state_variables_read_the_model_state_of_their_name() {
        let mut core = HaselCore::instantiate(InstanceKind::CoSimulation, None).unwrap();
        effects_on(&mut core, true);
        core.set_real(vr("U2"), 80.0).unwrap();
        core.enter_initialization(0.0, None, None).unwrap();
        core.exit_initialization().unwrap();
        core.do_step(0.01).unwrap();
        let Some(Run::Steps(sim)) = core.run.clone() else {
            panic!("a Co-Simulation run")
        };
        let mut states = 0;
        for (k, row) in rows().iter().enumerate() {
            if let Slot::State { .. } = row.slot {
                let x = sim.model().state_index(&row.name).map(|i| sim.state()[i]);
                let got = core.get_real(k as u32).unwrap();
                assert_eq!(Some(got), x, "{}", row.name);
                states += 1;
            }
        }
        assert_eq!(states, 3 * 33);
    }

    #[test]
    fn states_of_effects_that_are_off_read_zero() {
        let mut core = HaselCore::instantiate(InstanceKind::CoSimulation, None).unwrap();
        core.enter_initialization(0.0, None, None).unwrap();
        for name in ["Q3_1", "z_v_2", "z_h_3", "U_amp_1"] {
            assert_eq!(core.get_real(vr(name)), Ok(0.0), "{name}");
        }
        assert_ne!(core.get_real(vr("theta_1")), Ok(0.0), "the rest angle");
    }

    #[test]
    fn the_state_vector_is_the_table_states_with_their_derivatives() {
        let structure = model_structure(Reduction::Full);
        assert_eq!(structure.derivatives.len(), 3 * 33);
        for d in &structure.derivatives {
            let (state, der) = (&rows()[d.state as usize], &rows()[d.derivative as usize]);
            assert_eq!(der.name, format!("der({})", state.name));
        }
        // ME and CS agree: the same states give the same derivatives as the variables
        let (mut cs, x) = simulated(true);
        let mut me = started(InstanceKind::ModelExchange, true);
        me.u = cs.u;
        me.set_continuous_states(&x).unwrap();
        let mut back = vec![0.0; x.len()];
        me.continuous_states(&mut back).unwrap();
        assert_eq!(back, x);
        let (mut dx_me, mut dx_cs) = (vec![0.0; x.len()], vec![0.0; x.len()]);
        me.derivatives(&mut dx_me).unwrap();
        cs.derivatives(&mut dx_cs).unwrap();
        assert_eq!(dx_me, dx_cs);
        for (d, v) in structure.derivatives.iter().zip(&dx_me) {
            assert_eq!(me.get_real(d.derivative), Ok(*v));
        }
        for name in ["h1", "tip_z"] {
            assert_eq!(me.get_real(vr(name)), cs.get_real(vr(name)), "{name}");
        }
    }

    #[test]
    fn an_effect_that_is_off_keeps_its_state_at_zero() {
        let mut me = started(InstanceKind::ModelExchange, false);
        let mut x = vec![0.0; n_states()];
        me.continuous_states(&mut x).unwrap();
        let k = model_structure(Reduction::Full)
            .derivatives
            .iter()
            .position(|d| d.state == vr("Q3_2"))
            .unwrap();
        x[k] = 1e-9;
        me.set_continuous_states(&x).unwrap();
        let (mut back, mut dx) = (vec![0.0; x.len()], vec![0.0; x.len()]);
        me.continuous_states(&mut back).unwrap();
        me.derivatives(&mut dx).unwrap();
        assert_eq!((back[k], dx[k]), (0.0, 0.0));
    }

    #[test]
    fn nominals_are_the_model_scales() {
        let me = started(InstanceKind::ModelExchange, false);
        let mut nominal = vec![0.0; n_states()];
        me.nominals(&mut nominal).unwrap();
        let at = |name: &str| {
            let k = model_structure(Reduction::Full)
                .derivatives
                .iter()
                .position(|d| d.state == vr(name));
            nominal[k.unwrap()]
        };
        assert!((1e-3..1e-1).contains(&at("theta_1")), "{}", at("theta_1"));
        assert!((1e-11..1e-7).contains(&at("Q2_3")), "{}", at("Q2_3"));
        assert_eq!(at("z_h_2"), 1.0, "an effect that is off");
    }

    #[test]
    fn model_exchange_refuses_the_transport_delay_at_initialization() {
        let mut me = HaselCore::instantiate(InstanceKind::ModelExchange, None).unwrap();
        me.set_real(vr("tau_d"), 1e-3).unwrap();
        me.enter_initialization(0.0, None, None).unwrap();
        let e = me.exit_initialization().unwrap_err();
        assert!(e.contains("tau_d") && e.contains("history"), "{e}");
        let mut cs = HaselCore::instantiate(InstanceKind::CoSimulation, None).unwrap();
        cs.set_real(vr("tau_d"), 1e-3).unwrap();
        cs.enter_initialization(0.0, None, None).unwrap();
        cs.exit_initialization().unwrap();
    }

    #[test]
    fn model_exchange_states_survive_serialization() {
        let (_, x) = simulated(true);
        let mut me = started(InstanceKind::ModelExchange, true);
        me.set_continuous_states(&x).unwrap();
        me.set_time(0.02).unwrap();
        let restored = me.deserialize_state(&me.serialize_state()).unwrap();
        let mut back = restored.clone();
        let mut y = vec![0.0; x.len()];
        back.continuous_states(&mut y).unwrap();
        assert_eq!((y, back.time()), (x, 0.02));
        let cs = HaselCore::instantiate(InstanceKind::CoSimulation, None).unwrap();
        assert!(cs.deserialize_state(&me.serialize_state()).is_err());
    }

    /// Every column of the directional derivatives of all state derivatives and outputs
    /// against central differences of the derivatives and outputs, each row relative to its
    /// scale: the state's nominal per second for a derivative, 1 µm for an output.
    /// `nonzero` columns must be nonzero (the others are the states of effects that are off).
    fn check_directional_derivatives<K: FmuModel>(core: &mut PlatformCore<K>, nonzero: usize) {
        let structure = model_structure(K::REDUCTION);
        let outputs: Vec<u32> = structure.outputs.iter().map(|o| o.output).collect();
        let unknowns: Vec<u32> = structure
            .derivatives
            .iter()
            .map(|d| d.derivative)
            .chain(outputs.iter().copied())
            .collect();
        let n = structure.derivatives.len();
        let mut nominal = vec![0.0; n];
        core.nominals(&mut nominal).unwrap();
        let row_scale: Vec<f64> = nominal.iter().copied().chain([1e-6; 6]).collect();
        let inputs = [vr("U1"), vr("U2"), vr("U3")];
        let knowns: Vec<(u32, f64)> = structure
            .derivatives
            .iter()
            .zip(&nominal)
            .map(|(d, &s)| (d.state, s))
            .chain(inputs.iter().map(|&u| (u, 1.0)))
            .collect();
        let mut x = vec![0.0; n];
        core.continuous_states(&mut x).unwrap();
        // the derivatives and outputs at the states and inputs moved along `known` by `h`
        let evaluate = |core: &mut PlatformCore<K>, known: usize, h: f64| -> Vec<f64> {
            let mut c = core.clone();
            if let Some(Run::Steps(sim)) = &core.run {
                // a Co-Simulation core is moved through its Model Exchange twin
                c.run = Some(Run::Importer {
                    model: Box::new(sim.model().clone()),
                    t: sim.t(),
                    x: sim.state().to_vec(),
                });
            }
            if known < n {
                let mut xh = x.clone();
                xh[known] += h;
                c.set_continuous_states(&xh).unwrap();
            } else {
                let u = knowns[known].0;
                let v = c.get_real(u).unwrap();
                c.set_real(u, v + h).unwrap();
            }
            let mut f = vec![0.0; n];
            c.derivatives(&mut f).unwrap();
            f.extend(outputs.iter().map(|&o| c.get_real(o).unwrap()));
            f
        };
        let mut checked = 0;
        for (j, &(known, scale)) in knowns.iter().enumerate() {
            let mut dd = vec![0.0; unknowns.len()];
            core.directional_derivative(&unknowns, &[known], &[1.0], &mut dd)
                .unwrap();
            // within a hundredth of the state itself: the hysteresis has kinks at θ̇ = 0, z = 0
            let at = if j < n { x[j].abs() } else { 0.0 };
            let h = if at > 0.0 {
                (1e-6 * scale).min(1e-2 * at)
            } else {
                1e-6 * scale
            };
            let (fp, fm) = (evaluate(core, j, h), evaluate(core, j, -h));
            let fd: Vec<f64> = fp
                .iter()
                .zip(&fm)
                .map(|(p, m)| (p - m) / (2.0 * h))
                .collect();
            let size = dd
                .iter()
                .zip(&row_scale)
                .map(|(d, s)| (d * scale / s).abs())
                .fold(0.0, f64::max);
            for (r, ((a, f), s)) in dd.iter().zip(&fd).zip(&row_scale).enumerate() {
                let name = &rows_of(K::REDUCTION)[unknowns[r] as usize].name;
                let known_name = &rows_of(K::REDUCTION)[known as usize].name;
                assert!(
                    ((a - f) * scale / s).abs() <= 1e-6 * size,
                    "d {name} / d {known_name}: analytic {a:e}, central differences {f:e}"
                );
            }
            checked += usize::from(size > 0.0);
        }
        assert_eq!(checked, nonzero, "nonzero columns");
    }

    #[test]
    fn directional_derivatives_match_central_differences_at_a_simulated_state() {
        // 15 states and 3 inputs; with the effects, 27 states
        for (effects, nonzero) in [(false, 18), (true, 30)] {
            let (mut cs, x) = simulated(effects);
            check_directional_derivatives(&mut cs, nonzero);
            let mut me = started(InstanceKind::ModelExchange, effects);
            me.u = cs.u;
            me.set_continuous_states(&x).unwrap();
            check_directional_derivatives(&mut me, nonzero);
        }
    }

    /// HaselPlatformReduced: one angle per actuator (and the effects' states) whose derivatives
    /// are the slow model's, the same in Model Exchange as in Co-Simulation, and directional
    /// derivatives that match central differences.
    #[test]
    fn the_reduced_core_runs_the_slow_model() {
        let structure = model_structure(Reduction::Slow);
        // the full FMU's states but l_p, p, Q1 and Q2 of each actuator
        let full = model_structure(Reduction::Full).derivatives.len();
        assert_eq!(structure.derivatives.len(), full - 3 * 4);
        let theta_1 = vr_in::<SlowModel>("theta_1");
        assert_eq!(structure.derivatives[0].state, theta_1);
        // 3 angles and 3 inputs; with the effects, their 12 states too
        for (effects, nonzero) in [(false, 6), (true, 18)] {
            let (mut cs, x) = simulated_as::<SlowModel>(effects);
            let Some(Run::Steps(sim)) = cs.run.clone() else {
                panic!("a Co-Simulation run")
            };
            assert_eq!(sim.model().reduction(), Reduction::Slow);
            let mut me: HaselReducedCore = started_as(InstanceKind::ModelExchange, effects);
            me.u = cs.u;
            me.set_continuous_states(&x).unwrap();
            let (mut dx_me, mut dx_cs) = (vec![0.0; x.len()], vec![0.0; x.len()]);
            me.derivatives(&mut dx_me).unwrap();
            cs.derivatives(&mut dx_cs).unwrap();
            assert_eq!(dx_me, dx_cs);
            let mut f = vec![0.0; sim.model().n_states()];
            sim.model().rhs(sim.state(), cs.u, &mut f).unwrap();
            assert_eq!(dx_cs[0], f[0], "der(theta_1)");
            check_directional_derivatives(&mut cs, nonzero);
            check_directional_derivatives(&mut me, nonzero);
        }
    }

    #[test]
    fn directional_derivatives_combine_columns_linearly() {
        let (mut cs, _) = simulated(true);
        let unknowns = [vr("der(p_1)"), vr("der(Q1_2)"), vr("tip_x")];
        let knowns = [vr("theta_1"), vr("U2"), vr("theta_3")];
        let seed = [2.0, -0.5, 3.0];
        let mut both = [0.0; 3];
        cs.directional_derivative(&unknowns, &knowns, &seed, &mut both)
            .unwrap();
        let mut sum = [0.0; 3];
        for (k, s) in knowns.iter().zip(seed) {
            let mut one = [0.0; 3];
            cs.directional_derivative(&unknowns, &[*k], &[s], &mut one)
                .unwrap();
            for (t, o) in sum.iter_mut().zip(one) {
                *t += o;
            }
        }
        for (a, b) in both.iter().zip(sum) {
            assert!((a - b).abs() <= 1e-12 * a.abs().max(b.abs()), "{a} vs {b}");
        }
        let e = cs
            .directional_derivative(&[vr("h1")], &[vr("k_c")], &[1.0], &mut both[..1])
            .unwrap_err();
        assert!(e.contains("k_c"), "{e}");
    }

    #[test]
    fn the_structure_is_the_block_structure_with_the_coupling() {
        let structure = model_structure(Reduction::Full);
        let actuator_of = |vr: u32| match rows()[vr as usize].slot {
            Slot::State { actuator, .. } | Slot::Input(actuator) => actuator,
            ref other => panic!(
                "dependency on {}",
                rows()[vr as usize].name.clone() + &format!("{:?}", std::mem::discriminant(other))
            ),
        };
        for d in &structure.derivatives {
            let (own, name) = (actuator_of(d.state), &rows()[d.state as usize].name);
            assert!(
                d.dependencies.contains(&d.state) || name.starts_with("theta"),
                "{name}"
            );
            for &on in &d.dependencies {
                let on_name = &rows()[on as usize].name;
                // only the coupling's torque on p reaches across, through the angles
                assert!(
                    actuator_of(on) == own
                        || (name.starts_with("p_") && on_name.starts_with("theta_")),
                    "der({name}) depends on {on_name}"
                );
            }
        }
        let deps = |name: &str| {
            let d = structure
                .derivatives
                .iter()
                .find(|d| d.state == vr(name))
                .unwrap();
            d.dependencies
                .iter()
                .map(|&v| rows()[v as usize].name.as_str())
                .collect::<Vec<_>>()
        };
        assert_eq!(deps("theta_1"), ["p_1"]);
        assert!(deps("p_2").contains(&"theta_3"));
        assert!(deps("U_amp_3").contains(&"U3") && deps("Q1_3").contains(&"U3"));
        for o in &structure.outputs {
            let name = &rows()[o.output as usize].name;
            let on: Vec<&str> = o
                .dependencies
                .iter()
                .map(|&v| rows()[v as usize].name.as_str())
                .collect();
            match name.as_str() {
                "h2" => assert_eq!(on, ["theta_2"]),
                _ if name.starts_with("tip") => {
                    assert_eq!(on, ["theta_1", "theta_2", "theta_3"], "{name}")
                }
                _ => assert_eq!(on.len(), 1, "{name}"),
            }
        }
    }
}
