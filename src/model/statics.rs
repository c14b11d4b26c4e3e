//! The statics of the platform (book/src/model.md, "Statics"): the constant voltages that hold
//! the actuators at given heights, the inverse of the equilibrium map that `hasel linearize`
//! solves forwards (voltages to equilibrium). Per actuator it is closed-form: the height fixes θ,
//! the invariant curve l_p, and the torque balance ṗ = 0 is affine in V2², with V2 from the DC
//! circuit.

use super::actuator::{Actuator, N, P};
use super::kinematics::{IkmError, Inverse};
use super::shell::DomainError;
use super::{Effect, Platform};

/// Why no constant voltage holds an actuator at a height.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum UnreachableError {
    /// h = ½ Lv sin θ has no angle: |h| > ½ Lv.
    #[error(
        "h = {height:.6e} m is beyond the film length: |h| must be below 1/2 Lv = {limit:.6e} m"
    )]
    NoAngle { height: f64, limit: f64 },
    /// The shell geometry does not exist there (model.md, "Shell geometry and C2").
    #[error("{0}")]
    Domain(#[from] DomainError),
    /// Below the rest height the springs and gravity would have to be pulled down, and the
    /// electrostatic force only pulls up.
    #[error(
        "h = {height:.6e} m is below the rest height {rest:.6e} m (the electrostatic force only lifts)"
    )]
    BelowRest { height: f64, rest: f64 },
    /// At or beyond θ* = π/(2γ2) the input gain ga = γ1 cos(γ2 θ) is no longer positive.
    #[error(
        "h = {height:.6e} m is at or beyond the height {limit:.6e} m where the input gain ga = gamma1 cos(gamma2 theta) vanishes"
    )]
    BeyondGain { height: f64, limit: f64 },
    /// The holding voltage falls as θ grows: the equilibrium there is unstable (past a fold).
    #[error(
        "h = {height:.6e} m is held only by an unstable equilibrium (the holding voltage falls as the height grows: past pull-in)"
    )]
    Unstable { height: f64 },
}

/// Why no constant voltages hold the platform at the heights asked.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StaticsError {
    #[error("actuator {actuator}: {cause}")]
    Actuator {
        actuator: usize,
        cause: UnreachableError,
    },
    /// The closed form is the paper's model's; these effects are active.
    #[error("the holding voltages are implemented for the paper's model; active effects: {}",
        .0.iter().map(|e| e.name()).collect::<Vec<_>>().join(", "))]
    Effects(Vec<Effect>),
}

/// How far below the rest height [m] a height is still the rest height: the kinematics
/// recover heights to 1e-15 m, so a tip path that starts at rest asks for heights a rounding
/// below it.
const REST_ROUNDING: f64 = 1e-12;

/// Relative step of θ (of θ*) over which the holding voltage must grow for a stable equilibrium.
const STABILITY_PROBE: f64 = 1e-7;

/// The voltage U ≥ 0 [V] that holds actuator `a` at the angle θ at equilibrium
/// (model.md, "Statics"): p = 0, l_p on the invariant curve, the charges of the DC circuit
/// V1 = R1 i, V2 = R2 i, i = ga(θ) U / (R0 + R1 + R2), and
/// ṗ = −(∂H/∂θ + d ∂H/∂l_p) = ṗ₀ + s V2² = 0, which gives V2² = −ṗ₀ / s.
fn voltage_at(a: &Actuator, theta: f64, height: f64) -> Result<f64, UnreachableError> {
    let l_p = a.l_p_on_curve(theta)?;
    let par = &a.par;
    // ṗ at p = 0 with the DC charges of a given V2 = R2 i: affine in V2²
    let p_dot = |v2: f64| -> Result<f64, DomainError> {
        let x = a.dc_state(theta, l_p, v2 / par.r2)?;
        let mut dx = [0.0; N];
        a.rhs(&x, 0.0, &mut dx)?;
        Ok(dx[P])
    };
    let p_dot_0 = p_dot(0.0)?;
    // the slope s from a probe at 1 V loses digits to the difference ṗ(1 V) − ṗ₀ (V2 is kV);
    // measured again at the estimate, where the difference is −ṗ₀ itself, it is exact
    let mut v2_squared = -p_dot_0 / (p_dot(1.0)? - p_dot_0);
    if v2_squared > 0.0 {
        let v2 = v2_squared.sqrt();
        v2_squared = -p_dot_0 / ((p_dot(v2)? - p_dot_0) / (v2 * v2));
    }
    if v2_squared < 0.0 {
        let rest = a.height(a.rest_state()?[0]);
        // at the rest height ṗ₀ is 0 to rounding, of either sign: held by U = 0
        if height >= rest - REST_ROUNDING {
            return Ok(0.0);
        }
        return Err(UnreachableError::BelowRest { height, rest });
    }
    // ga = γ1 cos(γ2 θ) > 0 on the first lobe only: beyond θ* the force's branches repeat
    let theta_star = std::f64::consts::FRAC_PI_2 / par.gamma2;
    if theta >= theta_star {
        let limit = a.height(theta_star);
        return Err(UnreachableError::BeyondGain { height, limit });
    }
    Ok(v2_squared.sqrt() * (par.r0 + par.r1 + par.r2) / (par.r2 * a.ga(theta)))
}

/// The voltage \[V\] that holds actuator `a` at the height `h` \[m\] at equilibrium, on a stable
/// branch: h = ½ Lv sin θ (model.md, "Shell geometry and C2") gives θ; the equilibrium is
/// stable where the stiffness along the curve −∂ṗ/∂θ at fixed U is positive, i.e. where the
/// holding voltage grows with θ (∂ṗ/∂U > 0), checked over a step of `STABILITY_PROBE` θ*.
fn holding_voltage(a: &Actuator, lv: f64, h: f64) -> Result<f64, UnreachableError> {
    let limit = 0.5 * lv;
    if h.is_nan() || h.abs() >= limit {
        return Err(UnreachableError::NoAngle { height: h, limit });
    }
    let theta = (h / limit).asin();
    let u = voltage_at(a, theta, h)?;
    let step = STABILITY_PROBE * a.state_scales()[0];
    match voltage_at(a, theta + step, h) {
        Ok(above) if above <= u => Err(UnreachableError::Unstable { height: h }),
        Ok(_) | Err(UnreachableError::BeyondGain { .. }) => Ok(u),
        Err(e) => Err(e),
    }
}

/// The voltages that hold the three actuators of `model` at `heights` \[m\] at equilibrium.
pub fn holding_voltages(model: &Platform, heights: [f64; 3]) -> Result<[f64; 3], StaticsError> {
    let active = model.params().effects.active();
    if !active.is_empty() {
        return Err(StaticsError::Effects(active));
    }
    let lv = model.params().lv;
    let mut u = [0.0; 3];
    for (i, a) in model.actuators.iter().enumerate() {
        u[i] = holding_voltage(a, lv, heights[i]).map_err(|cause| StaticsError::Actuator {
            actuator: i + 1,
            cause,
        })?;
    }
    Ok(u)
}

/// Why a tip position has no feedforward.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FeedforwardError {
    #[error("inverse kinematics: {0}")]
    Kinematics(#[from] IkmError),
    #[error(transparent)]
    Statics(#[from] StaticsError),
}

/// The heights \[m\] that put the tip at `tip` \[m\] by `method`, and the constant voltages \[V\]
/// that hold them at equilibrium: the feedforward of a tip path.
pub fn feedforward(
    model: &Platform,
    method: Inverse,
    tip: [f64; 3],
) -> Result<([f64; 3], [f64; 3]), FeedforwardError> {
    let heights = model.kinematics.inverse(method, tip)?;
    Ok((heights, holding_voltages(model, heights)?))
}
