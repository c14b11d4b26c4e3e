//! The HaselPlatform FMU's per-model core: the variable table (the one source of truth for
//! `modelDescription.xml`, the value references and the variable documentation) and the mapping
//! of FMI calls onto a [`Simulator`]. The generic FMI 2.0 shell of [`crate::fmi2`] does every
//! check of the standard around it.

use std::path::Path;
use std::sync::OnceLock;

use serde::{Deserialize, Serialize};

use crate::fmi_common::model_api::FmuCore;
use crate::fmi_common::variables::{
    Causality, DefaultExperiment, Initial, ModelInfo, Variability, Variable,
};
use crate::io::params_file;
use crate::model::params::{ParamDef, parameters};
use crate::model::{Params, Platform};
use crate::simulation::{DEFAULT_RTOL, Simulator, Snapshot};

/// `modelIdentifier` and the shared library's name in `binaries/linux64/`.
pub const MODEL_IDENTIFIER: &str = "HaselPlatform";

/// The parameter file inside the FMU's `resources/` that `hasel fmu --params` packs; its values
/// are the parameters' start values.
pub const RESOURCE_PARAMS: &str = "parameters.toml";

/// What a value reference stands for.
#[derive(Clone, Copy)]
pub enum Slot {
    Input(usize),
    Height(usize),
    Tip(usize),
    Param(&'static ParamDef),
    Rtol,
    /// A state, looked up by the row's name (effect states read 0 while their effect is off).
    State,
    Energy,
    SuppliedPower,
    DissipatedPower,
}

/// One row of the variable table; its value reference is its index.
pub struct Row {
    pub name: String,
    pub slot: Slot,
    pub unit: &'static str,
    pub description: String,
}

const STATE_UNITS: [(&str, &str, &str); 9] = [
    ("theta", "rad", "Film rotation angle theta"),
    ("l_p", "m", "Top film length l_p"),
    (
        "p",
        "kg.m/s",
        "Angular momentum p = I dtheta/dt with the paper's I = Lv m/24 [kg.m]",
    ),
    ("Q1", "C", "Charge Q1 of the retention capacitor C1"),
    ("Q2", "C", "Charge Q2 of the electrode capacitor C2"),
    (
        "Q3",
        "C",
        "charge_drift: charge Q3 of the drift stage's capacitor C3 (0 while off)",
    ),
    (
        "z_v",
        "rad",
        "creep: internal angle z of the standard linear solid (0 while off)",
    ),
    ("z_h", "rad", "hysteresis: Bouc-Wen state z_h (0 while off)"),
    (
        "U_amp",
        "V",
        "amplifier_lag: amplifier output voltage (0 while off)",
    ),
];

/// The variable table, in value-reference order.
pub fn rows() -> &'static [Row] {
    static ROWS: OnceLock<Vec<Row>> = OnceLock::new();
    ROWS.get_or_init(|| {
        let mut rows = Vec::new();
        let mut add = |name: String, slot, unit, description: String| rows.push(Row { name, slot, unit, description });
        for i in 0..3 {
            add(format!("U{}", i + 1), Slot::Input(i), "V", format!("Voltage command of actuator {}, held over a communication step", i + 1));
        }
        for i in 0..3 {
            add(format!("h{}", i + 1), Slot::Height(i), "m", format!("Height of actuator {}: h = 1/2 Lv sin(theta)", i + 1));
        }
        for (i, axis) in ["x", "y", "z"].iter().enumerate() {
            add(format!("tip_{axis}"), Slot::Tip(i), "m", format!("Antenna tip {axis} from the forward kinematics"));
        }
        for d in parameters() {
            add(d.name.to_string(), Slot::Param(d), d.unit, d.description.to_string());
        }
        add("rtol".into(), Slot::Rtol, "1", "Relative tolerance of the internal Radau IIA solver (a tolerance given to fmi2SetupExperiment takes precedence)".into());
        for a in 0..3 {
            for (name, unit, desc) in STATE_UNITS {
                add(format!("{name}_{}", a + 1), Slot::State, unit, format!("{desc} of actuator {}", a + 1));
            }
        }
        add("H".into(), Slot::Energy, "J", "Stored energy (Hamiltonian) of the three actuators".into());
        add("P_supplied".into(), Slot::SuppliedPower, "W", "Power supplied through the electrical ports, sum of y_i U_i".into());
        add("P_dissipated".into(), Slot::DissipatedPower, "W", "Power dissipated in the resistors and the damping".into());
        rows
    })
}

/// The FMI variables with the start values of `params` and `rtol`.
pub fn variables(params: &Params, rtol: f64) -> Vec<Variable> {
    rows()
        .iter()
        .enumerate()
        .map(|(vr, row)| {
            let (causality, variability, initial, start) = match row.slot {
                Slot::Input(_) => (Causality::Input, Variability::Continuous, None, Some(0.0)),
                Slot::Height(_) | Slot::Tip(_) => (
                    Causality::Output,
                    Variability::Continuous,
                    Some(Initial::Calculated),
                    None,
                ),
                Slot::Param(d) => (
                    Causality::Parameter,
                    Variability::Fixed,
                    Some(Initial::Exact),
                    Some((d.get)(params)),
                ),
                Slot::Rtol => (
                    Causality::Parameter,
                    Variability::Fixed,
                    Some(Initial::Exact),
                    Some(rtol),
                ),
                Slot::State | Slot::Energy | Slot::SuppliedPower | Slot::DissipatedPower => (
                    Causality::Local,
                    Variability::Continuous,
                    Some(Initial::Calculated),
                    None,
                ),
            };
            Variable {
                name: row.name.clone(),
                value_reference: vr as u32,
                causality,
                variability,
                initial,
                unit: Some(row.unit.to_string()),
                description: row.description.clone(),
                start,
            }
        })
        .collect()
}

/// The model-level data of `modelDescription.xml`.
pub fn model_info() -> ModelInfo {
    ModelInfo {
        model_name: MODEL_IDENTIFIER.into(),
        model_identifier: MODEL_IDENTIFIER.into(),
        description: "3-DOF micro parallel platform (3PS) driven by three HASEL actuators, each a port-Hamiltonian system (Feregrino et al.); inputs U1..U3 [V], outputs actuator heights and antenna tip [m]".into(),
        author: "hasel-fmu".into(),
        version: env!("CARGO_PKG_VERSION").into(),
        generation_tool: concat!("hasel-fmu ", env!("CARGO_PKG_VERSION")).into(),
        default_experiment: DefaultExperiment { start_time: 0.0, stop_time: 10.0, step_size: 1e-3, tolerance: DEFAULT_RTOL },
        log_categories: vec![],
    }
}

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

/// The core: parameters until initialization ends, then a running simulation.
#[derive(Clone, Debug)]
pub struct HaselCore {
    params: Params,
    rtol: f64,
    /// Tolerance from fmi2SetupExperiment, which takes precedence over `rtol`.
    tolerance: Option<f64>,
    u: [f64; 3],
    t_start: f64,
    sim: Option<Simulator>,
}

/// The serialized dynamic state.
#[derive(Serialize, Deserialize)]
struct State {
    params: Vec<f64>,
    rtol: f64,
    tolerance: Option<f64>,
    u: [f64; 3],
    t_start: f64,
    sim: Option<Snapshot>,
}

impl HaselCore {
    /// A simulator at the start values, for outputs asked for in Initialization Mode.
    fn preview(&self) -> Result<Simulator, String> {
        let model = Platform::new(self.params.clone()).map_err(|e| e.to_string())?;
        Simulator::new(model, self.t_start, self.effective_rtol()).map_err(|e| e.to_string())
    }

    fn effective_rtol(&self) -> f64 {
        self.tolerance.unwrap_or(self.rtol)
    }

    fn value(&self, row: &Row, sim: &Simulator) -> Result<f64, String> {
        let slot = row.slot;
        let x = sim.state();
        let model = sim.model();
        let ok = |r: Result<f64, crate::model::ModelError>| r.map_err(|e| e.to_string());
        Ok(match slot {
            Slot::Input(i) => self.u[i],
            Slot::Height(i) => model.heights(x)[i],
            Slot::Tip(i) => model.tip(x)[i],
            Slot::Param(d) => (d.get)(&self.params),
            Slot::Rtol => self.rtol,
            Slot::State => model.state_index(&row.name).map_or(0.0, |k| x[k]),
            Slot::Energy => ok(model.energy(x))?,
            Slot::SuppliedPower => ok(model.supplied_power(x, self.u))?,
            Slot::DissipatedPower => ok(model.dissipated_power(x))?,
        })
    }
}

impl FmuCore for HaselCore {
    fn model_info() -> ModelInfo {
        model_info()
    }

    fn instantiate(resource_dir: Option<&Path>) -> Result<Self, String> {
        Ok(HaselCore {
            params: resource_params(resource_dir)?,
            rtol: DEFAULT_RTOL,
            tolerance: None,
            u: [0.0; 3],
            t_start: 0.0,
            sim: None,
        })
    }

    fn variables(&self) -> Vec<Variable> {
        variables(&self.params, self.rtol)
    }

    fn get_real(&mut self, vr: u32) -> Result<f64, String> {
        let row = &rows()[vr as usize];
        match row.slot {
            Slot::Input(i) => return Ok(self.u[i]),
            Slot::Param(d) => return Ok((d.get)(&self.params)),
            Slot::Rtol => return Ok(self.rtol),
            _ => {}
        }
        match &self.sim {
            Some(sim) => self.value(row, sim),
            None => {
                let sim = self.preview()?;
                self.value(row, &sim)
            }
        }
    }

    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), String> {
        let row = &rows()[vr as usize];
        match row.slot {
            Slot::Input(i) => {
                if !value.is_finite() {
                    return Err(format!("{} = {value}: a voltage must be finite", row.name));
                }
                self.u[i] = value;
            }
            Slot::Param(d) => self.params.set(d.name, value).map_err(|e| e.to_string())?,
            Slot::Rtol => {
                if !(value.is_finite() && value > 0.0 && value < 0.1) {
                    return Err(format!("rtol = {value}: must be in (0, 0.1)"));
                }
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
        if let Some(tol) = tolerance
            && !(tol.is_finite() && tol > 0.0 && tol < 0.1)
        {
            return Err(format!("tolerance = {tol}: must be in (0, 0.1)"));
        }
        self.t_start = start_time;
        self.tolerance = tolerance;
        Ok(())
    }

    fn exit_initialization(&mut self) -> Result<(), String> {
        self.sim = Some(self.preview()?);
        Ok(())
    }

    fn do_step(&mut self, step: f64) -> Result<(), String> {
        let sim = self
            .sim
            .as_mut()
            .ok_or("the simulation has not been initialized")?;
        let t_end = sim.t() + step;
        sim.step_held(self.u, t_end).map_err(|e| e.to_string())
    }

    fn time(&self) -> f64 {
        self.sim.as_ref().map_or(self.t_start, Simulator::t)
    }

    fn serialize_state(&self) -> Vec<u8> {
        let state = State {
            params: parameters().map(|d| (d.get)(&self.params)).collect(),
            rtol: self.rtol,
            tolerance: self.tolerance,
            u: self.u,
            t_start: self.t_start,
            sim: self.sim.as_ref().map(Simulator::snapshot),
        };
        postcard::to_stdvec(&state).expect("serializing to memory cannot fail")
    }

    fn deserialize_state(&self, bytes: &[u8]) -> Result<Self, String> {
        let state: State =
            postcard::from_bytes(bytes).map_err(|e| format!("not a HaselPlatform state: {e}"))?;
        let defs: Vec<&ParamDef> = parameters().collect();
        if state.params.len() != defs.len() {
            return Err(format!(
                "state holds {} parameters, this FMU has {}",
                state.params.len(),
                defs.len()
            ));
        }
        let mut params = Params::default();
        for (d, v) in defs.iter().zip(&state.params) {
            params.set(d.name, *v).map_err(|e| format!("state: {e}"))?;
        }
        let sim = match state.sim {
            Some(snapshot) => {
                let model = Platform::new(params.clone()).map_err(|e| format!("state: {e}"))?;
                Some(Simulator::from_snapshot(model, snapshot).map_err(|e| format!("state: {e}"))?)
            }
            None => None,
        };
        Ok(HaselCore {
            params,
            rtol: state.rtol,
            tolerance: state.tolerance,
            u: state.u,
            t_start: state.t_start,
            sim,
        })
    }
}

crate::export_fmi2!(HaselCore);
