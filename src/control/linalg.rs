//! Dense linear algebra for the control design, on nalgebra: diagonal scaling by the state
//! scales, eigenvalues of a scaled and balanced matrix, complex solves for G(jω), Lyapunov
//! equations and symmetric square roots. The matrices are small (15 states, a few dozen with
//! effects), so clarity wins over speed.

use nalgebra::{Complex, DMatrix, DVector, Schur};

use super::ControlError;

/// Column-major `rows × cols` slice (the model's layout) into a matrix.
pub fn from_column_major(rows: usize, cols: usize, data: &[f64]) -> DMatrix<f64> {
    DMatrix::from_column_slice(rows, cols, &data[..rows * cols])
}

/// S⁻¹ M S for the diagonal S = diag(scales): the matrix in scaled states x = S x̃.
pub fn scale_similar(m: &DMatrix<f64>, scales: &[f64]) -> DMatrix<f64> {
    DMatrix::from_fn(m.nrows(), m.ncols(), |r, c| {
        m[(r, c)] * scales[c] / scales[r]
    })
}

/// S⁻¹ M: rows divided by the scales (B in scaled states).
pub fn scale_rows(m: &DMatrix<f64>, scales: &[f64]) -> DMatrix<f64> {
    DMatrix::from_fn(m.nrows(), m.ncols(), |r, c| m[(r, c)] / scales[r])
}

/// M S: columns multiplied by the scales (C in scaled states).
pub fn scale_columns(m: &DMatrix<f64>, scales: &[f64]) -> DMatrix<f64> {
    DMatrix::from_fn(m.nrows(), m.ncols(), |r, c| m[(r, c)] * scales[c])
}

/// Every entry finite?
pub fn finite(m: &DMatrix<f64>) -> bool {
    m.iter().all(|v| v.is_finite())
}

/// Eigenvalues of A, computed on S⁻¹ A S (S = diag(scales)) balanced once more by
/// Parlett–Reinsch, sorted by real part from the largest (the slowest first).
pub fn eigenvalues(a: &DMatrix<f64>, scales: &[f64]) -> Result<Vec<Complex<f64>>, ControlError> {
    if a.nrows() == 0 {
        return Ok(Vec::new());
    }
    let mut m = scale_similar(a, scales);
    if !finite(&m) {
        return Err(ControlError::Numerics {
            what: "eigenvalues",
            why: "the matrix has entries that are not finite",
        });
    }
    nalgebra::linalg::balancing::balance_parlett_reinsch(&mut m);
    let schur = Schur::try_new(m, f64::EPSILON, 10_000).ok_or(ControlError::Numerics {
        what: "eigenvalues",
        why: "the real Schur iteration did not converge",
    })?;
    let mut ev: Vec<Complex<f64>> = schur.complex_eigenvalues().iter().copied().collect();
    ev.sort_by(|x, y| y.re.total_cmp(&x.re).then(y.im.total_cmp(&x.im)));
    Ok(ev)
}

/// Frobenius norm.
pub fn norm(m: &DMatrix<f64>) -> f64 {
    m.norm()
}

/// Largest singular value of a complex matrix (the gain of a transfer matrix at one frequency).
pub fn spectral_norm(m: &DMatrix<Complex<f64>>) -> f64 {
    if m.is_empty() {
        return 0.0;
    }
    m.clone()
        .singular_values()
        .iter()
        .copied()
        .fold(0.0, f64::max)
}

/// Smallest eigenvalue of the Hermitian part (M + Mᴴ)/2 of a square complex matrix.
pub fn min_hermitian_eigenvalue(m: &DMatrix<Complex<f64>>) -> f64 {
    let n = m.nrows();
    // (M + Mᴴ)/2 = X + iY with X symmetric, Y skew; its eigenvalues are those of the real
    // symmetric [[X, −Y], [Y, X]] (each twice)
    let mut big = DMatrix::zeros(2 * n, 2 * n);
    for r in 0..n {
        for c in 0..n {
            let h = (m[(r, c)] + m[(c, r)].conj()) * 0.5;
            big[(r, c)] = h.re;
            big[(r + n, c + n)] = h.re;
            big[(r, c + n)] = -h.im;
            big[(r + n, c)] = h.im;
        }
    }
    symmetric_eigenvalues(&big)
        .into_iter()
        .fold(f64::INFINITY, f64::min)
}

/// Eigenvalues of the symmetric part of a real square matrix, ascending.
pub fn symmetric_eigenvalues(m: &DMatrix<f64>) -> Vec<f64> {
    if m.nrows() == 0 {
        return Vec::new();
    }
    let s = (m + m.transpose()) * 0.5;
    let mut ev: Vec<f64> = s.symmetric_eigenvalues().iter().copied().collect();
    ev.sort_by(f64::total_cmp);
    ev
}

/// Solves A X + X Aᵀ + W = 0 for symmetric X through the Kronecker form
/// (I ⊗ A + A ⊗ I) vec X = −vec W (n² unknowns: fine for the few dozen states here), refined
/// with residuals computed in twice the working precision. The time scales of this model span
/// eight decades, so the Kronecker matrix has a condition number near 1e8 and a plain solve
/// keeps only about eight digits of the Gramians, which the square-root balancing halves
/// again; each refinement step gains about eight digits back.
pub fn lyapunov(a: &DMatrix<f64>, w: &DMatrix<f64>) -> Result<DMatrix<f64>, ControlError> {
    let n = a.nrows();
    let mut k = DMatrix::<f64>::zeros(n * n, n * n);
    // vec(A X)_{(j, i)} = Σ_l A_il X_lj ; vec(X Aᵀ)_{(j, i)} = Σ_l X_il A_jl (column-major vec)
    for j in 0..n {
        for i in 0..n {
            let row = j * n + i;
            for l in 0..n {
                k[(row, j * n + l)] += a[(i, l)];
                k[(row, l * n + i)] += a[(j, l)];
            }
        }
    }
    let lu = k.lu();
    let singular = ControlError::Numerics {
        what: "Lyapunov equation",
        why: "singular (an eigenvalue pair sums to zero)",
    };
    let mut x = DMatrix::<f64>::zeros(n, n);
    let mut residual = w.clone();
    for _ in 0..6 {
        let rhs = DVector::from_iterator(n * n, residual.iter().map(|v| -v));
        let step = lu.solve(&rhs).ok_or(singular.clone())?;
        let step = DMatrix::from_column_slice(n, n, step.as_slice());
        x += (&step + step.transpose()) * 0.5;
        residual = lyapunov_residual(a, &x, w);
        if step.norm() <= f64::EPSILON * x.norm() {
            break;
        }
    }
    if !finite(&x) {
        return Err(singular);
    }
    Ok(x)
}

/// A X + X Aᵀ + W, each entry summed in twice the working precision (Ogita, Rump & Oishi's
/// Dot2: error-free products by fused multiply-add, error-free sums by TwoSum).
fn lyapunov_residual(a: &DMatrix<f64>, x: &DMatrix<f64>, w: &DMatrix<f64>) -> DMatrix<f64> {
    let n = a.nrows();
    DMatrix::from_fn(n, n, |i, j| {
        let (mut s, mut c) = (w[(i, j)], 0.0);
        let mut add = |p: f64, q: f64| {
            let h = p * q;
            let e = p.mul_add(q, -h);
            let t = s + h;
            let z = t - s;
            c += (s - (t - z)) + (h - z) + e;
            s = t;
        };
        for l in 0..n {
            add(a[(i, l)], x[(l, j)]);
            add(x[(i, l)], a[(j, l)]);
        }
        s + c
    })
}

/// A factor L with L Lᵀ = X for a symmetric positive semi-definite X: Cholesky with complete
/// (diagonal) pivoting, stopped at the first non-positive pivot. Unlike a factor from the
/// eigenvalues, whose errors are a rounding of ‖X‖ in every entry, it keeps the small rows of
/// a graded X (the slow angles beside the charges) to their own relative accuracy, so the small
/// Hankel singular values come out above the rounding of the large ones.
pub fn psd_factor(x: &DMatrix<f64>) -> DMatrix<f64> {
    let n = x.nrows();
    let mut a = (x + x.transpose()) * 0.5;
    let mut l = DMatrix::zeros(n, n);
    let mut done = vec![false; n];
    for k in 0..n {
        let Some(p) = (0..n)
            .filter(|&i| !done[i])
            .max_by(|&i, &j| a[(i, i)].total_cmp(&a[(j, j)]))
        else {
            break;
        };
        let d = a[(p, p)];
        if d.is_nan() || d <= 0.0 {
            break;
        }
        let s = d.sqrt();
        for i in 0..n {
            l[(i, k)] = if done[i] { 0.0 } else { a[(i, p)] / s };
        }
        done[p] = true;
        for i in 0..n {
            for j in 0..n {
                a[(i, j)] -= l[(i, k)] * l[(j, k)];
            }
        }
    }
    l
}

/// Solves the square real system A X = B.
pub fn solve(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    what: &'static str,
) -> Result<DMatrix<f64>, ControlError> {
    a.clone().lu().solve(b).ok_or(ControlError::Numerics {
        what,
        why: "singular matrix",
    })
}

/// Writes a square matrix as row-major rows (for JSON and CSV).
pub fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|r| (0..m.ncols()).map(|c| m[(r, c)]).collect())
        .collect()
}
