//! A reduced model for controller design: balanced singular-perturbation approximation of the
//! minimal model (the Casimir directions removed, see [`linearize`]).
//!
//! The electrical modes (~1e8 s⁻¹) and the fast mechanical ones (~1e5 s⁻¹) are far beyond any
//! controller's bandwidth. The minimal model is balanced (its controllability and observability
//! Gramians made equal and diagonal, the Hankel singular values σ_1 ≥ σ_2 ≥ … on the diagonal)
//! and its weakly coupled states are singularly perturbed: ẋ2 = 0 is solved for x2, which keeps
//! the DC gain of what is kept (Liu & Anderson 1989). The order r is the smallest whose a-priori
//! bound ‖G − G_r‖∞ ≤ 2 Σ_{k>r} σ_k is at most `tolerance` times ‖G‖∞ (‖G‖∞ estimated on a
//! frequency grid from 0 to 1e10 Hz). States with σ_k below 1e-7 σ_1 are truncated first (they
//! are uncontrollable or unobservable to working precision; their share of the bound is
//! counted). The frequency-response error against the full linearization up to 100 Hz is
//! measured on a grid and reported beside the bound.
//!
//! [`linearize`]: super::linearize

use nalgebra::{Complex, DMatrix, SVD};

use super::frequency::{Evaluator, log_grid};
use super::linearize::{Linearization, StateSpace, tie};
use super::{ControlError, linalg};

/// Hankel singular values below this fraction of σ_1 are truncated before the singular
/// perturbation: the Gramian factors' rounding puts spurious values near 1e-17 m/V (1e-11 to
/// 1e-8 of σ_1 at the voltages tried), where the balancing transformation cannot be formed
/// accurately. Their share of the bound, 2 Σ σ_k, is counted all the same.
const NUMERICAL_ZERO: f64 = 1e-7;

/// The highest frequency of the reported error \[Hz\].
const ERROR_BAND: f64 = 100.0;

/// How far the reduced model's frequency response is from the full one.
#[derive(Clone, Debug, PartialEq)]
pub struct ResponseError {
    /// Up to this frequency \[Hz\] (from ω = 0).
    pub f_max: f64,
    /// max over the band of ‖G(jω) − G_r(jω)‖₂ [m/V].
    pub max_abs: f64,
    /// max_abs / ‖G‖∞.
    pub relative: f64,
    /// Where it is reached \[Hz\].
    pub at_frequency: f64,
    /// Per output: max over the band and the inputs of |G_ij − G_r,ij| over max |G_ij|.
    pub per_output: Vec<f64>,
}

/// The reduced model.
#[derive(Clone, Debug, PartialEq)]
pub struct Reduced {
    /// In balanced coordinates z (deviations from the linearization's point).
    pub system: StateSpace,
    /// Hankel singular values of the minimal model, descending [m/V].
    pub hankel: Vec<f64>,
    pub order: usize,
    /// The requested bound relative to ‖G‖∞.
    pub tolerance: f64,
    /// 2 Σ_{k>r} σ_k [m/V].
    pub bound: f64,
    /// ‖G‖∞ of the full linearization on the grid [m/V].
    pub peak_gain: f64,
    pub error: ResponseError,
    /// Eigenvalues of the reduced A, slowest first.
    pub eigenvalues: Vec<Complex<f64>>,
    /// δx ≈ state_map z + input_map δU: the full state (every state of the FMU) from the
    /// reduced one, the singularly perturbed states at their quasi-steady state.
    pub state_map: DMatrix<f64>,
    pub input_map: DMatrix<f64>,
}

/// Reduces the linearization (see the module documentation).
pub fn reduce(lin: &Linearization, tolerance: f64) -> Result<Reduced, ControlError> {
    if !(tolerance.is_finite() && tolerance > 0.0 && tolerance < 1.0) {
        return Err(ControlError::Setting {
            name: "reduction tolerance",
            value: tolerance,
        });
    }
    let minimal = lin.minimal();
    if let Some(e) = lin.minimal_eigenvalues.iter().find(|e| e.re >= 0.0) {
        return Err(ControlError::NotStable {
            eigenvalue: (e.re, e.im),
        });
    }
    let z = &minimal.scales;
    let a = linalg::scale_similar(&minimal.a, z);
    let b = linalg::scale_rows(&minimal.b, z);
    let c = linalg::scale_columns(&minimal.c, z);
    let d = minimal.d.clone();

    // Gramians and the square-root balancing
    let p = linalg::lyapunov(&a, &(&b * b.transpose()))?;
    let q = linalg::lyapunov(&a.transpose(), &(c.transpose() * &c))?;
    let (lc, lo) = (linalg::psd_factor(&p), linalg::psd_factor(&q));
    let svd = SVD::try_new(lo.transpose() * &lc, true, true, f64::EPSILON, 10_000).ok_or(
        ControlError::Numerics {
            what: "balanced reduction",
            why: "the SVD of the Gramian factors did not converge",
        },
    )?;
    let (Some(u), Some(v_t)) = (svd.u.as_ref(), svd.v_t.as_ref()) else {
        return Err(ControlError::Numerics {
            what: "balanced reduction",
            why: "no singular vectors",
        });
    };
    let hankel: Vec<f64> = svd.singular_values.iter().copied().collect();
    let sigma1 = hankel.first().copied().unwrap_or(0.0);
    let n_min = hankel
        .iter()
        .take_while(|&&s| s > NUMERICAL_ZERO * sigma1)
        .count();

    let ev_full = Evaluator::new(&minimal);
    let peak_gain = peak_gain(&ev_full)?;
    if n_min == 0 || peak_gain == 0.0 {
        return Err(ControlError::NoGain);
    }
    let tail = |r: usize| 2.0 * hankel[r..].iter().sum::<f64>();
    let order = (1..=n_min)
        .find(|&r| tail(r) <= tolerance * peak_gain)
        .unwrap_or(n_min);
    let bound = tail(order);

    // balanced realization of the numerically minimal part
    let inv_sqrt = DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(
        n_min,
        hankel[..n_min].iter().map(|s| 1.0 / s.sqrt()),
    ));
    let t_bal = &lc * v_t.rows(0, n_min).transpose() * &inv_sqrt;
    let t_inv = &inv_sqrt * u.columns(0, n_min).transpose() * lo.transpose();
    let ab = &t_inv * &a * &t_bal;
    let bb = &t_inv * &b;
    let cb = &c * &t_bal;

    let r = order;
    let k = n_min - r;
    let (system, x21, x2u) = singular_perturbation(&ab, &bb, &cb, &d, r, &minimal)?;
    let eigenvalues = linalg::eigenvalues(&system.a, &system.scales)?;

    // the full state from z: δx = T_tie Z T_bal [I; X21] z + T_tie Z T_bal [0; X2u] δU
    let (t_tie, _) = tie(lin.system.n_states(), &lin.casimirs.slopes);
    let to_full = t_tie * DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(z)) * &t_bal;
    let mut lift_z = DMatrix::zeros(n_min, r);
    lift_z.view_mut((0, 0), (r, r)).fill_with_identity();
    lift_z.view_mut((r, 0), (k, r)).copy_from(&x21);
    let mut lift_u = DMatrix::zeros(n_min, 3);
    lift_u.view_mut((r, 0), (k, 3)).copy_from(&x2u);
    let state_map = &to_full * lift_z;
    let input_map = &to_full * lift_u;

    let error = response_error(&ev_full, &system, peak_gain)?;
    Ok(Reduced {
        system,
        hankel,
        order,
        tolerance,
        bound,
        peak_gain,
        error,
        eigenvalues,
        state_map,
        input_map,
    })
}

/// ‖G‖∞ on a wide grid (the peak is at DC for this plant, the grid confirms it).
fn peak_gain(ev_full: &Evaluator) -> Result<f64, ControlError> {
    let mut wide = vec![0.0];
    wide.extend(log_grid(1e-3, 1e10, 20));
    let mut peak_gain: f64 = 0.0;
    for f in &wide {
        let g = ev_full.at(2.0 * std::f64::consts::PI * f)?;
        peak_gain = peak_gain.max(linalg::spectral_norm(&g));
    }
    Ok(peak_gain)
}

/// The balanced realization (`ab`, `bb`, `cb`, `d`) cut to its first `r` states by singular
/// perturbation of the others (held at their quasi-steady state); with the maps X21, X2u that
/// give those states from the kept ones and the input.
fn singular_perturbation(
    ab: &DMatrix<f64>,
    bb: &DMatrix<f64>,
    cb: &DMatrix<f64>,
    d: &DMatrix<f64>,
    r: usize,
    minimal: &StateSpace,
) -> Result<(StateSpace, DMatrix<f64>, DMatrix<f64>), ControlError> {
    let n_min = ab.nrows();
    let k = n_min - r;
    let (a11, a12, a21, a22) = (
        ab.view((0, 0), (r, r)).into_owned(),
        ab.view((0, r), (r, k)).into_owned(),
        ab.view((r, 0), (k, r)).into_owned(),
        ab.view((r, r), (k, k)).into_owned(),
    );
    let (b1, b2) = (bb.rows(0, r).into_owned(), bb.rows(r, k).into_owned());
    let (c1, c2) = (cb.columns(0, r).into_owned(), cb.columns(r, k).into_owned());
    let (x21, x2u) = if k > 0 {
        (
            -linalg::solve(&a22, &a21, "singular perturbation")?,
            -linalg::solve(&a22, &b2, "singular perturbation")?,
        )
    } else {
        (DMatrix::zeros(0, r), DMatrix::zeros(0, 3))
    };
    let system = StateSpace {
        a: &a11 + &a12 * &x21,
        b: &b1 + &a12 * &x2u,
        c: &c1 + &c2 * &x21,
        d: d + &c2 * &x2u,
        states: (1..=r).map(|i| format!("z{i}")).collect(),
        inputs: minimal.inputs.clone(),
        outputs: minimal.outputs.clone(),
        scales: vec![1.0; r],
    };
    Ok((system, x21, x2u))
}

/// The error of `reduced` against the full response from 0 to [`ERROR_BAND`].
fn response_error(
    full: &Evaluator,
    reduced: &StateSpace,
    peak_gain: f64,
) -> Result<ResponseError, ControlError> {
    let ev_r = Evaluator::new(reduced);
    let mut freqs = vec![0.0];
    freqs.extend(log_grid(1e-2, ERROR_BAND, 40));
    let p = reduced.outputs.len();
    let (mut max_abs, mut at) = (0.0, 0.0);
    let mut err_out = vec![0.0f64; p];
    let mut peak_out = vec![0.0f64; p];
    for &f in &freqs {
        let omega = 2.0 * std::f64::consts::PI * f;
        let (g, gr) = (full.at(omega)?, ev_r.at(omega)?);
        let e = &g - &gr;
        let s = linalg::spectral_norm(&e);
        if s > max_abs {
            (max_abs, at) = (s, f);
        }
        for row in 0..p {
            for col in 0..g.ncols() {
                err_out[row] = err_out[row].max(e[(row, col)].norm());
                peak_out[row] = peak_out[row].max(g[(row, col)].norm());
            }
        }
    }
    Ok(ResponseError {
        f_max: ERROR_BAND,
        max_abs,
        relative: max_abs / peak_gain.max(f64::MIN_POSITIVE),
        at_frequency: at,
        per_output: err_out
            .iter()
            .zip(&peak_out)
            .map(|(e, p)| if *p > 0.0 { e / p } else { *e })
            .collect(),
    })
}
