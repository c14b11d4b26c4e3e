//! The inverse path (book/src/model.md, "Inverse kinematics" and "Statics"): the voltages of a
//! tip path hold its heights in a simulation, the holding voltages invert the equilibrium of
//! `hasel linearize`, and heights without one are named. `hasel inverse` itself: tests/cli.rs.

use hasel_fmu::control::equilibrium;
use hasel_fmu::model::kinematics::Inverse;
use hasel_fmu::model::statics::{StaticsError, UnreachableError, feedforward, holding_voltages};
use hasel_fmu::model::{Params, Platform};
use hasel_fmu::simulation::Simulator;

fn paper() -> Platform {
    Platform::new(Params::default()).unwrap()
}

/// Mean height of the paths [m].
const MEAN: f64 = 60e-6;

/// A tip circle of radius 40 µm around the level platform at MEAN (the z of the level
/// platform: its forward kinematics), `n` points over one period of 2 s: rows t, x, y, z.
fn circle(n: usize) -> Vec<[f64; 4]> {
    let z = paper().kinematics.tip([MEAN; 3])[2];
    (0..n)
        .map(|k| {
            let t = 2.0 * k as f64 / (n - 1) as f64;
            let phase = std::f64::consts::PI * t;
            [t, 40e-6 * phase.cos(), 40e-6 * phase.sin(), z]
        })
        .collect()
}

#[test]
fn the_voltages_hold_the_heights_in_a_simulation() {
    let model = paper();
    let rest = model.heights(&model.rest_state().unwrap());
    for [t, x, y, z] in circle(5) {
        let (h, u) = feedforward(&model, Inverse::ClosedForm, [x, y, z]).unwrap();
        // from rest under the constant voltages: 4 s are 14 time constants of the slowest
        // mode (actuator 1, -3.6 1/s here)
        let mut sim = Simulator::new(model.clone(), 0.0, 1e-10).unwrap();
        sim.step_held(u, 4.0).unwrap();
        let reached = model.heights(sim.state());
        for i in 0..3 {
            let stroke = h[i] - rest[i];
            assert!(
                (reached[i] - h[i]).abs() <= 1e-3 * stroke,
                "t = {t}, actuator {}: {} m reached, {} m asked (stroke {stroke} m) under {u:?} V",
                i + 1,
                reached[i],
                h[i]
            );
        }
    }
}

#[test]
fn the_holding_voltages_invert_the_equilibrium_of_hasel_linearize() {
    let model = paper();
    for u in [[60.0, 30.0, 0.5], [45.0, 36.6, 40.4], [100.0, 100.0, 100.0]] {
        let eq = equilibrium::equilibrium(&model, u).unwrap();
        let back = holding_voltages(&model, model.heights(&eq.x)).unwrap();
        for i in 0..3 {
            assert!(
                (back[i] - u[i]).abs() <= 1e-12 * u[i],
                "{back:?} V vs {u:?} V"
            );
        }
    }
}

/// A tip path that starts at rest: the rest heights come back from the inverse kinematics a
/// rounding away from the rest, on either side, and are held by 0 V.
#[test]
fn the_tip_at_rest_is_held_by_zero_volts() {
    let model = paper();
    let rest = model.rest_state().unwrap();
    let tip = model.kinematics.tip(model.heights(&rest));
    let (_, u) = feedforward(&model, Inverse::Exact, tip).unwrap();
    assert_eq!(u, [0.0; 3]);
    // the paper's closed form is approximate: heights a little off the rest, either side
    assert!(feedforward(&model, Inverse::ClosedForm, tip).is_ok());
}

#[test]
fn heights_without_a_holding_voltage_are_named() {
    let model = paper();
    let rest = model.heights(&model.rest_state().unwrap());
    let cases = [
        ([rest[0] - 1e-6, 5e-5, 5e-5], 1, "below"),
        ([5e-5, 5e-5, 4e-4], 3, "beyond"),
        ([5e-5, 7e-3, 5e-5], 2, "no angle"),
    ];
    for (h, actuator, what) in cases {
        let e = holding_voltages(&model, h).unwrap_err();
        let StaticsError::Actuator { actuator: a, cause } = &e else {
            panic!("{e}")
        };
        assert_eq!(*a, actuator, "{e}");
        let matches = match what {
            "below" => matches!(cause, UnreachableError::BelowRest { .. }),
            "beyond" => matches!(cause, UnreachableError::BeyondGain { .. }),
            _ => matches!(cause, UnreachableError::NoAngle { .. }),
        };
        assert!(matches, "{what}: {e}");
    }
    let mut p = Params::default();
    p.set("k_v", 0.05).unwrap();
    let e = holding_voltages(&Platform::new(p).unwrap(), [5e-5; 3]).unwrap_err();
    assert!(matches!(e, StaticsError::Effects(_)), "{e}");
}
