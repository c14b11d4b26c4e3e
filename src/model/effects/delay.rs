//! `delay` (book/src/effects.md, "delay"): a transport delay between the command and
//! the actuator. It has no terms here: the simulation, which holds the input history, applies it.

use super::family::no_law;
use super::terms::{Law, States};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, log_between};
use crate::model::Params;
use crate::model::params::common_rows;

/// Transport delay between the command and the actuator; applied by the simulation, which
/// holds the input history. Before the first command has arrived the actuator sees U = 0.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Delay {
    /// τ_d \[s\].
    pub tau_d: f64,
}

/// Relative wander of the hidden transport delay, and its frequency \[Hz\].
pub const WANDER: f64 = 0.05;
pub const WANDER_HZ: f64 = 0.37;

const FORMS: [Form; 1] = [Form::new(Effect::Delay, "constant", &["tau_d"], &[])];

pub const FAMILY: Family = Family {
    effect: Effect::Delay,
    name: "delay",
    mechanism: "transport delay between command and actuator",
    form: "U_eff(t) = U(t - tau_d)",
    forms: &FORMS,
    rows: &common_rows! {
        "tau_d", "s", NonNegative, "delay: transport delay tau_d between command and actuator (0: off)", effects.delay.tau_d;
    },
    choices: &[],
    state: None,
    table_stages: 0,
    is_active: |p| p.delay.tau_d > 0.0,
    on: |f| f.delay.tau_d = 1e-3,
    structures: &[],
    delays_the_command: true,
    magnitude: Magnitude::Positive,
    probes: |_, _| {
        [0.005, 0.02]
            .into_iter()
            .map(|tau| Probe::one(&FORMS[0], vec![("tau_d", tau)]))
            .collect()
    },
    exposing: Exposing {
        text: "a multisine up to 100 rad/s: a delay shifts the fast tones' phase without attenuating them",
        drive: Drive::Multisine(&[5.0, 15.0, 40.0, 100.0]),
        t_end: 6.0,
    },
    hidden: wandering,
    variants: &[],
    law: no_law,
};

/// A delay wandering around its mean (network jitter), which the data generator applies.
fn wandering(_: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let tau = log_between(between, 0.008, 0.025);
    Planted {
        wandering_delay: Some((tau, between(0.0, 2.0 * std::f64::consts::PI))),
        text: format!(
            "a transport delay wandering by +-{:.0} % around {:.1} ms at {WANDER_HZ} Hz (network jitter)",
            100.0 * WANDER,
            1000.0 * tau
        ),
    }
}

/// No terms: the simulation delays the command.
#[derive(Clone, Debug)]
pub struct Terms;

impl Law for Terms {
    type Params = Delay;

    fn new(_: &Delay, _: &mut States) -> Terms {
        Terms
    }
}
