//! Bounded Levenberg–Marquardt on a vector of residuals, with the problem's own Jacobian where
//! it has one and a forward-difference Jacobian computed in parallel otherwise. Marquardt's
//! diagonal scaling, Nielsen's damping update, steps projected onto the bounds, and a parameter
//! held at its bound while the descent pushes it outward (an active set), so the others are not
//! solved for a move it cannot make.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use nalgebra::{DMatrix, DVector};

use super::Error;

/// A least-squares problem: residuals r(x) of fixed length.
pub trait Residuals: Sync {
    /// Number of residuals.
    fn count(&self) -> usize;
    /// r(x) into `r`; an error when the model cannot be evaluated at x.
    fn eval(&self, x: &[f64], r: &mut [f64]) -> Result<(), Error>;
    /// ∂r/∂x at x computed by the problem itself (for instance from sensitivities), or `None`
    /// (the default) for forward differences; an error also falls back to differences.
    fn jacobian(&self, _x: &[f64]) -> Option<Result<DMatrix<f64>, Error>> {
        None
    }
    /// Moves a trial point back into the problem's domain where that is more than the box
    /// bounds (the default: nothing to do).
    fn project(&self, _x: &mut [f64]) {}
}

#[derive(Clone, Debug)]
pub struct Options {
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction…
    pub ftol: f64,
    /// …or moves no parameter by more than this.
    pub xtol: f64,
    /// Forward-difference step in x.
    pub fd_step: f64,
    /// Give up with [`Error::TimeBudget`] when an iteration would begin after this instant.
    pub deadline: Option<Instant>,
    /// Whether convergence on the problem's own Jacobian is confirmed on differences of the
    /// residuals (a simulation per parameter). A fit that only competes (a diagnosis's refit)
    /// does without: the polish after it goes on along the sensitivities of tighter simulations.
    pub confirm: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_iterations: 60,
            ftol: 1e-10,
            xtol: 1e-8,
            fd_step: 1e-6,
            deadline: None,
            confirm: true,
        }
    }
}

/// Fits running in this process (see [`running`]).
static RUNNING: AtomicUsize = AtomicUsize::new(0);

/// Counts a fit as running while the guard lives: the Jacobians of the fits running at once
/// share the machine's cores (see [`share`]).
pub fn running() -> Running {
    RUNNING.fetch_add(1, Ordering::Relaxed);
    Running(())
}

/// A fit counted as running (see [`running`]); made only there, so that every drop undoes a count.
pub struct Running(());

impl Drop for Running {
    fn drop(&mut self) {
        RUNNING.fetch_sub(1, Ordering::Relaxed);
    }
}

/// Threads a Jacobian may use now: the machine's cores over the fits running in this process,
/// at least one. A diagnosis refits its candidates side by side, one core each, and the last
/// left takes every core; two diagnoses at once (the test suite's threads) keep to one each.
/// How many threads compute a Jacobian changes when it is ready, never its values.
pub fn share() -> usize {
    // asked once: on Linux the answer reads the cgroup's files, and every Jacobian asks
    static CORES: OnceLock<usize> = OnceLock::new();
    let cores = *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    (cores / RUNNING.load(Ordering::Relaxed).max(1)).max(1)
}

/// The minimiser's result: the point, its residuals, and the work done.
#[derive(Clone, Debug)]
pub struct Solution {
    pub x: Vec<f64>,
    pub residuals: DVector<f64>,
    pub cost: f64,
    pub iterations: usize,
    /// Residual evaluations (simulations) in all.
    pub evaluations: usize,
    pub converged: bool,
}

/// r(x), refusing non-finite residuals.
pub fn evaluate(p: &impl Residuals, x: &[f64]) -> Result<DVector<f64>, Error> {
    let mut r = DVector::zeros(p.count());
    p.eval(x, r.as_mut_slice())?;
    if r.iter().any(|v| !v.is_finite()) {
        return Err(Error::NonFiniteResidual);
    }
    Ok(r)
}

/// The Jacobian from its columns, computed in parallel over `threads` threads.
fn assemble(
    rows: usize,
    n: usize,
    threads: usize,
    column: impl Fn(usize) -> Result<Vec<f64>, Error> + Sync,
) -> Result<DMatrix<f64>, Error> {
    let threads = threads.clamp(1, n.max(1));
    let columns: Vec<(usize, Result<Vec<f64>, Error>)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let column = &column;
                s.spawn(move || {
                    (t..n)
                        .step_by(threads)
                        .map(|j| (j, column(j)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("a Jacobian thread panicked"))
            .collect()
    });
    let mut jac = DMatrix::zeros(rows, n);
    for (j, c) in columns {
        jac.set_column(j, &DVector::from_vec(c?));
    }
    Ok(jac)
}

/// ∂r/∂x: the problem's own if `own` and it has one, else by forward differences (backward where
/// the forward point is out of bounds or cannot be evaluated). Also returns the number of
/// residual evaluations spent and whether the problem's own Jacobian was used.
fn jacobian_at(
    p: &impl Residuals,
    x: &[f64],
    r: &DVector<f64>,
    (lo, hi): (&[f64], &[f64]),
    own: bool,
    opts: &Options,
) -> Result<(DMatrix<f64>, usize, bool), Error> {
    // asked only when it is wanted: the problem's own is a simulation with sensitivities
    match own.then(|| p.jacobian(x)).flatten() {
        Some(Ok(j)) if j.iter().all(|v| v.is_finite()) => Ok((j, 1, true)),
        _ => Ok((jacobian(p, x, r, lo, hi, opts)?, x.len(), false)),
    }
}

/// ∂r/∂x by forward differences (backward where the forward point is out of bounds or cannot
/// be evaluated). A direction the residuals cannot be evaluated along either way gets a zero
/// column, so the iteration does not move along it, as it rejects a trial it cannot evaluate: a
/// time constant at its bound 0, where the least step makes the model too stiff to integrate,
/// stays there rather than ending the fit.
pub fn jacobian(
    p: &impl Residuals,
    x: &[f64],
    r: &DVector<f64>,
    lo: &[f64],
    hi: &[f64],
    opts: &Options,
) -> Result<DMatrix<f64>, Error> {
    assemble(r.len(), x.len(), share(), |j| {
        let h = opts.fd_step * x[j].abs().max(1.0);
        let mut xp = x.to_vec();
        let forward = x[j] + h <= hi[j];
        xp[j] = if forward { x[j] + h } else { x[j] - h };
        let rp = match evaluate(p, &xp) {
            Ok(v) => v,
            Err(_) if forward && x[j] - h >= lo[j] => {
                xp[j] = x[j] - h;
                match evaluate(p, &xp) {
                    Ok(v) => v,
                    Err(_) => return Ok(vec![0.0; r.len()]),
                }
            }
            Err(_) => return Ok(vec![0.0; r.len()]),
        };
        let step = xp[j] - x[j];
        Ok(rp
            .iter()
            .zip(r.iter())
            .map(|(a, b)| (a - b) / step)
            .collect())
    })
}

/// ∂r/∂x by central differences with step `h` (for the covariance: second-order accurate,
/// so the weakly determined directions of a correlated problem are not distorted). Where one
/// side cannot be evaluated (a time constant at its bound 0 stepped below it) the column is
/// one-sided from `r`, the residuals at `x`; where neither can, zero, as in [`jacobian`].
pub fn jacobian_central(
    p: &impl Residuals,
    x: &[f64],
    r: &DVector<f64>,
    h: f64,
    threads: usize,
) -> Result<DMatrix<f64>, Error> {
    assemble(p.count(), x.len(), threads, |j| {
        let at = |step: f64| {
            let mut xs = x.to_vec();
            xs[j] += step;
            evaluate(p, &xs)
        };
        let (below, above) = (at(-h), at(h));
        let (from, to, width) = match (&below, &above) {
            (Ok(rm), Ok(rp)) => (rm, rp, 2.0 * h),
            (Err(_), Ok(rp)) => (r, rp, h),
            (Ok(rm), Err(_)) => (rm, r, h),
            (Err(_), Err(_)) => return Ok(vec![0.0; r.len()]),
        };
        Ok(to
            .iter()
            .zip(from.iter())
            .map(|(a, b)| (a - b) / width)
            .collect())
    })
}

/// [`Error::TimeBudget`] once `deadline` has passed.
pub fn check_deadline(deadline: Option<Instant>) -> Result<(), Error> {
    match deadline {
        Some(d) if Instant::now() > d => Err(Error::TimeBudget),
        _ => Ok(()),
    }
}

/// Minimises ½‖r(x)‖² over lo ≤ x ≤ hi from `x0`.
pub fn minimize(
    p: &impl Residuals,
    x0: &[f64],
    lo: &[f64],
    hi: &[f64],
    opts: &Options,
) -> Result<Solution, Error> {
    let n = x0.len();
    let mut x: Vec<f64> = (0..n).map(|j| x0[j].clamp(lo[j], hi[j])).collect();
    let mut r = evaluate(p, &x).map_err(|e| Error::AtStart(Box::new(e)))?;
    let mut evaluations = 1;
    let mut cost = 0.5 * r.norm_squared();
    let (mut lambda, mut nu) = (-1.0, 2.0);
    let mut converged = false;
    // an iteration on differences after the problem's own Jacobian stopped
    let mut confirming = false;
    let mut iterations = 0;
    let (mut jac, spent, mut own) = jacobian_at(p, &x, &r, (lo, hi), true, opts)?;
    evaluations += spent;
    while iterations < opts.max_iterations {
        if converged {
            if !own || !opts.confirm {
                break;
            }
            // convergence is confirmed on differences of the residuals themselves: the
            // problem's Jacobian may differ from them (adaptive steps) by more than the last
            // improvements
            let (j, spent, _) = jacobian_at(p, &x, &r, (lo, hi), false, opts)?;
            (jac, own, converged, lambda, confirming) = (j, false, false, -1.0, true);
            evaluations += spent;
        }
        check_deadline(opts.deadline)?;
        iterations += 1;
        let mut a = jac.transpose() * &jac;
        let mut g = jac.transpose() * &r;
        if a.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFiniteJacobian);
        }
        // a parameter at its bound that the descent (−g) pushes outward stays there: the
        // others are solved without it (else they compensate a move the clamp then undoes)
        for j in 0..n {
            if (x[j] <= lo[j] && g[j] > 0.0) || (x[j] >= hi[j] && g[j] < 0.0) {
                let keep = a[(j, j)].max(f64::MIN_POSITIVE);
                a.row_mut(j).fill(0.0);
                a.column_mut(j).fill(0.0);
                a[(j, j)] = keep;
                g[j] = 0.0;
            }
        }
        if g.iter().all(|&v| v == 0.0) {
            // every parameter is held at its bound, or the gradient vanishes: a minimum
            converged = true;
            continue;
        }
        let diag: Vec<f64> = (0..n)
            .map(|j| a[(j, j)].max(1e-12 * a.diagonal().max()))
            .collect();
        if lambda < 0.0 {
            lambda = 1e-3;
        }
        loop {
            let mut m = a.clone();
            for j in 0..n {
                m[(j, j)] += lambda * diag[j];
            }
            let Some(step) = m.cholesky().map(|c| c.solve(&(-&g))) else {
                lambda *= nu;
                nu *= 2.0;
                if lambda > 1e16 {
                    converged = true;
                    break;
                }
                continue;
            };
            let mut x_new: Vec<f64> = (0..n)
                .map(|j| (x[j] + step[j]).clamp(lo[j], hi[j]))
                .collect();
            p.project(&mut x_new);
            let d = DVector::from_iterator(n, (0..n).map(|j| x_new[j] - x[j]));
            let predicted = -(g.dot(&d) + 0.5 * d.dot(&(&a * &d)));
            if confirming && predicted <= opts.ftol * cost {
                // the differences promise no more than the stopping rule lets go: confirmed
                // without a trial (which could only fail, over and over, at the noise level)
                converged = true;
                break;
            }
            // a step the bounds bent until the model promises no descent is rejected unseen:
            // its ratio could not be positive (a simulation saved)
            let trial = (predicted > 0.0).then(|| {
                evaluations += 1;
                evaluate(p, &x_new)
            });
            let accepted = match trial {
                Some(Ok(r_new)) => {
                    let cost_new = 0.5 * r_new.norm_squared();
                    let rho = (cost - cost_new) / predicted;
                    if rho > 0.0 {
                        let small_x = d.amax()
                            <= opts.xtol * (1.0 + x.iter().fold(0.0f64, |m, v| m.max(v.abs())));
                        converged = (cost - cost_new) <= opts.ftol * cost || small_x;
                        x = x_new;
                        r = r_new;
                        cost = cost_new;
                        lambda *= (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                        nu = 2.0;
                        true
                    } else {
                        false
                    }
                }
                Some(Err(_)) | None => false,
            };
            if accepted {
                break;
            }
            lambda *= nu;
            nu *= 2.0;
            if lambda > 1e16 {
                // no descent left along any direction: at a (bounded) minimum
                converged = true;
                break;
            }
        }
        if !converged {
            // a confirmation that found more to go hands back to the problem's own Jacobian:
            // differences cost a simulation per parameter, every iteration
            let (j, spent, o) = jacobian_at(p, &x, &r, (lo, hi), own || confirming, opts)?;
            (jac, own) = (j, o);
            evaluations += spent;
        }
        confirming = false;
    }
    Ok(Solution {
        x,
        residuals: r,
        cost,
        iterations,
        evaluations,
        converged,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = a exp(−b t) + c, with noise-free data.
    struct Decay {
        t: Vec<f64>,
        y: Vec<f64>,
    }

    impl Decay {
        /// Noise-free data of y = 2 exp(−1.3 t) + 0.5, 50 samples 0.1 apart.
        fn exact() -> Decay {
            let t: Vec<f64> = (0..50).map(|k| k as f64 * 0.1).collect();
            let y = t.iter().map(|t| 2.0 * (-1.3 * t).exp() + 0.5).collect();
            Decay { t, y }
        }
    }

    impl Residuals for Decay {
        fn count(&self) -> usize {
            self.t.len()
        }
        fn eval(&self, x: &[f64], r: &mut [f64]) -> Result<(), Error> {
            for (k, &t) in self.t.iter().enumerate() {
                r[k] = x[0] * (-x[1] * t).exp() + x[2] - self.y[k];
            }
            Ok(())
        }
    }

    /// The decay with its own Jacobian, wrong by 30 % in ∂r/∂b, and noisy data (so the
    /// residuals do not vanish at the minimum and a wrong Jacobian points elsewhere).
    struct Misled(Decay);

    impl Residuals for Misled {
        fn count(&self) -> usize {
            self.0.count()
        }
        fn eval(&self, x: &[f64], r: &mut [f64]) -> Result<(), Error> {
            self.0.eval(x, r)
        }
        fn jacobian(&self, x: &[f64]) -> Option<Result<DMatrix<f64>, Error>> {
            let t = &self.0.t;
            Some(Ok(DMatrix::from_fn(t.len(), 3, |k, j| {
                let e = (-x[1] * t[k]).exp();
                [e, -0.7 * x[0] * t[k] * e, 1.0][j]
            })))
        }
    }

    #[test]
    fn a_wrong_own_jacobian_cannot_stop_the_fit_early() {
        let mut noisy = Decay::exact();
        for (k, y) in noisy.y.iter_mut().enumerate() {
            *y += 0.01 * ((k * 7919) % 13) as f64;
        }
        let inf = f64::INFINITY;
        let (lo, hi) = ([-inf; 3], [inf; 3]);
        let p = Misled(noisy);
        let own = minimize(&p, &[1.0, 0.5, 0.0], &lo, &hi, &Options::default()).unwrap();
        let fd = minimize(&p.0, &[1.0, 0.5, 0.0], &lo, &hi, &Options::default()).unwrap();
        assert!(own.converged && fd.converged);
        for (a, b) in own.x.iter().zip(&fd.x) {
            assert!((a - b).abs() < 1e-5, "{:?} {:?}", own.x, fd.x);
        }
    }

    #[test]
    fn a_parameter_at_its_bound_is_held_while_pushed_out_and_leaves_when_pulled_in() {
        let p = Decay::exact();
        let inf = f64::INFINITY;
        // starts on its lower bound, the minimum inside: it leaves
        let s = minimize(
            &p,
            &[1.0, 1.0, 0.0],
            &[-inf, 1.0, -inf],
            &[inf, 5.0, inf],
            &Options::default(),
        )
        .unwrap();
        assert!((s.x[1] - 1.3).abs() < 1e-6, "{:?}", s.x);
        // the minimum beyond the bound: it stays there and the others fit around it
        let s = minimize(
            &p,
            &[1.0, 1.0, 0.0],
            &[-inf, 1.5, -inf],
            &[inf, 5.0, inf],
            &Options::default(),
        )
        .unwrap();
        assert!(s.converged && s.x[1] == 1.5, "{:?}", s.x);
        assert!(s.iterations < 30, "{} iterations", s.iterations);
    }

    /// The decay beside a fourth parameter, an offset that the residuals cannot be evaluated at
    /// just above its bound 0 (as a time constant too small to integrate).
    struct Unsteppable(Decay);

    impl Residuals for Unsteppable {
        fn count(&self) -> usize {
            self.0.count()
        }
        fn eval(&self, x: &[f64], r: &mut [f64]) -> Result<(), Error> {
            if x[3] > 0.0 && x[3] < 1e-3 {
                return Err(Error::NonFiniteResidual);
            }
            self.0.eval(&x[..3], r)?;
            r.iter_mut().for_each(|v| *v += x[3]);
            Ok(())
        }
    }

    #[test]
    fn a_direction_that_cannot_be_evaluated_is_held_not_fatal() {
        let inf = f64::INFINITY;
        let s = minimize(
            &Unsteppable(Decay::exact()),
            &[1.0, 0.5, 0.0, 0.0],
            &[-inf, -inf, -inf, 0.0],
            &[inf; 4],
            &Options::default(),
        )
        .unwrap();
        assert!(s.converged && s.x[3] == 0.0, "{:?}", s.x);
        for (got, want) in s.x.iter().zip([2.0, 1.3, 0.5]) {
            assert!((got - want).abs() < 1e-6, "{:?}", s.x);
        }
        // the covariance's differences: one-sided where one side fails, zero where both do
        let p = Unsteppable(Decay::exact());
        let column = |x3: f64, h: f64| {
            let mut x = s.x.clone();
            x[3] = x3;
            let r = evaluate(&p, &x).unwrap_or_else(|_| DVector::zeros(p.count()));
            let j = jacobian_central(&p, &x, &r, h, 1).unwrap();
            j.column(3)
                .iter()
                .fold(0.0f64, |m, v| m.max((v - 1.0).abs()))
        };
        assert!(column(0.0, 1e-4) < 1e-9, "at the bound, backward");
        assert!(column(1.05e-3, 1e-4) < 1e-9, "just above the gap, forward");
        // inside the gap nothing can be evaluated: every column is zero
        assert!((column(5e-4, 1e-4) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn fits_an_exponential_and_respects_bounds() {
        let p = Decay::exact();
        let inf = f64::INFINITY;
        let s = minimize(
            &p,
            &[1.0, 0.5, 0.0],
            &[-inf; 3],
            &[inf; 3],
            &Options::default(),
        )
        .unwrap();
        assert!(s.converged);
        for (got, want) in s.x.iter().zip([2.0, 1.3, 0.5]) {
            assert!((got - want).abs() < 1e-6, "{:?}", s.x);
        }
        let s = minimize(
            &p,
            &[1.0, 0.5, 0.0],
            &[-inf, -inf, -inf],
            &[inf, 1.0, inf],
            &Options::default(),
        )
        .unwrap();
        assert!(s.x[1] <= 1.0 && (s.x[1] - 1.0).abs() < 1e-9, "{:?}", s.x);
    }

    /// Linear residuals J (x − x*) with correlated columns, whose minimum x* = (−1, 1.5) lies
    /// beyond the bound x0 ≥ −0.1; each evaluation's cost is recorded.
    struct Pressed(std::sync::Mutex<Vec<f64>>);

    impl Pressed {
        const J: [[f64; 2]; 2] = [[1.0, 1.0], [0.1, -0.1]];
    }

    impl Residuals for Pressed {
        fn count(&self) -> usize {
            2
        }
        fn eval(&self, x: &[f64], r: &mut [f64]) -> Result<(), Error> {
            let dx = [x[0] + 1.0, x[1] - 1.5];
            for (ri, row) in r.iter_mut().zip(Self::J) {
                *ri = row[0] * dx[0] + row[1] * dx[1];
            }
            self.0
                .lock()
                .unwrap()
                .push(0.5 * r.iter().map(|v| v * v).sum::<f64>());
            Ok(())
        }
        fn jacobian(&self, _x: &[f64]) -> Option<Result<DMatrix<f64>, Error>> {
            Some(Ok(DMatrix::from_fn(2, 2, |i, j| Self::J[i][j])))
        }
    }

    /// The first steps toward x* take x0 past its bound, and clamped there x1 keeps the move it
    /// made for x0's: the model promises an ascent. Such a step is rejected without a
    /// simulation: on linear residuals the model is exact, so every trial simulated lowers the
    /// cost.
    #[test]
    fn a_step_the_bounds_bend_into_no_descent_is_not_simulated() {
        let p = Pressed(Default::default());
        let opts = Options {
            confirm: false,
            ..Options::default()
        };
        let inf = f64::INFINITY;
        let s = minimize(&p, &[0.0, 0.0], &[-0.1, -inf], &[inf, inf], &opts).unwrap();
        assert!(s.converged && s.x[0] == -0.1, "{:?}", s.x);
        // with x0 at its bound, x1 where the cost is least given it: (JᵀJ)₁₀ / (JᵀJ)₁₁ of x0's miss
        assert!(
            (s.x[1] - (1.5 - 0.99 / 1.01 * 0.9)).abs() < 1e-6,
            "{:?}",
            s.x
        );
        let costs = p.0.into_inner().unwrap();
        for w in costs.windows(2) {
            assert!(w[1] < w[0], "a simulated trial raised the cost: {costs:?}");
        }
    }
}
