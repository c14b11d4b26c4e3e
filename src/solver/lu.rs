//! LU factorisation with partial pivoting of small dense blocks, in place on preallocated
//! column-major storage, for real and complex matrices (the Radau IIA iteration needs one of
//! each per step size), of block-diagonal matrices block by block ([`BlockLu`]), and of the
//! sensitivities' stage equations (`SparseLu`). Blocks beyond `UNROLLED` rows and the stage
//! equations, mostly zeros, are eliminated and solved over their nonzeros alone.
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

// The loops run over the whole block with the triangle as a condition inside: with m a
// constant, the compiler then unrolls them all and drops the conditions, which it does not do
// for loops that start at k + 1. (Larger blocks go to [`factor_sparse`].)
#[inline(always)]
fn factor_m<T: Entry>(m: usize, a: &mut [T], piv: &mut [usize]) -> Result<(), Singular> {
    let (a, piv) = (&mut a[..m * m], &mut piv[..m]);
    for k in 0..m {
        piv[k] = pivot(a, m, k, 0)?;
        let inv = a[k * m + k].recip();
        a[k * m + k] = inv;
        for i in 0..m {
            if i > k {
                a[k * m + i] = a[k * m + i] * inv;
            }
        }
        for j in 0..m {
            let akj = a[j * m + k];
            if j > k {
                for i in 0..m {
                    if i > k {
                        a[j * m + i] = a[j * m + i] - a[k * m + i] * akj;
                    }
                }
            }
        }
    }
    Ok(())
}

/// Partial pivoting at column k of the m × m matrix `a`: the row of the column's largest entry
/// at or below the diagonal (the first of equal ones), swapped with row k across the matrix.
/// Rows from `from` are searched, those above k not counted: 0 lets the compiler unroll the
/// whole column of a block of constant size.
#[inline(always)]
fn pivot<T: Entry>(a: &mut [T], m: usize, k: usize, from: usize) -> Result<usize, Singular> {
    let mut p = k;
    let mut best = a[k * m + k].norm1();
    for i in from..m {
        let v = a[k * m + i].norm1();
        if i > k && v > best {
            best = v;
            p = i;
        }
    }
    if best == 0.0 || !best.is_finite() {
        return Err(Singular(k));
    }
    if p != k {
        for j in 0..m {
            a.swap(j * m + k, j * m + p);
        }
    }
    Ok(p)
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
    for k in 0..m {
        let bk = b[k];
        for i in k + 1..m {
            b[i] = b[i] - lu[k * m + i] * bk;
        }
    }
    for k in (0..m).rev() {
        let bk = b[k] * lu[k * m + k];
        b[k] = bk;
        for i in 0..k {
            b[i] = b[i] - lu[k * m + i] * bk;
        }
    }
}

/// Where the nonzeros of a matrix factored by [`factor_sparse`] are. Before the factoring, each
/// row's columns that may hold one, a bit each (`words` per row): the elimination reads row k
/// right of the pivot through them rather than across every column (a read per column, a
/// cache line apart). After it, per column k, the rows of its nonzeros below the diagonal (L)
/// and above it (U), at `rows[starts[k].0..starts[k].1]` and `rows[starts[k].1..starts[k].2]`,
/// which the solves follow.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct Pattern {
    #[serde(skip)]
    bits: Vec<u64>,
    #[serde(skip)]
    words: usize,
    /// Scratch: the rows column k eliminates.
    #[serde(skip)]
    eliminated: Vec<usize>,
    starts: Vec<(usize, usize, usize)>,
    rows: Vec<usize>,
}

impl Pattern {
    /// No entry yet of an m × m matrix (the factors' pattern of earlier blocks is kept).
    fn clear_bits(&mut self, m: usize) {
        self.words = m.div_ceil(64);
        self.bits.clear();
        self.bits.resize(m * self.words, 0);
    }

    fn mark(&mut self, row: usize, col: usize) {
        self.bits[row * self.words + col / 64] |= 1 << (col % 64);
    }
}

/// Factors the m × m matrix `a` (column-major, m = `piv.len()`) into P A = L U in place as
/// [`factor`] does, with partial pivoting, the entries given in `pattern`'s bits; the factors'
/// pattern is appended to `pattern` for [`solve_sparse`]. Only the nonzeros are eliminated and
/// substituted, so that a block whose sparsest rows and columns come first (an effect's own
/// states, coupled to the actuator's few) costs little more than its dense part; the results
/// are [`factor`]'s, whose other products are by zero.
fn factor_sparse<T: Entry>(
    a: &mut [T],
    piv: &mut [usize],
    pattern: &mut Pattern,
) -> Result<(), Singular> {
    let (m, w) = (piv.len(), pattern.words);
    let zero = T::from(0.0);
    let mut rows = std::mem::take(&mut pattern.eliminated);
    for k in 0..m {
        let p = pivot(a, m, k, k + 1)?;
        piv[k] = p;
        if p != k {
            for q in 0..w {
                pattern.bits.swap(k * w + q, p * w + q);
            }
        }
        let (left, right) = a.split_at_mut((k + 1) * m);
        let col = &mut left[k * m..];
        let inv = col[k].recip();
        col[k] = inv;
        rows.clear();
        for (i, v) in col.iter_mut().enumerate().skip(k + 1) {
            if *v != zero {
                *v = *v * inv;
                rows.push(i);
            }
        }
        // the rows eliminated fill in where row k has entries
        let (above, below) = pattern.bits.split_at_mut((k + 1) * w);
        let row_k = &above[k * w..];
        for &i in &rows {
            for (b, &rk) in below[(i - k - 1) * w..(i - k) * w].iter_mut().zip(row_k) {
                *b |= rk;
            }
        }
        for (q, &word) in row_k.iter().enumerate().skip((k + 1) / 64) {
            let mut bits = if q == (k + 1) / 64 {
                word & (u64::MAX << ((k + 1) % 64))
            } else {
                word
            };
            while bits != 0 {
                let j = q * 64 + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let col_j = &mut right[(j - k - 1) * m..(j - k) * m];
                let akj = col_j[k];
                if akj != zero {
                    for &i in &rows {
                        col_j[i] = col_j[i] - col[i] * akj;
                    }
                }
            }
        }
    }
    // the pattern the solves follow, read off the final factors (a later pivot's swap moves
    // the rows of earlier columns)
    for k in 0..m {
        let col = &a[k * m..(k + 1) * m];
        let start = pattern.rows.len();
        pattern.rows.extend((k + 1..m).filter(|&i| col[i] != zero));
        let mid = pattern.rows.len();
        pattern.rows.extend((0..k).filter(|&i| col[i] != zero));
        pattern.starts.push((start, mid, pattern.rows.len()));
    }
    pattern.eliminated = rows;
    Ok(())
}

/// Solves A X = B in place with the factors of [`factor_sparse`], whose columns' patterns are
/// `starts`, for the `q` right-hand sides of `b`, row by row (row i's q values at
/// `b[i q..(i + 1) q]`; m = `piv.len()`): one pass over the factors for all of them, each row
/// operation over q values side by side. A row of zeros is skipped.
fn solve_sparse<T: Entry>(
    lu: &[T],
    piv: &[usize],
    pattern: (&[(usize, usize, usize)], &[usize]),
    b: &mut [T],
    q: usize,
) {
    // one right-hand side (the state's Newton solves) compiled apart: no loops of length q
    if q == 1 {
        solve_sparse_q(lu, piv, pattern, b, 1)
    } else {
        solve_sparse_q(lu, piv, pattern, b, q)
    }
}

#[inline(always)]
fn solve_sparse_q<T: Entry>(
    lu: &[T],
    piv: &[usize],
    (starts, rows): (&[(usize, usize, usize)], &[usize]),
    b: &mut [T],
    q: usize,
) {
    let (m, zero) = (piv.len(), T::from(0.0));
    for (k, &p) in piv.iter().enumerate() {
        if p != k {
            let (head, tail) = b.split_at_mut(p * q);
            head[k * q..(k + 1) * q].swap_with_slice(&mut tail[..q]);
        }
    }
    for (k, &(lo, mid, _)) in starts.iter().enumerate() {
        let (head, below) = b.split_at_mut((k + 1) * q);
        let bk = &head[k * q..];
        if bk.iter().all(|&v| v == zero) {
            continue;
        }
        for &i in &rows[lo..mid] {
            let l = lu[k * m + i];
            for (bi, &v) in below[(i - k - 1) * q..(i - k) * q].iter_mut().zip(bk) {
                *bi = *bi - l * v;
            }
        }
    }
    for (k, &(_, mid, hi)) in starts.iter().enumerate().rev() {
        let (above, tail) = b.split_at_mut(k * q);
        let bk = &mut tail[..q];
        let d = lu[k * m + k];
        for v in bk.iter_mut() {
            *v = *v * d;
        }
        if bk.iter().all(|&v| v == zero) {
            continue;
        }
        for &i in &rows[mid..hi] {
            let u = lu[k * m + i];
            for (bi, &v) in above[i * q..(i + 1) * q].iter_mut().zip(bk.iter()) {
                *bi = *bi - u * v;
            }
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
    /// The nonzeros of the blocks larger than [`UNROLLED`] (an effect's states beside the
    /// actuator's), one after another, factored and solved sparse.
    pattern: Pattern,
}

impl<T: Entry> BlockLu<T> {
    pub fn new(blocks: Vec<usize>) -> BlockLu<T> {
        BlockLu {
            lu: vec![T::from(0.0); blocks.iter().map(|m| m * m).sum()],
            piv: vec![0; blocks.iter().sum()],
            blocks,
            pattern: Pattern::default(),
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
        let pattern = &mut self.pattern;
        pattern.starts.clear();
        pattern.rows.clear();
        for &m in &self.blocks {
            let a = &mut self.lu[at..at + m * m];
            let sparse = m > UNROLLED;
            if sparse {
                pattern.clear_bits(m);
            }
            for c in 0..m {
                let col = &jac[(o + c) * n + o..(o + c) * n + o + m];
                for (r, &v) in col.iter().enumerate() {
                    a[c * m + r] = T::from(-v);
                    if sparse && (v != 0.0 || r == c) {
                        pattern.mark(r, c);
                    }
                }
                a[c * m + c] = a[c * m + c] + sigma;
            }
            let piv = &mut self.piv[o..o + m];
            if sparse {
                factor_sparse(a, piv, pattern)
            } else {
                factor(a, piv)
            }
            .map_err(|Singular(k)| Singular(o + k))?;
            o += m;
            at += m * m;
        }
        Ok(())
    }

    /// Solves (σ I − J) x = b in place with the factors of [`BlockLu::factor_shifted`].
    pub fn solve(&self, b: &mut [T]) {
        let (mut o, mut at, mut sparse_at) = (0, 0, 0);
        for &m in &self.blocks {
            let (lu, piv, b) = (
                &self.lu[at..at + m * m],
                &self.piv[o..o + m],
                &mut b[o..o + m],
            );
            if m > UNROLLED {
                let starts = &self.pattern.starts[sparse_at..sparse_at + m];
                solve_sparse(lu, piv, (starts, &self.pattern.rows), b, 1);
                sparse_at += m;
            } else {
                solve(lu, piv, b);
            }
            o += m;
            at += m * m;
        }
    }
}

/// The LU factors (P A = L U) of a real m × m matrix with many zeros, in dense storage: the
/// elimination and the solves touch only the nonzeros ([`factor_sparse`]), so a matrix whose
/// rows and columns are ordered with the sparsest first (an effect's own states in the
/// sensitivities' stage equations) costs little more than its dense part.
#[derive(Clone, Debug, Default)]
pub(super) struct SparseLu {
    /// Column-major; after [`SparseLu::factor`] L below the diagonal, U above, 1/U_kk on it.
    lu: Vec<f64>,
    piv: Vec<usize>,
    pattern: Pattern,
}

impl SparseLu {
    /// Starts an m × m matrix to factor, zero but for the entries [`SparseLu::set`] then gives.
    pub fn start(&mut self, m: usize) {
        self.lu.clear();
        self.lu.resize(m * m, 0.0);
        self.piv.resize(m, 0);
        self.pattern.clear_bits(m);
    }

    /// Entry (`row`, `col`) of the matrix to factor.
    pub fn set(&mut self, row: usize, col: usize, v: f64) {
        self.lu[col * self.piv.len() + row] = v;
        self.pattern.mark(row, col);
    }

    /// Factors the matrix [`SparseLu::set`] gave, with partial pivoting.
    pub fn factor(&mut self) -> Result<(), Singular> {
        self.pattern.starts.clear();
        self.pattern.rows.clear();
        factor_sparse(&mut self.lu, &mut self.piv, &mut self.pattern)
    }

    /// Solves A X = B in place with the factors for the `q` right-hand sides of `b`, row by
    /// row (row i's q values side by side).
    pub fn solve(&self, b: &mut [f64], q: usize) {
        let p = &self.pattern;
        solve_sparse(&self.lu, &self.piv, (&p.starts, &p.rows), b, q);
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

    /// σ I − J.
    fn shifted(sigma: Complex<f64>, jac: &DMatrix<f64>) -> DMatrix<Complex<f64>> {
        DMatrix::from_fn(jac.nrows(), jac.ncols(), |r, c| {
            let s = if r == c {
                sigma
            } else {
                Complex::new(0.0, 0.0)
            };
            s - Complex::new(jac[(r, c)], 0.0)
        })
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
        let b = &shifted(sigma, &m) * &x;
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
    /// that swaps a dense row up: the sparse factors solve it as the dense ones do, and
    /// several right-hand sides at once each as it is solved alone, to the bit.
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
        lu.solve(&mut rhs, 1);
        for i in 0..n {
            assert!((rhs[i] - x[i]).abs() < 1e-12, "{rhs:?}");
        }
        // three right-hand sides at once, one of them zero: each as it is solved alone
        let b2 = b.map(|v| 2.0 * v - 1.0);
        let mut alone = b2.as_slice().to_vec();
        lu.solve(&mut alone, 1);
        let mut many: Vec<f64> = (0..n).flat_map(|i| [b[i], 0.0, b2[i]]).collect();
        lu.solve(&mut many, 3);
        for i in 0..n {
            assert_eq!(many[3 * i..3 * i + 3], [rhs[i], 0.0, alone[i]]);
        }
        let mut singular = SparseLu::default();
        singular.start(2);
        for (r, c, v) in [(0, 0, 1.0), (1, 0, 2.0), (0, 1, 2.0), (1, 1, 4.0)] {
            singular.set(r, c, v);
        }
        assert_eq!(singular.factor(), Err(Singular(1)));
    }

    /// A block of 70 states beside one of 3 (its rows' patterns two words each), mostly zeros
    /// with a dense corner and pivots that swap rows up from it: [`BlockLu`] factors it sparse,
    /// and its solution is the dense factors' to the bit.
    #[test]
    fn sparse_blocks_solve_as_the_dense_ones_to_the_bit() {
        let (small, big) = (3, 70);
        let n = small + big;
        let mut jac = DMatrix::from_fn(n, n, |r, c| match (r, c) {
            _ if (r < small) != (c < small) => 0.0,
            _ if r == c => -2.0 - r as f64 * 0.1,
            _ if r < small => 0.5,
            _ if r >= 60 && c >= 60 => ((r * 3 + c) % 5) as f64 - 2.0,
            _ if (r >= 60 || c >= 60) && (r + c) % 4 == 0 => 0.5 + ((r + c) % 3) as f64,
            _ if r == c + 1 => 0.3,
            _ => 0.0,
        });
        jac[(66, small)] = 40.0;
        jac[(small + 1, 67)] = -50.0;
        let sigma = Complex::new(3.0, 1.0);
        let x = DVector::from_fn(n, |i, _| Complex::new(i as f64 - 30.5, 1.0));
        let shifted = shifted(sigma, &jac);
        let b = &shifted * &x;
        let mut lu = BlockLu::new(vec![small, big]);
        lu.factor_shifted(sigma, jac.as_slice()).unwrap();
        let mut sparse = b.as_slice().to_vec();
        lu.solve(&mut sparse);
        let mut dense = b.as_slice()[small..].to_vec();
        let (mut a, mut piv) = (vec![Complex::new(0.0, 0.0); big * big], vec![0; big]);
        for c in 0..big {
            for r in 0..big {
                a[c * big + r] = shifted[(small + r, small + c)];
            }
        }
        factor(&mut a, &mut piv).unwrap();
        solve(&a, &piv, &mut dense);
        assert_eq!(&sparse[small..], &dense[..]);
        for i in 0..n {
            assert!((sparse[i] - x[i]).norm() < 1e-10, "x{i}: {}", sparse[i]);
        }
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
