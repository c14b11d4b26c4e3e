//! `coupling` (book/src/effects.md, "coupling"): elastic coupling of the actuators'
//! heights through the shared platform, a convex energy of the pairs' height differences: the
//! linear spring (the library form, of equal or of any three pair stiffnesses) and a
//! non-negative series of convex powers, which holds any hardening of the platform's tilt
//! spring from a Duffing spring's to a strain limit's.

use std::f64::consts::PI;

use super::convex::{Hardening, power_force, series, sum, weights_text};
use super::family::{FittedLaw, TextbookForm, golden, sampled, scaled_to};
use super::log_between;
use super::terms::{At, Law, States, Torque};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, Scaling};
use crate::model::Params;
use crate::model::actuator::{Actuator, P, THETA};
use crate::model::params::common_rows;
use crate::model::shell::DomainError;

/// The series' powers: the linear spring's, and harder ones up to a strain limit's wall.
pub const POWERS: [i32; 4] = [2, 4, 6, 8];

/// The series' weights, rows of the parameter table, one per power of [`POWERS`].
const SERIES_NAMES: [&str; 4] = ["k_c2", "k_c4", "k_c6", "k_c8"];

/// Height difference at which a weight of the series is its power's secant stiffness: within
/// the pairs' reach (up to about 85 µm in the paper's 60 V experiment) [m].
const D_REF: f64 = 50e-6;

/// The pairs (i, j) in the order of the pair weights (w_12, w_13, w_23).
const PAIRS: [(usize, usize); 3] = [(0, 1), (0, 2), (1, 2)];

/// A hardening tilt spring for synthetic data only (no row of the table reaches it): `law` of
/// the platform's tilt about one axis, measured as the height `axis · h` it lifts an anchor by.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HiddenTilt {
    pub law: Hardening,
    pub axis: [f64; 3],
}

/// Elastic coupling through the platform. Library form: equal weights on the three pairs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coupling {
    /// k_c [N/m]: H += ½ k_c Σ_{i<j} w_ij (h_i − h_j)².
    pub k_c: f64,
    /// Pair weights (w_12, w_13, w_23); all 1 in the library's form.
    pub weights: [f64; 3],
    /// The series' weights [N/m], one per power of [`POWERS`]: the secant stiffness each adds
    /// at a difference of d_ref, on every pair times its weight.
    pub series: [f64; 4],
    pub hidden: HiddenTilt,
}

impl Default for Coupling {
    fn default() -> Self {
        Coupling {
            k_c: 0.0,
            weights: [1.0; 3],
            series: [0.0; 4],
            hidden: HiddenTilt {
                law: Hardening::None,
                axis: [0.0; 3],
            },
        }
    }
}

/// An energy in the heights: its value, gradient and Hessian.
type InHeights = (f64, [f64; 3], [[f64; 3]; 3]);

impl Coupling {
    fn is_on(&self) -> bool {
        self.k_c != 0.0
            || self.series.iter().any(|&w| w > 0.0)
            || self.hidden.law != Hardening::None
    }

    /// A pair's energy, force and stiffness at the height difference d, per unit of its weight
    /// (effects.md, "coupling"): the linear spring and the series, each convex and even.
    fn pair_law(&self, d: f64) -> (f64, f64, f64) {
        let spring = (0.5 * self.k_c * d * d, self.k_c * d, self.k_c);
        sum([spring, series(&POWERS, &self.series, D_REF, d)])
    }

    /// The energy at the heights h, its gradient and Hessian: a sum of convex laws E of
    /// combinations c · h with c · 1 = 0 (the pairs' differences, the hidden tilt), each adding
    /// E(c · h), E' c and E'' c cᵀ; so the energy is convex in h and blind to a common heave.
    fn in_heights(&self, h: [f64; 3]) -> InHeights {
        let mut out: InHeights = (0.0, [0.0; 3], [[0.0; 3]; 3]);
        let mut add = |c: [f64; 3], (e, f, k): (f64, f64, f64)| {
            out.0 += e;
            for i in 0..3 {
                out.1[i] += f * c[i];
                for j in 0..3 {
                    out.2[i][j] += k * c[i] * c[j];
                }
            }
        };
        for (&(i, j), &w) in PAIRS.iter().zip(&self.weights) {
            let mut c = [0.0; 3];
            (c[i], c[j]) = (1.0, -1.0);
            let (e, f, k) = self.pair_law(h[i] - h[j]);
            add(c, (w * e, w * f, w * k));
        }
        let tilt = self.hidden;
        if tilt.law != Hardening::None {
            let a: f64 = (0..3).map(|i| tilt.axis[i] * h[i]).sum();
            add(tilt.axis, tilt.law.at(D_REF, a));
        }
        out
    }
}

const FORMS: [Form; 3] = [
    Form::new(Effect::Coupling, "equal", &["k_c"], &[]),
    Form::new(Effect::Coupling, "pairs", &["k_c", "w_c13", "w_c23"], &[]),
    Form {
        magnitudes: &SERIES_NAMES,
        ..Form::new(
            Effect::Coupling,
            "convex",
            &["k_c2", "k_c4", "k_c6", "k_c8", "w_c13", "w_c23"],
            &[],
        )
    },
];

pub const FAMILY: Family = Family {
    effect: Effect::Coupling,
    name: "coupling",
    mechanism: "elastic coupling of the actuators through the shared platform",
    form: "H += 1/2 k_c sum_{i<j} (h_i - h_j)^2",
    forms: &FORMS,
    rows: &common_rows! {
        "k_c", "N/m", NonNegative, "coupling: stiffness k_c of H += 1/2 k_c sum_{i<j} w_ij (h_i - h_j)^2 (0: off)", effects.coupling.k_c;
        "w_c12", "1", NonNegative, "coupling: weight w_12 of the pair (1, 2) (1: the equal pairs)", effects.coupling.weights[0];
        "w_c13", "1", NonNegative, "coupling: weight w_13 of the pair (1, 3) (1: the equal pairs)", effects.coupling.weights[1];
        "w_c23", "1", NonNegative, "coupling: weight w_23 of the pair (2, 3) (1: the equal pairs)", effects.coupling.weights[2];
        "k_c2", "N/m", Weight, "coupling: weight of the convex series' 2nd power (a linear spring) on every pair times w_ij, its stiffness (0: off)", effects.coupling.series[0];
        "k_c4", "N/m", Weight, "coupling: weight of the convex series' 4th power on every pair times w_ij, the secant stiffness it adds at h_i - h_j = 50 um (0: off)", effects.coupling.series[1];
        "k_c6", "N/m", Weight, "coupling: weight of the convex series' 6th power on every pair times w_ij, the secant stiffness it adds at h_i - h_j = 50 um (0: off)", effects.coupling.series[2];
        "k_c8", "N/m", Weight, "coupling: weight of the convex series' 8th power on every pair times w_ij, the secant stiffness it adds at h_i - h_j = 50 um (0: off)", effects.coupling.series[3];
    },
    choices: &[],
    state: None,
    table_stages: 0,
    is_active: |p| p.coupling.is_on(),
    on: |f| {
        f.coupling.k_c = 40.0;
        f.coupling.weights = [1.0, 0.5, 1.5];
        f.coupling.series = [40.0; 4];
    },
    structures: &[],
    delays_the_command: false,
    magnitude: Magnitude::Positive,
    probes,
    exposing: Exposing {
        text: "driving one actuator alone: coupling moves the undriven ones",
        drive: Drive::Alone { omega: 3.0 * PI },
        t_end: 6.0,
    },
    hidden: unequal_pairs,
    variants: &[
        ("coupling_tilt", tilt_spring),
        ("coupling_hardening_tilt", hardening_tilt),
    ],
    law: |p, _| Some(law(p)),
};

/// The equal pairs at k_c, each pair alone, and the series, one column per power at the same
/// stiffness at d_ref (book/src/diagnose.md, "Screening").
fn probes(_: &Params, _: f64) -> Vec<Probe> {
    let pairs = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    vec![
        Probe::one(&FORMS[0], vec![("k_c", 1000.0)]),
        Probe {
            form: &FORMS[1],
            columns: pairs
                .iter()
                .map(|w| {
                    vec![
                        ("k_c", 1000.0),
                        ("w_c12", w[0]),
                        ("w_c13", w[1]),
                        ("w_c23", w[2]),
                    ]
                })
                .collect(),
            scaling: Scaling::Pairs,
        },
        Probe {
            form: &FORMS[2],
            columns: SERIES_NAMES.iter().map(|&n| vec![(n, 1000.0)]).collect(),
            scaling: Scaling::Weights,
        },
    ]
}

/// Coupling with unequal pair weights.
fn unequal_pairs(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let c = &mut params.effects.coupling;
    c.k_c = log_between(between, 800.0, 3000.0);
    let k = (between(0.0, 3.0) as usize).min(2);
    c.weights = [[0.5, 1.0, 1.5], [1.5, 0.5, 1.0], [1.0, 1.5, 0.5]][k];
    Planted::text(format!(
        "coupling k_c = {:.0} N/m with unequal pair weights {:?}",
        c.k_c, c.weights
    ))
}

/// A platform tilt spring stiffer about one axis (effects.md, "coupling", "Forms").
fn tilt_spring(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    tilt_spring_axis(params, between).0
}

/// The tilt spring of [`tilt_spring`], its stiffer axis (the tilt about it in heights, as
/// `HiddenTilt::axis`) and that axis' stiffness K / r² [N/m].
fn tilt_spring_axis(
    params: &mut Params,
    between: &mut dyn FnMut(f64, f64) -> f64,
) -> (Planted, [f64; 3], f64) {
    // a tilt spring H = 1/2 (K_x phi_x^2 + K_y phi_y^2), stiffer about one axis; with
    // the anchors at 90, 210 and 330 degrees, phi_x = (h3 - h2) / (sqrt 3 r) and
    // phi_y = (h1 - (h2 + h3)/2) / (1.5 r), so (in units of K_y / r^2)
    // w_12 = w_13 = 2/9 and w_23 = K_x/(3 K_y) - 1/9 (positive for K_x > K_y / 3)
    let ratio = if between(0.0, 1.0) < 0.5 {
        between(1.6, 2.5)
    } else {
        1.0 / between(1.6, 2.5)
    };
    let w = [2.0 / 9.0, 2.0 / 9.0, ratio / 3.0 - 1.0 / 9.0];
    let mean = w.iter().sum::<f64>() / 3.0;
    let c = &mut params.effects.coupling;
    c.weights = w.map(|x| x / mean);
    c.k_c = log_between(between, 800.0, 3000.0);
    // the tilts in heights, r phi: K_y / r^2 is k_c / mean; the stiffer axis' tilt and stiffness
    let k_y = c.k_c / mean;
    let (axis, k) = if ratio > 1.0 {
        ([0.0, -1.0, 1.0].map(|x| x / 3f64.sqrt()), ratio * k_y)
    } else {
        ([2.0, -1.0, -1.0].map(|x| x / 3.0), k_y)
    };
    let planted = Planted::text(format!(
        "a platform tilt spring, K_x / K_y = {ratio:.2}: pair weights {:.2?}, k_c = {:.0} N/m",
        c.weights, c.k_c
    ));
    (planted, axis, k)
}

/// A tilt spring that hardens about its stiffer axis in a law drawn at random from outside
/// the series (`Hardening::random`: a power of any real exponent in [3, 10], or exponential
/// hardening of scale 20–50 µm), adding 0.5 to 1.5 times that axis' stiffness at d_ref.
fn hardening_tilt(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let (spring, axis, k) = tilt_spring_axis(params, between);
    let s = between(0.5, 1.5);
    let (law, text) = Hardening::random(
        between,
        s * k,
        D_REF,
        (0.4 * D_REF, D_REF),
        "a",
        ("um", 1e-6),
    );
    params.effects.coupling.hidden = HiddenTilt { law, axis };
    Planted::text(format!(
        "{}, hardening about its stiffer axis (tilt a lifting an anchor by a) as {text}, adding {:.0} % of its stiffness at a = {:.0} um",
        spring.text,
        100.0 * s,
        D_REF * 1e6
    ))
}

/// The fitted force of a pair of unit weight against its height difference over ±2 d_ref,
/// beside the textbook springs fitted to it (book/src/diagnose.md, "The fitted law"): the
/// linear spring k d, Duffing's k d (1 + (d/d_s)²), a power law k d_ref |d/d_ref|ⁿ⁻¹ of free
/// exponent, and exponential hardening k d_s sinh(d/d_s).
fn law(params: &Params) -> FittedLaw {
    let c = params.effects.coupling;
    let reach = 2.0 * D_REF;
    let curve = sampled(-reach, reach, |d| c.pair_law(d).1);
    let scaled = |g: &dyn Fn(f64) -> f64| scaled_to(&curve, g);
    let linear = |d: f64| d;
    let duffing = |s: f64| move |d: f64| d * (1.0 + (d / s).powi(2));
    let power = |n: f64| power_force(D_REF, n);
    let exponential = |s: f64| move |d: f64| s * (d / s).sinh();
    let (k, _) = scaled(&linear);
    let ds = golden(0.05 * D_REF, 100.0 * D_REF, |s| scaled(&duffing(s)).1);
    let (kd, _) = scaled(&duffing(ds));
    let n = golden(1.5, 20.0, |n| scaled(&power(n)).1);
    let (kn, _) = scaled(&power(n));
    let es = golden(0.05 * D_REF, 100.0 * D_REF, |s| scaled(&exponential(s)).1);
    let (ke, _) = scaled(&exponential(es));
    let text = format!(
        "force of a pair of unit weight (pair weights {:.2?}): k_c {:.0} N/m, series weights {} N/m",
        c.weights,
        c.k_c,
        weights_text(&POWERS, &c.series, 0)
    );
    let um = |x: f64| 1e6 * x;
    let forms: Vec<TextbookForm> = vec![
        (
            "linear spring",
            format!("k = {k:.0} N/m"),
            Box::new(move |d| k * linear(d)),
        ),
        (
            "Duffing spring",
            format!("k = {kd:.0} N/m, doubling at d_s = {:.1} um", um(ds)),
            Box::new(move |d| kd * duffing(ds)(d)),
        ),
        (
            "power law",
            format!("n = {n:.2}, k = {kn:.0} N/m at d = {:.0} um", um(D_REF)),
            Box::new(move |d| kn * power(n)(d)),
        ),
        (
            "exponential hardening",
            format!("d_s = {:.1} um, k = {ke:.0} N/m", um(es)),
            Box::new(move |d| ke * exponential(es)(d)),
        ),
    ];
    FittedLaw::of_curve(text, ["h_i - h_j [m]", "force [N]"], curve, forms)
}

/// The coupling's terms: H_c, convex in the heights (effects.md, "coupling").
#[derive(Clone, Debug)]
pub struct Terms(Coupling);

/// The heights of the three actuators at angles θ.
fn heights(a: &[&Actuator; 3], theta: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|j| a[j].height(theta[j]))
}

impl Law for Terms {
    type Params = Coupling;

    fn new(p: &Coupling, _: &mut States) -> Terms {
        Terms(*p)
    }

    fn links_actuators(&self) -> bool {
        self.0.is_on()
    }

    /// ∂H/∂θ_i = g_i h_i' and its slope G_ii h_i'² + g_i h_i'' (g, G: the energy's gradient
    /// and Hessian in the heights; h' = ½ Lv cos θ, h'' = −h).
    #[inline]
    fn static_torque(&self, a: &[&Actuator; 3], theta: [f64; 3], i: usize, t: &mut Torque) {
        if !self.0.is_on() {
            return;
        }
        let h = heights(a, theta);
        let (_, g, hess) = self.0.in_heights(h);
        let s = a[i].height_slope(theta[i]);
        t.h_t += g[i] * s;
        t.h_tt += hess[i][i] * s * s - g[i] * h[i];
    }

    #[inline]
    fn add_jacobian(
        &self,
        at: &At,
        offset: [usize; 3],
        add: &mut impl FnMut(usize, usize, f64),
    ) -> Result<(), DomainError> {
        if !self.0.is_on() {
            return Ok(());
        }
        // the other blocks' θ in p_i' = −∂H/∂θ_i (its own θ is in the static torque's h_tt)
        let (i, o) = (at.i, offset[at.i]);
        let theta = [0, 1, 2].map(|j| at.x[j][THETA]);
        let (_, _, hess) = self.0.in_heights(heights(at.a, theta));
        let s = [0, 1, 2].map(|j| at.a[j].height_slope(theta[j]));
        for j in (0..3).filter(|&j| j != i) {
            add(o + P, offset[j] + THETA, -hess[i][j] * s[i] * s[j]);
        }
        Ok(())
    }

    fn energy(&self, a: &[&Actuator; 3], x: [&[f64]; 3]) -> f64 {
        if !self.0.is_on() {
            return 0.0;
        }
        self.0.in_heights(heights(a, x.map(|xi| xi[THETA]))).0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::actuator;
    use crate::model::effects::terms::Port;

    /// Every form on at once, with a hidden hardening tilt of each law.
    fn every_form() -> [Coupling; 2] {
        let c = Coupling {
            k_c: 900.0,
            weights: [1.0, 0.5, 1.5],
            series: [300.0, 0.0, 800.0, 200.0],
            ..Coupling::default()
        };
        let axis = [0.0, -1.0, 1.0].map(|x: f64| x / 3f64.sqrt());
        [
            Hardening::Power { k: 2000.0, n: 4.6 },
            Hardening::Exponential {
                k: 500.0,
                x_s: 3e-5,
            },
        ]
        .map(|law| Coupling {
            hidden: HiddenTilt { law, axis },
            ..c
        })
    }

    /// Heights within the pairs' reach, no two alike.
    fn heights_at(k: usize) -> [f64; 3] {
        let x = k as f64;
        [
            (0.7 * x).sin(),
            (1.3 * x + 1.0).sin(),
            (2.1 * x + 2.0).sin(),
        ]
        .map(|s| 9e-5 * s)
    }

    /// The energy is convex in the heights (its Hessian positive semi-definite, the midpoint
    /// below the chord) and blind to a common heave; its gradient and Hessian are its
    /// derivatives by finite differences.
    #[test]
    fn the_energy_is_convex_and_its_derivatives_exact() {
        for c in every_form() {
            for k in 0..40 {
                let (h, v) = (heights_at(k), heights_at(k + 100));
                let (e, g, hess) = c.in_heights(h);
                let vhv: f64 = (0..3)
                    .flat_map(|i| (0..3).map(move |j| (i, j)))
                    .map(|(i, j)| v[i] * hess[i][j] * v[j])
                    .sum();
                assert!(vhv >= 0.0, "{vhv}");
                let mid = c.in_heights([0, 1, 2].map(|i| 0.5 * (h[i] + v[i]))).0;
                assert!(mid <= 0.5 * (e + c.in_heights(v).0) * (1.0 + 1e-12));
                let heave = c.in_heights(h.map(|x| x + 3e-5)).0;
                assert!((heave - e).abs() <= 1e-12 * e, "{heave} {e}");
                for i in 0..3 {
                    let dh = 1e-9;
                    let at = |x: f64| {
                        let mut h = h;
                        h[i] += x;
                        c.in_heights(h)
                    };
                    let (up, down) = (at(dh), at(-dh));
                    let fd = (up.0 - down.0) / (2.0 * dh);
                    assert!(
                        (fd - g[i]).abs() <= 1e-6 * (1.0 + g[i].abs()),
                        "{fd} {}",
                        g[i]
                    );
                    for (j, &want) in hess[i].iter().enumerate() {
                        let fd = (up.1[j] - down.1[j]) / (2.0 * dh);
                        assert!(
                            (fd - want).abs() <= 1e-5 * (1.0 + want.abs()),
                            "{fd} {want}"
                        );
                    }
                }
            }
        }
    }

    /// The terms' torque is ∂H/∂θ_i, its slope and the Jacobian's entries across the blocks
    /// the derivatives of the torque by finite differences.
    #[test]
    fn torque_and_jacobian_are_the_energys_derivatives() {
        let params = Params::default();
        let acts = [0, 1, 2].map(|i| Actuator::new(&params, i));
        let a = [&acts[0], &acts[1], &acts[2]];
        for c in every_form() {
            let terms = Terms::new(&c, &mut States::default());
            for k in 0..20 {
                let theta = heights_at(k).map(|h| h / 0.006 + 0.01);
                let energy = |theta: [f64; 3]| {
                    let x = theta.map(|t| {
                        let mut xi = [0.0; actuator::N];
                        xi[THETA] = t;
                        xi
                    });
                    terms.energy(&a, [&x[0], &x[1], &x[2]])
                };
                let torque = |theta: [f64; 3], i: usize| {
                    let mut t = Torque::default();
                    terms.static_torque(&a, theta, i, &mut t);
                    t
                };
                let shifted = |i: usize, d: f64| {
                    let mut t = theta;
                    t[i] += d;
                    t
                };
                let d = 1e-7;
                for i in 0..3 {
                    let t = torque(theta, i);
                    let fd = (energy(shifted(i, d)) - energy(shifted(i, -d))) / (2.0 * d);
                    assert!(
                        (fd - t.h_t).abs() <= 1e-6 * (1e-6 + t.h_t.abs()),
                        "{fd} {}",
                        t.h_t
                    );
                    // the Jacobian's row p_i: −∂(torque_i)/∂θ_j
                    let x = theta.map(|t| {
                        let mut xi = [0.0; actuator::N];
                        xi[THETA] = t;
                        xi
                    });
                    let at = At {
                        a: &a,
                        x: [&x[0], &x[1], &x[2]],
                        u: 0.0,
                        i,
                        port: Port {
                            u_eff: 0.0,
                            slope: 1.0,
                            column: None,
                        },
                    };
                    let n = actuator::N;
                    let mut row = [0.0; 3];
                    row[i] = -t.h_tt;
                    let add = &mut |r: usize, col: usize, v: f64| {
                        assert_eq!(r, i * n + P);
                        row[col / n] += v;
                        assert_eq!(col % n, THETA);
                    };
                    terms.add_jacobian(&at, [0, n, 2 * n], add).unwrap();
                    for (j, &entry) in row.iter().enumerate() {
                        let up = torque(shifted(j, d), i).h_t;
                        let fd = -(up - torque(shifted(j, -d), i).h_t) / (2.0 * d);
                        let scale = 1e-6 * (1e-3 + entry.abs());
                        assert!((fd - entry).abs() <= scale, "{i},{j}: {fd} {entry}");
                    }
                }
            }
        }
    }

    /// The law of a pure linear spring is nearest the linear spring, at its stiffness; a
    /// strong sixth power's is not.
    #[test]
    fn the_law_names_a_linear_spring_and_a_hardening_one() {
        let mut p = Params::default();
        p.effects.coupling.series[0] = 1500.0;
        let linear = law(&p);
        let nearest = &linear.textbook[linear.nearest];
        assert_eq!(nearest.name, "linear spring", "{linear:?}");
        assert_eq!(nearest.values, "k = 1500 N/m", "{linear:?}");
        assert!(nearest.distance < 1e-9, "{linear:?}");
        p.effects.coupling.series[2] = 3000.0;
        let hard = law(&p);
        assert_ne!(
            hard.textbook[hard.nearest].name, "linear spring",
            "{hard:?}"
        );
    }
}
