//! The equilibrium under constant voltages U (book/src/control.md, "Equilibrium").
//!
//! θ and l_p of an actuator are tied by l̇_p = d θ̇ (model.md, "Dynamics"): c(θ, l_p) with
//! ∂c/∂θ + d ∂c/∂l_p = 0 is a Casimir of J, so each trajectory stays on one invariant curve and
//! the equilibria form a one-parameter family per actuator. The equilibrium wanted is the one on
//! the curve through the rest state (model.md, "Open choices and pinned defaults": (θ, l_p) on the curve
//! dl_p/dθ = d through (0, Lp)), found by Newton on the reduced equations:
//!
//! - per actuator the unknown is θ; l_p = ℓ(θ) on the curve ([`Actuator::l_p_on_curve`]),
//!   p = 0 (so θ̇ = l̇_p = 0);
//! - the charges (and the effects' circuit, creep and amplifier states) solve their own
//!   equations at that geometry, which are linear in them: the DC circuit, V1 = R1 i,
//!   V2 = R2 i, i = ga(θ) U / (R0 + R1 + R2) for the paper's model;
//! - the remaining equation ṗ = −(∂H/∂θ + d ∂H/∂l_p) − b ∂H/∂p = 0 is solved for θ, with its
//!   derivative along the curve from the analytic Jacobian (the implicit-function theorem
//!   for the charges: ∂x_e/∂θ = −A_ee⁻¹ A_e,geometry ∂x_geometry/∂θ).
//!
//! If Newton from the rest state does not reach U directly, the branch is continued in U from
//! 0 V; it is accepted only where the reduced stiffness −∂ṗ/∂θ along the curve is positive
//! definite (the branch through the rest state, stable), so a fold (pull-in) or the end of the
//! geometry's domain ends the continuation with a typed error.
//!
//! [`Actuator::l_p_on_curve`]: crate::model::actuator::Actuator::l_p_on_curve

use nalgebra::{DMatrix, Matrix3, Vector3};

use super::{ControlError, NoEquilibrium};
use crate::model::Effect;
use crate::model::actuator::{self, L_P, P, Q1, Q2, THETA};
use crate::model::shell::Shell;
use crate::model::{ModelError, Platform};

/// An equilibrium on the branch through the rest state.
#[derive(Clone, Debug, PartialEq)]
pub struct Equilibrium {
    /// The constant voltages \[V\].
    pub u: [f64; 3],
    /// The state x0 with f(x0, U) = 0.
    pub x: Vec<f64>,
    /// max_r |f_r(x0, U)| / (the sum of the magnitudes of the terms of row r).
    pub residual: f64,
    /// Newton iterations, all continuation steps together.
    pub iterations: usize,
    /// Continuation steps in U (1: Newton reached U directly from the rest state).
    pub steps: usize,
    /// The reduced stiffness K = −∂ṗ_i/∂θ_j along the invariant curves [N m/rad], positive
    /// definite on the stable branch.
    pub stiffness: [[f64; 3]; 3],
}

/// Largest number of Newton iterations per solve.
const NEWTON_ITERATIONS: usize = 40;
/// Smallest continuation step, as a fraction of U.
const MIN_STEP: f64 = 1e-12;
/// Largest move of the corrector away from the predictor in one continuation step, as a
/// fraction of θ* = π/(2γ2) (where the input gain ga vanishes).
const MAX_CORRECTION: f64 = 0.05;

/// The equilibrium under the constant voltages `u` on the branch through the rest state.
pub fn equilibrium(model: &Platform, u: [f64; 3]) -> Result<Equilibrium, ControlError> {
    for (input, &value) in u.iter().enumerate() {
        if !value.is_finite() {
            return Err(ControlError::BadVoltage { input, value });
        }
    }
    let solver = Reduced::new(model)?;
    let theta_rest = solver.theta_rest;
    let (mut s, mut theta, mut ds) = (0.0f64, theta_rest, 1.0f64);
    let mut previous: Option<(f64, [f64; 3])> = None;
    let mut last = None;
    let (mut iterations, mut steps) = (0, 0);
    let mut failure;
    let mut failed_actuator = 1;
    while s < 1.0 {
        let s_try = (s + ds).min(1.0);
        // secant predictor from the last two points of the branch
        let guess = match previous {
            Some((s0, t0)) => {
                [0, 1, 2].map(|i| theta[i] + (theta[i] - t0[i]) * (s_try - s) / (s - s0))
            }
            None => theta,
        };
        let u_try = u.map(|v| v * s_try);
        match solver.newton(guess, u_try) {
            Ok(sol) => {
                iterations += sol.iterations;
                let k_min = min_stiffness(&sol.stiffness);
                // a corrector that moves far from the predictor may have jumped to another
                // branch (the gain ga(θ) = γ1 cos(γ2 θ) makes the force periodic in θ, so
                // stable branches repeat beyond θ* = π/(2γ2)): take a smaller step instead
                let jumps =
                    [0, 1, 2].map(|i| (sol.theta[i] - guess[i]).abs() / solver.theta_star[i]);
                let (far, jump) = (0..3)
                    .map(|i| (i, jumps[i]))
                    .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
                if jump > MAX_CORRECTION {
                    failure = NoEquilibrium::NotConverged;
                    failed_actuator = far + 1;
                } else if k_min > 0.0 {
                    previous = Some((s, theta));
                    (s, theta) = (s_try, sol.theta);
                    last = Some(sol);
                    steps += 1;
                    ds = (2.0 * ds).min(1.0);
                    continue;
                } else {
                    failure = NoEquilibrium::PullIn { stiffness: k_min };
                    failed_actuator = weakest(&sol.stiffness);
                }
            }
            Err(Failure::Model(e)) => {
                failed_actuator = e.actuator;
                failure = NoEquilibrium::Domain(e.cause);
            }
            Err(Failure::NotConverged(it)) => {
                iterations += it;
                failure = NoEquilibrium::NotConverged;
            }
        }
        ds *= 0.25;
        if ds < MIN_STEP {
            if let (NoEquilibrium::NotConverged, Some(sol)) = (&failure, &last) {
                // the branch ends where its stiffness vanishes: report how close it came
                let k = min_stiffness(&sol.stiffness);
                failed_actuator = weakest(&sol.stiffness);
                if k < 1e-3 * solver.stiffness_scale {
                    failure = NoEquilibrium::PullIn { stiffness: k };
                }
            }
            return Err(ControlError::NoEquilibrium {
                actuator: failed_actuator,
                requested: u,
                reached: u.map(|v| v * s),
                cause: failure,
            });
        }
    }
    let sol = match last {
        Some(sol) => sol,
        // U = 0: the rest state itself, polished by the same Newton
        None => solver
            .newton(theta_rest, u)
            .map_err(|_| ControlError::Numerics {
                what: "equilibrium",
                why: "Newton does not converge at the rest state",
            })?,
    };
    let residual = relative_residual(model, &sol.x, u)?;
    Ok(Equilibrium {
        u,
        x: sol.x,
        residual,
        iterations,
        steps,
        stiffness: sol.stiffness,
    })
}

/// Smallest eigenvalue of the symmetric part of the reduced stiffness.
fn min_stiffness(k: &[[f64; 3]; 3]) -> f64 {
    let m = Matrix3::from_fn(|r, c| 0.5 * (k[r][c] + k[c][r]));
    m.symmetric_eigenvalues().min()
}

/// The actuator with the smallest diagonal stiffness (1-based).
fn weakest(k: &[[f64; 3]; 3]) -> usize {
    (0..3)
        .min_by(|&a, &b| k[a][a].total_cmp(&k[b][b]))
        .unwrap_or(0)
        + 1
}

enum Failure {
    Model(ModelError),
    NotConverged(usize),
}

impl From<ModelError> for Failure {
    fn from(e: ModelError) -> Self {
        Failure::Model(e)
    }
}

/// The state at angles θ on the curves, ṗ there and ∂ṗ_i/∂θ_j along the curves.
struct Residual {
    x: Vec<f64>,
    p_dot: [f64; 3],
    dp: [[f64; 3]; 3],
}

struct Solution {
    theta: [f64; 3],
    x: Vec<f64>,
    stiffness: [[f64; 3]; 3],
    iterations: usize,
}

/// The reduced equations of one platform: which states follow θ, which solve their own
/// (linear) equations, and the rest state's angles.
struct Reduced<'m> {
    model: &'m Platform,
    /// States per actuator block.
    nb: usize,
    /// Indices (in the whole state) of the states solved at fixed geometry: the charges and
    /// the effects' circuit, creep and amplifier states.
    inner: Vec<usize>,
    /// Index of each block's hysteresis state, if the effect is on.
    hysteresis: Option<usize>,
    theta_rest: [f64; 3],
    /// θ* = π/(2γ2) of each actuator (the scale of θ) [rad].
    theta_star: [f64; 3],
    scales: Vec<f64>,
    /// Typical stiffness Kb [N m/rad], to judge a vanishing stiffness.
    stiffness_scale: f64,
}

impl<'m> Reduced<'m> {
    fn new(model: &'m Platform) -> Result<Reduced<'m>, ControlError> {
        let nb = model.n_states() / 3;
        let extras = model.extra_states();
        let mut local = vec![Q1, Q2];
        let mut hysteresis = None;
        for (k, e) in extras.iter().enumerate() {
            if e.effect == Effect::Hysteresis {
                hysteresis = Some(actuator::N + k);
            } else {
                local.push(actuator::N + k);
            }
        }
        let inner = (0..3)
            .flat_map(|i| local.iter().map(move |&k| nb * i + k))
            .collect();
        let rest = model.rest_state()?;
        let theta_rest = [0, 1, 2].map(|i| rest[nb * i + THETA]);
        let stiffness_scale = model
            .actuators
            .iter()
            .map(|a| a.par.kb)
            .fold(f64::INFINITY, f64::min);
        let scales = model.state_scales();
        Ok(Reduced {
            model,
            nb,
            inner,
            hysteresis,
            theta_rest,
            theta_star: [0, 1, 2].map(|i| scales[nb * i + THETA]),
            scales,
            stiffness_scale,
        })
    }

    /// The hysteretic state after a slow monotone travel from the rest angle (the virgin
    /// loading curve of Bouc–Wen and Dahl alike: dz/dθ = 1 − z/θ_h for z sign(Δθ) ≥ 0), and
    /// its slope dz/dθ.
    fn virgin(&self, i: usize, theta: f64) -> (f64, f64) {
        let theta_h = self.model.params().effects.hysteresis.theta_h;
        let travel = theta - self.theta_rest[i];
        let decay = (-travel.abs() / theta_h).exp();
        (travel.signum() * theta_h * (1.0 - decay), decay)
    }

    /// The state on the curves at angles θ with p = 0 and the inner states solved.
    fn state(&self, theta: [f64; 3], u: [f64; 3]) -> Result<Vec<f64>, ModelError> {
        let (model, nb) = (self.model, self.nb);
        let mut x = vec![0.0; model.n_states()];
        let fx = &model.params().effects;
        for (i, a) in model.actuators.iter().enumerate() {
            let wrap = |cause| ModelError {
                actuator: i + 1,
                cause,
            };
            let o = nb * i;
            let l_p = a.l_p_on_curve(theta[i]).map_err(wrap)?;
            x[o + THETA] = theta[i];
            x[o + L_P] = l_p;
            // the DC circuit as the first guess of the charges
            let i_dc = a.ga(theta[i]) * u[i] / (a.par.r0 + a.par.r1 + a.par.r2);
            x[o + Q1] = a.par.c1 * a.par.r1 * i_dc;
            x[o + Q2] = a.c2(theta[i], l_p).map_err(wrap)? * a.par.r2 * i_dc;
            for (k, e) in model.extra_states().iter().enumerate() {
                // a family without a guess here starts from 0; Newton solves its states
                x[o + actuator::N + k] = match e.effect {
                    Effect::Creep => theta[i],
                    Effect::Hysteresis => self.virgin(i, theta[i]).0,
                    Effect::AmplifierLag => u[i],
                    Effect::ChargeDrift => fx.charge_drift.tau3 * i_dc,
                    _ => 0.0,
                };
            }
        }
        // the inner states' equations are linear at fixed geometry (up to the clipping of the
        // saturation effect): Newton converges in one or two steps
        let n = x.len();
        let (mut f, mut jac) = (vec![0.0; n], vec![0.0; n * n]);
        for _ in 0..20 {
            model.rhs(&x, u, &mut f)?;
            model.jacobian(&x, u, &mut jac)?;
            let m = self.inner.len();
            let a_ii = DMatrix::from_fn(m, m, |r, c| jac[self.inner[c] * n + self.inner[r]]);
            let rhs = DMatrix::from_fn(m, 1, |r, _| -f[self.inner[r]]);
            let Some(step) = a_ii.lu().solve(&rhs) else {
                break;
            };
            let mut moved: f64 = 0.0;
            for (r, &k) in self.inner.iter().enumerate() {
                x[k] += step[r];
                moved = moved.max(step[r].abs() / self.scales[k]);
            }
            if moved <= 1e-15 {
                break;
            }
        }
        Ok(x)
    }

    /// ṗ_i at angles θ, and its derivative along the curves ∂ṗ_i/∂θ_j (3×3).
    fn residual(&self, theta: [f64; 3], u: [f64; 3]) -> Result<Residual, ModelError> {
        let (model, nb) = (self.model, self.nb);
        let x = self.state(theta, u)?;
        let n = x.len();
        let (mut f, mut jac) = (vec![0.0; n], vec![0.0; n * n]);
        model.rhs(&x, u, &mut f)?;
        model.jacobian(&x, u, &mut jac)?;
        let at = |r: usize, c: usize| jac[c * n + r];
        let m = self.inner.len();
        let a_ii = DMatrix::from_fn(m, m, |r, c| at(self.inner[r], self.inner[c]));
        let lu = a_ii.lu();
        let mut dp = [[0.0; 3]; 3];
        for j in 0..3 {
            // the tangent ∂x/∂θ_j: θ_j, l_p along the curve (slope d), the hysteresis state
            // along its virgin curve, the inner states by the implicit-function theorem
            let o = nb * j;
            let shell =
                Shell::new(x[o + THETA], x[o + L_P], model.params().lv).map_err(|cause| {
                    ModelError {
                        actuator: j + 1,
                        cause,
                    }
                })?;
            let mut t = vec![0.0; n];
            t[o + THETA] = 1.0;
            t[o + L_P] = shell.d;
            if let Some(k) = self.hysteresis {
                t[o + k] = self.virgin(j, theta[j]).1;
            }
            let rhs = DMatrix::from_fn(m, 1, |r, _| {
                -(0..n).map(|c| at(self.inner[r], c) * t[c]).sum::<f64>()
            });
            let inner = lu.solve(&rhs).unwrap_or_else(|| DMatrix::zeros(m, 1));
            for (r, &k) in self.inner.iter().enumerate() {
                t[k] = inner[r];
            }
            for (i, row) in dp.iter_mut().enumerate() {
                let p_i = nb * i + P;
                row[j] = (0..n).map(|c| at(p_i, c) * t[c]).sum();
            }
        }
        let p_dot = [0, 1, 2].map(|i| f[nb * i + P]);
        Ok(Residual { x, p_dot, dp })
    }

    /// Newton on ṗ(θ) = 0 from `theta`.
    fn newton(&self, mut theta: [f64; 3], u: [f64; 3]) -> Result<Solution, Failure> {
        let theta_star = self.theta_star;
        let (mut last_size, mut polish) = (f64::INFINITY, 3);
        for it in 1..=NEWTON_ITERATIONS {
            let Residual { p_dot, dp, .. } = self.residual(theta, u)?;
            let jr = Matrix3::from_fn(|r, c| dp[r][c]);
            let Some(step) = jr.lu().solve(&Vector3::from(p_dot)) else {
                return Err(Failure::NotConverged(it));
            };
            let mut converged = true;
            let mut size: f64 = 0.0;
            for i in 0..3 {
                theta[i] -= step[i];
                converged &= step[i].abs() <= 1e-13 * theta_star[i];
                size = size.max(step[i].abs() / theta_star[i]);
            }
            if !theta.iter().all(|t| t.is_finite()) {
                return Err(Failure::NotConverged(it));
            }
            // once converged, polish while the steps still shrink (to the rounding of θ)
            if converged && (size == 0.0 || size >= last_size || polish == 0) {
                // the state and stiffness at the final angles
                let Residual { x, dp, .. } = self.residual(theta, u)?;
                return Ok(Solution {
                    theta,
                    x,
                    stiffness: dp.map(|row| row.map(|v| -v)),
                    iterations: it,
                });
            }
            if converged {
                polish -= 1;
            }
            last_size = size;
        }
        Err(Failure::NotConverged(NEWTON_ITERATIONS))
    }
}

/// max_r |f_r(x, U)| / size_r, where size_r sums the magnitudes of the terms of row r of
/// ẋ = (J − R)∇H + g U (model.md, "Dynamics"): the rounding of f_r is a few ulps of size_r,
/// so at an equilibrium computed to round-off this is a small multiple of 1e-16. The effects'
/// contributions are counted as the magnitudes of their Jacobian terms |∂f_r/∂x_k x_k|.
fn relative_residual(model: &Platform, x: &[f64], u: [f64; 3]) -> Result<f64, ControlError> {
    let sizes = term_sizes(model, x, u)?;
    let n = x.len();
    let mut f = vec![0.0; n];
    model.rhs(x, u, &mut f)?;
    Ok(f.iter()
        .zip(&sizes)
        .map(|(fr, s)| if *fr == 0.0 { 0.0 } else { fr.abs() / s })
        .fold(0.0, f64::max))
}

/// The magnitudes of the terms of each row of ẋ at (x, U) (see [`relative_residual`]).
fn term_sizes(model: &Platform, x: &[f64], u: [f64; 3]) -> Result<Vec<f64>, ControlError> {
    let n = x.len();
    let nb = n / 3;
    let params = model.params();
    let gravity = 0.5 * params.g * params.lv * params.m;
    let u_port = model.port_voltages(x, u);
    let (mut f, mut jac, mut b) = (vec![0.0; n], vec![0.0; n * n], vec![0.0; n * 3]);
    model.rhs(x, u, &mut f)?;
    model.jacobian(x, u, &mut jac)?;
    model.input_jacobian(x, u, &mut b)?;
    let mut sizes = vec![0.0; n];
    for (i, a) in model.actuators.iter().enumerate() {
        let o = nb * i;
        let xi = &x[o..o + actuator::N];
        let wrap = |cause| ModelError {
            actuator: i + 1,
            cause,
        };
        let grad = a.grad_h(xi).map_err(wrap)?;
        let v = a.voltages(xi).map_err(wrap)?;
        let d = Shell::new(xi[THETA], xi[L_P], params.lv).map_err(wrap)?.d;
        let theta = xi[THETA];
        let spring = a.par.kb * theta;
        let weight = gravity * theta.cos();
        let film = 0.5 * a.par.k * (xi[L_P] - params.lp);
        let omega = grad[P];
        let source = a.g0 * a.ga(theta) * u_port[i];
        sizes[o + THETA] = omega.abs();
        sizes[o + L_P] = (d * omega).abs();
        sizes[o + P] = spring.abs()
            + weight.abs()
            + (grad[THETA] - spring - weight).abs()
            + d.abs() * (film.abs() + (grad[L_P] - film).abs())
            + (a.par.b * omega).abs();
        sizes[o + Q1] = ((a.g0 + a.g1) * v.v1).abs() + (a.g0 * v.v2).abs() + source.abs();
        sizes[o + Q2] = (a.g0 * v.v1).abs() + ((a.g0 + a.g2) * v.v2).abs() + source.abs();
        if nb > actuator::N {
            // the effects: what they add to the actuator's rows, and their own rows
            let mut base = [0.0; actuator::N];
            a.rhs(xi, u_port[i], &mut base).map_err(wrap)?;
            for r in 0..actuator::N {
                sizes[o + r] += (f[o + r] - base[r]).abs();
            }
            for r in 0..nb {
                let row = o + r;
                let linear: f64 = (0..n)
                    .filter(|&c| r >= actuator::N || c % nb >= actuator::N)
                    .map(|c| (jac[c * n + row] * x[c]).abs())
                    .sum();
                let input: f64 = (0..3).map(|j| (b[j * n + row] * u[j]).abs()).sum();
                sizes[row] += linear + input;
            }
        }
    }
    Ok(sizes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Params;

    #[test]
    fn zero_volts_is_the_rest_state() {
        let model = Platform::new(Params::default()).unwrap();
        let eq = equilibrium(&model, [0.0; 3]).unwrap();
        let rest = model.rest_state().unwrap();
        for (a, b) in eq.x.iter().zip(&rest) {
            assert!((a - b).abs() <= 1e-15 + 1e-12 * b.abs(), "{a} vs {b}");
        }
        assert!(eq.residual < 1e-14, "residual {}", eq.residual);
    }

    #[test]
    fn non_finite_voltages_are_refused() {
        let model = Platform::new(Params::default()).unwrap();
        let e = equilibrium(&model, [1.0, f64::NAN, 0.0]).unwrap_err();
        assert!(matches!(e, ControlError::BadVoltage { input: 1, value } if value.is_nan()));
        assert_eq!(e.to_string(), "U2 = NaN: must be a finite number");
    }
}
