//! The HaselPlatform model core: the mapping of FMI calls onto a [`Simulator`], parameters
//! until initialization ends, then a running simulation. The generic FMI shell does every
//! check of the standard around it; the variable table says what each value reference is.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::variables::{Slot, rows, variables};
use super::{RESOURCE_PARAMS, model_info};
use crate::fmi_common::model_api::FmuCore;
use crate::fmi_common::variables::{ModelInfo, Variable};
use crate::io::params_file;
use crate::model::params::{ParamDef, parameters};
use crate::model::{Params, Platform};
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

    fn value(&self, slot: Slot, sim: &Simulator) -> Result<f64, String> {
        let x = sim.state();
        let model = sim.model();
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
            Some(sim) => self.value(row.slot, sim),
            None => {
                let sim = self.preview()?;
                self.value(row.slot, &sim)
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
            params: saved_params(&self.params),
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
        let params = restored_params(&state.params)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The value reference of the variable `name`.
    fn vr(name: &str) -> u32 {
        rows().iter().position(|r| r.name == name).unwrap() as u32
    }

    #[test]
    fn state_variables_read_the_model_state_of_their_name() {
        let mut core = HaselCore::instantiate(None).unwrap();
        // the effects with states on, two stages each where an effect has a choice
        let effects = [
            ("R3", 2e4),
            ("tau3", 0.5),
            ("k_v", 0.05),
            ("tau_v", 0.3),
            ("k_h", 0.04),
            ("theta_h", 2e-3),
            ("tau_a", 0.02),
        ];
        for (name, value) in effects {
            core.set_real(vr(name), value).unwrap();
        }
        core.params.effects.charge_drift.two_stages = true;
        core.params.effects.amplifier_lag.order = 2;
        core.set_real(vr("U2"), 80.0).unwrap();
        core.enter_initialization(0.0, None, None).unwrap();
        core.exit_initialization().unwrap();
        core.do_step(0.01).unwrap();
        let sim = core.sim.clone().unwrap();
        let mut states = 0;
        for (k, row) in rows().iter().enumerate() {
            if let Slot::State { .. } = row.slot {
                let x = sim.model().state_index(&row.name).map(|i| sim.state()[i]);
                let got = core.get_real(k as u32).unwrap();
                assert_eq!(Some(got), x, "{}", row.name);
                states += 1;
            }
        }
        assert_eq!(states, 3 * 9);
    }

    #[test]
    fn states_of_effects_that_are_off_read_zero() {
        let mut core = HaselCore::instantiate(None).unwrap();
        core.enter_initialization(0.0, None, None).unwrap();
        for name in ["Q3_1", "z_v_2", "z_h_3", "U_amp_1"] {
            assert_eq!(core.get_real(vr(name)), Ok(0.0), "{name}");
        }
        assert_ne!(core.get_real(vr("theta_1")), Ok(0.0), "the rest angle");
    }
}
