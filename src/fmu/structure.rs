//! The model structure the FMU declares: its continuous states (the state variables of the
//! table, in value-reference order) and what their derivatives and the outputs can depend on.
//! Read from the positions the analytic Jacobians write ([`Platform::jacobian_entries`],
//! [`Platform::input_jacobian_entries`], [`Platform::output_jacobian_entries`]) in every
//! configuration of effects the FMU's parameters can reach, so a dependency is declared when
//! some parameter values make it nonzero.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::OnceLock;

use super::variables::{Slot, rows, state_vr};
use crate::fmi_common::model_api::{ModelStructure, OutputDependency, StateDerivative};
use crate::model::effects::{DriftSite, Effect, EffectParams};
use crate::model::{Params, Platform};

/// Every effect on, in the library's forms (the ones the FMU's parameters set).
fn all_on() -> Params {
    let mut p = Params::default();
    let f = &mut p.effects;
    f.coupling.k_c = 40.0;
    f.charge_drift.r3 = 2e4;
    f.charge_drift.tau3 = 0.5;
    f.coupling.weights = [1.0, 0.5, 1.5];
    f.creep.k_v = 0.05;
    f.creep.tau_v = 0.3;
    f.creep.k_v2 = 0.02;
    f.hysteresis.k_h = 0.04;
    f.hysteresis.theta_h = 2e-3;
    f.hysteresis.r_h = 2.0;
    f.amplifier_lag.tau_a = 0.02;
    f.amplifier_lag.tau_a2 = 0.005;
    f.delay.tau_d = 1e-3;
    f.saturation.u_max = 50.0;
    f.stiffening.k3 = 30.0;
    f.preload.tau0 = [1e-4, -2e-4, 3e-4];
    p
}

/// `effect` back at its neutral default.
fn switch_off(f: &mut EffectParams, effect: Effect) {
    let d = EffectParams::default();
    match effect {
        Effect::Coupling => f.coupling = d.coupling,
        Effect::ChargeDrift => f.charge_drift = d.charge_drift,
        Effect::Creep => f.creep = d.creep,
        Effect::Hysteresis => f.hysteresis = d.hysteresis,
        Effect::AmplifierLag => f.amplifier_lag = d.amplifier_lag,
        Effect::Delay => f.delay = d.delay,
        Effect::Saturation => f.saturation = d.saturation,
        Effect::Stiffening => f.stiffening = d.stiffening,
        Effect::Preload => f.preload = d.preload,
    }
}

/// The configurations whose structures together hold every other's: all effects on, and all
/// on but one (an effect's terms only add entries, except the amplifier's lag, which moves the
/// command's entry from the circuit to its own state), and the drift element at each site.
fn configurations() -> Vec<Params> {
    let mut all = vec![all_on()];
    for site in [DriftSite::Electrode, DriftSite::Film] {
        let mut p = all_on();
        p.effects.charge_drift.site = site;
        p.effects.charge_drift.c3 = 1e-9;
        all.push(p);
    }
    for effect in Effect::ALL {
        let mut p = all_on();
        switch_off(&mut p.effects, effect);
        all.push(p);
    }
    all
}

fn vr_of(slot: impl Fn(&Slot) -> bool) -> u32 {
    rows()
        .iter()
        .position(|r| slot(&r.slot))
        .expect("the table has the variable") as u32
}

/// The structure, built once.
pub fn model_structure() -> ModelStructure {
    static STRUCTURE: OnceLock<ModelStructure> = OnceLock::new();
    STRUCTURE.get_or_init(build).clone()
}

fn build() -> ModelStructure {
    let input = |j: usize| vr_of(|s| matches!(s, Slot::Input(i) if *i == j));
    let mut state_deps: BTreeMap<u32, BTreeSet<u32>> = BTreeMap::new();
    let mut output_deps: [BTreeSet<u32>; 6] = Default::default();
    for params in configurations() {
        let m = Platform::new(params).expect("the configurations are valid");
        // the entries' positions do not depend on the state: any state in the domain will do
        let x = m
            .uncoupled_rest_state()
            .expect("the configurations have a rest state");
        // value reference of each position of the model's state vector
        let vrs: Vec<u32> = (0..3)
            .flat_map(|i| m.block_states().map(move |s| (i, s)))
            .map(|(i, s)| state_vr(i, s).expect("library forms have table states only"))
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
    let derivatives = rows()
        .iter()
        .enumerate()
        .filter_map(|(vr, row)| match row.slot {
            Slot::State { actuator, state } => Some(StateDerivative {
                state: vr as u32,
                derivative: vr_of(|s| matches!(s, Slot::Derivative { actuator: a, state: b } if *a == actuator && *b == state)),
                dependencies: state_deps
                    .get(&(vr as u32))
                    .map_or(Vec::new(), |d| d.iter().copied().collect()),
            }),
            _ => None,
        })
        .collect();
    let outputs = rows()
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
