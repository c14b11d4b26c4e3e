//! The inverse FMU's core: stateless apart from what it holds between calls. Its outputs map
//! the current inputs, the tip's X and Y and the mean height, to the heights (inverse
//! kinematics from X and Y, book/src/model.md "Inverse kinematics") and the voltages that hold
//! them ("Statics"): direct feedthrough, declared in `modelDescription.xml`, so a master that
//! sets the inputs reads their feedforward at once, not a step late. A step checks that its
//! inputs can be reached (and fails otherwise, the core as it was).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::model_info;
use super::variables::{Slot, rows, variables};
use crate::fmi_common::model_api::{FmuCore, InstanceKind, ModelStructure, OutputDependency};
use crate::fmi_common::variables::{ModelInfo, Variable};
use crate::fmu::hasel_core::{resource_params, restored_params, saved_params};
use crate::model::kinematics::Inverse;
use crate::model::statics::feedforward;
use crate::model::{Params, Platform};

/// Why the Model Exchange calls are refused.
const NOT_ME: &str = "HaselInverse has no continuous states: Co-Simulation only";

/// Heights [m] and voltages [V] of one tip position.
type Outputs = ([f64; 3], [f64; 3]);

/// The core: parameters and inputs, and the outputs of the inputs last asked for.
#[derive(Clone, Debug)]
pub struct InverseCore {
    params: Params,
    /// tip_x, tip_y, mean_height [m].
    inputs: [f64; 3],
    /// The inputs the outputs were last computed for, and those outputs (each output read
    /// would otherwise build the model again).
    last: Option<([f64; 3], Outputs)>,
    initialized: bool,
    t: f64,
}

/// The serialized state.
#[derive(Serialize, Deserialize)]
struct State {
    params: Vec<f64>,
    inputs: [f64; 3],
    initialized: bool,
    t: f64,
}

impl InverseCore {
    /// The heights and holding voltages of the current inputs.
    fn outputs(&mut self) -> Result<Outputs, String> {
        if let Some((inputs, outputs)) = self.last
            && inputs == self.inputs
        {
            return Ok(outputs);
        }
        let model = Platform::new(self.params.clone()).map_err(|e| e.to_string())?;
        let [x, y, mean_height] = self.inputs;
        let outputs =
            feedforward(&model, Inverse::Xy { mean_height }, [x, y, 0.0]).map_err(|e| {
                format!("tip ({x:e}, {y:e}) m at the mean height {mean_height:e} m: {e}")
            })?;
        self.last = Some((self.inputs, outputs));
        Ok(outputs)
    }
}

impl FmuCore for InverseCore {
    fn model_info() -> ModelInfo {
        model_info()
    }

    /// No states; every output depends on every input directly (the mean height and the
    /// tip's X and Y set all three heights).
    fn model_structure() -> ModelStructure {
        let rows = rows().iter().enumerate();
        let inputs: Vec<u32> = rows
            .clone()
            .filter(|(_, r)| matches!(r.slot, Slot::Input(_)))
            .map(|(vr, _)| vr as u32)
            .collect();
        ModelStructure {
            derivatives: vec![],
            outputs: rows
                .filter(|(_, r)| matches!(r.slot, Slot::Height(_) | Slot::Voltage(_)))
                .map(|(vr, _)| OutputDependency {
                    output: vr as u32,
                    dependencies: inputs.clone(),
                })
                .collect(),
        }
    }

    fn instantiate(kind: InstanceKind, resource_dir: Option<&Path>) -> Result<Self, String> {
        if kind == InstanceKind::ModelExchange {
            return Err(
                "HaselInverse is a Co-Simulation FMU only: it has no dynamics for an \
                        importer to integrate, its outputs map the inputs held over a step"
                    .into(),
            );
        }
        Ok(InverseCore {
            params: resource_params(resource_dir)?,
            inputs: super::variables::START,
            last: None,
            initialized: false,
            t: 0.0,
        })
    }

    fn variables(&self) -> Vec<Variable> {
        variables(&self.params)
    }

    fn get_real(&mut self, vr: u32) -> Result<f64, String> {
        Ok(match rows()[vr as usize].slot {
            Slot::Input(i) => self.inputs[i],
            Slot::Param(d) => (d.get)(&self.params),
            Slot::Height(i) => self.outputs()?.0[i],
            Slot::Voltage(i) => self.outputs()?.1[i],
        })
    }

    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), String> {
        let row = &rows()[vr as usize];
        match row.slot {
            Slot::Input(i) => {
                if !value.is_finite() {
                    return Err(format!("{} = {value}: must be finite", row.name));
                }
                self.inputs[i] = value;
            }
            Slot::Param(d) => {
                self.params.set_param(d, value).map_err(|e| e.to_string())?;
                self.last = None;
            }
            Slot::Height(_) | Slot::Voltage(_) => {
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
        _tolerance: Option<f64>,
    ) -> Result<(), String> {
        self.t = start_time;
        Ok(())
    }

    fn exit_initialization(&mut self) -> Result<(), String> {
        self.outputs()?;
        self.initialized = true;
        Ok(())
    }

    fn do_step(&mut self, step: f64) -> Result<(), String> {
        if !self.initialized {
            return Err("the FMU has not been initialized".into());
        }
        self.outputs()?;
        self.t += step;
        Ok(())
    }

    fn time(&self) -> f64 {
        self.t
    }

    fn set_time(&mut self, _time: f64) -> Result<(), String> {
        Err(NOT_ME.into())
    }

    fn continuous_states(&mut self, x: &mut [f64]) -> Result<(), String> {
        // no states: the empty vector
        if x.is_empty() {
            Ok(())
        } else {
            Err(NOT_ME.into())
        }
    }

    fn set_continuous_states(&mut self, _x: &[f64]) -> Result<(), String> {
        Err(NOT_ME.into())
    }

    fn derivatives(&mut self, _dx: &mut [f64]) -> Result<(), String> {
        Err(NOT_ME.into())
    }

    fn nominals(&self, nominal: &mut [f64]) -> Result<(), String> {
        if nominal.is_empty() {
            Ok(())
        } else {
            Err(NOT_ME.into())
        }
    }

    fn directional_derivative(
        &mut self,
        _unknowns: &[u32],
        _knowns: &[u32],
        _seed: &[f64],
        _result: &mut [f64],
    ) -> Result<(), String> {
        Err(
            "HaselInverse provides no directional derivatives (its modelDescription says so)"
                .into(),
        )
    }

    fn serialize_state(&self) -> Vec<u8> {
        let state = State {
            params: saved_params(&self.params),
            inputs: self.inputs,
            initialized: self.initialized,
            t: self.t,
        };
        postcard::to_stdvec(&state).expect("serializing to memory cannot fail")
    }

    fn deserialize_state(&self, bytes: &[u8]) -> Result<Self, String> {
        let state: State =
            postcard::from_bytes(bytes).map_err(|e| format!("not a HaselInverse state: {e}"))?;
        Ok(InverseCore {
            params: restored_params(&state.params)?,
            inputs: state.inputs,
            last: None,
            initialized: state.initialized,
            t: state.t,
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

    fn outputs(core: &mut InverseCore) -> Vec<f64> {
        ["h1", "h2", "h3", "U1", "U2", "U3"]
            .map(|n| core.get_real(vr(n)).unwrap())
            .to_vec()
    }

    #[test]
    fn the_outputs_are_the_feedforward_of_the_inputs_as_they_are_set() {
        let mut core = InverseCore::instantiate(InstanceKind::CoSimulation, None).unwrap();
        core.enter_initialization(0.0, None, None).unwrap();
        core.exit_initialization().unwrap();
        let (x, y, mean) = (20e-6, -10e-6, 70e-6);
        for (name, value) in [("tip_x", x), ("tip_y", y), ("mean_height", mean)] {
            core.set_real(vr(name), value).unwrap();
        }
        // direct feedthrough: the outputs follow the inputs before the step, and the model's
        // parameters as they are set
        let model = Platform::new(Params::default()).unwrap();
        let mean_height = mean;
        let (h, u) = feedforward(&model, Inverse::Xy { mean_height }, [x, y, 0.0]).unwrap();
        let expected: Vec<f64> = h.iter().chain(&u).copied().collect();
        assert_eq!(outputs(&mut core), expected);
        core.do_step(1e-3).unwrap();
        assert_eq!(outputs(&mut core), expected);
        assert_eq!(core.time(), 1e-3);
        core.set_real(vr("Kb_1"), 0.31).unwrap();
        assert_ne!(outputs(&mut core)[3], expected[3]);
        let dependencies = &InverseCore::model_structure().outputs[0].dependencies;
        assert_eq!(dependencies, &["tip_x", "tip_y", "mean_height"].map(vr));
    }

    #[test]
    fn a_tip_out_of_reach_fails_the_step_and_leaves_the_core_as_it_was() {
        let mut core = InverseCore::instantiate(InstanceKind::CoSimulation, None).unwrap();
        core.enter_initialization(0.0, None, None).unwrap();
        core.exit_initialization().unwrap();
        core.set_real(vr("tip_x"), 1e-3).unwrap();
        let e = core.do_step(1e-3).unwrap_err();
        assert!(e.contains("actuator 2") && e.contains("input gain"), "{e}");
        assert!(core.get_real(vr("U2")).unwrap_err().contains("input gain"));
        assert_eq!(core.time(), 0.0);
        assert!(core.set_real(vr("h1"), 0.0).is_err());
        assert!(core.set_real(vr("tip_y"), f64::NAN).is_err());
    }

    #[test]
    fn a_restored_state_is_the_same_core() {
        let mut core = InverseCore::instantiate(InstanceKind::CoSimulation, None).unwrap();
        core.set_real(vr("Kb_1"), 0.31).unwrap();
        core.enter_initialization(0.0, None, None).unwrap();
        core.exit_initialization().unwrap();
        core.set_real(vr("tip_y"), 15e-6).unwrap();
        core.do_step(1e-3).unwrap();
        let mut back = core.deserialize_state(&core.serialize_state()).unwrap();
        assert_eq!(outputs(&mut back), outputs(&mut core));
        assert_eq!(back.get_real(vr("Kb_1")), Ok(0.31));
        assert!(core.deserialize_state(b"garbage").is_err());
    }
}
