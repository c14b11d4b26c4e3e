//! `stiffening` (book/src/effects.md, "stiffening"): nonlinear stiffness of the film,
//! a convex energy added to the bending spring: the quartic (the library form) and a
//! non-negative series of convex powers, which holds any hardening from gentle to a strain
//! limit's.

use std::f64::consts::PI;

use super::convex::{Hardening, power_force, series, sum, weights_text};
use super::family::{FittedLaw, TextbookForm, golden, mean_kb, sampled, scaled_to};
use super::terms::{Law, States, Torque};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, Scaling};
use crate::model::Params;
use crate::model::actuator::{Actuator, THETA};
use crate::model::params::common_rows;

/// The series' powers: the quartic's, and steeper ones up to a strain limit's wall.
pub const POWERS: [i32; 4] = [4, 6, 8, 12];

/// The series' weights, rows of the parameter table, one per power of [`POWERS`].
const SERIES_NAMES: [&str; 4] = ["k_s4", "k_s6", "k_s8", "k_s12"];

/// Angle at which the stiffness terms are compared with Kb θ: within the stroke of actuators 2
/// and 3 [rad]. A weight of the series is the extra stiffness its power adds there.
const THETA_REF: f64 = 0.012;

/// Nonlinear film stiffness: H += k3 θ⁴/4 + Σ_n w_n θ_ref² |θ/θ_ref|ⁿ / n (+ a synthetic law).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stiffening {
    /// k3 [N m/rad³] of the quartic.
    pub k3: f64,
    /// The series' weights w_n [N m/rad], one per power of [`POWERS`]: the stiffness each adds
    /// at θ_ref.
    pub series: [f64; 4],
    pub hidden: Hardening,
}

impl Default for Stiffening {
    fn default() -> Self {
        Stiffening {
            k3: 0.0,
            series: [0.0; 4],
            hidden: Hardening::None,
        }
    }
}

impl Stiffening {
    fn is_on(&self) -> bool {
        self.k3 != 0.0 || self.series.iter().any(|&w| w > 0.0) || self.hidden != Hardening::None
    }

    /// The added energy, its torque dH/dθ and stiffness d²H/dθ² at θ (effects.md,
    /// "stiffening"): each term convex and even, so the torque is odd and monotone.
    fn energy_torque_stiffness(&self, theta: f64) -> (f64, f64, f64) {
        let a = theta.abs();
        let quartic = (
            0.25 * self.k3 * a.powi(4),
            self.k3 * theta.powi(3),
            3.0 * self.k3 * theta * theta,
        );
        sum([
            quartic,
            series(&POWERS, &self.series, THETA_REF, theta),
            self.hidden.at(THETA_REF, theta),
        ])
    }
}

const FORMS: [Form; 2] = [
    Form::new(Effect::Stiffening, "quartic", &["k3"], &[]),
    Form {
        magnitudes: &SERIES_NAMES,
        ..Form::new(Effect::Stiffening, "convex", &SERIES_NAMES, &[])
    },
];

pub const FAMILY: Family = Family {
    effect: Effect::Stiffening,
    name: "stiffening",
    mechanism: "nonlinear stiffness of the film",
    form: "H += 1/4 k3 theta^4",
    forms: &FORMS,
    rows: &common_rows! {
        "k3", "N.m", NonNegative, "stiffening: coefficient k3 [N.m/rad^3] of H += 1/4 k3 theta^4 (0: off)", effects.stiffening.k3;
        "k_s4", "N.m/rad", Weight, "stiffening: weight of the convex series' 4th power, the stiffness it adds at theta = 0.012 rad (0: off)", effects.stiffening.series[0];
        "k_s6", "N.m/rad", Weight, "stiffening: weight of the convex series' 6th power, the stiffness it adds at theta = 0.012 rad (0: off)", effects.stiffening.series[1];
        "k_s8", "N.m/rad", Weight, "stiffening: weight of the convex series' 8th power, the stiffness it adds at theta = 0.012 rad (0: off)", effects.stiffening.series[2];
        "k_s12", "N.m/rad", Weight, "stiffening: weight of the convex series' 12th power, the stiffness it adds at theta = 0.012 rad (0: off)", effects.stiffening.series[3];
    },
    choices: &[],
    state: None,
    table_stages: 0,
    is_active: |p| p.stiffening.is_on(),
    on: |f| {
        f.stiffening.k3 = 30.0;
        f.stiffening.series = [0.01; 4];
    },
    structures: &[],
    delays_the_command: false,
    magnitude: Magnitude::Positive,
    probes,
    exposing: Exposing {
        text: "the same sine at 30 V and 60 V: stiffening grows with the stroke, not the voltage peak",
        drive: Drive::Levels {
            omega: 3.0 * PI,
            switch: 6.0,
        },
        t_end: 12.0,
    },
    hidden: fifth_power,
    variants: &[("stiffening_random", random_hardening)],
    law: |p, u_peak| Some(law(p, u_peak)),
};

/// A fifth of Kb θ at 15 mrad for the quartic; the series, one column per power, each adding a
/// fifth of Kb at θ_ref (book/src/diagnose.md, "Screening").
fn probes(params: &Params, _: f64) -> Vec<Probe> {
    let kb = mean_kb(params);
    vec![
        Probe::one(&FORMS[0], vec![("k3", 0.2 * kb / 0.015f64.powi(2))]),
        Probe {
            form: &FORMS[1],
            columns: SERIES_NAMES.iter().map(|&n| vec![(n, 0.2 * kb)]).collect(),
            scaling: Scaling::Weights,
        },
    ]
}

/// Stiffening of the fifth power.
fn fifth_power(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let kb = mean_kb(params);
    let s = between(0.3, 0.8);
    params.effects.stiffening.hidden = Hardening::Power { k: s * kb, n: 5.0 };
    Planted::text(format!(
        "fifth-power stiffening H += k |theta|^5 / 5, {:.0} % of Kb theta at theta = {THETA_REF} rad",
        100.0 * s
    ))
}

/// A hardening law drawn at random from outside the series: a power of any real exponent in
/// [3, 10], or exponential hardening of scale θ_s in [5, 12] mrad; its added stiffness at θ_ref
/// 0.3 to 0.8 of Kb, as the fifth power's (weaker, an exponential hardening left the paper's
/// model within 0.2–0.4 points of the noise floor: not a mechanism the data show).
fn random_hardening(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let kb = mean_kb(params);
    let s = between(0.3, 0.8);
    let (law, text) = Hardening::random(
        between,
        s * kb,
        THETA_REF,
        (0.005, 0.012),
        "theta",
        ("mrad", 1e-3),
    );
    params.effects.stiffening.hidden = law;
    Planted::text(format!(
        "stiffening of {text}, adding {:.0} % of Kb at theta = {THETA_REF} rad",
        100.0 * s
    ))
}

/// The fitted torque dH/dθ over ±2.5 θ_ref, beside the textbook forms fitted to it
/// (book/src/diagnose.md, "The fitted law"): the quartic k3 θ³, a power k θ_ref |θ/θ_ref|ⁿ⁻¹
/// of free exponent, and exponential hardening.
fn law(params: &Params, _: f64) -> FittedLaw {
    let st = params.effects.stiffening;
    let reach = 2.5 * THETA_REF;
    let curve = sampled(-reach, reach, |th| st.energy_torque_stiffness(th).1);
    let scaled = |g: &dyn Fn(f64) -> f64| scaled_to(&curve, g);
    let cube = |th: f64| th.powi(3);
    let power = |n: f64| power_force(THETA_REF, n);
    let exponential = |s: f64| move |th: f64| s * ((th / s).sinh() - th / s);
    let (k3, _) = scaled(&cube);
    let n = golden(3.0, 20.0, |n| scaled(&power(n)).1);
    let (kn, _) = scaled(&power(n));
    let s = golden(0.002, 0.1, |s| scaled(&exponential(s)).1);
    let (ks, _) = scaled(&exponential(s));
    let text = format!(
        "added torque dH/dtheta: k3 {:.3e} N.m/rad^3, series weights {} N.m/rad",
        st.k3,
        weights_text(&POWERS, &st.series, 3)
    );
    let forms: Vec<TextbookForm> = vec![
        (
            "quartic",
            format!("k3 = {k3:.3e} N.m/rad^3"),
            Box::new(move |th| k3 * cube(th)),
        ),
        (
            "power law",
            format!("n = {n:.2}, adding {kn:.3} N.m/rad at theta = {THETA_REF} rad"),
            Box::new(move |th| kn * power(n)(th)),
        ),
        (
            "exponential hardening",
            format!("theta_s = {:.2} mrad, k = {ks:.3} N.m/rad", 1000.0 * s),
            Box::new(move |th| ks * exponential(s)(th)),
        ),
    ];
    FittedLaw::of_curve(text, ["theta [rad]", "dH/dtheta [N.m]"], curve, forms)
}

/// The film's added energy (effects.md, "stiffening").
#[derive(Clone, Debug)]
pub struct Terms(Stiffening);

impl Law for Terms {
    type Params = Stiffening;

    fn new(s: &Stiffening, _: &mut States) -> Terms {
        Terms(*s)
    }

    /// The torque dH/dθ and its slope, odd and monotone in θ.
    #[inline]
    fn static_torque(&self, _: &[&Actuator; 3], theta: [f64; 3], i: usize, t: &mut Torque) {
        if self.0.is_on() {
            let (_, torque, stiffness) = self.0.energy_torque_stiffness(theta[i]);
            t.h_t += torque;
            t.h_tt += stiffness;
        }
    }

    fn energy(&self, _: &[&Actuator; 3], x: [&[f64]; 3]) -> f64 {
        if !self.0.is_on() {
            return 0.0;
        }
        x.iter()
            .map(|xi| self.0.energy_torque_stiffness(xi[THETA]).0)
            .sum()
    }
}
