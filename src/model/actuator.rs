//! One HASEL actuator as a port-Hamiltonian system (book/src/model.md, "State and energy" and
//! "Dynamics").
//!
//! State x = (θ, l_p, p, Q1, Q2):
//!
//! ```text
//! H  = ½ Kb θ² + ½ g Lv m sin θ + ¼ K (l_p − Lp)² + p²/(2 I) + Q1²/(2 C1) + Q2²/(2 C2(θ, l_p))
//! ẋ  = (J(x) − R) ∇H + g(x) U
//! θ̇   = ∂H/∂p
//! l̇_p = d ∂H/∂p
//! ṗ   = −∂H/∂θ − d ∂H/∂l_p − b ∂H/∂p
//! Q̇1  = −(G0 + G1) ∂H/∂Q1 − G0 ∂H/∂Q2 + G0 ga(θ) U
//! Q̇2  = −G0 ∂H/∂Q1 − (G0 + G2) ∂H/∂Q2 + G0 ga(θ) U
//! ```

use super::params::{ActuatorParams, Params};
use super::shell::{DomainError, Shell};

/// Index of each state inside an actuator's block of five.
pub const THETA: usize = 0;
pub const L_P: usize = 1;
pub const P: usize = 2;
pub const Q1: usize = 3;
pub const Q2: usize = 4;
/// States per actuator.
pub const N: usize = 5;

/// What the model says of one of its states: name (without the actuator's suffix), unit and
/// meaning, for every table and output that names states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StateInfo {
    pub name: &'static str,
    pub unit: &'static str,
    pub description: &'static str,
}

/// The five states of an actuator, in block order ([`THETA`] … [`Q2`]).
pub const STATES: [StateInfo; N] = [
    StateInfo {
        name: "theta",
        unit: "rad",
        description: "Film rotation angle theta",
    },
    StateInfo {
        name: "l_p",
        unit: "m",
        description: "Top film length l_p",
    },
    StateInfo {
        name: "p",
        unit: "kg.m/s",
        description: "Angular momentum p = I dtheta/dt with the paper's I = Lv m/24 [kg.m]",
    },
    StateInfo {
        name: "Q1",
        unit: "C",
        description: "Charge Q1 of the retention capacitor C1",
    },
    StateInfo {
        name: "Q2",
        unit: "C",
        description: "Charge Q2 of the electrode capacitor C2",
    },
];

/// One actuator's constants, derived once from the parameters.
#[derive(Clone, Debug)]
pub struct Actuator {
    pub par: ActuatorParams,
    /// I = Lv m / 24, as written in the paper (book/src/model.md, "Open choices and pinned
    /// defaults").
    pub inertia: f64,
    pub g0: f64,
    pub g1: f64,
    pub g2: f64,
    /// ½ g Lv m: the gravity term's coefficient [J].
    gravity: f64,
    lp: f64,
    lv: f64,
    /// C2 = c2_0 + c2_a A_s, since le = Le − (A_T − A_s)/Xh is affine in A_s.
    c2_0: f64,
    c2_a: f64,
    /// C2 with le = 0 [F].
    c2_unzipped: f64,
}

/// Capacitor voltages at one state \[V\] and C2 \[F\], with ∂V2/∂θ [V/rad] and ∂V2/∂l_p [V/m].
#[derive(Clone, Copy, Debug)]
pub struct Voltages {
    pub v1: f64,
    pub v2: f64,
    pub c2: f64,
    pub v2_t: f64,
    pub v2_l: f64,
}

/// The port-Hamiltonian structure matrices of one actuator at a state (row-major 5×5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Structure {
    /// Interconnection J(x), skew-symmetric.
    pub j: [[f64; N]; N],
    /// Dissipation R, symmetric positive semi-definite.
    pub r: [[f64; N]; N],
    /// Input map g(x).
    pub g: [f64; N],
}

/// The slow model's θ̇ = a + b u² at one angle on the invariant curve, at port voltage u, and
/// the derivatives of a and b along the curve [`Actuator::slow_rate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct SlowRate {
    pub(super) a: f64,
    pub(super) a_t: f64,
    pub(super) b: f64,
    pub(super) b_t: f64,
}

impl SlowRate {
    /// θ̇ [rad/s] at port voltage `u` [V].
    pub(super) fn at(&self, u: f64) -> f64 {
        self.a + self.b * u * u
    }
}

/// Quantities shared by H, ∇H, f and ∂f/∂x at one state.
struct Eval {
    shell: Shell,
    c2: f64,
    /// V1 = Q1/C1, V2 = Q2/C2 [V]
    v1: f64,
    v2: f64,
    /// ω = ∂H/∂p = p/I [rad/s]
    omega: f64,
    h_t: f64,
    h_l: f64,
}

impl Actuator {
    pub fn new(params: &Params, i: usize) -> Actuator {
        let par = params.act[i];
        // C2 = ε0 εr w ( le/(2t) + (Le − le)/(2t + Xh) ),  le = Le − (A_T − A_s)/Xh
        let e = params.eps0 * params.eps_r * params.w;
        let (thin, thick) = (
            1.0 / (2.0 * params.t_film),
            1.0 / (2.0 * params.t_film + params.xh),
        );
        let le_0 = params.le - params.a_t / params.xh;
        Actuator {
            par,
            inertia: params.lv * params.m / 24.0,
            g0: 1.0 / par.r0,
            g1: 1.0 / par.r1,
            g2: 1.0 / par.r2,
            gravity: 0.5 * params.g * params.lv * params.m,
            lp: params.lp,
            lv: params.lv,
            c2_0: e * (params.le * thick + le_0 * (thin - thick)),
            c2_a: e * (thin - thick) / params.xh,
            c2_unzipped: e * params.le * thick,
        }
    }

    #[inline(always)]
    fn eval(&self, x: &[f64]) -> Result<Eval, DomainError> {
        let shell = Shell::new(x[THETA], x[L_P], self.lv)?;
        let c2 = self.c2_0 + self.c2_a * shell.a_s;
        let v1 = x[Q1] / self.par.c1;
        let v2 = x[Q2] / c2;
        let (h_t, h_l) = self.geometric_gradient(&shell, x[THETA], x[L_P], v2);
        Ok(Eval {
            c2,
            v1,
            v2,
            omega: x[P] / self.inertia,
            h_t,
            h_l,
            shell,
        })
    }

    /// (∂H/∂θ, ∂H/∂l_p) at the geometry of `shell` with the electrode at voltage `v2`.
    #[inline(always)]
    fn geometric_gradient(&self, shell: &Shell, theta: f64, l_p: f64, v2: f64) -> (f64, f64) {
        // ∂/∂x of Q2²/(2 C2) = −½ V2² ∂C2/∂x
        let e_x = -0.5 * v2 * v2 * self.c2_a;
        (
            self.par.kb * theta + self.gravity * shell.cos_theta + e_x * shell.a_s_t,
            0.5 * self.par.k * (l_p - self.lp) + e_x * shell.a_s_l,
        )
    }

    /// θ̇ of the slow model without effects (src/model/reduced.rs) at (θ, l_p) on the invariant
    /// curve, as θ̇ = a(θ) + b(θ) u² with its derivatives along the curve. On the DC circuit
    /// V2 = R2 ga(θ) u/(R0 + R1 + R2), so the electrode's term e_x = −½ V2² ∂C2/∂A_s of
    /// [`Actuator::geometric_gradient`] is −E(θ) u², E = ½ c2_a (R2 ga/(R0 + R1 + R2))², and
    /// ṗ = 0 gives ω = −(∂H/∂θ + d ∂H/∂l_p)/b:
    ///
    /// ```text
    /// a = −(kb θ + G cos θ + ½ k d (l_p − Lp)) / b          b = E S / b,  S = A_s,θ + d A_s,l
    /// a' = −(kb − G sin θ + ½ k (d' (l_p − Lp) + d²)) / b    b' = (E' S + E S') / b
    /// ```
    ///
    /// with ' = ∂/∂θ + d ∂/∂l_p along the curve (dl_p/dθ = d): d' = d_θ + d d_l,
    /// S' = A_s,θθ + 2 d A_s,θl + d² A_s,ll + d' A_s,l, E' = c2_a (R2/(R0 + R1 + R2))² ga ga'.
    /// One geometry and its curvature, for the table of [`super::invariant_curve::Curve`].
    pub(super) fn slow_rate(&self, theta: f64, l_p: f64) -> Result<SlowRate, DomainError> {
        let shell = Shell::new(theta, l_p, self.lv)?;
        let c = shell.curvature();
        let damping = self.par.b;
        let (d, dl) = (shell.d, l_p - self.lp);
        let d_t = c.d_t + d * c.d_l;
        let gain = self.par.r2 / (self.par.r0 + self.par.r1 + self.par.r2);
        let (ga, ga_t) = (self.ga(theta), self.ga_prime(theta));
        let e = 0.5 * self.c2_a * gain * gain * ga * ga;
        let e_t = self.c2_a * gain * gain * ga * ga_t;
        let s = shell.a_s_t + d * shell.a_s_l;
        let s_t = c.a_s_tt + 2.0 * d * c.a_s_tl + d * d * c.a_s_ll + d_t * shell.a_s_l;
        Ok(SlowRate {
            a: -(self.par.kb * theta + self.gravity * shell.cos_theta + 0.5 * self.par.k * d * dl)
                / damping,
            a_t: -(self.par.kb - self.gravity * shell.sin_theta
                + 0.5 * self.par.k * (d_t * dl + d * d))
                / damping,
            b: e * s / damping,
            b_t: (e_t * s + e * s_t) / damping,
        })
    }

    /// Electrode capacitance C2(θ, l_p) \[F\].
    pub fn c2(&self, theta: f64, l_p: f64) -> Result<f64, DomainError> {
        Ok(self.c2_0 + self.c2_a * Shell::new(theta, l_p, self.lv)?.a_s)
    }

    /// Input gain ga(θ) = γ1 cos(γ2 θ).
    pub fn ga(&self, theta: f64) -> f64 {
        self.par.gamma1 * (self.par.gamma2 * theta).cos()
    }

    /// dga/dθ = −γ1 γ2 sin(γ2 θ).
    pub fn ga_prime(&self, theta: f64) -> f64 {
        -self.par.gamma1 * self.par.gamma2 * (self.par.gamma2 * theta).sin()
    }

    /// The capacitor voltages and how V2 = Q2/C2 moves with the geometry, for terms that
    /// extend the circuit (the effect library).
    pub fn voltages(&self, x: &[f64]) -> Result<Voltages, DomainError> {
        let e = self.eval(x)?;
        Ok(Voltages {
            v1: e.v1,
            v2: e.v2,
            c2: e.c2,
            // ∂V2/∂x = −V2 C2_x / C2 = ∂²H/∂x∂Q2
            v2_t: -e.v2 * self.c2_a * e.shell.a_s_t / e.c2,
            v2_l: -e.v2 * self.c2_a * e.shell.a_s_l / e.c2,
        })
    }

    /// The loop current \[A\] of the DC circuit at the port voltage u (book/src/model.md,
    /// "Statics"): with Q̇1 = Q̇2 = 0 the capacitors carry no current, so one current
    /// i = ga(θ) u / (R0 + R1 + R2) runs through the three resistors.
    pub fn dc_current(&self, theta: f64, u: f64) -> f64 {
        self.ga(theta) * u / (self.par.r0 + self.par.r1 + self.par.r2)
    }

    /// The state at (θ, l_p) at rest (p = 0) with the DC circuit carrying the loop current
    /// i \[A\]: V1 = R1 i, V2 = R2 i, so Q1 = C1 R1 i and Q2 = C2(θ, l_p) R2 i.
    pub fn dc_state(&self, theta: f64, l_p: f64, i: f64) -> Result<[f64; N], DomainError> {
        let (q1, q2) = (
            self.par.c1 * self.par.r1 * i,
            self.c2(theta, l_p)? * self.par.r2 * i,
        );
        Ok([theta, l_p, 0.0, q1, q2])
    }

    /// dh/dθ = ½ Lv cos θ [m/rad].
    pub fn height_slope(&self, theta: f64) -> f64 {
        0.5 * self.lv * theta.cos()
    }

    /// Stored energy H \[J\].
    pub fn energy(&self, x: &[f64]) -> Result<f64, DomainError> {
        let e = self.eval(x)?;
        let dl = x[L_P] - self.lp;
        Ok(0.5 * self.par.kb * x[THETA] * x[THETA]
            + self.gravity * e.shell.sin_theta
            + 0.25 * self.par.k * dl * dl
            + 0.5 * x[P] * e.omega
            + 0.5 * x[Q1] * e.v1
            + 0.5 * x[Q2] * e.v2)
    }

    /// ∇H = (∂H/∂θ, ∂H/∂l_p, ∂H/∂p, ∂H/∂Q1, ∂H/∂Q2).
    pub fn grad_h(&self, x: &[f64]) -> Result<[f64; N], DomainError> {
        let e = self.eval(x)?;
        Ok([e.h_t, e.h_l, e.omega, e.v1, e.v2])
    }

    /// ẋ = (J − R) ∇H + g U.
    #[inline]
    pub fn rhs(&self, x: &[f64], u: f64, dx: &mut [f64]) -> Result<(), DomainError> {
        let e = self.eval(x)?;
        let d = e.shell.d;
        let source = self.g0 * self.ga(x[THETA]) * u;
        dx[THETA] = e.omega;
        dx[L_P] = d * e.omega;
        dx[P] = -e.h_t - d * e.h_l - self.par.b * e.omega;
        dx[Q1] = -(self.g0 + self.g1) * e.v1 - self.g0 * e.v2 + source;
        dx[Q2] = -self.g0 * e.v1 - (self.g0 + self.g2) * e.v2 + source;
        Ok(())
    }

    /// ∂ẋ/∂x as a 5×5 block, written through `set(row, col, value)`.
    pub fn jacobian(
        &self,
        x: &[f64],
        u: f64,
        mut set: impl FnMut(usize, usize, f64),
    ) -> Result<(), DomainError> {
        let e = self.eval(x)?;
        let s = e.shell.curvature();
        let (d, inv_i) = (e.shell.d, 1.0 / self.inertia);
        // Hessian of H in (θ, l_p, Q2); E = Q2²/(2 C2):
        // E_xy = (V2²/C2) C2_x C2_y − ½ V2² C2_xy,  E_xQ2 = −V2 C2_x / C2
        let (c2_t, c2_l) = (self.c2_a * e.shell.a_s_t, self.c2_a * e.shell.a_s_l);
        let w = e.v2 * e.v2 / e.c2;
        let half_v2sq = 0.5 * e.v2 * e.v2 * self.c2_a;
        let h_tt =
            self.par.kb - self.gravity * e.shell.sin_theta + w * c2_t * c2_t - half_v2sq * s.a_s_tt;
        let h_tl = w * c2_t * c2_l - half_v2sq * s.a_s_tl;
        let h_ll = 0.5 * self.par.k + w * c2_l * c2_l - half_v2sq * s.a_s_ll;
        let h_tq2 = -e.v2 * c2_t / e.c2;
        let h_lq2 = -e.v2 * c2_l / e.c2;
        let source_t = self.g0 * self.ga_prime(x[THETA]) * u;

        set(THETA, P, inv_i);
        set(L_P, THETA, s.d_t * e.omega);
        set(L_P, L_P, s.d_l * e.omega);
        set(L_P, P, d * inv_i);
        set(P, THETA, -h_tt - s.d_t * e.h_l - d * h_tl);
        set(P, L_P, -h_tl - s.d_l * e.h_l - d * h_ll);
        set(P, P, -self.par.b * inv_i);
        set(P, Q2, -h_tq2 - d * h_lq2);
        // ∂V2/∂θ = H_θQ2, ∂V2/∂l_p = H_lQ2
        set(Q1, THETA, -self.g0 * h_tq2 + source_t);
        set(Q1, L_P, -self.g0 * h_lq2);
        set(Q1, Q1, -(self.g0 + self.g1) / self.par.c1);
        set(Q1, Q2, -self.g0 / e.c2);
        set(Q2, THETA, -(self.g0 + self.g2) * h_tq2 + source_t);
        set(Q2, L_P, -(self.g0 + self.g2) * h_lq2);
        set(Q2, Q1, -self.g0 / self.par.c1);
        set(Q2, Q2, -(self.g0 + self.g2) / e.c2);
        Ok(())
    }

    /// ∇²H, the Hessian of the energy H (module doc), symmetric 5×5; the entries the
    /// Jacobian uses: H_θθ, H_θl, H_ll of the bending, gravity, film and zipping-electrode terms,
    /// H_xQ2 = ∂V2/∂x = −V2 C2_x / C2, and the diagonal 1/I, 1/C1, 1/C2.
    pub fn hessian(&self, x: &[f64]) -> Result<[[f64; N]; N], DomainError> {
        let e = self.eval(x)?;
        let s = e.shell.curvature();
        // E = Q2²/(2 C2): E_xy = (V2²/C2) C2_x C2_y − ½ V2² C2_xy (as in `jacobian`)
        let (c2_t, c2_l) = (self.c2_a * e.shell.a_s_t, self.c2_a * e.shell.a_s_l);
        let w = e.v2 * e.v2 / e.c2;
        let half_v2sq = 0.5 * e.v2 * e.v2 * self.c2_a;
        let mut h = [[0.0; N]; N];
        h[THETA][THETA] =
            self.par.kb - self.gravity * e.shell.sin_theta + w * c2_t * c2_t - half_v2sq * s.a_s_tt;
        h[THETA][L_P] = w * c2_t * c2_l - half_v2sq * s.a_s_tl;
        h[L_P][L_P] = 0.5 * self.par.k + w * c2_l * c2_l - half_v2sq * s.a_s_ll;
        h[THETA][Q2] = -e.v2 * c2_t / e.c2;
        h[L_P][Q2] = -e.v2 * c2_l / e.c2;
        h[P][P] = 1.0 / self.inertia;
        h[Q1][Q1] = 1.0 / self.par.c1;
        h[Q2][Q2] = 1.0 / e.c2;
        h[L_P][THETA] = h[THETA][L_P];
        h[Q2][THETA] = h[THETA][Q2];
        h[Q2][L_P] = h[L_P][Q2];
        Ok(h)
    }

    /// The port-Hamiltonian structure at x (module doc, ẋ = (J(x) − R) ∇H + g(x) U): the skew
    /// J(x) (J_θp = 1, J_l p = d(θ, l_p)), the constant R ≥ 0 (b on p; the circuit's
    /// conductances on (Q1, Q2)) and the input map g(x) = G0 ga(θ) (e_Q1 + e_Q2).
    pub fn structure(&self, x: &[f64]) -> Result<Structure, DomainError> {
        let shell = Shell::new(x[THETA], x[L_P], self.lv)?;
        let mut j = [[0.0; N]; N];
        j[THETA][P] = 1.0;
        j[P][THETA] = -1.0;
        j[L_P][P] = shell.d;
        j[P][L_P] = -shell.d;
        let mut r = [[0.0; N]; N];
        r[P][P] = self.par.b;
        r[Q1][Q1] = self.g0 + self.g1;
        r[Q1][Q2] = self.g0;
        r[Q2][Q1] = self.g0;
        r[Q2][Q2] = self.g0 + self.g2;
        let mut g = [0.0; N];
        g[Q1] = self.g0 * self.ga(x[THETA]);
        g[Q2] = g[Q1];
        Ok(Structure { j, r, g })
    }

    /// ∂y/∂x of the port output y = G0 ga(θ) (V1 + V2) (`port_output`):
    /// G0 ga'(θ) (V1 + V2) e_θ + G0 ga(θ) (∂V1/∂x + ∂V2/∂x), with ∂V1/∂Q1 = 1/C1 and
    /// ∂V2/∂x = (H_θQ2, H_lQ2, 0, 0, 1/C2).
    pub fn port_output_jacobian(&self, x: &[f64]) -> Result<[f64; N], DomainError> {
        let v = self.voltages(x)?;
        let k = self.g0 * self.ga(x[THETA]);
        let mut c = [0.0; N];
        c[THETA] = self.g0 * self.ga_prime(x[THETA]) * (v.v1 + v.v2) + k * v.v2_t;
        c[L_P] = k * v.v2_l;
        c[Q1] = k / self.par.c1;
        c[Q2] = k / v.c2;
        Ok(c)
    }

    /// Port output y = G0 ga(θ) (Q1/C1 + Q2/C2) \[A\]; y·U is the supplied power.
    pub fn port_output(&self, x: &[f64]) -> Result<f64, DomainError> {
        let e = self.eval(x)?;
        Ok(self.g0 * self.ga(x[THETA]) * (e.v1 + e.v2))
    }

    /// Dissipated power b ω² + G0 (V1+V2)² + G1 V1² + G2 V2² \[W\].
    pub fn dissipation(&self, x: &[f64]) -> Result<f64, DomainError> {
        let e = self.eval(x)?;
        let vs = e.v1 + e.v2;
        Ok(self.par.b * e.omega * e.omega
            + self.g0 * vs * vs
            + self.g1 * e.v1 * e.v1
            + self.g2 * e.v2 * e.v2)
    }

    /// Power into storage, dH/dt = y U − dissipation, written so that the large electrical terms
    /// cancel analytically: y U − G0 (V1+V2)² = (V1+V2) · G0 (ga U − V1 − V2) = (V1+V2) i0.
    pub fn stored_power(&self, x: &[f64], u: f64) -> Result<f64, DomainError> {
        let e = self.eval(x)?;
        let vs = e.v1 + e.v2;
        let i0 = self.g0 * (self.ga(x[THETA]) * u - vs);
        Ok(e.v1 * (i0 - self.g1 * e.v1) + e.v2 * (i0 - self.g2 * e.v2)
            - self.par.b * e.omega * e.omega)
    }

    /// Actuator height h = ½ Lv sin θ \[m\] (the prismatic joint).
    pub fn height(&self, theta: f64) -> f64 {
        0.5 * self.lv * theta.sin()
    }

    /// Scale of each state, for absolute tolerances: θ* = π/(2γ2) (where ga vanishes); Lp; for p,
    /// (b + I·1/s) θ*, since a momentum error δp relaxes at the rate b/I and so moves θ by δp/b:
    /// p is weighted by its effect on θ, not by its own tiny size (≈ 1e-7), which would make the
    /// error control resolve every fast velocity transient after an input jump; the charges at a
    /// 100 V command in the quasi-static divider (C2 unzipped).
    pub fn state_scales(&self) -> [f64; N] {
        let theta_star = std::f64::consts::FRAC_PI_2 / self.par.gamma2;
        let v_source = self.par.gamma1 * 100.0;
        let i_dc = v_source / (self.par.r0 + self.par.r1 + self.par.r2);
        [
            theta_star,
            self.lp,
            (self.par.b + self.inertia * 1.0) * theta_star,
            self.par.c1 * i_dc * self.par.r1,
            self.c2_unzipped * i_dc * self.par.r2,
        ]
    }
}

impl Actuator {
    /// l_p on the constraint curve through (θ, l_p) = (0, Lp): l̇_p = d θ̇ keeps (θ, l_p) on the
    /// curve dl_p/dθ = d(θ, l_p), integrated here with classical RK4 (16 steps; θ is small).
    pub fn l_p_on_curve(&self, theta: f64) -> Result<f64, DomainError> {
        const STEPS: usize = 16;
        let dt = theta / STEPS as f64;
        let mut l = self.lp;
        for k in 0..STEPS {
            l = self.curve_step(k as f64 * dt, l, dt)?;
        }
        Ok(l)
    }

    /// One classical RK4 step of dl_p/dθ = d(θ, l_p) from (θ, l) over dt: l_p at θ + dt.
    pub(super) fn curve_step(&self, theta: f64, l: f64, dt: f64) -> Result<f64, DomainError> {
        let slope = |t: f64, l: f64| Shell::new(t, l, self.lv).map(|s| s.d);
        let k1 = slope(theta, l)?;
        let k2 = slope(theta + 0.5 * dt, l + 0.5 * dt * k1)?;
        let k3 = slope(theta + 0.5 * dt, l + 0.5 * dt * k2)?;
        let k4 = slope(theta + dt, l + dt * k3)?;
        Ok(l + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4))
    }

    /// The U = 0 equilibrium under gravity on the curve through (0, Lp), with p = Q1 = Q2 = 0
    /// (book/src/model.md, "Initial state"): ṗ = 0 ⇔ ∂H/∂θ + d ∂H/∂l_p = 0, solved by the
    /// secant method on θ.
    pub fn rest_state(&self) -> Result<[f64; N], DomainError> {
        self.rest_state_with(|_| 0.0)
    }

    /// The same equilibrium with an extra static torque `load(θ)` [N m] acting against θ
    /// (the ∂H/∂θ of terms added to the model).
    pub fn rest_state_with(&self, load: impl Fn(f64) -> f64) -> Result<[f64; N], DomainError> {
        let residual = |theta: f64| -> Result<f64, DomainError> {
            let x = [theta, self.l_p_on_curve(theta)?, 0.0, 0.0, 0.0];
            let e = self.eval(&x)?;
            Ok(e.h_t + e.shell.d * e.h_l + load(theta))
        };
        // start from the gravity sag of the bending spring alone
        let mut t0 = 0.0;
        let mut t1 = -self.gravity / self.par.kb;
        let (mut r0, mut r1) = (residual(t0)?, residual(t1)?);
        for _ in 0..50 {
            if r1 == 0.0 || r1 == r0 {
                break;
            }
            let t2 = t1 - r1 * (t1 - t0) / (r1 - r0);
            (t0, r0) = (t1, r1);
            t1 = t2;
            r1 = residual(t1)?;
            if (t1 - t0).abs() <= 1e-16 * t1.abs().max(1e-12) {
                break;
            }
        }
        Ok([t1, self.l_p_on_curve(t1)?, 0.0, 0.0, 0.0])
    }
}
