//! The port-Hamiltonian structure of the linearization, and the passivity of its port.
//!
//! The model is ẋ = F(x) ∇H(x) + g(x) U with F = J(x) − R, J(x) skew (its entries J_θp = 1,
//! J_{l_p p} = d(θ, l_p) depend on the state), R ≥ 0 constant and g(x) = G0 ga(θ)(e_Q1 + e_Q2)
//! (model.md, "Dynamics"). At an equilibrium x0 under U0, with e0 = ∇H(x0) and the plain
//! Hessian ∇²H(x0), the linearization is
//!
//! ```text
//! A δx = F(x0) ∇²H δx + (∂F/∂x δx) e0 + (∂g/∂x δx) U0
//! ```
//!
//! and the two extra terms are treated as follows.
//!
//! **The structure matrix's variation is absorbed exactly.** (∂F/∂x δx) e0 has one nonzero
//! row, ṗ: −(d_θ δθ + d_l δl_p) ∂H/∂l_p (the p-row of (∂J/∂x δx) e0; its l_p-row is
//! δd · ∂H/∂p = 0 since p = 0). It is nonzero even at rest (gravity leaves ∂H/∂l_p ≠ 0). It
//! equals F(x0) M for the symmetric M that is nonzero only on (θ, l_p) × (θ, l_p):
//! F(x0) M has the ṗ-row −(M_θ· + d M_l·), so M must satisfy
//! M_θθ + d M_lθ = d_θ ∂H/∂l_p and M_θl + d M_ll = d_l ∂H/∂l_p. The kernel of F(x0)
//! (the Casimir gradient direction (−d, 1) on (θ, l_p)) leaves one free parameter; we take
//! M_ll = 0, so M_θl = d_l ∂H/∂l_p and M_θθ = (d_θ − d d_l) ∂H/∂l_p. Every choice gives the
//! same form on the reachable subspace δl_p = d δθ, where it adds the curve's curvature term
//! ℓ''(θ) ∂H/∂l_p (ℓ'' = d_θ + d d_l) to the stiffness along the curve: Q = ∇²H + M is the
//! Hessian of the energy restricted to the invariant curve, written in the full coordinates
//! (the Hessian of H in coordinates (θ, c) of the Casimir, where J is constant).
//!
//! **The input map's variation is a modulated source.** (∂g/∂x δx) U0 = G0 ga'(θ0) U0 δθ
//! (e_Q1 + e_Q2) is not of the form F(x0)·(symmetric): its ṗ-row is zero, so the symmetric
//! matrix would need a nonzero (θ, Q) entry in Q whose partner (Q, θ) moves the electrical
//! rows. The circuit sees the source voltage w = ga(θ) U behind R0; with w as the input the
//! input map g̃ = G0 (e_Q1 + e_Q2) is constant, and the linearization is exactly
//!
//! ```text
//! δẋ = (J(x0) − R) Q δx + g̃ δw,   δỹ = g̃ᵀ Q δx  (ỹ = G0 (V1 + V2), the current into R0's node)
//! δw = ga(θ0) δU + ga'(θ0) U0 δθ
//! ```
//!
//! a port-Hamiltonian system with the shifted Hamiltonian H(x) − ∇H(x0)ᵀ(x − x0) − H(x0)
//! (whose Hessian at x0 is ∇²H; Q adds the curvature of the Casimir leaf), passive from δw to
//! δỹ with the storage ½ δxᵀ Q δx. The voltage port (U, y = gᵀ∇H = ga(θ) ỹ, the model's port
//! output) sees it through the modulated transformer ga(θ): A = (J − R) Q + g̃ ga'(θ0) U0 e_θᵀ
//! and the collocated output δy = Bᵀ Q δx + G0 ga'(θ0)(V1 + V2) δθ. Both extra terms vanish at
//! U0 = 0 (or where ga'(θ0) = 0); otherwise the storage ½ δxᵀ Q δx does not certify the
//! voltage port's passivity (the KYP matrix is indefinite, reported), and its passivity is
//! checked on a dense frequency grid instead.
//!
//! Away from an equilibrium (`--at-time`), p ≠ 0 adds terms (δd · ∂H/∂p in the l_p-row) that
//! none of this absorbs; the residuals say how large they are.

use nalgebra::DMatrix;

use super::frequency::{Evaluator, log_grid};
use super::linearize::{Linearization, StateSpace, tie};
use super::{ControlError, linalg};
use crate::model::actuator::{self, L_P, Q1, Q2, THETA};
use crate::model::shell::Shell;
use crate::model::{ModelError, Platform};

/// The decomposition and its checks.
#[derive(Clone, Debug, PartialEq)]
pub struct PortHamiltonian {
    /// J(x0), skew-symmetric.
    pub j: DMatrix<f64>,
    /// R, symmetric positive semi-definite.
    pub r: DMatrix<f64>,
    /// Q = ∇²H(x0) + M (the Hessian with the Casimir leaf's curvature).
    pub q: DMatrix<f64>,
    /// The plain Hessian ∇²H(x0).
    pub hessian: DMatrix<f64>,
    /// g̃ (n × 3): the constant input map of the source voltages w_i = ga(θ_i) U_i.
    pub source_map: DMatrix<f64>,
    /// δw = K_u δU + K_x δx: K_u = diag(ga(θ0_i)).
    pub source_gain: [f64; 3],
    /// K_x (3 × n): ga'(θ0_i) U0_i on θ_i.
    pub source_feedback: DMatrix<f64>,
    /// The voltage port's collocated output δy = C_port δx (y = gᵀ∇H \[A\]; D_port = 0).
    pub port_c: DMatrix<f64>,
    pub checks: Checks,
    pub passivity: Passivity,
}

/// Numerical checks, every matrix in the scaled states x = S x̃ (so that charges and angles
/// weigh alike); norms are Frobenius norms.
#[derive(Clone, Debug, PartialEq)]
pub struct Checks {
    /// ‖J + Jᵀ‖ / ‖J‖.
    pub j_skew: f64,
    /// ‖R − Rᵀ‖ / ‖R‖.
    pub r_asymmetry: f64,
    /// Smallest and largest eigenvalue of R (scaled).
    pub r_eigenvalues: (f64, f64),
    /// ‖Q − Qᵀ‖ / ‖Q‖.
    pub q_asymmetry: f64,
    /// Eigenvalues of Q on the reachable subspace (Tᵀ Q T, δl_p = d δθ), smallest and largest.
    pub q_reachable_eigenvalues: (f64, f64),
    /// Smallest and largest eigenvalue of Q on the whole space.
    pub q_eigenvalues: (f64, f64),
    /// ‖A − (J − R) ∇²H‖ / ‖A‖: the plain Hessian.
    pub residual_hessian: f64,
    /// The same row by row: max_r ‖row_r‖ / ‖row_r(A)‖ (the mechanical rows are small beside
    /// the electrical ones, so the whole-matrix ratio hides them).
    pub residual_hessian_rows: f64,
    /// ‖A − (J − R) Q‖ / ‖A‖: what the voltage port's PH form misses (the modulated source).
    pub residual_voltage_port: f64,
    pub residual_voltage_port_rows: f64,
    /// ‖A − (J − R) Q − g̃ K_x‖ / ‖A‖: the source port's exact PH form.
    pub residual_source_port: f64,
    pub residual_source_port_rows: f64,
    /// ‖B − g̃ K_u‖ / ‖B‖.
    pub residual_input: f64,
    /// ‖C_port − Bᵀ Q‖ / ‖C_port‖: the voltage port's output beyond the collocated Bᵀ Q.
    pub collocation_voltage_port: f64,
    /// Smallest eigenvalue of the KYP matrix [[−(Q A + Aᵀ Q), C_portᵀ − Q B], [·, 0]] of the
    /// voltage port with the storage ½ δxᵀ Q δx on the reachable subspace, relative to its
    /// largest: ≥ 0 (up to rounding) certifies passivity with that storage.
    pub kyp_voltage_port: f64,
}

/// Passivity of the voltage port's transfer matrix G_port(jω) = C_port (jωI − A)⁻¹ B on a
/// dense grid: the smallest eigenvalue of its Hermitian part.
#[derive(Clone, Debug, PartialEq)]
pub struct Passivity {
    /// The grid \[Hz\]: ω = 0 and `points` frequencies from `f_min` to `f_max`.
    pub f_min: f64,
    pub f_max: f64,
    pub points: usize,
    /// min over the grid of λ_min(G + Gᴴ)/2 \[S\].
    pub min_hermitian: f64,
    /// Where it is reached \[Hz\].
    pub worst_frequency: f64,
    /// max over the grid of ‖G_port‖ \[S\], the scale of the check.
    pub scale: f64,
    /// Are all eigenvalues of the minimal model in the open left half-plane? (Without that
    /// the frequency-domain test says nothing.)
    pub stable: bool,
    /// stable and min_hermitian ≥ −`PASSIVITY_TOLERANCE` · scale.
    pub passive: bool,
    /// The port's DC conductance G_port(0) per actuator (diagonal) \[S\].
    pub dc: Vec<f64>,
}

/// Rounding allowance of the grid check, relative to the port's largest gain: G(jω) is
/// computed with a condition number of about 1e8 (the time scales span eight decades).
const PASSIVITY_TOLERANCE: f64 = 1e-9;

/// The decomposition at the linearization's point (see the module documentation).
pub fn decompose(model: &Platform, lin: &Linearization) -> Result<PortHamiltonian, ControlError> {
    let active = model.params().effects.active();
    if !active.is_empty() {
        return Err(ControlError::Unsupported {
            what: "the port-Hamiltonian decomposition",
            effects: active.iter().map(|e| e.name().to_string()).collect(),
        });
    }
    let Parts {
        j,
        r,
        hessian,
        m,
        source_map,
        source_feedback,
        port_c,
        source_gain,
    } = parts(model, lin)?;
    let q = &hessian + &m;

    let n = model.n_states();
    let (t, _) = tie(n, &lin.casimirs.slopes);
    let minimal = lin.minimal();
    let checks = checks(
        lin,
        (&j, &r, &q, &hessian),
        (&source_map, &source_feedback, &source_gain, &port_c),
        &t,
        &minimal,
    );
    let stable = lin.minimal_eigenvalues.iter().all(|e| e.re < 0.0);
    let passivity = passivity(&minimal, &(&port_c * &t), stable)?;
    Ok(PortHamiltonian {
        j,
        r,
        q,
        hessian,
        source_map,
        source_gain,
        source_feedback,
        port_c,
        checks,
        passivity,
    })
}

/// The structure of the whole platform at the point, actuator by actuator (the effects all
/// off): J, R, the Hessian of H, the Casimir leaf's curvature M, the source voltage's map,
/// gain and feedback, and the voltage port's output Jacobian.
struct Parts {
    j: DMatrix<f64>,
    r: DMatrix<f64>,
    hessian: DMatrix<f64>,
    m: DMatrix<f64>,
    source_map: DMatrix<f64>,
    source_feedback: DMatrix<f64>,
    port_c: DMatrix<f64>,
    source_gain: [f64; 3],
}

/// Assembles the [`Parts`] from each actuator's at the linearization's state and voltages.
fn parts(model: &Platform, lin: &Linearization) -> Result<Parts, ControlError> {
    let n = model.n_states();
    let nb = actuator::N;
    let x0 = &lin.x0;
    let u0 = lin.u0;
    let lv = model.params().lv;
    let mut j = DMatrix::zeros(n, n);
    let mut r = DMatrix::zeros(n, n);
    let mut hessian = DMatrix::zeros(n, n);
    let mut m = DMatrix::zeros(n, n);
    let mut source_map = DMatrix::zeros(n, 3);
    let mut source_feedback = DMatrix::zeros(3, n);
    let mut port_c = DMatrix::zeros(3, n);
    let mut source_gain = [0.0; 3];
    for (i, a) in model.actuators.iter().enumerate() {
        let o = nb * i;
        let xi = &x0[o..o + nb];
        let wrap = |cause| ModelError {
            actuator: i + 1,
            cause,
        };
        let st = a.structure(xi).map_err(wrap)?;
        let h = a.hessian(xi).map_err(wrap)?;
        let grad = a.grad_h(xi).map_err(wrap)?;
        let shell = Shell::new(xi[THETA], xi[L_P], lv).map_err(wrap)?;
        let curv = shell.curvature();
        let cp = a.port_output_jacobian(xi).map_err(wrap)?;
        for rr in 0..nb {
            for cc in 0..nb {
                j[(o + rr, o + cc)] = st.j[rr][cc];
                r[(o + rr, o + cc)] = st.r[rr][cc];
                hessian[(o + rr, o + cc)] = h[rr][cc];
            }
            port_c[(i, o + rr)] = cp[rr];
        }
        // the Casimir leaf's curvature (module documentation), with M_ll = 0
        let h_l = grad[L_P];
        m[(o + THETA, o + THETA)] = (curv.d_t - shell.d * curv.d_l) * h_l;
        m[(o + THETA, o + L_P)] = curv.d_l * h_l;
        m[(o + L_P, o + THETA)] = curv.d_l * h_l;
        // the source voltage w = ga(θ) U behind R0
        source_map[(o + Q1, i)] = a.g0;
        source_map[(o + Q2, i)] = a.g0;
        source_gain[i] = a.ga(xi[THETA]);
        source_feedback[(i, o + THETA)] = a.ga_prime(xi[THETA]) * u0[i];
    }
    Ok(Parts {
        j,
        r,
        hessian,
        m,
        source_map,
        source_feedback,
        port_c,
        source_gain,
    })
}

/// The checks of the decomposition (J, R, Q; the residuals of A against (J − R) Q from each
/// port; collocation and KYP) in the state scales, with `t` the Casimir tie and `minimal` the
/// minimal model.
fn checks(
    lin: &Linearization,
    (j, r, q, hessian): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    (source_map, source_feedback, source_gain, port_c): (
        &DMatrix<f64>,
        &DMatrix<f64>,
        &[f64; 3],
        &DMatrix<f64>,
    ),
    t: &DMatrix<f64>,
    minimal: &StateSpace,
) -> Checks {
    let n = j.nrows();
    let s = &lin.system.scales;
    // scaled: A_s = S⁻¹AS, J_s = S⁻¹JS⁻¹, Q_s = SQS, g̃_s = S⁻¹g̃, K_x,s = K_x S
    let congruent_inv = |x: &DMatrix<f64>| DMatrix::from_fn(n, n, |a, b| x[(a, b)] / (s[a] * s[b]));
    let congruent = |x: &DMatrix<f64>| DMatrix::from_fn(n, n, |a, b| x[(a, b)] * s[a] * s[b]);
    let a_s = linalg::scale_similar(&lin.system.a, s);
    let (j_s, r_s) = (congruent_inv(j), congruent_inv(r));
    let (q_s, hess_s) = (congruent(q), congruent(hessian));
    let f_s = &j_s - &r_s;
    let modulated = linalg::scale_rows(source_map, s) * linalg::scale_columns(source_feedback, s);
    let a_norm = a_s.norm();
    let rel = |x: DMatrix<f64>, scale: f64| x.norm() / scale.max(f64::MIN_POSITIVE);
    let range = |ev: Vec<f64>| {
        (
            ev.first().copied().unwrap_or(0.0),
            ev.last().copied().unwrap_or(0.0),
        )
    };
    let t_s = DMatrix::from_fn(t.nrows(), t.ncols(), |a, b| t[(a, b)] / s[a]);
    // the reachable subspace in scaled coordinates: x̃ = S⁻¹ T z, with z scaled likewise
    let z_scale = &minimal.scales;
    let t_sz = DMatrix::from_fn(n, t.ncols(), |a, b| t_s[(a, b)] * z_scale[b]);
    let q_reach = t_sz.transpose() * &q_s * &t_sz;
    let b = &lin.system.b;
    let c_port_s = linalg::scale_columns(port_c, s);
    let bq = linalg::scale_rows(b, s).transpose() * &q_s;
    Checks {
        j_skew: rel(&j_s + j_s.transpose(), j_s.norm()),
        r_asymmetry: rel(&r_s - r_s.transpose(), r_s.norm()),
        r_eigenvalues: range(linalg::symmetric_eigenvalues(&r_s)),
        q_asymmetry: rel(&q_s - q_s.transpose(), q_s.norm()),
        q_reachable_eigenvalues: range(linalg::symmetric_eigenvalues(&q_reach)),
        q_eigenvalues: range(linalg::symmetric_eigenvalues(&q_s)),
        residual_hessian: rel(&a_s - &f_s * &hess_s, a_norm),
        residual_hessian_rows: by_rows(&(&a_s - &f_s * &hess_s), &a_s),
        residual_voltage_port: rel(&a_s - &f_s * &q_s, a_norm),
        residual_voltage_port_rows: by_rows(&(&a_s - &f_s * &q_s), &a_s),
        residual_source_port: rel(&a_s - &f_s * &q_s - &modulated, a_norm),
        residual_source_port_rows: by_rows(&(&a_s - &f_s * &q_s - &modulated), &a_s),
        residual_input: rel(
            b - source_map
                * DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(source_gain)),
            b.norm(),
        ),
        collocation_voltage_port: rel(&c_port_s - &bq, c_port_s.norm()),
        kyp_voltage_port: kyp(minimal, &q_reach, port_c, t),
    }
}

/// max over the rows of `a` of ‖row_r(x)‖ / ‖row_r(a)‖.
fn by_rows(x: &DMatrix<f64>, a: &DMatrix<f64>) -> f64 {
    (0..a.nrows())
        .filter(|&r| a.row(r).norm() > 0.0)
        .map(|r| x.row(r).norm() / a.row(r).norm())
        .fold(0.0, f64::max)
}

/// The KYP matrix of the voltage port on the reachable subspace (scaled minimal states):
/// smallest eigenvalue relative to the largest magnitude.
fn kyp(
    minimal: &StateSpace,
    q_reach: &DMatrix<f64>,
    port_c: &DMatrix<f64>,
    t: &DMatrix<f64>,
) -> f64 {
    let z = &minimal.scales;
    let a = linalg::scale_similar(&minimal.a, z);
    let b = linalg::scale_rows(&minimal.b, z);
    let c = linalg::scale_columns(&(port_c * t), z);
    let nz = a.nrows();
    let mut w = DMatrix::zeros(nz + 3, nz + 3);
    let lyap = -(q_reach * &a + a.transpose() * q_reach);
    let off = c.transpose() - q_reach * &b;
    w.view_mut((0, 0), (nz, nz)).copy_from(&lyap);
    w.view_mut((0, nz), (nz, 3)).copy_from(&off);
    w.view_mut((nz, 0), (3, nz)).copy_from(&off.transpose());
    let ev = linalg::symmetric_eigenvalues(&w);
    let largest = ev.iter().map(|v| v.abs()).fold(0.0, f64::max);
    ev.first().copied().unwrap_or(0.0) / largest.max(f64::MIN_POSITIVE)
}

/// The grid check of the voltage port (minimal model, so that ω = 0 is included).
fn passivity(
    minimal: &StateSpace,
    port_c: &DMatrix<f64>,
    stable: bool,
) -> Result<Passivity, ControlError> {
    let port = StateSpace {
        c: port_c.clone(),
        d: DMatrix::zeros(3, 3),
        outputs: vec!["y1".into(), "y2".into(), "y3".into()],
        ..minimal.clone()
    };
    let ev = Evaluator::new(&port);
    let (f_min, f_max) = (1e-3, 1e10);
    let grid = log_grid(f_min, f_max, 40);
    let mut freqs = vec![0.0];
    freqs.extend(&grid);
    let (mut min_h, mut worst, mut scale) = (f64::INFINITY, 0.0, 0.0f64);
    let mut dc = Vec::new();
    for &f in &freqs {
        let g = ev.at(2.0 * std::f64::consts::PI * f)?;
        if f == 0.0 {
            dc = (0..3).map(|i| g[(i, i)].re).collect();
        }
        scale = scale.max(linalg::spectral_norm(&g));
        let h = linalg::min_hermitian_eigenvalue(&g);
        if h < min_h {
            (min_h, worst) = (h, f);
        }
    }
    Ok(Passivity {
        f_min,
        f_max,
        points: freqs.len(),
        min_hermitian: min_h,
        worst_frequency: worst,
        scale,
        stable,
        passive: stable && min_h >= -PASSIVITY_TOLERANCE * scale,
        dc,
    })
}
