//! `coupling` (src/model/effects/effects.md, "coupling"): elastic coupling of the actuators'
//! heights through the shared platform.

use std::f64::consts::PI;

use super::log_between;
use super::terms::{At, Law, States, Torque};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, Scaling};
use crate::model::Params;
use crate::model::actuator::{Actuator, P, THETA};
use crate::model::params::common_rows;
use crate::model::shell::DomainError;

/// Elastic coupling through the platform. Library form: equal weights on the three pairs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coupling {
    /// k_c [N/m]: H += ½ k_c Σ_{i<j} w_ij (h_i − h_j)².
    pub k_c: f64,
    /// Pair weights (w_12, w_13, w_23); all 1 in the library's form.
    pub weights: [f64; 3],
}

impl Default for Coupling {
    fn default() -> Self {
        Coupling {
            k_c: 0.0,
            weights: [1.0; 3],
        }
    }
}

const FORMS: [Form; 2] = [
    Form::new(Effect::Coupling, "equal", &["k_c"], &[]),
    Form::new(Effect::Coupling, "pairs", &["k_c", "w_c13", "w_c23"], &[]),
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
    },
    choices: &[],
    state: None,
    table_stages: 0,
    is_active: |p| p.coupling.k_c != 0.0,
    on: |f| {
        f.coupling.k_c = 40.0;
        f.coupling.weights = [1.0, 0.5, 1.5];
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
    variants: &[("coupling_tilt", tilt_spring)],
    law: None,
};

/// The equal pairs at k_c, and each pair alone (src/diagnose/diagnose.md, "Screening").
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
    Planted::text(format!(
        "a platform tilt spring, K_x / K_y = {ratio:.2}: pair weights {:.2?}, k_c = {:.0} N/m",
        c.weights, c.k_c
    ))
}

/// The coupling's terms: H_c = ½ k_c Σ w_ij (h_i − h_j)² (effects.md, "coupling").
#[derive(Clone, Debug)]
pub struct Terms(Coupling);

impl Law for Terms {
    type Params = Coupling;

    fn new(p: &Coupling, _: &mut States) -> Terms {
        Terms(*p)
    }

    fn links_actuators(&self) -> bool {
        self.0.k_c != 0.0
    }

    #[inline]
    fn static_torque(&self, a: &[&Actuator; 3], theta: [f64; 3], i: usize, t: &mut Torque) {
        let c = self.0;
        if c.k_c == 0.0 {
            return;
        }
        // h' = ½ Lv cos θ, h'' = −h
        let h = [0, 1, 2].map(|j| a[j].height(theta[j]));
        let s = a[i].height_slope(theta[i]);
        for j in (0..3).filter(|&j| j != i) {
            let w = c.k_c * c.weights[pair(i, j)];
            t.h_t += w * (h[i] - h[j]) * s;
            t.h_tt += w * (s * s - (h[i] - h[j]) * h[i]);
        }
    }

    #[inline]
    fn add_jacobian(
        &self,
        at: &At,
        offset: [usize; 3],
        add: &mut impl FnMut(usize, usize, f64),
    ) -> Result<(), DomainError> {
        let c = self.0;
        if c.k_c == 0.0 {
            return Ok(());
        }
        // the other blocks' θ in p_i' (its own θ is in the static torque's h_tt)
        let (i, o) = (at.i, offset[at.i]);
        let s_i = at.act().height_slope(at.x[i][THETA]);
        for j in (0..3).filter(|&j| j != i) {
            let w = c.k_c * c.weights[pair(i, j)];
            let s_j = at.a[j].height_slope(at.x[j][THETA]);
            add(o + P, offset[j] + THETA, w * s_i * s_j);
        }
        Ok(())
    }

    fn energy(&self, a: &[&Actuator; 3], x: [&[f64]; 3]) -> f64 {
        let c = self.0;
        if c.k_c == 0.0 {
            return 0.0;
        }
        let h = [0, 1, 2].map(|j| a[j].height(x[j][THETA]));
        let mut e = 0.0;
        for (i, j) in [(0, 1), (0, 2), (1, 2)] {
            e += 0.5 * c.k_c * c.weights[pair(i, j)] * (h[i] - h[j]).powi(2);
        }
        e
    }
}

/// Index of the pair (i, j) in (w_12, w_13, w_23).
fn pair(i: usize, j: usize) -> usize {
    match (i.min(j), i.max(j)) {
        (0, 1) => 0,
        (0, 2) => 1,
        _ => 2,
    }
}
