//! The inverse FMU's variable table: one row per variable, its value reference being its
//! index; the one source of truth for its `modelDescription.xml`, its documentation and what
//! each value reference reads or sets. The parameters are the platform's (the kinematics and the
//! actuators the holding voltages come from).

use std::sync::OnceLock;

use crate::fmi_common::variables::{Causality, Variability, Variable};
use crate::fmu::variables::{OUTPUT, parameter, variable};
use crate::model::Params;
use crate::model::params::{ParamDef, parameters};

/// What a value reference stands for.
#[derive(Clone, Copy)]
pub enum Slot {
    /// tip_x, tip_y, mean_height.
    Input(usize),
    Height(usize),
    Voltage(usize),
    Param(&'static ParamDef),
}

/// One row of the variable table.
pub struct Row {
    pub name: String,
    pub slot: Slot,
    pub unit: &'static str,
    pub description: String,
}

/// The inputs' start values: the level platform at 50 µm, which the paper's actuators reach.
pub const START: [f64; 3] = [0.0, 0.0, 50e-6];

/// Outputs by three: name prefix, slot of actuator i, unit, description (with {n}).
type OutputRows = (&'static str, fn(usize) -> Slot, &'static str, &'static str);

/// The variable table, in value-reference order; built once.
pub fn rows() -> &'static [Row] {
    static ROWS: OnceLock<Vec<Row>> = OnceLock::new();
    ROWS.get_or_init(|| {
        let mut rows = Vec::new();
        let inputs = [
            (
                "tip_x",
                "Antenna tip x asked for, held over a communication step",
            ),
            (
                "tip_y",
                "Antenna tip y asked for, held over a communication step",
            ),
            (
                "mean_height",
                "Mean height of the three actuators asked for (the heave that tip x, y leave open)",
            ),
        ];
        for (i, (name, description)) in inputs.into_iter().enumerate() {
            rows.push(Row {
                name: name.into(),
                slot: Slot::Input(i),
                unit: "m",
                description: description.into(),
            });
        }
        let outputs: [OutputRows; 2] = [
            (
                "h",
                Slot::Height,
                "m",
                "Height of actuator {n} that puts the tip at (tip_x, tip_y) with the mean height \
                 (inverse kinematics from X and Y)",
            ),
            (
                "U",
                Slot::Voltage,
                "V",
                "Feedforward: the constant voltage that holds actuator {n} at h{n} at equilibrium",
            ),
        ];
        for (prefix, slot, unit, description) in outputs {
            for i in 0..3 {
                let n = (i + 1).to_string();
                rows.push(Row {
                    name: format!("{prefix}{n}"),
                    slot: slot(i),
                    unit,
                    description: description.replace("{n}", &n),
                });
            }
        }
        for d in parameters() {
            rows.push(Row {
                name: d.name.to_string(),
                slot: Slot::Param(d),
                unit: d.unit,
                description: d.description.to_string(),
            });
        }
        rows
    })
}

/// The FMI variables with the start values of `params`.
pub fn variables(params: &Params) -> Vec<Variable> {
    rows()
        .iter()
        .enumerate()
        .map(|(vr, row)| {
            let kind = match row.slot {
                Slot::Input(i) => (
                    Causality::Input,
                    Variability::Continuous,
                    None,
                    Some(START[i]),
                ),
                Slot::Height(_) | Slot::Voltage(_) => OUTPUT,
                Slot::Param(d) => parameter((d.get)(params)),
            };
            variable(vr, &row.name, row.unit, &row.description, kind)
        })
        .collect()
}
