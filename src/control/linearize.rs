//! The linearization δẋ = A δx + B δU, δy = C δx + D δU at an equilibrium or at a point of a
//! trajectory, from the model's analytic Jacobians ([`Platform::jacobian`],
//! [`Platform::input_jacobian`], [`Platform::output_jacobian`]), with its eigenvalues, the zero
//! eigenvalue of each actuator's Casimir and the minimal model without it.
//!
//! **The Casimir.** l̇_p = d θ̇ makes c(θ, l_p), with ∂c/∂θ + d ∂c/∂l_p = 0, a conserved
//! quantity of every trajectory (a Casimir of J). At an equilibrium (p = 0) the row of l_p in A
//! is d times the row of θ (both are ∂/∂x of d·p/I and p/I), so w_i = e_{l_p,i} − d_i e_{θ,i}
//! satisfies w_iᵀ A = 0 and w_iᵀ B = 0: one zero eigenvalue per actuator, uncontrollable, that
//! moves along the family of equilibria to a neighbouring invariant curve. The minimal model
//! keeps the trajectories on their curve: l_p_i is dropped and follows δl_p_i = d_i δθ_i, i.e.
//! δx = T z with z the other states, and A_m = L A T, B_m = L B, C_m = C T (L drops the l_p
//! rows). On the invariant curve this is the exact Jacobian of the dynamics restricted to it
//! (at any point of a trajectory that starts on the curve, not only at equilibria).

use nalgebra::{Complex, DMatrix};

use super::equilibrium::{self, Equilibrium};
use super::{ControlError, linalg};
use crate::model::Effect;
use crate::model::actuator::{self, L_P, P, THETA};
use crate::model::effects::hysteresis::HysteresisLaw;
use crate::model::shell::Shell;
use crate::model::{ModelError, Platform};

/// Names of the inputs and outputs, as the FMU's variables.
pub const INPUTS: [&str; 3] = ["U1", "U2", "U3"];
pub const OUTPUTS: [&str; 6] = ["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"];

/// A linear state-space model in SI units (row/column names alongside).
#[derive(Clone, Debug, PartialEq)]
pub struct StateSpace {
    pub a: DMatrix<f64>,
    pub b: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub d: DMatrix<f64>,
    pub states: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    /// The typical size of each state, by which the numerics scale it (x = S x̃).
    pub scales: Vec<f64>,
}

impl StateSpace {
    pub fn n_states(&self) -> usize {
        self.a.nrows()
    }
}

/// Where the model was linearized.
#[derive(Clone, Debug, PartialEq)]
pub enum Point {
    /// At the equilibrium under constant voltages.
    Equilibrium(Equilibrium),
    /// At the state a simulation reached at time `t` (generally not an equilibrium:
    /// f(x0, u0) ≠ 0, the linearization is the frozen Jacobian there).
    Trajectory {
        t: f64,
        /// How fast the state moves there: max_r |f_r(x0, u0)| / scale_r [1/s] (state scales
        /// per second; 0 at an equilibrium).
        rate: f64,
    },
}

/// An effect that makes the linearization special at this point.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectNote {
    pub effect: &'static str,
    /// 1-based actuator, if the note is about one.
    pub actuator: Option<usize>,
    /// Is the model differentiable at this point?
    pub smooth: bool,
    pub text: String,
}

/// The zero eigenvalues of the Casimirs and the check of their structure.
#[derive(Clone, Debug, PartialEq)]
pub struct Casimirs {
    /// d_i = dl_p/dθ of each actuator's invariant curve at x0.
    pub slopes: [f64; 3],
    /// max_i ‖w_iᵀ A S‖ / ‖A S‖ (S the state scales): zero up to rounding at an equilibrium.
    pub left_residual: f64,
    /// max_i |w_iᵀ B| / ‖B‖: the Casimirs are not reachable from the inputs.
    pub input_residual: f64,
    /// The eigenvalues of A nearest zero, one per actuator, as computed.
    pub eigenvalues: Vec<Complex<f64>>,
}

/// The linearization at one point.
#[derive(Clone, Debug, PartialEq)]
pub struct Linearization {
    pub u0: [f64; 3],
    pub x0: Vec<f64>,
    pub y0: [f64; 6],
    /// The full model: every state of the FMU.
    pub system: StateSpace,
    /// Eigenvalues of A (scaled and balanced), slowest first.
    pub eigenvalues: Vec<Complex<f64>>,
    /// Eigenvalues of the minimal model (A without the Casimir directions).
    pub minimal_eigenvalues: Vec<Complex<f64>>,
    pub point: Point,
    pub casimirs: Casimirs,
    pub notes: Vec<EffectNote>,
    /// Transport delay of the `delay` effect \[s\]: the model's inputs are U(t − τ_d), so the
    /// transfer matrix is G(s) e^{−s τ_d}; 0 without the effect.
    pub input_delay: f64,
}

/// Linearizes at the equilibrium under the constant voltages `u` (see [`equilibrium`]).
///
/// [`equilibrium`]: super::equilibrium::equilibrium
pub fn linearize_equilibrium(model: &Platform, u: [f64; 3]) -> Result<Linearization, ControlError> {
    let eq = equilibrium::equilibrium(model, u)?;
    let x = eq.x.clone();
    build(model, &x, u, Point::Equilibrium(eq))
}

/// Linearizes at the state `x` reached at time `t` under the voltages `u` the model sees there.
pub fn linearize_at(
    model: &Platform,
    x: &[f64],
    u: [f64; 3],
    t: f64,
) -> Result<Linearization, ControlError> {
    let mut f = vec![0.0; x.len()];
    model.rhs(x, u, &mut f)?;
    let rate = f
        .iter()
        .zip(model.state_scales())
        .map(|(fr, s)| fr.abs() / s)
        .fold(0.0, f64::max);
    build(model, x, u, Point::Trajectory { t, rate })
}

fn build(
    model: &Platform,
    x: &[f64],
    u: [f64; 3],
    point: Point,
) -> Result<Linearization, ControlError> {
    let n = model.n_states();
    let mut jac = vec![0.0; n * n];
    model.jacobian(x, u, &mut jac)?;
    let mut b = vec![0.0; n * 3];
    model.input_jacobian(x, u, &mut b)?;
    let mut c = vec![0.0; 6 * n];
    model.output_jacobian(x, &mut c);
    let d = model.output_input_jacobian();
    let system = StateSpace {
        a: linalg::from_column_major(n, n, &jac),
        b: linalg::from_column_major(n, 3, &b),
        c: linalg::from_column_major(6, n, &c),
        d: DMatrix::from_fn(6, 3, |r, c| d[r][c]),
        states: model.state_names(),
        inputs: INPUTS.map(String::from).to_vec(),
        outputs: OUTPUTS.map(String::from).to_vec(),
        scales: model.state_scales(),
    };
    let eigenvalues = linalg::eigenvalues(&system.a, &system.scales)?;
    let slopes = curve_slopes(model, x)?;
    let minimal = minimal_model(&system, &slopes);
    let minimal_eigenvalues = linalg::eigenvalues(&minimal.a, &minimal.scales)?;
    let casimirs = casimirs(&system, &slopes, &eigenvalues);
    Ok(Linearization {
        u0: u,
        x0: x.to_vec(),
        y0: model.outputs(x),
        eigenvalues,
        minimal_eigenvalues,
        casimirs,
        notes: effect_notes(model, x, u),
        input_delay: model.params().effects.delay.tau_d,
        point,
        system,
    })
}

/// d_i = dl_p/dθ of each actuator's invariant curve at x.
fn curve_slopes(model: &Platform, x: &[f64]) -> Result<[f64; 3], ModelError> {
    let nb = model.n_states() / 3;
    let lv = model.params().lv;
    let mut d = [0.0; 3];
    for (i, di) in d.iter_mut().enumerate() {
        let o = nb * i;
        *di = Shell::new(x[o + THETA], x[o + L_P], lv)
            .map_err(|cause| ModelError {
                actuator: i + 1,
                cause,
            })?
            .d;
    }
    Ok(d)
}

/// The tie δx = T z of the minimal model: z drops each l_p_i, which follows d_i δθ_i.
/// Returns T (n × (n − 3)) and the kept state indices.
pub fn tie(n: usize, slopes: &[f64; 3]) -> (DMatrix<f64>, Vec<usize>) {
    let nb = n / 3;
    let kept: Vec<usize> = (0..n).filter(|k| k % nb != L_P).collect();
    let mut t = DMatrix::zeros(n, kept.len());
    for (col, &k) in kept.iter().enumerate() {
        t[(k, col)] = 1.0;
        if k % nb == THETA {
            t[(k - THETA + L_P, col)] = slopes[k / nb];
        }
    }
    (t, kept)
}

/// The minimal model on the invariant curves: A_m = L A T, B_m = L B, C_m = C T, D_m = D.
fn minimal_model(full: &StateSpace, slopes: &[f64; 3]) -> StateSpace {
    let n = full.n_states();
    let (t, kept) = tie(n, slopes);
    let select = |m: &DMatrix<f64>| DMatrix::from_fn(kept.len(), m.ncols(), |r, c| m[(kept[r], c)]);
    StateSpace {
        a: select(&(&full.a * &t)),
        b: select(&full.b),
        c: &full.c * &t,
        d: full.d.clone(),
        states: kept.iter().map(|&k| full.states[k].clone()).collect(),
        inputs: full.inputs.clone(),
        outputs: full.outputs.clone(),
        scales: kept.iter().map(|&k| full.scales[k]).collect(),
    }
}

impl Linearization {
    /// The minimal model without the Casimir directions (see the module documentation).
    pub fn minimal(&self) -> StateSpace {
        minimal_model(&self.system, &self.casimirs.slopes)
    }

    /// Is this an equilibrium?
    pub fn at_equilibrium(&self) -> bool {
        matches!(self.point, Point::Equilibrium(_))
    }
}

fn casimirs(system: &StateSpace, slopes: &[f64; 3], eigenvalues: &[Complex<f64>]) -> Casimirs {
    let n = system.n_states();
    let nb = n / 3;
    let a_s = linalg::scale_columns(&system.a, &system.scales);
    let (mut left, mut input) = (0.0f64, 0.0f64);
    for (i, d) in slopes.iter().enumerate() {
        let (l, t) = (nb * i + L_P, nb * i + THETA);
        let w_a = a_s.row(l) - a_s.row(t) * *d;
        left = left.max(w_a.norm() / a_s.norm());
        let w_b = system.b.row(l) - system.b.row(t) * *d;
        input = input.max(w_b.norm() / system.b.norm().max(f64::MIN_POSITIVE));
    }
    let mut near: Vec<Complex<f64>> = eigenvalues.to_vec();
    near.sort_by(|x, y| x.norm().total_cmp(&y.norm()));
    near.truncate(3);
    Casimirs {
        slopes: *slopes,
        left_residual: left,
        input_residual: input,
        eigenvalues: near,
    }
}

/// The effects that are not smooth at (x, U), or that the state-space form leaves out.
fn effect_notes(model: &Platform, x: &[f64], u: [f64; 3]) -> Vec<EffectNote> {
    let fx = model.params().effects;
    let nb = model.n_states() / 3;
    let extras = model.extra_states();
    let mut notes = Vec::new();
    for i in 0..3 {
        let xi = &x[nb * i..nb * (i + 1)];
        let sat = fx.saturation;
        if sat.is_on() {
            let amp = extras
                .iter()
                .rposition(|e| e.effect == Effect::AmplifierLag);
            let v = amp.map_or(u[i], |k| xi[actuator::N + k]);
            let (_, slope) = sat.map(v);
            let limits = format!("limits {}, dead zone {} V", sat.limits_text(), sat.u_dead);
            let (smooth, text) = if sat.at_corner(v) {
                (
                    false,
                    format!(
                        "the amplifier output {v} V is exactly at a corner of the output map ({limits}): it has no derivative there (the Jacobian takes the slope of the inner side)"
                    ),
                )
            } else if slope < 1.0 {
                (
                    true,
                    format!(
                        "the amplifier output {v} V is outside the output map's linear range ({limits}): the port voltage's slope is reduced to {slope:.3}"
                    ),
                )
            } else {
                continue;
            };
            notes.push(EffectNote {
                effect: "saturation",
                actuator: Some(i + 1),
                smooth,
                text,
            });
        }
    }
    if let Some(k) = extras.iter().position(|e| e.effect == Effect::Hysteresis) {
        for i in 0..3 {
            let xi = &x[nb * i..nb * (i + 1)];
            let (omega, z) = (xi[P] / model.actuators[i].inertia, xi[actuator::N + k]);
            let law = match fx.hysteresis.law {
                HysteresisLaw::BoucWen => "Bouc-Wen",
                HysteresisLaw::Dahl => "Dahl",
            };
            let (smooth, text) = if omega == 0.0 && z != 0.0 {
                (
                    false,
                    format!(
                        "at rest (dtheta/dt = 0) with z_h = {z:e} rad the {law} law's |dtheta/dt| has no derivative: the Jacobian takes the side of increasing theta; z_h is a memory state (dz_h/dt = 0 for any z_h at rest), so A has a second zero eigenvalue for this actuator"
                    ),
                )
            } else if omega == 0.0 {
                (
                    true,
                    "at rest with z_h = 0: differentiable, but z_h is a memory state (a second zero eigenvalue)".to_string(),
                )
            } else {
                (
                    true,
                    format!(
                        "moving (dtheta/dt = {omega:e} rad/s): the {law} law is differentiable here"
                    ),
                )
            };
            notes.push(EffectNote {
                effect: "hysteresis",
                actuator: Some(i + 1),
                smooth,
                text,
            });
        }
    }
    if fx.delay.tau_d > 0.0 {
        notes.push(EffectNote {
            effect: "delay",
            actuator: None,
            smooth: true,
            text: format!(
                "a transport delay of {} s is no finite state: this model's inputs are U(t - tau_d), its transfer matrix G(s) exp(-s tau_d)",
                fx.delay.tau_d
            ),
        });
    }
    notes
}
