//! The FMU's variable table: one row per variable, its value reference being its index. The
//! one source of truth for `modelDescription.xml`, `documentation/index.html` and what each
//! value reference reads or sets ([`Slot`], resolved here once, so a get or set is an index
//! and a match). State names, units and meanings come from the model.

use std::sync::OnceLock;

use crate::fmi_common::units;
use crate::fmi_common::variables::{Causality, Initial, Variability, Variable};
use crate::model::effects::terms::Extra;
use crate::model::params::{ParamDef, parameters};
use crate::model::platform::BlockState;
use crate::model::{Params, Reduction};

/// What a value reference stands for.
#[derive(Clone, Copy)]
pub enum Slot {
    Input(usize),
    Height(usize),
    Tip(usize),
    Param(&'static ParamDef),
    Rtol,
    /// A state of actuator `actuator` (0-based); an effect's state reads 0 while it is off.
    State {
        actuator: usize,
        state: BlockState,
    },
    Energy,
    SuppliedPower,
    DissipatedPower,
    /// The time derivative of a state (0 while its effect is off).
    Derivative {
        actuator: usize,
        state: BlockState,
    },
}

/// One row of the variable table.
pub struct Row {
    pub name: String,
    pub slot: Slot,
    pub unit: &'static str,
    pub description: String,
}

/// The states every actuator shows: the paper's states the model `reduction` keeps and every
/// effect state the parameter table can switch on (synthetic data's further stages are not
/// variables).
fn fmu_states(reduction: Reduction) -> impl Iterator<Item = BlockState> {
    (0..reduction.kept())
        .map(BlockState::Paper)
        .chain(Extra::table_states().map(BlockState::Extra))
}

/// A state's description: the model's, with the effect and what it reads while off.
fn state_description(state: BlockState, actuator: usize) -> String {
    let info = state.info();
    match state {
        BlockState::Paper(_) => format!("{} of actuator {actuator}", info.description),
        BlockState::Extra(e) => format!(
            "{}: {} (0 while off) of actuator {actuator}",
            e.effect.name(),
            info.description
        ),
    }
}

/// HaselPlatform's variable table (the full model's), in value-reference order.
pub fn rows() -> &'static [Row] {
    rows_of(Reduction::Full)
}

/// The variable table of the FMU of the model `reduction`, in value-reference order; built
/// once for each model.
pub fn rows_of(reduction: Reduction) -> &'static [Row] {
    static ROWS: [OnceLock<Vec<Row>>; 3] = [OnceLock::new(), OnceLock::new(), OnceLock::new()];
    ROWS[reduction as usize].get_or_init(|| {
        let mut rows = Vec::new();
        let mut add = |name: String, slot, unit, description: String| {
            rows.push(Row {
                name,
                slot,
                unit,
                description,
            })
        };
        for i in 0..3 {
            let n = i + 1;
            let desc = format!("Voltage command of actuator {n}, held over a communication step");
            add(format!("U{n}"), Slot::Input(i), "V", desc);
        }
        for i in 0..3 {
            let n = i + 1;
            let desc = format!("Height of actuator {n}: h = 1/2 Lv sin(theta)");
            add(format!("h{n}"), Slot::Height(i), "m", desc);
        }
        for (i, axis) in ["x", "y", "z"].iter().enumerate() {
            let desc = format!("Antenna tip {axis} from the forward kinematics");
            add(format!("tip_{axis}"), Slot::Tip(i), "m", desc);
        }
        for d in parameters() {
            let desc = d.description.to_string();
            add(d.name.to_string(), Slot::Param(d), d.unit, desc);
        }
        let desc = "Relative tolerance of the internal Radau IIA solver (a tolerance given to \
                    fmi2SetupExperiment takes precedence)";
        add("rtol".into(), Slot::Rtol, "1", desc.into());
        for actuator in 0..3 {
            for state in fmu_states(reduction) {
                let name = format!("{}_{}", state.name(), actuator + 1);
                let desc = state_description(state, actuator + 1);
                add(
                    name,
                    Slot::State { actuator, state },
                    state.info().unit,
                    desc,
                );
            }
        }
        let desc = "Stored energy (Hamiltonian) of the three actuators";
        add("H".into(), Slot::Energy, "J", desc.into());
        let desc = "Power supplied through the electrical ports, sum of y_i U_i";
        add("P_supplied".into(), Slot::SuppliedPower, "W", desc.into());
        let desc = "Power dissipated in the resistors and the damping";
        add(
            "P_dissipated".into(),
            Slot::DissipatedPower,
            "W",
            desc.into(),
        );
        for actuator in 0..3 {
            for state in fmu_states(reduction) {
                let name = format!("der({}_{})", state.name(), actuator + 1);
                let unit = units::per_second(state.info().unit)
                    .expect("the unit table has the rate of every state's unit");
                let desc = format!("Time derivative of {}_{}", state.name(), actuator + 1);
                add(name, Slot::Derivative { actuator, state }, unit, desc);
            }
        }
        rows
    })
}

/// Causality, variability, initial and start of a variable.
type Kind = (Causality, Variability, Option<Initial>, Option<f64>);

/// An output the model computes.
pub const OUTPUT: Kind = (
    Causality::Output,
    Variability::Continuous,
    Some(Initial::Calculated),
    None,
);

/// A fixed parameter whose start value is `start`.
pub fn parameter(start: f64) -> Kind {
    (
        Causality::Parameter,
        Variability::Fixed,
        Some(Initial::Exact),
        Some(start),
    )
}

/// The FMI variable at value reference `vr` (not the derivative of a state).
pub fn variable(vr: usize, name: &str, unit: &str, description: &str, kind: Kind) -> Variable {
    let (causality, variability, initial, start) = kind;
    Variable {
        name: name.to_string(),
        value_reference: vr as u32,
        causality,
        variability,
        initial,
        unit: Some(unit.to_string()),
        description: description.to_string(),
        start,
        derivative: None,
    }
}

/// The value reference of actuator `actuator`'s (0-based) state `state` in the FMU of the model
/// `reduction`.
pub fn state_vr(reduction: Reduction, actuator: usize, state: BlockState) -> Option<u32> {
    let is = |r: &Row| matches!(r.slot, Slot::State { actuator: a, state: s } if a == actuator && s == state);
    rows_of(reduction).iter().position(is).map(|k| k as u32)
}

/// The FMI variables of the FMU of the model `reduction` with the start values of `params`
/// and `rtol`.
pub fn variables(reduction: Reduction, params: &Params, rtol: f64) -> Vec<Variable> {
    rows_of(reduction)
        .iter()
        .enumerate()
        .map(|(vr, row)| {
            let kind = match row.slot {
                Slot::Input(_) => (Causality::Input, Variability::Continuous, None, Some(0.0)),
                Slot::Height(_) | Slot::Tip(_) => OUTPUT,
                Slot::Param(d) => parameter((d.get)(params)),
                Slot::Rtol => parameter(rtol),
                Slot::State { .. }
                | Slot::Derivative { .. }
                | Slot::Energy
                | Slot::SuppliedPower
                | Slot::DissipatedPower => (
                    Causality::Local,
                    Variability::Continuous,
                    Some(Initial::Calculated),
                    None,
                ),
            };
            Variable {
                derivative: match row.slot {
                    Slot::Derivative { actuator, state } => state_vr(reduction, actuator, state),
                    _ => None,
                },
                ..variable(vr, &row.name, row.unit, &row.description, kind)
            }
        })
        .collect()
}
