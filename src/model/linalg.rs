//! An SVD bounded in its iterations, for the solves of the model (settling, a series' weights)
//! and of the diagnosis' screening.

use nalgebra::{DMatrix, Dyn, SVD};

/// Iterations at most: a few dozen converge the matrices here (states, sensitivities, series);
/// more means one that never will.
const SWEEPS: usize = 1000;

/// The SVD of `m` (with U and Vᵀ), or `None` where it does not converge: nalgebra's plain
/// `svd` iterates until it does, which a NaN never lets it (a hung diagnosis was traced there).
pub fn bounded_svd(m: DMatrix<f64>) -> Option<SVD<f64, Dyn, Dyn>> {
    SVD::try_new(m, true, true, f64::EPSILON, SWEEPS)
}
