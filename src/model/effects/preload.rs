//! `preload` (book/src/effects.md, "preload"): a constant load on each actuator.

use super::family::{mean_kb, no_law};
use super::terms::{Law, States, Torque};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, Scaling};
use crate::model::Params;
use crate::model::actuator::{Actuator, THETA};
use crate::model::params::common_rows;

/// How a preload acts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PreloadLaw {
    /// Library form: a constant torque τ0 against θ (H += τ0 θ).
    Constant,
    /// A weight carried on the platform: the torque τ0 cos θ (H += τ0 sin θ).
    Weight,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Preload {
    /// τ0,i [N m] per actuator, positive against θ.
    pub tau0: [f64; 3],
    pub law: PreloadLaw,
}

impl Default for Preload {
    fn default() -> Self {
        Preload {
            tau0: [0.0; 3],
            law: PreloadLaw::Constant,
        }
    }
}

const FORMS: [Form; 1] = [Form::new(
    Effect::Preload,
    "constant",
    &["tau0_1", "tau0_2", "tau0_3"],
    &[],
)];

pub const FAMILY: Family = Family {
    effect: Effect::Preload,
    name: "preload",
    mechanism: "a constant load on each actuator",
    form: "H += tau0_i theta_i (a constant torque against theta)",
    forms: &FORMS,
    rows: &common_rows! {
        "tau0_1", "N.m", Finite, "preload: constant torque against theta on actuator 1 (0: off)", effects.preload.tau0[0];
        "tau0_2", "N.m", Finite, "preload: constant torque against theta on actuator 2 (0: off)", effects.preload.tau0[1];
        "tau0_3", "N.m", Finite, "preload: constant torque against theta on actuator 3 (0: off)", effects.preload.tau0[2];
    },
    choices: &[],
    state: None,
    table_stages: 0,
    is_active: |p| p.preload.tau0.iter().any(|&t| t != 0.0),
    on: |f| f.preload.tau0 = [1e-4, -2e-4, 3e-4],
    structures: &[],
    delays_the_command: false,
    magnitude: Magnitude::Signed,
    // each actuator's torque alone, of either sign
    probes: |params, _| {
        let kb = mean_kb(params);
        vec![Probe {
            form: &FORMS[0],
            columns: FORMS[0]
                .free
                .iter()
                .map(|n| vec![(*n, kb * 1e-3)])
                .collect(),
            scaling: Scaling::Signed,
        }]
    },
    exposing: Exposing {
        text: "a record of the rest position before the drive starts: a preload shifts it",
        drive: Drive::Corners(&[(0.0, 0.0), (2.0, 0.0), (2.5, 1.0), (6.0, 1.0)]),
        t_end: 6.0,
    },
    hidden: weight,
    variants: &[],
    law: no_law,
};

/// A weight on the platform.
fn weight(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let (kb, lv) = (params.act.map(|a| a.kb), params.lv);
    let pl = &mut params.effects.preload;
    pl.law = PreloadLaw::Weight;
    // a load that lowers each actuator by 3–10 µm at rest: Δθ = 2 Δh / Lv
    for (tau0, kb) in pl.tau0.iter_mut().zip(kb) {
        *tau0 = kb * 2.0 * between(3e-6, 10e-6) / lv;
    }
    Planted::text(format!(
        "a weight on the platform, torques {:.2e} {:.2e} {:.2e} N.m (tau0 cos theta)",
        pl.tau0[0], pl.tau0[1], pl.tau0[2]
    ))
}

/// The preload's energy H = τ0 θ, or τ0 sin θ for a weight (effects.md, "preload").
#[derive(Clone, Debug)]
pub struct Terms(Preload);

impl Law for Terms {
    type Params = Preload;

    fn new(p: &Preload, _: &mut States) -> Terms {
        Terms(*p)
    }

    #[inline]
    fn static_torque(&self, _: &[&Actuator; 3], theta: [f64; 3], i: usize, t: &mut Torque) {
        let (tau0, th) = (self.0.tau0[i], theta[i]);
        if tau0 != 0.0 {
            match self.0.law {
                PreloadLaw::Constant => t.h_t += tau0,
                PreloadLaw::Weight => {
                    t.h_t += tau0 * th.cos();
                    t.h_tt -= tau0 * th.sin();
                }
            }
        }
    }

    fn energy(&self, _: &[&Actuator; 3], x: [&[f64]; 3]) -> f64 {
        x.iter()
            .zip(self.0.tau0)
            .map(|(xi, tau0)| match self.0.law {
                PreloadLaw::Constant => tau0 * xi[THETA],
                PreloadLaw::Weight => tau0 * xi[THETA].sin(),
            })
            .sum()
    }
}
