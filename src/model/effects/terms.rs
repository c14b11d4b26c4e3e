//! The effects' terms around the actuator equations: the extra states of each actuator, the
//! voltage the actuator's port receives, the torques on θ, the extra circuit branch, and their
//! energy, dissipation and Jacobian entries.
//!
//! Each actuator's block of states is its five (θ, l_p, p, Q1, Q2) followed by the extra
//! states of the active effects, in the order of [`Extra`]. Only `coupling` links the blocks.

use super::{DriftSite, Effect, EffectParams, HysteresisLaw, PreloadLaw};
use crate::model::actuator::{self, Actuator, P, Q1, Q2, StateInfo, THETA};
use crate::model::shell::DomainError;

/// Width of the soft saturation's knee, as a fraction of U_max.
const SOFT_KNEE: f64 = 0.15;

/// An extra state of one actuator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Extra {
    /// Charge of drift stage k's capacitor [C].
    Q3(usize),
    /// Creep state z of branch k [rad].
    Creep(usize),
    /// Hysteretic state z_h [rad].
    Hysteresis,
    /// Output of amplifier stage k [V]; the last one drives the actuator.
    Amplifier(usize),
}

impl Extra {
    /// The states the parameter table can switch on, in block order: the effect states
    /// every configuration can name (the FMU's state variables).
    pub const TABLE_STATES: [Extra; 6] = [
        Extra::Q3(0),
        Extra::Creep(0),
        Extra::Creep(1),
        Extra::Hysteresis,
        Extra::Amplifier(0),
        Extra::Amplifier(1),
    ];

    /// The effect that adds the state.
    pub fn effect(self) -> Effect {
        match self {
            Extra::Q3(_) => Effect::ChargeDrift,
            Extra::Creep(_) => Effect::Creep,
            Extra::Hysteresis => Effect::Hysteresis,
            Extra::Amplifier(_) => Effect::AmplifierLag,
        }
    }

    /// Name of the first stage, unit and meaning; every stage shares unit and meaning.
    pub fn info(self) -> StateInfo {
        let (name, unit, description) = match self {
            Extra::Q3(_) => ("Q3", "C", "charge Q3 of the drift stage's capacitor C3"),
            Extra::Creep(_) => (
                "z_v",
                "rad",
                "internal angle z of the standard linear solid",
            ),
            Extra::Hysteresis => ("z_h", "rad", "Bouc-Wen state z_h"),
            Extra::Amplifier(_) => ("U_amp", "V", "amplifier output voltage"),
        };
        StateInfo {
            name,
            unit,
            description,
        }
    }

    /// Name without the actuator suffix: the first stage's name, numbered from the second.
    pub fn name(self) -> String {
        let name = self.info().name;
        match self {
            Extra::Q3(k) | Extra::Creep(k) | Extra::Amplifier(k) if k > 0 => {
                format!("{name}{}", k + 1)
            }
            _ => name.into(),
        }
    }
}

/// The terms of the active effects, derived once from the parameters.
#[derive(Clone, Debug)]
pub struct Terms {
    pub fx: EffectParams,
    /// No effect is on: the platform skips the terms (the paper's model, at its own speed).
    pub neutral: bool,
    /// The extra states of every actuator, in block order.
    pub extras: Vec<Extra>,
    drift: Vec<(usize, f64, f64)>, // (index, R, τ) per series stage
    /// The absorption branch across part of the film: (index, C3, τ3), the film's part.
    branch: Option<(usize, f64, f64, DriftSite)>,
    creep: Vec<(usize, f64, f64)>, // (index, k, τ) per branch
    hyst: Option<usize>,
    amp: Vec<(usize, f64)>, // (index, time constant) per stage
}

/// The voltage at an actuator's port.
pub struct Port {
    /// Voltage at the actuator's port after amplifier and clipping [V].
    pub u_eff: f64,
    /// ∂u_eff / ∂(the last amplifier state), or ∂u_eff/∂U without an amplifier state.
    pub slope: f64,
}

impl Terms {
    pub fn new(fx: &EffectParams) -> Terms {
        let mut extras = Vec::new();
        let mut push = |e: Extra| {
            extras.push(e);
            Some(actuator::N + extras.len() - 1)
        };
        let mut drift = Vec::new();
        let mut branch = None;
        let cd = fx.charge_drift;
        if Effect::ChargeDrift.is_active(fx) {
            if cd.site == DriftSite::Series {
                let stages = if cd.two_stages {
                    vec![(0.5 * cd.r3, cd.tau3 / 3.0), (0.5 * cd.r3, 3.0 * cd.tau3)]
                } else {
                    vec![(cd.r3, cd.tau3)]
                };
                for (k, (rk, tk)) in stages.into_iter().enumerate() {
                    drift.push((push(Extra::Q3(k)).unwrap(), rk, tk));
                }
            } else {
                branch = Some((push(Extra::Q3(0)).unwrap(), cd.c3, cd.tau3, cd.site));
            }
        }
        let mut creep = Vec::new();
        let cr = fx.creep;
        for (b, (kb, tb)) in [(cr.k_v, cr.tau_v), (cr.k_v2, cr.tau_v2)]
            .into_iter()
            .enumerate()
        {
            if kb > 0.0 {
                creep.push((push(Extra::Creep(b)).unwrap(), kb, tb));
            }
        }
        let hyst = if fx.hysteresis.k_h > 0.0 {
            push(Extra::Hysteresis)
        } else {
            None
        };
        let mut amp = Vec::new();
        let al = fx.amplifier_lag;
        if al.tau_a > 0.0 {
            amp.push((push(Extra::Amplifier(0)).unwrap(), al.tau_a));
            if al.tau_a2 > 0.0 {
                amp.push((push(Extra::Amplifier(1)).unwrap(), al.tau_a2));
            }
        }
        Terms {
            fx: *fx,
            neutral: fx.active().is_empty(),
            extras,
            drift,
            branch,
            creep,
            hyst,
            amp,
        }
    }

    /// States per actuator block.
    pub fn block_size(&self) -> usize {
        actuator::N + self.extras.len()
    }

    /// The extra states at rest (U = 0, θ at its rest value).
    pub fn rest(&self, theta: f64) -> Vec<f64> {
        self.extras
            .iter()
            .map(|e| match e {
                Extra::Creep(_) => theta,
                _ => 0.0,
            })
            .collect()
    }

    /// Scale of each extra state for absolute tolerances.
    pub fn scales(&self, a: &Actuator, theta_star: f64) -> Vec<f64> {
        let i_dc = a.par.gamma1 * 100.0 / (a.par.r0 + a.par.r1 + a.par.r2);
        self.extras
            .iter()
            .map(|e| match e {
                // the charge at the stage's voltage i R3, with C3 = τ3 / R3; a branch's C3 at
                // the film's 100 V
                Extra::Q3(_) => match self.branch {
                    Some((_, c3, _, _)) => 100.0 * c3,
                    None => i_dc * self.fx.charge_drift.tau3,
                },
                Extra::Creep(_) | Extra::Hysteresis => theta_star,
                Extra::Amplifier(_) => 100.0,
            })
            .collect()
    }

    /// The clipping of the amplifier and its slope.
    fn clip(&self, v: f64) -> (f64, f64) {
        let s = self.fx.saturation;
        if !s.u_max.is_finite() {
            return (v, 1.0);
        }
        // the soft form: linear up to U_max − w, then a tanh knee of width w into U_max
        let knee = if s.soft { SOFT_KNEE * s.u_max } else { 0.0 };
        let start = s.u_max - knee;
        if v.abs() <= start {
            (v, 1.0)
        } else if knee == 0.0 {
            (s.u_max.copysign(v), 0.0)
        } else {
            let t = ((v.abs() - start) / knee).tanh();
            ((start + knee * t).copysign(v), 1.0 - t * t)
        }
    }

    /// The voltage at the actuator's port: U through the amplifier's lag and its clipping.
    pub fn port(&self, x: &[f64], u: f64) -> Port {
        let v = self.amp.last().map_or(u, |&(k, _)| x[k]);
        let (u_eff, slope) = self.clip(v);
        Port { u_eff, slope }
    }

    /// ∂H_effects/∂θ_i of the static terms (coupling, stiffening, preload) at angles θ, and
    /// its derivative in θ_i, given the heights and slopes of all actuators.
    fn static_torque(&self, a: &[&Actuator; 3], theta: [f64; 3], i: usize) -> (f64, f64) {
        let mut h_t = 0.0;
        let mut h_tt = 0.0;
        let th = theta[i];
        let c = self.fx.coupling;
        if c.k_c != 0.0 {
            // H_c = ½ k_c Σ w_ij (h_i − h_j)²; h' = ½ Lv cos θ, h'' = −h
            let h = [0, 1, 2].map(|j| a[j].height(theta[j]));
            let s = a[i].height_slope(th);
            for j in (0..3).filter(|&j| j != i) {
                let w = c.k_c * c.weights[pair(i, j)];
                h_t += w * (h[i] - h[j]) * s;
                h_tt += w * (s * s - (h[i] - h[j]) * h[i]);
            }
        }
        let st = self.fx.stiffening;
        if st.k3 != 0.0 {
            // H = k3 |θ|ⁿ / n: the torque k3 θ |θ|ⁿ⁻², odd in θ for any n
            let n = st.exponent;
            h_t += st.k3 * th * th.abs().powi(n - 2);
            h_tt += st.k3 * f64::from(n - 1) * th.abs().powi(n - 2);
        }
        let tau0 = self.fx.preload.tau0[i];
        if tau0 != 0.0 {
            match self.fx.preload.law {
                PreloadLaw::Constant => h_t += tau0,
                PreloadLaw::Weight => {
                    h_t += tau0 * th.cos();
                    h_tt -= tau0 * th.sin();
                }
            }
        }
        (h_t, h_tt)
    }

    /// The static load on actuator i at angles θ, for the rest state.
    pub fn rest_load(&self, a: &[&Actuator; 3], theta: [f64; 3], i: usize) -> f64 {
        self.static_torque(a, theta, i).0
    }

    /// Adds the terms to actuator i's block of ẋ (`dx`, whose first five entries hold the
    /// actuator's own equations evaluated at the port voltage).
    pub fn add_rhs(
        &self,
        a: &[&Actuator; 3],
        x: [&[f64]; 3],
        u: f64,
        i: usize,
        dx: &mut [f64],
    ) -> Result<(), DomainError> {
        let xi = x[i];
        let act = a[i];
        let theta = [x[0][THETA], x[1][THETA], x[2][THETA]];
        let (h_t, _) = self.static_torque(a, theta, i);
        dx[P] -= h_t;
        for &(k, kb, tb) in &self.creep {
            dx[P] -= kb * (xi[THETA] - xi[k]);
            dx[k] = (xi[THETA] - xi[k]) / tb;
        }
        let omega = xi[P] / act.inertia;
        if let Some(k) = self.hyst {
            let hy = self.fx.hysteresis;
            dx[P] -= hy.k_h * xi[k];
            dx[k] = self.hysteresis_rate(omega, xi[k]).0;
            debug_assert!(hy.theta_h > 0.0);
        }
        let port = self.port(xi, u);
        if !self.drift.is_empty() {
            let v = act.voltages(xi)?;
            let v3 = self.drift_voltage(xi);
            dx[Q1] -= act.g0 * v3;
            dx[Q2] -= act.g0 * v3;
            let i0 = act.g0 * (act.ga(xi[THETA]) * port.u_eff - v.v1 - v.v2 - v3);
            for &(k, _, tk) in &self.drift {
                dx[k] = i0 - xi[k] / tk;
            }
        }
        if let Some((k, _, _, site)) = self.branch {
            // the branch takes i3 from the part of the film it spans
            let i3 = self.branch_current(&act.voltages(xi)?, xi);
            dx[Q2] -= i3;
            if site == DriftSite::Film {
                dx[Q1] -= i3;
            }
            dx[k] = i3;
        }
        // each stage follows the one before it (the first follows U)
        let mut prev = u;
        for &(k, t) in &self.amp {
            dx[k] = (prev - xi[k]) / t;
            prev = xi[k];
        }
        Ok(())
    }

    /// Voltage over the drift stages, Σ R_k Q_k / τ_k [V].
    fn drift_voltage(&self, xi: &[f64]) -> f64 {
        self.drift.iter().map(|&(k, r, t)| r * xi[k] / t).sum()
    }

    /// Current into the absorption branch, i3 = (C3 V_across − Q3) / τ3 (src/model/effects/
    /// effects.md, "charge_drift"), V_across = V2 across the electrode, V1 + V2 across the film.
    fn branch_current(&self, v: &actuator::Voltages, xi: &[f64]) -> f64 {
        match self.branch {
            Some((k, c3, t3, site)) => {
                let across = if site == DriftSite::Film {
                    v.v1 + v.v2
                } else {
                    v.v2
                };
                (c3 * across - xi[k]) / t3
            }
            None => 0.0,
        }
    }

    /// ż_h and its partial derivatives (∂/∂ω, ∂/∂z), the relaxation −r_h z_h included.
    fn hysteresis_rate(&self, omega: f64, z: f64) -> (f64, f64, f64) {
        let hy = self.fx.hysteresis;
        let (rate, d_omega, d_z) = self.hysteresis_law(omega, z);
        (rate - hy.r_h * z, d_omega, d_z - hy.r_h)
    }

    /// The hysteresis law's ż_h and its partial derivatives (∂/∂ω, ∂/∂z).
    fn hysteresis_law(&self, omega: f64, z: f64) -> (f64, f64, f64) {
        let hy = self.fx.hysteresis;
        match hy.law {
            HysteresisLaw::BoucWen => {
                let c = 0.5 / hy.theta_h; // β = γ
                (
                    omega - c * omega.abs() * z - c * omega * z.abs(),
                    1.0 - c * omega.signum() * z - c * z.abs(),
                    -c * omega.abs() - c * omega * z.signum(),
                )
            }
            HysteresisLaw::Dahl => (
                omega - omega.abs() * z / hy.theta_h,
                1.0 - omega.signum() * z / hy.theta_h,
                -omega.abs() / hy.theta_h,
            ),
        }
    }

    /// Adds the terms' entries of ∂ẋ/∂x through `add(row, col, value)`, rows and columns
    /// counted in the whole state vector; `offset[j]` is where block j starts. The actuator's
    /// own entries are already there (evaluated at the port voltage).
    pub fn add_jacobian(
        &self,
        a: &[&Actuator; 3],
        x: [&[f64]; 3],
        u: f64,
        i: usize,
        offset: [usize; 3],
        mut add: impl FnMut(usize, usize, f64),
    ) -> Result<(), DomainError> {
        let xi = x[i];
        let act = a[i];
        let o = offset[i];
        let theta = [x[0][THETA], x[1][THETA], x[2][THETA]];
        let (_, h_tt) = self.static_torque(a, theta, i);
        add(o + P, o + THETA, -h_tt);
        let c = self.fx.coupling;
        if c.k_c != 0.0 {
            let s_i = act.height_slope(theta[i]);
            for j in (0..3).filter(|&j| j != i) {
                let w = c.k_c * c.weights[pair(i, j)];
                add(
                    o + P,
                    offset[j] + THETA,
                    w * s_i * a[j].height_slope(theta[j]),
                );
            }
        }
        for &(k, kb, tb) in &self.creep {
            add(o + P, o + THETA, -kb);
            add(o + P, o + k, kb);
            add(o + k, o + THETA, 1.0 / tb);
            add(o + k, o + k, -1.0 / tb);
        }
        if let Some(k) = self.hyst {
            let (_, d_omega, d_z) = self.hysteresis_rate(xi[P] / act.inertia, xi[k]);
            add(o + P, o + k, -self.fx.hysteresis.k_h);
            add(o + k, o + P, d_omega / act.inertia);
            add(o + k, o + k, d_z);
        }
        let port = self.port(xi, u);
        // the port voltage's dependence on the last amplifier state
        let source = act.g0 * act.ga(xi[THETA]) * port.slope;
        if let Some(&(last, _)) = self.amp.last() {
            add(o + Q1, o + last, source);
            add(o + Q2, o + last, source);
        }
        if !self.drift.is_empty() {
            let v = act.voltages(xi)?;
            let g0 = act.g0;
            let u_eff = port.u_eff;
            for &(j, rj, tj) in &self.drift {
                add(o + Q1, o + j, -g0 * rj / tj);
                add(o + Q2, o + j, -g0 * rj / tj);
            }
            for &(k, _, tk) in &self.drift {
                add(
                    o + k,
                    o + THETA,
                    g0 * (act.ga_prime(xi[THETA]) * u_eff - v.v2_t),
                );
                add(o + k, o + actuator::L_P, -g0 * v.v2_l);
                add(o + k, o + Q1, -g0 / act.par.c1);
                add(o + k, o + Q2, -g0 / v.c2);
                for &(j, rj, tj) in &self.drift {
                    add(o + k, o + j, -g0 * rj / tj);
                }
                add(o + k, o + k, -1.0 / tk);
                if let Some(&(last, _)) = self.amp.last() {
                    add(o + k, o + last, source);
                }
            }
        }
        if let Some((k, c3, t3, site)) = self.branch {
            let v = act.voltages(xi)?;
            // ∂i3/∂x, entered in the branch's row and (negated) in the rows it takes from
            let mut d = vec![
                (THETA, c3 * v.v2_t / t3),
                (actuator::L_P, c3 * v.v2_l / t3),
                (Q2, c3 / (v.c2 * t3)),
                (k, -1.0 / t3),
            ];
            let mut rows = vec![Q2];
            if site == DriftSite::Film {
                d.push((Q1, c3 / (act.par.c1 * t3)));
                rows.push(Q1);
            }
            for (col, value) in d {
                add(o + k, o + col, value);
                for &r in &rows {
                    add(o + r, o + col, -value);
                }
            }
        }
        let mut prev = None;
        for &(k, t) in &self.amp {
            add(o + k, o + k, -1.0 / t);
            if let Some(j) = prev {
                add(o + k, o + j, 1.0 / t);
            }
            prev = Some(k);
        }
        Ok(())
    }

    /// ∂(actuator i's block of ẋ)/∂U through `add(row, value)`, rows counted inside the block:
    /// the command drives the first amplifier stage if there is one (τ U̇_amp = U − U_amp),
    /// otherwise the port voltage clamp(U) enters the circuit (Q1, Q2) and the drift stages
    /// through G0 ga(θ) times the clipping's slope.
    pub fn add_input_jacobian(
        &self,
        act: &Actuator,
        xi: &[f64],
        u: f64,
        mut add: impl FnMut(usize, f64),
    ) {
        if let Some(&(k, t)) = self.amp.first() {
            add(k, 1.0 / t);
            return;
        }
        let source = act.g0 * act.ga(xi[THETA]) * self.port(xi, u).slope;
        add(Q1, source);
        add(Q2, source);
        for &(k, _, _) in &self.drift {
            add(k, source);
        }
    }

    /// Energy stored in the terms [J] (hysteresis, a rate-independent dissipative law with no
    /// storage function here, adds none).
    pub fn energy(&self, a: &[&Actuator; 3], x: [&[f64]; 3]) -> f64 {
        let mut e = 0.0;
        let c = self.fx.coupling;
        if c.k_c != 0.0 {
            let h = [0, 1, 2].map(|j| a[j].height(x[j][THETA]));
            for (i, j) in [(0, 1), (0, 2), (1, 2)] {
                e += 0.5 * c.k_c * c.weights[pair(i, j)] * (h[i] - h[j]).powi(2);
            }
        }
        for (xi, tau0) in x.iter().zip(self.fx.preload.tau0) {
            let th = xi[THETA];
            let st = self.fx.stiffening;
            if st.k3 != 0.0 {
                e += st.k3 * th.abs().powi(st.exponent) / f64::from(st.exponent);
            }
            e += match self.fx.preload.law {
                PreloadLaw::Constant => tau0 * th,
                PreloadLaw::Weight => tau0 * th.sin(),
            };
            for &(k, kb, _) in &self.creep {
                e += 0.5 * kb * (th - xi[k]).powi(2);
            }
            for &(k, r, t) in &self.drift {
                e += 0.5 * r * xi[k] * xi[k] / t;
            }
            if let Some((k, c3, _, _)) = self.branch {
                e += 0.5 * xi[k] * xi[k] / c3;
            }
        }
        e
    }

    /// Extra power at actuator i's port beyond the actuator's own y·u_eff [W]: the drift
    /// stage in series adds V3 to the port output.
    pub fn port_power(&self, act: &Actuator, xi: &[f64], u: f64) -> f64 {
        let port = self.port(xi, u);
        act.g0 * act.ga(xi[THETA]) * port.u_eff * self.drift_voltage(xi)
    }

    /// Extra dissipation of actuator i beyond the actuator's own [W]: the hysteretic work, the
    /// creep dashpots and the drift stage's resistor, with the source resistor's share of V3.
    pub fn dissipation(&self, act: &Actuator, xi: &[f64]) -> Result<f64, DomainError> {
        let mut p = 0.0;
        if let Some(k) = self.hyst {
            // the hysteretic torque's work: no storage function, so all of it counts here
            p += self.fx.hysteresis.k_h * xi[k] * xi[P] / act.inertia;
        }
        for &(k, kb, tb) in &self.creep {
            p += kb * (xi[THETA] - xi[k]).powi(2) / tb;
        }
        if !self.drift.is_empty() {
            let v = act.voltages(xi)?;
            let (vs, v3) = (v.v1 + v.v2, self.drift_voltage(xi));
            p += act.g0 * ((vs + v3).powi(2) - vs * vs);
            for &(k, r, t) in &self.drift {
                let vk = r * xi[k] / t;
                p += vk * vk / r;
            }
        }
        if let Some((_, c3, t3, _)) = self.branch {
            // the branch's resistor R3 = τ3 / C3
            let i3 = self.branch_current(&act.voltages(xi)?, xi);
            p += i3 * i3 * t3 / c3;
        }
        Ok(p)
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
