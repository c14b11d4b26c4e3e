//! Dense LU factorisation with partial pivoting, in place on preallocated column-major storage,
//! for real and complex matrices (the Radau IIA iteration needs one of each per step size).
//! Written here rather than taken from nalgebra because nalgebra's `LU` owns and reallocates
//! its matrix, and the solver must not allocate per step.

use nalgebra::ComplexField;

/// The matrix is singular to working precision at this column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Singular(pub usize);

/// Factors `a` (n×n, column-major) into P A = L U in place; `piv[k]` is the row swapped with k.
pub fn factor<T>(a: &mut [T], n: usize, piv: &mut [usize]) -> Result<(), Singular>
where
    T: ComplexField<RealField = f64> + Copy,
{
    for k in 0..n {
        let col = k * n;
        let mut p = k;
        let mut best = a[col + k].norm1();
        for i in k + 1..n {
            let v = a[col + i].norm1();
            if v > best {
                best = v;
                p = i;
            }
        }
        piv[k] = p;
        if best == 0.0 || !best.is_finite() {
            return Err(Singular(k));
        }
        if p != k {
            for j in 0..n {
                a.swap(j * n + k, j * n + p);
            }
        }
        let inv = T::one() / a[col + k];
        for i in k + 1..n {
            a[col + i] *= inv;
        }
        for j in k + 1..n {
            let akj = a[j * n + k];
            if akj != T::zero() {
                for i in k + 1..n {
                    let l = a[col + i];
                    a[j * n + i] -= l * akj;
                }
            }
        }
    }
    Ok(())
}

/// Solves A x = b in place with the factors from [`factor`].
pub fn solve<T>(lu: &[T], n: usize, piv: &[usize], b: &mut [T])
where
    T: ComplexField<RealField = f64> + Copy,
{
    // the factors hold rows in their final order: permute b fully, then substitute
    for k in 0..n {
        b.swap(k, piv[k]);
    }
    for k in 0..n {
        let bk = b[k];
        if bk != T::zero() {
            for i in k + 1..n {
                b[i] -= lu[k * n + i] * bk;
            }
        }
    }
    for k in (0..n).rev() {
        b[k] /= lu[k * n + k];
        let bk = b[k];
        if bk != T::zero() {
            for i in 0..k {
                b[i] -= lu[k * n + i] * bk;
            }
        }
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
        factor(&mut a, n, &mut piv).unwrap();
        solve(&a, n, &piv, &mut rhs);
        for i in 0..n {
            assert!((rhs[i] - x[i]).abs() < 1e-12);
        }

        let mc = m.map(|v| Complex::new(v, 0.3 * v));
        let xc = x.map(|v| Complex::new(1.0, v));
        let bc = &mc * &xc;
        let (mut a, mut rhs) = (mc.as_slice().to_vec(), bc.as_slice().to_vec());
        factor(&mut a, n, &mut piv).unwrap();
        solve(&a, n, &piv, &mut rhs);
        for i in 0..n {
            assert!((rhs[i] - xc[i]).norm() < 1e-12);
        }
    }

    #[test]
    fn reports_singular_matrices() {
        let mut a = vec![1.0, 2.0, 2.0, 4.0];
        assert_eq!(factor(&mut a, 2, &mut [0; 2]), Err(Singular(1)));
    }
}
