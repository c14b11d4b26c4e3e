//! `stiffening` (src/model/effects/effects.md, "stiffening"): nonlinear stiffness of the film.

use std::f64::consts::PI;

use super::family::mean_kb;
use super::terms::{Law, States, Torque};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe};
use crate::model::Params;
use crate::model::actuator::{Actuator, THETA};
use crate::model::params::common_rows;

/// Nonlinear film stiffness: H += k3 |θ|^n / n.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stiffening {
    /// k3 [N m/rad^(n−1)].
    pub k3: f64,
    /// Library form: 4.
    pub exponent: i32,
}

impl Default for Stiffening {
    fn default() -> Self {
        Stiffening {
            k3: 0.0,
            exponent: 4,
        }
    }
}

/// Angle at which the stiffness terms are compared with Kb θ: within the stroke of actuators 2
/// and 3 [rad].
const THETA_REF: f64 = 0.012;

const FORMS: [Form; 1] = [Form::new(Effect::Stiffening, "quartic", &["k3"], &[])];

pub const FAMILY: Family = Family {
    effect: Effect::Stiffening,
    name: "stiffening",
    mechanism: "nonlinear stiffness of the film",
    form: "H += 1/4 k3 theta^4",
    forms: &FORMS,
    rows: &common_rows! {
        "k3", "N.m", NonNegative, "stiffening: coefficient k3 [N.m/rad^3] of H += 1/4 k3 theta^4 (0: off)", effects.stiffening.k3;
    },
    choices: &[],
    state: None,
    table_stages: 0,
    is_active: |p| p.stiffening.k3 != 0.0,
    on: |f| f.stiffening.k3 = 30.0,
    structures: &[],
    delays_the_command: false,
    magnitude: Magnitude::Positive,
    // a fifth of Kb θ at 15 mrad
    probes: |params, _| {
        vec![Probe::one(
            &FORMS[0],
            vec![("k3", 0.2 * mean_kb(params) / 0.015f64.powi(2))],
        )]
    },
    exposing: Exposing {
        text: "the same sine at 30 V and 60 V: stiffening grows with the stroke, not the voltage peak",
        drive: Drive::Levels {
            omega: 3.0 * PI,
            switch: 6.0,
        },
        t_end: 12.0,
    },
    hidden: fifth_power,
    variants: &[],
    law: None,
};

/// Stiffening of the fifth power.
fn fifth_power(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let kb = mean_kb(params);
    let st = &mut params.effects.stiffening;
    st.exponent = 5;
    let s = between(0.3, 0.8);
    st.k3 = s * kb / THETA_REF.powi(3);
    Planted::text(format!(
        "fifth-power stiffening H += k |theta|^5 / 5, {:.0} % of Kb theta at theta = {THETA_REF} rad",
        100.0 * s
    ))
}

/// The film's stiffening energy H = k3 |θ|ⁿ / n (effects.md, "stiffening").
#[derive(Clone, Debug)]
pub struct Terms(Stiffening);

impl Law for Terms {
    type Params = Stiffening;

    fn new(s: &Stiffening, _: &mut States) -> Terms {
        Terms(*s)
    }

    /// The torque k3 θ |θ|ⁿ⁻², odd in θ for any n.
    #[inline]
    fn static_torque(&self, _: &[&Actuator; 3], theta: [f64; 3], i: usize, t: &mut Torque) {
        let st = self.0;
        if st.k3 != 0.0 {
            let (th, n) = (theta[i], st.exponent);
            t.h_t += st.k3 * th * th.abs().powi(n - 2);
            t.h_tt += st.k3 * f64::from(n - 1) * th.abs().powi(n - 2);
        }
    }

    fn energy(&self, _: &[&Actuator; 3], x: [&[f64]; 3]) -> f64 {
        let st = self.0;
        if st.k3 == 0.0 {
            return 0.0;
        }
        x.iter()
            .map(|xi| st.k3 * xi[THETA].abs().powi(st.exponent) / f64::from(st.exponent))
            .sum()
    }
}
