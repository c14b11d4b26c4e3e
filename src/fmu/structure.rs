//! The model structure the FMU declares: its continuous states (the state variables of the
//! table, in value-reference order) and what their derivatives and the outputs can depend on.
//! Read from the positions the analytic Jacobians write ([`Platform::jacobian_entries`],
//! [`Platform::input_jacobian_entries`], [`Platform::output_jacobian_entries`]) in every
//! configuration of effects the FMU's parameters can reach, so a dependency is declared when
//! some parameter values make it nonzero.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::OnceLock;

use super::variables::{Slot, rows_of, state_vr};
use crate::fmi_common::model_api::{ModelStructure, OutputDependency, StateDerivative};
use crate::model::{Effect, Params, Platform, Reduction};

/// Every family on, every form the FMU's parameters reach at once (each family's `on`).
fn all_on() -> Params {
    let mut p = Params::default();
    for e in Effect::ALL {
        (e.family().on)(&mut p.effects);
    }
    p
}

/// The configurations whose structures together hold every other's: all families on, and all
/// on but one (a family's terms only add entries, except the amplifier's lag, which moves the
/// command's entry from the circuit to its own state), and all on with each family's further
/// structures (the drift element at each site).
fn configurations() -> Vec<Params> {
    let mut all = vec![all_on()];
    for effect in Effect::ALL {
        for structure in effect.family().structures {
            let mut p = all_on();
            structure(&mut p.effects);
            all.push(p);
        }
    }
    for effect in Effect::ALL {
        let mut p = all_on();
        p.effects.switch_off(effect);
        all.push(p);
    }
    all
}

fn vr_of(reduction: Reduction, slot: impl Fn(&Slot) -> bool) -> u32 {
    rows_of(reduction)
        .iter()
        .position(|r| slot(&r.slot))
        .expect("the table has the variable") as u32
}

/// The structure of the FMU of the model `reduction`, built once for each model.
pub fn model_structure(reduction: Reduction) -> ModelStructure {
    static STRUCTURE: [OnceLock<ModelStructure>; 3] =
        [OnceLock::new(), OnceLock::new(), OnceLock::new()];
    STRUCTURE[reduction as usize]
        .get_or_init(|| build(reduction))
        .clone()
}

fn build(reduction: Reduction) -> ModelStructure {
    let input = |j: usize| vr_of(reduction, |s| matches!(s, Slot::Input(i) if *i == j));
    let mut state_deps: BTreeMap<u32, BTreeSet<u32>> = BTreeMap::new();
    let mut output_deps: [BTreeSet<u32>; 6] = Default::default();
    for params in configurations() {
        let m = Platform::reduced(params, reduction).expect("the configurations are valid");
        // the entries' positions do not depend on the state: any state in the domain will do
        let x = m
            .uncoupled_rest_state()
            .expect("the configurations have a rest state");
        // value reference of each position of the model's state vector
        let vrs: Vec<u32> = (0..3)
            .flat_map(|i| m.block_states().map(move |s| (i, s)))
            .map(|(i, s)| state_vr(reduction, i, s).expect("library forms have table states only"))
            .collect();
        let mut depend = |r: usize, on: u32| {
            state_deps.entry(vrs[r]).or_default().insert(on);
        };
        m.jacobian_entries(&x, [0.0; 3], |r, c, _| depend(r, vrs[c]))
            .expect("the rest state is evaluable");
        m.input_jacobian_entries(&x, [0.0; 3], |r, j, _| depend(r, input(j)))
            .expect("the rest state is evaluable");
        m.output_jacobian_entries(&x, |o, c, _| {
            output_deps[o].insert(vrs[c]);
        });
    }
    let derivatives = rows_of(reduction)
        .iter()
        .enumerate()
        .filter_map(|(vr, row)| match row.slot {
            Slot::State { actuator, state } => Some(StateDerivative {
                state: vr as u32,
                derivative: vr_of(reduction, |s| matches!(s, Slot::Derivative { actuator: a, state: b } if *a == actuator && *b == state)),
                dependencies: state_deps
                    .get(&(vr as u32))
                    .map_or(Vec::new(), |d| d.iter().copied().collect()),
            }),
            _ => None,
        })
        .collect();
    let outputs = rows_of(reduction)
        .iter()
        .enumerate()
        .filter_map(|(vr, row)| {
            let k = match row.slot {
                Slot::Height(i) => i,
                Slot::Tip(i) => 3 + i,
                _ => return None,
            };
            Some(OutputDependency {
                output: vr as u32,
                dependencies: output_deps[k].iter().copied().collect(),
            })
        })
        .collect();
    ModelStructure {
        derivatives,
        outputs,
    }
}
