//! Dense LU factorisation with partial pivoting, in place on preallocated column-major storage,
//! for real and complex matrices (the Radau IIA iteration needs one of each per step size).
//! Written here rather than taken from nalgebra because nalgebra's `LU` owns and reallocates
//! its matrix, and the solver must not allocate per step.

use nalgebra::ComplexField;

/// The matrix is singular to working precision at this column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Singular(pub usize);

/// Factors the diagonal block of `a` (column-major, leading dimension `ld`) that starts at row
/// and column `o` and has size `m` into P A = L U in place; `piv[k]` is the row (relative to
/// `o`) swapped with k. Entries outside the block are neither read nor written.
pub fn factor<T>(
    a: &mut [T],
    ld: usize,
    o: usize,
    m: usize,
    piv: &mut [usize],
) -> Result<(), Singular>
where
    T: ComplexField<RealField = f64> + Copy,
{
    let at = |r: usize, c: usize| (o + c) * ld + o + r;
    for k in 0..m {
        let mut p = k;
        let mut best = a[at(k, k)].norm1();
        for i in k + 1..m {
            let v = a[at(i, k)].norm1();
            if v > best {
                best = v;
                p = i;
            }
        }
        piv[k] = p;
        if best == 0.0 || !best.is_finite() {
            return Err(Singular(o + k));
        }
        if p != k {
            for j in 0..m {
                a.swap(at(k, j), at(p, j));
            }
        }
        let inv = T::one() / a[at(k, k)];
        for i in k + 1..m {
            a[at(i, k)] *= inv;
        }
        for j in k + 1..m {
            let akj = a[at(k, j)];
            if akj != T::zero() {
                for i in k + 1..m {
                    let l = a[at(i, k)];
                    a[at(i, j)] -= l * akj;
                }
            }
        }
    }
    Ok(())
}

/// Solves A x = b in place for the block factored by [`factor`] (`b` is the block's part).
pub fn solve<T>(lu: &[T], ld: usize, o: usize, piv: &[usize], b: &mut [T])
where
    T: ComplexField<RealField = f64> + Copy,
{
    let m = b.len();
    let at = |r: usize, c: usize| (o + c) * ld + o + r;
    // the factors hold rows in their final order: permute b fully, then substitute
    for (k, &p) in piv.iter().enumerate().take(m) {
        b.swap(k, p);
    }
    for k in 0..m {
        let bk = b[k];
        if bk != T::zero() {
            for i in k + 1..m {
                b[i] -= lu[at(i, k)] * bk;
            }
        }
    }
    for k in (0..m).rev() {
        b[k] /= lu[at(k, k)];
        let bk = b[k];
        if bk != T::zero() {
            for i in 0..k {
                b[i] -= lu[at(i, k)] * bk;
            }
        }
    }
}

/// Factors a block-diagonal matrix block by block (`blocks`: the sizes, summing to n).
pub fn factor_blocks<T>(
    a: &mut [T],
    n: usize,
    blocks: &[usize],
    piv: &mut [usize],
) -> Result<(), Singular>
where
    T: ComplexField<RealField = f64> + Copy,
{
    let mut o = 0;
    for &m in blocks {
        factor(a, n, o, m, &mut piv[o..o + m])?;
        o += m;
    }
    Ok(())
}

/// Solves with the factors of [`factor_blocks`].
pub fn solve_blocks<T>(lu: &[T], n: usize, blocks: &[usize], piv: &[usize], b: &mut [T])
where
    T: ComplexField<RealField = f64> + Copy,
{
    let mut o = 0;
    for &m in blocks {
        solve(lu, n, o, &piv[o..o + m], &mut b[o..o + m]);
        o += m;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Complex, DMatrix, DVector};

    #[test]
    fn solves_real_and_complex_systems() {
        let n = 6;
        // diagonally dominant, then rows reversed so that every column needs a pivot swap
        let m = DMatrix::from_fn(n, n, |r, c| {
            let r = n - 1 - r;
            ((r * 7 + c * 3) % 5) as f64 - 2.0 + if r == c { 6.0 } else { 0.0 }
        });
        let x = DVector::from_fn(n, |i, _| i as f64 - 1.5);
        let b = &m * &x;
        let (mut a, mut piv, mut rhs) = (m.as_slice().to_vec(), vec![0; n], b.as_slice().to_vec());
        factor_blocks(&mut a, n, &[n], &mut piv).unwrap();
        solve_blocks(&a, n, &[n], &piv, &mut rhs);
        for i in 0..n {
            assert!((rhs[i] - x[i]).abs() < 1e-12);
        }

        let mc = m.map(|v| Complex::new(v, 0.3 * v));
        let xc = x.map(|v| Complex::new(1.0, v));
        let bc = &mc * &xc;
        let (mut a, mut rhs) = (mc.as_slice().to_vec(), bc.as_slice().to_vec());
        factor_blocks(&mut a, n, &[n], &mut piv).unwrap();
        solve_blocks(&a, n, &[n], &piv, &mut rhs);
        for i in 0..n {
            assert!((rhs[i] - xc[i]).norm() < 1e-12);
        }
    }

    #[test]
    fn block_diagonal_factors_ignore_what_lies_outside_the_blocks() {
        let n = 5;
        let blocks = [2, 3];
        let inside = |r: usize, c: usize| (r < 2) == (c < 2);
        let m = DMatrix::from_fn(n, n, |r, c| {
            if inside(r, c) {
                (r + 2 * c) as f64 - 3.0 + if r == c { 9.0 } else { 1.0 }
            } else {
                0.0
            }
        });
        let x = DVector::from_fn(n, |i, _| 1.0 + i as f64);
        let b = &m * &x;
        // garbage off the blocks must not matter
        let mut a = DMatrix::from_fn(n, n, |r, c| if inside(r, c) { m[(r, c)] } else { 1e6 })
            .as_slice()
            .to_vec();
        let (mut piv, mut rhs) = (vec![0; n], b.as_slice().to_vec());
        factor_blocks(&mut a, n, &blocks, &mut piv).unwrap();
        solve_blocks(&a, n, &blocks, &piv, &mut rhs);
        for i in 0..n {
            assert!((rhs[i] - x[i]).abs() < 1e-12, "{rhs:?}");
        }
    }

    #[test]
    fn reports_singular_matrices() {
        let mut a = vec![1.0, 2.0, 2.0, 4.0];
        assert_eq!(
            factor_blocks(&mut a, 2, &[2], &mut [0; 2]),
            Err(Singular(1))
        );
    }
}
