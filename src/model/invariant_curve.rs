//! An actuator's invariant curve l_p(θ) tabulated once, for the slow reduced model
//! (src/model/reduced.rs), which reads it at every evaluation.

use super::actuator::Actuator;
use super::shell::{DomainError, Shell};

/// Nodes of a [`Curve`] per θ* = π/(2γ2) (where the input gain vanishes): h = θ*/256 makes the
/// cubic's error (h⁴/384 · d⁴l_p/dθ⁴) a rounding of l_p.
const CURVE_NODES_PER_THETA_STAR: f64 = 256.0;

/// How far the [`Curve`] reaches on either side of θ = 0, in θ*: past the angle the electrode
/// can hold; beyond it [`Actuator::l_p_on_curve`] integrates the curve from 0 each time.
const CURVE_REACH: f64 = 2.0;

/// An actuator's invariant curve l_p(θ) through (0, Lp) (model.md, "Initial state"), tabulated
/// once at nodes h apart by the same RK4 steps as [`Actuator::l_p_on_curve`], marching from 0,
/// with its exact slopes d(θ, l_p) there, and read between them by the cubic Hermite
/// interpolant: the slow model reads l_p at every evaluation, where integrating from 0 each
/// time costs 64 shell geometries.
#[derive(Clone, Debug)]
pub(super) struct Curve {
    /// θ of the first node [rad] and the spacing h [rad].
    theta0: f64,
    h: f64,
    /// l_p [m] and d = dl_p/dθ [m/rad] at the nodes.
    l: Vec<f64>,
    d: Vec<f64>,
}

impl Curve {
    /// The curve of actuator `a` with lateral film length `lv`, as far as the shell geometry
    /// goes within [`CURVE_REACH`].
    pub(super) fn new(a: &Actuator, lv: f64) -> Curve {
        let theta_star = std::f64::consts::FRAC_PI_2 / a.par.gamma2;
        let h = theta_star / CURVE_NODES_PER_THETA_STAR;
        let steps = (CURVE_REACH * CURVE_NODES_PER_THETA_STAR) as usize;
        let node = |theta: f64, l: f64| Shell::new(theta, l, lv).ok().map(|s| (l, s.d));
        // march out from (0, Lp) each way until the shell geometry ends
        let march = |dir: f64| {
            let mut nodes = Vec::new();
            let mut next = a.l_p_on_curve(0.0).ok();
            for k in 0..=steps {
                let theta = dir * k as f64 * h;
                let Some((l, d)) = next.and_then(|l| node(theta, l)) else {
                    break;
                };
                nodes.push((l, d));
                next = a.curve_step(theta, l, dir * h).ok();
            }
            nodes
        };
        let (up, down) = (march(1.0), march(-1.0));
        let below = down.len().saturating_sub(1);
        let nodes: Vec<(f64, f64)> = down
            .into_iter()
            .rev()
            .chain(up.into_iter().skip(1))
            .collect();
        Curve {
            theta0: -(below as f64) * h,
            h,
            l: nodes.iter().map(|n| n.0).collect(),
            d: nodes.iter().map(|n| n.1).collect(),
        }
    }

    /// l_p on the curve at θ: the interpolant inside the nodes, the integration from 0 outside.
    pub(super) fn l_p(&self, a: &Actuator, theta: f64) -> Result<f64, DomainError> {
        let x = (theta - self.theta0) / self.h;
        let k = x.floor();
        if !(k >= 0.0 && (k as usize) + 1 < self.l.len()) {
            return a.l_p_on_curve(theta);
        }
        let (k, s) = (k as usize, x - k);
        // cubic Hermite basis on [0, 1]
        let (s2, s3) = (s * s, s * s * s);
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        Ok(h00 * self.l[k]
            + h10 * self.h * self.d[k]
            + h01 * self.l[k + 1]
            + h11 * self.h * self.d[k + 1])
    }
}
