//! LU factorisation with partial pivoting of small dense blocks, in place on preallocated
//! column-major storage, for real and complex matrices (the Radau IIA iteration needs one of
//! each per step size), of block-diagonal matrices block by block ([`BlockLu`]), and of the
//! sensitivities' stage equations (`SparseLu`). Blocks beyond `UNROLLED` rows and the stage
//! equations, mostly zeros, are eliminated and solved over their nonzeros alone, the
//! elimination kept and repeated on the next matrix of the same pattern (`Elimination`).
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
// for loops that start at k + 1. (Larger blocks go to an [`Elimination`].)
#[inline(always)]
fn factor_m<T: Entry>(m: usize, a: &mut [T], piv: &mut [usize]) -> Result<(), Singular> {
    let (a, piv) = (&mut a[..m * m], &mut piv[..m]);
    for k in 0..m {
        piv[k] = pivot(a, m, k)?;
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
/// The whole column is searched, the rows above k not counted, so that the compiler unrolls
/// it for a block of constant size.
#[inline(always)]
fn pivot<T: Entry>(a: &mut [T], m: usize, k: usize) -> Result<usize, Singular> {
    let mut p = k;
    let mut best = a[k * m + k].norm1();
    for i in 0..m {
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

/// Where the nonzeros of factors made by an [`Elimination`] may be: per column k, the rows
/// below the diagonal (L) and above it (U), at `rows[starts[k].0..starts[k].1]` and
/// `rows[starts[k].1..starts[k].2]`, which the solves follow.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
struct Pattern {
    starts: Vec<(usize, usize, usize)>,
    rows: Vec<usize>,
}

/// One step k of an [`Elimination`]: the pivot's row and the ends of the step's lists.
#[derive(Clone, Copy, Debug)]
struct Step {
    pivot: usize,
    rows: usize,
    cols: usize,
    swaps: usize,
}

/// The elimination of a matrix with many zeros (LU with partial pivoting), kept so that the
/// next matrix of the same pattern is factored by repeating it over the same entries (the
/// symbolic work done once, the numeric many times): the sensitivities' stage equations and
/// the iteration matrices of a step keep their pattern and, mostly, their pivots from step to
/// step. From a step whose pivot partial pivoting now picks otherwise the elimination is made
/// anew, so that the factors are always partial pivoting's ([`factor`]'s, whose other products
/// are by zero).
#[derive(Clone, Debug, Default)]
struct Elimination {
    /// The order of the matrix it was made for (0: none yet, or it ended singular) and that
    /// matrix's entries, their positions c m + r in the order given.
    m: usize,
    given: Vec<usize>,
    steps: Vec<Step>,
    /// Per step k: the rows below the diagonal of column k that may hold nonzeros (the pivot's
    /// candidates, then the rows eliminated), the columns right of the diagonal of row k that
    /// may, and the columns where the two rows the pivot swaps may.
    rows: Vec<usize>,
    cols: Vec<usize>,
    swaps: Vec<usize>,
    /// The factors' pattern.
    factors: Pattern,
    /// Scratch of [`Elimination::make`]: each row's columns that may hold a nonzero, a bit each.
    bits: Vec<u64>,
}

impl Elimination {
    /// Factors the m × m matrix `a` (column-major, m = `piv.len()`), zero but at the positions
    /// `given`, into P A = L U in place as [`factor`] does, the diagonal holding 1/U_kk: by
    /// repeating the kept elimination when it was made for this pattern, as far as partial
    /// pivoting picks its pivots again, and by a new one from there on.
    fn factor<T: Entry>(
        &mut self,
        a: &mut [T],
        piv: &mut [usize],
        given: &[usize],
    ) -> Result<(), Singular> {
        let from = if self.m == piv.len() && self.given == given {
            match self.repeat(a, piv) {
                Ok(()) => return Ok(()),
                Err(k) => k,
            }
        } else {
            0
        };
        self.make(a, piv, given, from)
    }

    /// The kept elimination over `a`, or the first step k whose pivot partial pivoting picks
    /// otherwise (or finds none): `a` is then eliminated up to k.
    fn repeat<T: Entry>(&self, a: &mut [T], piv: &mut [usize]) -> Result<(), usize> {
        let m = self.m;
        let (mut rows_at, mut cols_at, mut swaps_at) = (0, 0, 0);
        for (k, step) in self.steps.iter().enumerate() {
            let rows = &self.rows[rows_at..step.rows];
            let cols = &self.cols[cols_at..step.cols];
            let swaps = &self.swaps[swaps_at..step.swaps];
            (rows_at, cols_at, swaps_at) = (step.rows, step.cols, step.swaps);
            if pivot_of(a, m, k, rows) != Some(step.pivot) {
                return Err(k);
            }
            piv[k] = step.pivot;
            for &j in swaps {
                a.swap(j * m + k, j * m + step.pivot);
            }
            eliminate(a, m, k, rows, cols);
        }
        Ok(())
    }

    /// A new elimination of `a` from step `from` on (its steps before kept, `a` eliminated up
    /// to there), made and kept: each row's pattern as bits, column k's rows that may be
    /// nonzero read off them, row k's pattern right of the pivot added to the rows it
    /// eliminates.
    fn make<T: Entry>(
        &mut self,
        a: &mut [T],
        piv: &mut [usize],
        given: &[usize],
        from: usize,
    ) -> Result<(), Singular> {
        let m = piv.len();
        let w = m.div_ceil(64);
        self.m = 0;
        let Elimination {
            given: kept,
            steps,
            rows,
            cols,
            swaps,
            factors,
            bits,
            ..
        } = self;
        kept.clear();
        kept.extend_from_slice(given);
        let bit = |bits: &[u64], row: usize, col: usize| {
            bits[row * w + col / 64] & (1 << (col % 64)) != 0
        };
        let mark =
            |bits: &mut [u64], row: usize, col: usize| bits[row * w + col / 64] |= 1 << (col % 64);
        let fill = |bits: &mut [u64], rows: &[usize], cols: &[usize]| {
            for &i in rows {
                for &j in cols {
                    mark(bits, i, j);
                }
            }
        };
        bits.clear();
        bits.resize(m * w, 0);
        for &at in given {
            mark(bits, at % m, at / m);
        }
        for k in 0..m {
            mark(bits, k, k);
        }
        // the pattern as the kept steps left it
        steps.truncate(from);
        let ends = steps
            .last()
            .map_or((0, 0, 0), |s| (s.rows, s.cols, s.swaps));
        rows.truncate(ends.0);
        cols.truncate(ends.1);
        swaps.truncate(ends.2);
        let (mut rows_at, mut cols_at) = (0, 0);
        for (k, step) in steps.iter().enumerate() {
            for q in 0..w {
                bits.swap(k * w + q, step.pivot * w + q);
            }
            fill(bits, &rows[rows_at..step.rows], &cols[cols_at..step.cols]);
            (rows_at, cols_at) = (step.rows, step.cols);
        }
        for (k, pk) in piv.iter_mut().enumerate().skip(from) {
            let rows_from = rows.len();
            rows.extend((k + 1..m).filter(|&i| bit(bits, i, k)));
            let p = pivot_of(a, m, k, &rows[rows_from..]).ok_or(Singular(k))?;
            *pk = p;
            if p != k {
                let from = swaps.len();
                swaps.extend((0..m).filter(|&j| bit(bits, k, j) || bit(bits, p, j)));
                for &j in &swaps[from..] {
                    a.swap(j * m + k, j * m + p);
                }
                for q in 0..w {
                    bits.swap(k * w + q, p * w + q);
                }
            }
            let cols_from = cols.len();
            cols.extend((k + 1..m).filter(|&j| bit(bits, k, j)));
            // the rows eliminated fill in where row k has entries right of the pivot
            fill(bits, &rows[rows_from..], &cols[cols_from..]);
            eliminate(a, m, k, &rows[rows_from..], &cols[cols_from..]);
            steps.push(Step {
                pivot: p,
                rows: rows.len(),
                cols: cols.len(),
                swaps: swaps.len(),
            });
        }
        // the factors' pattern: a later pivot's swap moved the rows of earlier columns, with
        // their bits
        factors.starts.clear();
        factors.rows.clear();
        for k in 0..m {
            let start = factors.rows.len();
            factors.rows.extend((k + 1..m).filter(|&i| bit(bits, i, k)));
            let mid = factors.rows.len();
            factors.rows.extend((0..k).filter(|&i| bit(bits, i, k)));
            factors.starts.push((start, mid, factors.rows.len()));
        }
        self.m = m;
        Ok(())
    }
}

/// Partial pivoting's row at column k of `a` (m × m, column-major), whose entries below the
/// diagonal are zero but in `rows` (ascending): the row of the largest entry at or below the
/// diagonal, the first of equal ones as [`pivot`] picks it; none where all are zero.
#[inline(always)]
fn pivot_of<T: Entry>(a: &[T], m: usize, k: usize, rows: &[usize]) -> Option<usize> {
    let (mut p, mut best) = (k, a[k * m + k].norm1());
    for &i in rows {
        let v = a[k * m + i].norm1();
        if v > best {
            best = v;
            p = i;
        }
    }
    (best != 0.0 && best.is_finite()).then_some(p)
}

/// Step k of the elimination of `a` (m × m, column-major, row k the pivot's): column k's
/// `rows` scaled by 1/U_kk, which the diagonal keeps, and subtracted from the columns `cols`
/// right of it (a product by a zero of row k skipped, as the dense code's is by zero).
#[inline(always)]
fn eliminate<T: Entry>(a: &mut [T], m: usize, k: usize, rows: &[usize], cols: &[usize]) {
    let zero = T::from(0.0);
    let (left, right) = a.split_at_mut((k + 1) * m);
    let col = &mut left[k * m..];
    let inv = col[k].recip();
    col[k] = inv;
    for &i in rows {
        let v = col[i];
        if v != zero {
            col[i] = v * inv;
        }
    }
    for &j in cols {
        let col_j = &mut right[(j - k - 1) * m..(j - k) * m];
        let akj = col_j[k];
        if akj != zero {
            for &i in rows {
                col_j[i] = col_j[i] - col[i] * akj;
            }
        }
    }
}

/// Sets the entries of `a` (m × m, column-major) where factors of `pattern` may be nonzero, the
/// diagonal among them, to zero: `a` is then zero everywhere.
fn clear<T: Entry>(a: &mut [T], pattern: &Pattern) {
    let m = pattern.starts.len();
    for (k, &(lo, _, hi)) in pattern.starts.iter().enumerate() {
        a[k * m + k] = T::from(0.0);
        for &i in &pattern.rows[lo..hi] {
            a[k * m + i] = T::from(0.0);
        }
    }
}

/// Solves A X = B in place with the factors of an [`Elimination`], whose columns' patterns are
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
    /// The factors' patterns of the blocks larger than [`UNROLLED`] (an effect's states beside
    /// the actuator's), one after another: those blocks are factored and solved sparse.
    pattern: Pattern,
    /// Their eliminations, one per such block, and the scratch of a block's pattern (a restored
    /// state makes them anew at its next factorization).
    #[serde(skip)]
    eliminations: Vec<Elimination>,
    #[serde(skip)]
    given: Vec<usize>,
}

impl<T: Entry> BlockLu<T> {
    pub fn new(blocks: Vec<usize>) -> BlockLu<T> {
        BlockLu {
            lu: vec![T::from(0.0); blocks.iter().map(|m| m * m).sum()],
            piv: vec![0; blocks.iter().sum()],
            blocks,
            pattern: Pattern::default(),
            eliminations: Vec::new(),
            given: Vec::new(),
        }
    }

    pub fn blocks(&self) -> &[usize] {
        &self.blocks
    }

    /// Factors σ I − J block by block, J dense column-major n × n (entries outside the blocks
    /// are not read). A singular block reports its column in J.
    pub fn factor_shifted(&mut self, sigma: T, jac: &[f64]) -> Result<(), Singular> {
        let n = self.piv.len();
        let (mut o, mut at, mut sparse) = (0, 0, 0);
        self.pattern.starts.clear();
        self.pattern.rows.clear();
        for &m in &self.blocks {
            let a = &mut self.lu[at..at + m * m];
            let piv = &mut self.piv[o..o + m];
            shifted(a, sigma, jac, n, o);
            if m > UNROLLED {
                self.given.clear();
                for c in 0..m {
                    let col = &jac[(o + c) * n + o..(o + c) * n + o + m];
                    let nonzero = col.iter().enumerate().filter(|&(r, &v)| v != 0.0 || r == c);
                    self.given.extend(nonzero.map(|(r, _)| c * m + r));
                }
                if self.eliminations.len() == sparse {
                    self.eliminations.push(Elimination::default());
                }
                let elimination = &mut self.eliminations[sparse];
                elimination
                    .factor(a, piv, &self.given)
                    .map_err(|Singular(k)| Singular(o + k))?;
                let (factors, base) = (&elimination.factors, self.pattern.rows.len());
                let shift = |(lo, mid, hi)| (base + lo, base + mid, base + hi);
                self.pattern
                    .starts
                    .extend(factors.starts.iter().map(|&s| shift(s)));
                self.pattern.rows.extend_from_slice(&factors.rows);
                sparse += 1;
            } else {
                factor(a, piv).map_err(|Singular(k)| Singular(o + k))?;
            }
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

/// The diagonal block of σ I − J from row and column `o` into `a` (its size m × m,
/// column-major), J dense column-major n × n.
fn shifted<T: Entry>(a: &mut [T], sigma: T, jac: &[f64], n: usize, o: usize) {
    let m = a.len().isqrt();
    for c in 0..m {
        let col = &jac[(o + c) * n + o..(o + c) * n + o + m];
        for (entry, &v) in a[c * m..(c + 1) * m].iter_mut().zip(col) {
            *entry = T::from(-v);
        }
        a[c * m + c] = a[c * m + c] + sigma;
    }
}

/// The LU factors (P A = L U) of a real m × m matrix with many zeros, in dense storage: the
/// elimination and the solves touch only the nonzeros ([`Elimination`]), so a matrix whose
/// rows and columns are ordered with the sparsest first (an effect's own states in the
/// sensitivities' stage equations) costs little more than its dense part, and the next matrix
/// of the same pattern repeats the elimination.
#[derive(Clone, Debug, Default)]
pub(super) struct SparseLu {
    /// Column-major; after [`SparseLu::factor`] L below the diagonal, U above, 1/U_kk on it.
    lu: Vec<f64>,
    piv: Vec<usize>,
    /// The positions c m + r of the entries [`SparseLu::set`] gave.
    given: Vec<usize>,
    elimination: Elimination,
}

impl SparseLu {
    /// Starts an m × m matrix to factor, zero but for the entries [`SparseLu::set`] then gives.
    pub fn start(&mut self, m: usize) {
        if self.piv.len() == m && self.elimination.m == m {
            // the last factors are nonzero only where their pattern says
            clear(&mut self.lu, &self.elimination.factors);
        } else {
            self.lu.clear();
            self.lu.resize(m * m, 0.0);
            self.piv.resize(m, 0);
        }
        self.given.clear();
    }

    /// Entry (`row`, `col`) of the matrix to factor.
    pub fn set(&mut self, row: usize, col: usize, v: f64) {
        let at = col * self.piv.len() + row;
        self.lu[at] = v;
        self.given.push(at);
    }

    /// Factors the matrix [`SparseLu::set`] gave, with partial pivoting.
    pub fn factor(&mut self) -> Result<(), Singular> {
        let result = self
            .elimination
            .factor(&mut self.lu, &mut self.piv, &self.given);
        if result.is_err() {
            // partly eliminated, its pattern not made: the next start clears it all
            self.piv.clear();
        }
        result
    }

    /// Solves A X = B in place with the factors for the `q` right-hand sides of `b`, row by
    /// row (row i's q values side by side).
    pub fn solve(&self, b: &mut [f64], q: usize) {
        let p = &self.elimination.factors;
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

    /// A solution and the pivots that made it.
    type Solved = (Vec<f64>, Vec<usize>);

    /// The solution of `m x = b` by the dense factors, and by `lu` given m's nonzeros.
    fn dense_and_sparse(m: &DMatrix<f64>, b: &DVector<f64>, lu: &mut SparseLu) -> (Solved, Solved) {
        let n = m.nrows();
        let (mut a, mut piv, mut dense) =
            (m.as_slice().to_vec(), vec![0; n], b.as_slice().to_vec());
        factor(&mut a, &mut piv).unwrap();
        solve(&a, &piv, &mut dense);
        lu.start(n);
        for c in 0..n {
            for r in 0..n {
                if m[(r, c)] != 0.0 {
                    lu.set(r, c, m[(r, c)]);
                }
            }
        }
        lu.factor().unwrap();
        let mut sparse = b.as_slice().to_vec();
        lu.solve(&mut sparse, 1);
        ((dense, piv), (sparse, lu.piv.clone()))
    }

    /// A matrix of the pattern an elimination was made for repeats it (the pivots the same),
    /// repeats it up to the first pivot partial pivoting picks otherwise and eliminates anew
    /// from there, or (another pattern) is eliminated anew: each time the dense factors'
    /// solution to the bit.
    #[test]
    fn repeated_eliminations_solve_as_new_ones() {
        let n = 12;
        let arrow = |scale: f64, big: f64| {
            let mut m = DMatrix::from_fn(n, n, |r, c| match (r, c) {
                _ if r == c => 2.0 + r as f64 * 0.1,
                _ if r >= 8 && c >= 8 => scale * (((r * 3 + c) % 5) as f64 - 2.0),
                _ if r >= 8 || c >= 8 => scale * (0.5 + ((r + c) % 3) as f64),
                _ => 0.0,
            });
            m[(8, 0)] = 40.0;
            m[(11, 9)] = big;
            m
        };
        let b = DVector::from_fn(n, |i, _| 1.0 + (i as f64).sin());
        let mut lu = SparseLu::default();
        let mut pivots = Vec::new();
        let mut other_pattern = arrow(1.0, 0.5);
        other_pattern[(3, 9)] = 0.25;
        for (m, what) in [
            (arrow(1.0, 0.5), "made"),
            (arrow(1.0, 0.6), "repeated"),
            (arrow(1.0, 90.0), "repeated, then made from column 9"),
            (other_pattern, "another pattern"),
        ] {
            let ((dense, dense_piv), (sparse, piv)) = dense_and_sparse(&m, &b, &mut lu);
            assert_eq!(sparse, dense, "{what}");
            assert_eq!(piv, dense_piv, "{what}");
            pivots.push(piv);
        }
        assert_eq!(pivots[0], pivots[1]);
        assert_eq!(pivots[1][..9], pivots[2][..9]);
        assert_ne!(pivots[1][9..], pivots[2][9..]);
    }

    /// Matrices of one random pattern (a sparse head, a denser tail) with random values, one
    /// after another through one [`SparseLu`]: whether each repeats the kept elimination or
    /// meets a pivot partial pivoting picks otherwise and is eliminated anew from there, the
    /// dense factors' solution and pivots to the bit.
    #[test]
    fn random_matrices_of_one_pattern_solve_as_the_dense_ones() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let n = 14;
        let pattern =
            DMatrix::from_fn(n, n, |r, c| r == c || (r + 2 * c) % 5 == 0 || r.min(c) >= 9);
        let (mut lu, mut orders) = (SparseLu::default(), std::collections::BTreeSet::new());
        for draw in 0..200 {
            let m = pattern.map(|p| if p { next() - 0.5 } else { 0.0 });
            let b = DVector::from_fn(n, |i, _| i as f64 - 3.0);
            let ((dense, dense_piv), (sparse, piv)) = dense_and_sparse(&m, &b, &mut lu);
            assert_eq!(sparse, dense, "draw {draw}");
            assert_eq!(piv, dense_piv, "draw {draw}");
            orders.insert(piv);
        }
        assert!(orders.len() > 50, "{} pivot orders", orders.len());
    }

    /// [`BlockLu`] factoring σ I − J anew for another σ repeats its blocks' eliminations: the
    /// dense factors' solution to the bit.
    #[test]
    fn block_factors_repeated_for_another_shift_solve_as_the_dense_ones() {
        let n = 10;
        let jac = DMatrix::from_fn(n, n, |r, c| match (r, c) {
            _ if r == c => -1.0 - r as f64,
            _ if r >= 6 || c >= 6 => 0.3 * ((r + 2 * c) % 4) as f64 - 0.4,
            _ => 0.0,
        });
        let mut lu = BlockLu::new(vec![n]);
        for sigma in [
            Complex::new(2.0, 1.0),
            Complex::new(0.5, -3.0),
            Complex::new(9.0, 0.1),
        ] {
            let shifted = shifted(sigma, &jac);
            let b = DVector::from_fn(n, |i, _| Complex::new(i as f64, 1.0));
            lu.factor_shifted(sigma, jac.as_slice()).unwrap();
            let mut sparse = b.as_slice().to_vec();
            lu.solve(&mut sparse);
            let (mut a, mut piv) = (shifted.as_slice().to_vec(), vec![0; n]);
            factor(&mut a, &mut piv).unwrap();
            let mut dense = b.as_slice().to_vec();
            solve(&a, &piv, &mut dense);
            assert_eq!(sparse, dense, "σ = {sigma}");
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
