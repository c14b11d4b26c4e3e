//! LU factorisation with partial pivoting of small dense blocks, in place on preallocated
//! column-major storage, for real and complex matrices (the Radau IIA iteration needs one of
//! each per step size), of block-diagonal matrices block by block ([`BlockLu`]), and of the
//! sensitivities' stage equations, mostly zeros, by a sparse elimination (`SparseLu`).
//!
//! Written here rather than taken from nalgebra because nalgebra's `LU` owns and reallocates
//! its matrix, and the solver must not allocate per step. Blocks of up to `UNROLLED` rows are
//! factored and solved by code compiled for their size (loops unrolled, no bounds checks), with
//! the pivots' reciprocals kept so that solving only multiplies: the block solves of a 1 ms
//! co-simulation step of the platform take a tenth of the instructions of generic code over
//! runtime sizes (book/src/solver.md, "Block LU").

use std::ops::{Add, Mul, Sub};

use nalgebra::Complex;
use serde::{Deserialize, Serialize};

/// The matrix is singular to working precision at this column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Singular(pub usize);

/// An entry of a matrix to factor: a real or a complex number.
pub trait Entry:
    Copy + PartialEq + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + From<f64>
{
    /// |re| + |im|, the pivot's size.
    fn norm1(self) -> f64;
    fn recip(self) -> Self;
}

impl Entry for f64 {
    fn norm1(self) -> f64 {
        self.abs()
    }
    fn recip(self) -> f64 {
        1.0 / self
    }
}

impl Entry for Complex<f64> {
    fn norm1(self) -> f64 {
        self.re.abs() + self.im.abs()
    }
    fn recip(self) -> Complex<f64> {
        let d = self.re * self.re + self.im * self.im;
        Complex::new(self.re / d, -self.im / d)
    }
}

/// Largest block size with code of its own.
const UNROLLED: usize = 8;

/// Calls `$f(m, args…)` with `m` a constant for each size up to [`UNROLLED`], so that the
/// inlined body is compiled for that size.
macro_rules! by_size {
    ($m:expr, $f:ident($($arg:expr),*)) => {
        match $m {
            1 => $f(1, $($arg),*),
            2 => $f(2, $($arg),*),
            3 => $f(3, $($arg),*),
            4 => $f(4, $($arg),*),
            5 => $f(5, $($arg),*),
            6 => $f(6, $($arg),*),
            7 => $f(7, $($arg),*),
            8 => $f(8, $($arg),*),
            m => $f(m, $($arg),*),
        }
    };
}

/// Factors the m × m matrix `a` (column-major, m = `piv.len()`) into P A = L U in place;
/// `piv[k]` is the row swapped with row k. The diagonal holds 1/U_kk, for [`solve`].
fn factor<T: Entry>(a: &mut [T], piv: &mut [usize]) -> Result<(), Singular> {
    by_size!(piv.len(), factor_m(a, piv))
}

// For the sizes up to UNROLLED the loops run over the whole block with the triangle as a
// condition inside: with m a constant, the compiler then unrolls them all and drops the
// conditions, which it does not do for loops that start at k + 1. Larger blocks (an effect's
// states beside the actuator's) start there and skip the zeros of sparse columns.
#[inline(always)]
fn factor_m<T: Entry>(m: usize, a: &mut [T], piv: &mut [usize]) -> Result<(), Singular> {
    let (a, piv) = (&mut a[..m * m], &mut piv[..m]);
    for k in 0..m {
        let below = if m <= UNROLLED { 0 } else { k + 1 };
        let mut p = k;
        let mut best = a[k * m + k].norm1();
        for i in below..m {
            let v = a[k * m + i].norm1();
            if i > k && v > best {
                best = v;
                p = i;
            }
        }
        piv[k] = p;
        if best == 0.0 || !best.is_finite() {
            return Err(Singular(k));
        }
        if p != k {
            for j in 0..m {
                a.swap(j * m + k, j * m + p);
            }
        }
        let inv = a[k * m + k].recip();
        a[k * m + k] = inv;
        for i in below..m {
            if i > k {
                a[k * m + i] = a[k * m + i] * inv;
            }
        }
        for j in below..m {
            let akj = a[j * m + k];
            if j > k && (m <= UNROLLED || akj != T::from(0.0)) {
                for i in below..m {
                    if i > k {
                        a[j * m + i] = a[j * m + i] - a[k * m + i] * akj;
                    }
                }
            }
        }
    }
    Ok(())
}

/// Solves A x = b in place with the factors of [`factor`] (m = `b.len()`).
fn solve<T: Entry>(lu: &[T], piv: &[usize], b: &mut [T]) {
    by_size!(b.len(), solve_m(lu, piv, b))
}

#[inline(always)]
fn solve_m<T: Entry>(m: usize, lu: &[T], piv: &[usize], b: &mut [T]) {
    let (lu, piv, b) = (&lu[..m * m], &piv[..m], &mut b[..m]);
    // the factors hold rows in their final order: permute b fully, then substitute
    for (k, &p) in piv.iter().enumerate() {
        b.swap(k, p);
    }
    let sparse = m > UNROLLED;
    for k in 0..m {
        let bk = b[k];
        if sparse && bk == T::from(0.0) {
            continue;
        }
        for i in k + 1..m {
            b[i] = b[i] - lu[k * m + i] * bk;
        }
    }
    for k in (0..m).rev() {
        let bk = b[k] * lu[k * m + k];
        b[k] = bk;
        if sparse && bk == T::from(0.0) {
            continue;
        }
        for i in 0..k {
            b[i] = b[i] - lu[k * m + i] * bk;
        }
    }
}

/// The LU factors of a block-diagonal matrix, block by block: each diagonal block stored
/// compactly (column-major, one after another), nothing of what lies outside them.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BlockLu<T> {
    /// Sizes of the diagonal blocks, summing to the dimension.
    blocks: Vec<usize>,
    lu: Vec<T>,
    piv: Vec<usize>,
}

impl<T: Entry> BlockLu<T> {
    pub fn new(blocks: Vec<usize>) -> BlockLu<T> {
        BlockLu {
            lu: vec![T::from(0.0); blocks.iter().map(|m| m * m).sum()],
            piv: vec![0; blocks.iter().sum()],
            blocks,
        }
    }

    pub fn blocks(&self) -> &[usize] {
        &self.blocks
    }

    /// Factors σ I − J block by block, J dense column-major n × n (entries outside the blocks
    /// are not read). A singular block reports its column in J.
    pub fn factor_shifted(&mut self, sigma: T, jac: &[f64]) -> Result<(), Singular> {
        let n = self.piv.len();
        let (mut o, mut at) = (0, 0);
        for &m in &self.blocks {
            let a = &mut self.lu[at..at + m * m];
            for c in 0..m {
                let col = &jac[(o + c) * n + o..(o + c) * n + o + m];
                for (r, &v) in col.iter().enumerate() {
                    a[c * m + r] = T::from(-v);
                }
                a[c * m + c] = a[c * m + c] + sigma;
            }
            factor(a, &mut self.piv[o..o + m]).map_err(|Singular(k)| Singular(o + k))?;
            o += m;
            at += m * m;
        }
        Ok(())
    }

    /// Solves (σ I − J) x = b in place with the factors of [`BlockLu::factor_shifted`].
    pub fn solve(&self, b: &mut [T]) {
        let (mut o, mut at) = (0, 0);
        for &m in &self.blocks {
            solve(
                &self.lu[at..at + m * m],
                &self.piv[o..o + m],
                &mut b[o..o + m],
            );
            o += m;
            at += m * m;
        }
    }
}

/// The LU factors (P A = L U) of a real m × m matrix with many zeros, in dense storage: the
/// elimination and the solves touch only the nonzeros, so a matrix whose rows and columns are
/// ordered with the sparsest first (an effect's own states in the sensitivities' stage
/// equations) costs little more than its dense part.
#[derive(Clone, Debug, Default)]
pub(super) struct SparseLu {
    m: usize,
    /// Column-major; after [`SparseLu::factor`] L below the diagonal, U above, 1/U_kk on it.
    lu: Vec<f64>,
    piv: Vec<usize>,
    /// Per row, the columns that may hold a nonzero, a bit each in `words` words: the
    /// elimination reads row k's entries right of the pivot through them rather than across
    /// every column (a read per column, a cache line apart).
    pattern: Vec<u64>,
    words: usize,
    /// Per column k, the rows of its nonzeros below the diagonal (L) and above it (U), at
    /// `rows[starts[k].0..starts[k].1]` and `rows[starts[k].1..starts[k].2]`.
    starts: Vec<(usize, usize, usize)>,
    rows: Vec<usize>,
}

impl SparseLu {
    /// Starts an m × m matrix to factor, zero but for the entries [`SparseLu::set`] then gives.
    pub fn start(&mut self, m: usize) {
        self.m = m;
        self.lu.clear();
        self.lu.resize(m * m, 0.0);
        self.words = m.div_ceil(64);
        self.pattern.clear();
        self.pattern.resize(m * self.words, 0);
    }

    /// Entry (`row`, `col`) of the matrix to factor.
    pub fn set(&mut self, row: usize, col: usize, v: f64) {
        self.lu[col * self.m + row] = v;
        self.pattern[row * self.words + col / 64] |= 1 << (col % 64);
    }

    /// Factors the matrix [`SparseLu::set`] gave, with partial pivoting.
    pub fn factor(&mut self) -> Result<(), Singular> {
        let (m, w, a) = (self.m, self.words, &mut self.lu);
        let pattern = &mut self.pattern;
        self.piv.resize(m, 0);
        for k in 0..m {
            let col = &a[k * m..(k + 1) * m];
            let mut p = k;
            for i in k + 1..m {
                if col[i].abs() > col[p].abs() {
                    p = i;
                }
            }
            let best = col[p].abs();
            if best == 0.0 || !best.is_finite() {
                return Err(Singular(k));
            }
            self.piv[k] = p;
            if p != k {
                for j in 0..m {
                    a.swap(j * m + k, j * m + p);
                }
                for q in 0..w {
                    pattern.swap(k * w + q, p * w + q);
                }
            }
            let (left, right) = a.split_at_mut((k + 1) * m);
            let col = &mut left[k * m..];
            let inv = 1.0 / col[k];
            col[k] = inv;
            self.rows.clear();
            for (i, v) in col.iter_mut().enumerate().skip(k + 1) {
                if *v != 0.0 {
                    *v *= inv;
                    self.rows.push(i);
                }
            }
            // row k's columns right of the pivot, and the rows eliminated fill in where it has
            // entries
            let (above, below) = pattern.split_at_mut((k + 1) * w);
            let row_k = &above[k * w..];
            for &i in &self.rows {
                for (b, &rk) in below[(i - k - 1) * w..(i - k) * w].iter_mut().zip(row_k) {
                    *b |= rk;
                }
            }
            for (q, &word) in row_k.iter().enumerate() {
                let mut bits = if q == (k + 1) / 64 {
                    word & (u64::MAX << ((k + 1) % 64))
                } else if q < (k + 1) / 64 {
                    0
                } else {
                    word
                };
                while bits != 0 {
                    let j = q * 64 + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    let col_j = &mut right[(j - k - 1) * m..(j - k) * m];
                    let akj = col_j[k];
                    if akj != 0.0 {
                        for &i in &self.rows {
                            col_j[i] -= col[i] * akj;
                        }
                    }
                }
            }
        }
        // the pattern the solves follow, read off the final factors (a later pivot's swap moves
        // the rows of earlier columns)
        self.rows.clear();
        self.starts.clear();
        for k in 0..m {
            let col = &a[k * m..(k + 1) * m];
            let start = self.rows.len();
            self.rows.extend((k + 1..m).filter(|&i| col[i] != 0.0));
            let mid = self.rows.len();
            self.rows.extend((0..k).filter(|&i| col[i] != 0.0));
            self.starts.push((start, mid, self.rows.len()));
        }
        Ok(())
    }

    /// Solves A x = b in place with the factors.
    pub fn solve(&self, b: &mut [f64]) {
        let (m, lu) = (self.m, &self.lu);
        for (k, &p) in self.piv[..m].iter().enumerate() {
            b.swap(k, p);
        }
        for (k, &(lo, mid, _)) in self.starts.iter().enumerate() {
            let bk = b[k];
            if bk != 0.0 {
                for &i in &self.rows[lo..mid] {
                    b[i] -= lu[k * m + i] * bk;
                }
            }
        }
        for (k, &(_, mid, hi)) in self.starts.iter().enumerate().rev() {
            let bk = b[k] * lu[k * m + k];
            b[k] = bk;
            if bk != 0.0 {
                for &i in &self.rows[mid..hi] {
                    b[i] -= lu[k * m + i] * bk;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    #[test]
    fn solves_real_and_complex_systems_of_every_size() {
        for n in [1, 3, 5, 6, 8, 9, 15] {
            // diagonally dominant, then rows reversed so that every column needs a pivot swap
            let m = DMatrix::from_fn(n, n, |r, c| {
                let r = n - 1 - r;
                ((r * 7 + c * 3) % 5) as f64 - 2.0 + if r == c { 6.0 } else { 0.0 }
            });
            let x = DVector::from_fn(n, |i, _| i as f64 - 1.5);
            let b = &m * &x;
            let (mut a, mut piv, mut rhs) =
                (m.as_slice().to_vec(), vec![0; n], b.as_slice().to_vec());
            factor(&mut a, &mut piv).unwrap();
            solve(&a, &piv, &mut rhs);
            for i in 0..n {
                assert!((rhs[i] - x[i]).abs() < 1e-12, "n = {n}: {rhs:?}");
            }

            let mc = m.map(|v| Complex::new(v, 0.3 * v));
            let xc = x.map(|v| Complex::new(1.0, v));
            let bc = &mc * &xc;
            let (mut a, mut rhs) = (mc.as_slice().to_vec(), bc.as_slice().to_vec());
            factor(&mut a, &mut piv).unwrap();
            solve(&a, &piv, &mut rhs);
            for i in 0..n {
                assert!((rhs[i] - xc[i]).norm() < 1e-12, "n = {n}: {rhs:?}");
            }
        }
    }

    #[test]
    fn block_diagonal_factors_ignore_what_lies_outside_the_blocks() {
        let n = 5;
        let inside = |r: usize, c: usize| (r < 2) == (c < 2);
        let m = DMatrix::from_fn(n, n, |r, c| {
            if inside(r, c) {
                (r + 2 * c) as f64 - 3.0 + if r == c { 9.0 } else { 1.0 }
            } else {
                0.0
            }
        });
        let sigma = Complex::new(2.0, -1.5);
        let x = DVector::from_fn(n, |i, _| Complex::new(1.0 + i as f64, 0.5));
        let shifted = DMatrix::from_fn(n, n, |r, c| {
            let s = if r == c {
                sigma
            } else {
                Complex::new(0.0, 0.0)
            };
            s - Complex::new(m[(r, c)], 0.0)
        });
        let b = &shifted * &x;
        // garbage off the blocks must not matter
        let jac = DMatrix::from_fn(n, n, |r, c| if inside(r, c) { m[(r, c)] } else { 1e6 });
        let mut lu = BlockLu::new(vec![2, 3]);
        lu.factor_shifted(sigma, jac.as_slice()).unwrap();
        let mut rhs = b.as_slice().to_vec();
        lu.solve(&mut rhs);
        for i in 0..n {
            assert!((rhs[i] - x[i]).norm() < 1e-12, "{rhs:?}");
        }
    }

    /// An arrowhead (the sparse rows and columns first, the dense part last), with a pivot
    /// that swaps a dense row up: the sparse factors solve it as the dense ones do.
    #[test]
    fn sparse_factors_solve_as_the_dense_ones() {
        let n = 12;
        let m = DMatrix::from_fn(n, n, |r, c| match (r, c) {
            _ if r == c => 2.0 + r as f64 * 0.1,
            _ if r >= 8 && c >= 8 => ((r * 3 + c) % 5) as f64 - 2.0,
            _ if r >= 8 || c >= 8 => 0.5 + ((r + c) % 3) as f64,
            _ => 0.0,
        });
        let mut m = m;
        m[(8, 0)] = 40.0; // the first column's pivot is a dense row's
        let x = DVector::from_fn(n, |i, _| i as f64 - 4.5);
        let b = &m * &x;
        let mut lu = SparseLu::default();
        lu.start(n);
        for ((r, c), &v) in (0..n)
            .flat_map(|c| (0..n).map(move |r| (r, c)))
            .zip(m.as_slice())
        {
            if v != 0.0 {
                lu.set(r, c, v);
            }
        }
        lu.factor().unwrap();
        let mut rhs = b.as_slice().to_vec();
        lu.solve(&mut rhs);
        for i in 0..n {
            assert!((rhs[i] - x[i]).abs() < 1e-12, "{rhs:?}");
        }
        let mut singular = SparseLu::default();
        singular.start(2);
        for (r, c, v) in [(0, 0, 1.0), (1, 0, 2.0), (0, 1, 2.0), (1, 1, 4.0)] {
            singular.set(r, c, v);
        }
        assert_eq!(singular.factor(), Err(Singular(1)));
    }

    #[test]
    fn reports_singular_matrices_at_their_column() {
        let mut a = vec![1.0, 2.0, 2.0, 4.0];
        assert_eq!(factor(&mut a, &mut [0; 2]), Err(Singular(1)));
        // σ I − J singular in the second block's first column: J = diag(0, 1, 1), σ = 1
        let jac = [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let mut lu = BlockLu::<f64>::new(vec![1, 2]);
        assert_eq!(lu.factor_shifted(1.0, &jac), Err(Singular(1)));
    }
}
