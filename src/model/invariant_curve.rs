//! An actuator's invariant curve l_p(θ) tabulated once, for the slow reduced model
//! (src/model/reduced.rs), which reads it at every evaluation, and with it the model's rate
//! θ̇ = a(θ) + b(θ) u² along the curve ([`Actuator::slow_rate`]).

use super::actuator::{Actuator, SlowRate};
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
/// time costs 64 shell geometries. The slow model's rate parts a(θ), b(θ) are tabulated at the
/// same nodes with their exact slopes along the curve and read by the same interpolant, so
/// that θ̇ costs no geometry and no trigonometry (the curve's error bound above holds for them
/// as for l_p: both are as smooth along the curve).
#[derive(Clone, Debug)]
pub(super) struct Curve {
    /// θ of the first node [rad] and 1/h, h the spacing [rad].
    theta0: f64,
    inv_h: f64,
    nodes: Vec<Node>,
}

/// What the interpolant needs at one node: each value with its slope along the curve times h
/// (the weight the cubic Hermite form gives a slope).
#[derive(Clone, Copy, Debug)]
struct Node {
    /// l_p [m] and h d, d = dl_p/dθ.
    l: f64,
    l_h: f64,
    /// The rate parts a, b of θ̇ = a + b u² ([`Actuator::slow_rate`]) and h a', h b'.
    a: f64,
    a_h: f64,
    b: f64,
    b_h: f64,
}

/// Where θ falls between two nodes: the left node k and the cubic Hermite basis on [0, 1] at
/// the fraction s, [h00, h10, h01, h11] (values at k and k + 1 weigh h00 and h01, slopes times
/// h weigh h10 and h11).
struct Between {
    k: usize,
    basis: [f64; 4],
}

impl Curve {
    /// The curve of actuator `a` with lateral film length `lv`, as far as the shell geometry
    /// goes within [`CURVE_REACH`].
    pub(super) fn new(a: &Actuator, lv: f64) -> Curve {
        let theta_star = std::f64::consts::FRAC_PI_2 / a.par.gamma2;
        let h = theta_star / CURVE_NODES_PER_THETA_STAR;
        let steps = (CURVE_REACH * CURVE_NODES_PER_THETA_STAR) as usize;
        let node = |theta: f64, l: f64| {
            let d = Shell::new(theta, l, lv).ok()?.d;
            let r: SlowRate = a.slow_rate(theta, l).ok()?;
            Some(Node {
                l,
                l_h: h * d,
                a: r.a,
                a_h: h * r.a_t,
                b: r.b,
                b_h: h * r.b_t,
            })
        };
        // march out from (0, Lp) each way until the shell geometry ends
        let march = |dir: f64| {
            let mut nodes = Vec::new();
            let mut next = a.l_p_on_curve(0.0).ok();
            for k in 0..=steps {
                let theta = dir * k as f64 * h;
                let Some(n) = next.and_then(|l| node(theta, l)) else {
                    break;
                };
                nodes.push(n);
                next = a.curve_step(theta, n.l, dir * h).ok();
            }
            nodes
        };
        let (up, down) = (march(1.0), march(-1.0));
        let below = down.len().saturating_sub(1);
        Curve {
            theta0: -(below as f64) * h,
            inv_h: 1.0 / h,
            nodes: down
                .into_iter()
                .rev()
                .chain(up.into_iter().skip(1))
                .collect(),
        }
    }

    /// Where θ falls inside the nodes, if it does.
    #[inline(always)]
    fn between(&self, theta: f64) -> Option<Between> {
        let x = (theta - self.theta0) * self.inv_h;
        // for x ≥ 0 the conversion truncates, which is the floor there, and takes an
        // instruction where `floor` is a call on the baseline x86-64 target
        if x.is_nan() || x < 0.0 {
            return None;
        }
        let k = x as usize;
        if k + 1 >= self.nodes.len() {
            return None;
        }
        let s = x - k as f64;
        let (s2, s3) = (s * s, s * s * s);
        Some(Between {
            k,
            basis: [
                2.0 * s3 - 3.0 * s2 + 1.0,
                s3 - 2.0 * s2 + s,
                -2.0 * s3 + 3.0 * s2,
                s3 - s2,
            ],
        })
    }

    /// l_p on the curve at θ: the interpolant inside the nodes, the integration from 0 outside.
    pub(super) fn l_p(&self, a: &Actuator, theta: f64) -> Result<f64, DomainError> {
        let Some(Between {
            k,
            basis: [h00, h10, h01, h11],
        }) = self.between(theta)
        else {
            return a.l_p_on_curve(theta);
        };
        let (n0, n1) = (&self.nodes[k], &self.nodes[k + 1]);
        Ok(h00 * n0.l + h10 * n0.l_h + h01 * n1.l + h11 * n1.l_h)
    }

    /// The slow model's θ̇ at θ and port voltage u [V]: the interpolant of a + b u² (values
    /// and slopes combined at the nodes first) inside them, [`Actuator::slow_rate`] at the
    /// integrated curve outside.
    #[inline]
    pub(super) fn slow_rate(&self, a: &Actuator, theta: f64, u: f64) -> Result<f64, DomainError> {
        let Some(Between {
            k,
            basis: [h00, h10, h01, h11],
        }) = self.between(theta)
        else {
            return Ok(a.slow_rate(theta, a.l_p_on_curve(theta)?)?.at(u));
        };
        let (n0, n1, u2) = (&self.nodes[k], &self.nodes[k + 1], u * u);
        Ok(h00 * (n0.a + n0.b * u2)
            + h10 * (n0.a_h + n0.b_h * u2)
            + h01 * (n1.a + n1.b * u2)
            + h11 * (n1.a_h + n1.b_h * u2))
    }
}
