//! Fitting one group of parameters against some channels: the residuals of the simulation
//! error, the optimisation in reduced coordinates, the covariance, and the directions of
//! parameter space the data do not determine.

use nalgebra::{DMatrix, DVector};

use super::experiment::{Channel, Experiment, Weighting};
use super::{Error, Hold, Options, lm, simulate};
use crate::model::Params;
use crate::model::params::{ParamDef, Rule};
use crate::simulation::sensitivity::{Direction, Sensitive, simulate_sensitive};

/// How a parameter is moved by the optimiser: in log space when it must be positive.
#[derive(Clone, Copy)]
pub(super) struct Coordinate {
    def: &'static ParamDef,
    pub(super) log: bool,
    pub(super) scale: f64,
}

impl Coordinate {
    /// The coordinates of `defs` from `base`: ln p where p must stay positive, otherwise p over
    /// its start value; a weight of a series (`Rule::Weight`) over the largest start among the
    /// weights of its unit, or where they all start at 0 among the parameters of its unit (a
    /// creep's weights against Kb), or else 1 in its unit, so that it can start at 0, leave it
    /// and come back.
    fn of(defs: &[&'static ParamDef], base: &Params) -> Vec<Coordinate> {
        let largest = |weights: bool, unit: &str| {
            defs.iter()
                .filter(|d| d.unit == unit && (!weights || d.rule == Rule::Weight))
                .map(|d| (d.get)(base).abs())
                .fold(0.0, f64::max)
        };
        defs.iter()
            .map(|&def| {
                let prior = (def.get)(base);
                let scale = match def.rule {
                    Rule::Weight => [largest(true, def.unit), largest(false, def.unit)]
                        .into_iter()
                        .find(|&s| s > 0.0)
                        .unwrap_or(1.0),
                    _ => prior.abs(),
                };
                Coordinate {
                    def,
                    log: def.rule.fitted_in_log(prior),
                    scale: scale.max(1e-300),
                }
            })
            .collect()
    }
    fn to_x(self, p: f64) -> f64 {
        if self.log { p.ln() } else { p / self.scale }
    }
    fn to_p(self, x: f64) -> f64 {
        if self.log { x.exp() } else { x * self.scale }
    }
}

/// The residuals of one group: some parameters, some channels, all estimation experiments.
struct Problem<'a> {
    base: &'a Params,
    coords: Vec<Coordinate>,
    channels: Vec<Channel>,
    experiments: &'a [Experiment],
    /// Per experiment, the factor on each of `channels`' residuals (`Weighting`).
    factors: Vec<Vec<f64>>,
    rtol: f64,
    len: usize,
    counter: std::sync::atomic::AtomicUsize,
}

/// Step in the coordinates of the differences of f, the rest state and the outputs that the
/// sensitivities carry (book/src/identify.md, "How `hasel identify` estimates").
const SENSITIVITY_STEP: f64 = 1e-6;

/// The sensitivities' simulations are this much looser than the residuals' (book/src/
/// identify.md, "How `hasel identify` estimates"): the tight tolerance keeps the step-size
/// control out of the residuals, whose differences a stopping rule and a BIC read; the
/// sensitivities follow their own run's steps and only steer the step (the fit's) or shape the
/// covariance (the polish's). Measured there: a fifth less time at 10; at 100 a slew's refit
/// ended at a worse optimum.
const SENSITIVITY_RTOL_FACTOR: f64 = 10.0;

impl Problem<'_> {
    fn params_at(&self, x: &[f64]) -> Result<Params, Error> {
        let mut p = self.base.clone();
        for (c, &xi) in self.coords.iter().zip(x) {
            p.set(c.def.name, c.to_p(xi))?;
        }
        Ok(p)
    }

    /// ∂r/∂x from the forward sensitivities of one simulation per experiment, or the reason
    /// they cannot be had (a direction that switches an effect's states, or moves the delay from
    /// 0).
    fn sensitivity_jacobian(&self, x: &[f64]) -> Result<DMatrix<f64>, Error> {
        let p = self.params_at(x)?;
        let directions = (0..x.len())
            .map(|j| {
                let mut xj = x.to_vec();
                xj[j] += SENSITIVITY_STEP;
                Ok(Direction {
                    params: self.params_at(&xj)?,
                    step: SENSITIVITY_STEP,
                })
            })
            .collect::<Result<Vec<_>, Error>>()?;
        let mut jac = DMatrix::zeros(self.len, x.len());
        let mut row = 0;
        // the directions in as many parts as the cores this fit may take now, a run each: each
        // direction's sensitivities are the same whichever run carries it
        let part = directions.len().div_ceil(lm::share()).max(1);
        for (exp, factors) in self.experiments.iter().zip(&self.factors) {
            let runs = self.sensitive_runs(&p, &directions, part, exp)?;
            self.counter
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            for (&c, &f) in self.channels.iter().zip(factors) {
                if exp.measured(c).is_some() {
                    let o = match c {
                        Channel::H(i) => i,
                        Channel::Tip(i) => 3 + i,
                    };
                    // column by column: the Jacobian is stored so
                    for j in 0..x.len() {
                        let (run, jj) = (&runs[j / part], j % part);
                        let mut column = jac.column_mut(j);
                        for k in 0..exp.t.len() {
                            column[row + k] = f * run.output(k, jj)[o];
                        }
                    }
                    row += exp.t.len();
                }
            }
        }
        Ok(jac)
    }

    /// The sensitive simulations of `exp` at `p`, one per `part` directions, side by side.
    fn sensitive_runs(
        &self,
        p: &Params,
        directions: &[Direction],
        part: usize,
        exp: &Experiment,
    ) -> Result<Vec<Sensitive>, Error> {
        let times = exp.sensed_times();
        let loose = self.rtol * SENSITIVITY_RTOL_FACTOR;
        let run = |d: &[Direction]| {
            simulate_sensitive(p, d, &exp.conditions.start, &exp.input, &times, loose).map_err(
                |source| Error::Experiment {
                    experiment: exp.name.clone(),
                    source,
                },
            )
        };
        if part >= directions.len() {
            return Ok(vec![run(directions)?]);
        }
        std::thread::scope(|s| {
            let handles: Vec<_> = directions
                .chunks(part)
                .map(|d| s.spawn(move || run(d)))
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("a sensitive simulation does not panic"))
                .collect()
        })
    }
}

impl lm::Residuals for Problem<'_> {
    fn count(&self) -> usize {
        self.len
    }
    fn eval(&self, x: &[f64], r: &mut [f64]) -> Result<(), Error> {
        let p = self.params_at(x)?;
        let mut k = 0;
        for (exp, factors) in self.experiments.iter().zip(&self.factors) {
            let sim = simulate(&p, exp, self.rtol)?;
            self.counter
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            for (&c, &f) in self.channels.iter().zip(factors) {
                if let Some(y) = exp.measured(c) {
                    for (s, m) in sim.iter().zip(y) {
                        r[k] = f * (c.of(s) - m);
                        k += 1;
                    }
                }
            }
        }
        Ok(())
    }
}

/// A group of parameters fitted together against some channels.
pub(super) struct Group {
    pub(super) params: Vec<&'static ParamDef>,
    pub(super) channels: Vec<Channel>,
}

/// Actuators are fitted separately when only heights are measured and every free parameter
/// belongs to one actuator (the model is decoupled); otherwise all at once.
pub(super) fn groups(free: &[&'static ParamDef], experiments: &[Experiment]) -> Vec<Group> {
    let measured: Vec<Channel> = Channel::ALL
        .into_iter()
        .filter(|&c| experiments.iter().any(|e| e.measured(c).is_some()))
        .collect();
    let heights_only = measured.iter().all(|c| matches!(c, Channel::H(_)));
    if heights_only && free.iter().all(|d| d.actuator.is_some()) {
        (0..3)
            .map(|i| Group {
                params: free
                    .iter()
                    .copied()
                    .filter(|d| d.actuator == Some(i))
                    .collect(),
                channels: vec![Channel::H(i)],
            })
            .filter(|g| !g.params.is_empty())
            .collect()
    } else {
        vec![Group {
            params: free.to_vec(),
            channels: measured,
        }]
    }
}

/// A held direction whose largest component exceeds this is that one parameter.
const SINGLE: f64 = 0.7;

/// The covariance's simulations are this much tighter than the fit's (see `fit_group`).
const COVARIANCE_RTOL_FACTOR: f64 = 1e-2;

/// Central-difference step (in log parameters) of the covariance Jacobian.
const COVARIANCE_FD_STEP: f64 = 1e-3;

/// A step that lowers the sum of squared residuals by less than this share of one sample's mean
/// square ends the fit: at the noise floor Δχ² < 0.01, a move of a tenth of a standard error,
/// which no decision drawn from the fit can see (a BIC moves by 0.01).
const NOISE_TELL: f64 = 0.01;

/// A parameter's axis is held when the basis of what the held directions leave reaches it by
/// less than this.
const HELD: f64 = 1e-9;

/// Gauss–Newton iterations at most in the polish.
const GN_POLISH: usize = 10;

/// Half-width in log space of the widest 95 % interval an estimate may have and still count as
/// determined by the data: ×/÷ 1.5.
const MAX_LOG_HALF_WIDTH: f64 = 0.405;

/// What fitting one group gives.
pub(super) struct GroupResult {
    pub(super) estimates: Vec<(String, f64, f64, (f64, f64))>, // name, value, std error, ci95
    pub(super) not_identifiable: Vec<(String, String)>,
    pub(super) held_combinations: Vec<Vec<(String, f64)>>,
    pub(super) names: Vec<String>,
    /// The fit's coordinate of each of `names`.
    pub(super) coords: Vec<Coordinate>,
    pub(super) covariance: DMatrix<f64>,
    pub(super) iterations: usize,
    pub(super) simulations: usize,
    /// A run of the fit ended unconverged because the iteration budget ran out.
    pub(super) out_of_budget: bool,
}

/// The group's problem seen in reduced coordinates z: x = anchor + B z, clamped to the bounds.
/// The columns of B span the directions the data determine; the others stay where they are
/// held, at the anchor (the start, or where the fit had taken them: [`Hold`]).
struct Reduced<'a, 'b> {
    inner: &'a Problem<'b>,
    anchor: &'a [f64],
    basis: &'a DMatrix<f64>,
    lo: &'a [f64],
    hi: &'a [f64],
}

impl Reduced<'_, '_> {
    /// anchor + B z before the clamping.
    fn unclamped(&self, z: &[f64]) -> Vec<f64> {
        (0..self.anchor.len())
            .map(|i| self.anchor[i] + (0..z.len()).map(|k| self.basis[(i, k)] * z[k]).sum::<f64>())
            .collect()
    }

    /// Bounds on z: a column of B along one coordinate of x carries that coordinate's bounds
    /// (so the optimiser keeps it inside, and it can leave its bound again); a column mixing
    /// several is unbounded, its coordinates clamped in [`Reduced::x_of`].
    fn z_bounds(&self) -> (Vec<f64>, Vec<f64>) {
        (0..self.basis.ncols())
            .map(|k| {
                let col = self.basis.column(k);
                let i = col.iamax();
                if (col[i].abs() - 1.0).abs() > 1e-9 {
                    return (f64::NEG_INFINITY, f64::INFINITY);
                }
                let (a, b) = (
                    (self.lo[i] - self.anchor[i]) / col[i],
                    (self.hi[i] - self.anchor[i]) / col[i],
                );
                (a.min(b), a.max(b))
            })
            .unzip()
    }

    fn x_of(&self, z: &[f64]) -> Vec<f64> {
        let x = self.unclamped(z);
        (0..x.len())
            .map(|i| x[i].clamp(self.lo[i], self.hi[i]))
            .collect()
    }
}

impl lm::Residuals for Reduced<'_, '_> {
    fn count(&self) -> usize {
        self.inner.len
    }
    fn eval(&self, z: &[f64], r: &mut [f64]) -> Result<(), Error> {
        self.inner.eval(&self.x_of(z), r)
    }
    fn jacobian(&self, z: &[f64]) -> Option<Result<DMatrix<f64>, Error>> {
        Some(self.sensitivity_jacobian(z))
    }
    /// z whose image is nearest to the clamped point: a step past a bound along a column that
    /// mixes coordinates is pulled back, so z never drifts where the residuals are flat.
    fn project(&self, z: &mut [f64]) {
        let (u, x) = (self.unclamped(z), self.x_of(z));
        if u != x {
            for (k, zk) in z.iter_mut().enumerate() {
                *zk = (0..x.len())
                    .map(|i| self.basis[(i, k)] * (x[i] - self.anchor[i]))
                    .sum();
            }
        }
    }
}

impl Reduced<'_, '_> {
    /// ∂r/∂z = ∂r/∂x D B from the sensitivities, with D zero for a coordinate clamped at a
    /// bound (where x does not move with z).
    fn sensitivity_jacobian(&self, z: &[f64]) -> Result<DMatrix<f64>, Error> {
        let mut jx = self.inner.sensitivity_jacobian(&self.x_of(z))?;
        for (i, x) in self.unclamped(z).into_iter().enumerate() {
            if x < self.lo[i] || x > self.hi[i] {
                jx.column_mut(i).fill(0.0);
            }
        }
        Ok(jx * self.basis)
    }
}

/// The Jacobian of the polish and the covariance: the sensitivities of the tighter simulations,
/// or central differences where they cannot be had.
fn polish_jacobian(
    sharp: &Reduced<'_, '_>,
    (z, r): (&[f64], &DVector<f64>),
    threads: usize,
) -> Result<DMatrix<f64>, Error> {
    match sharp.sensitivity_jacobian(z) {
        Ok(j) => Ok(j),
        Err(_) => lm::jacobian_central(sharp, z, r, COVARIANCE_FD_STEP, threads),
    }
}

/// An orthonormal basis of the span of `directions` (Gram–Schmidt; a direction already in the
/// span of those before it is left out).
pub fn orthonormal(directions: &[DVector<f64>]) -> Vec<DVector<f64>> {
    let mut ortho: Vec<DVector<f64>> = Vec::new();
    for v in directions {
        let mut w = v.clone();
        for q in &ortho {
            w -= q * q.dot(v);
        }
        if w.norm() > 1e-9 {
            ortho.push(w.normalize());
        }
    }
    ortho
}

/// An orthonormal basis of the complement of the directions `held` in Rⁿ.
fn complement(n: usize, held: &[DVector<f64>]) -> DMatrix<f64> {
    // the projector onto what the held directions leave
    let ortho = orthonormal(held);
    let mut p = DMatrix::<f64>::identity(n, n);
    for v in &ortho {
        p -= v * v.transpose();
    }
    let eig = p.symmetric_eigen();
    let cols: Vec<DVector<f64>> = (0..n)
        .filter(|&k| eig.eigenvalues[k] > 0.5)
        .map(|k| eig.eigenvectors.column(k).into_owned())
        .collect();
    if cols.is_empty() {
        DMatrix::zeros(n, 0)
    } else {
        DMatrix::from_columns(&cols)
    }
}

/// Describes a direction the data do not determine: one parameter, or a combination of the
/// logarithms of several.
fn describe(v: &DVector<f64>, coords: &[Coordinate]) -> (Option<String>, String) {
    let j = v.iamax();
    if v[j].abs() > SINGLE {
        return (
            Some(coords[j].def.name.to_string()),
            coords[j].def.name.to_string(),
        );
    }
    let sign = if v.iter().sum::<f64>() < 0.0 {
        -1.0
    } else {
        1.0
    };
    let terms: Vec<String> = (0..v.len())
        .filter(|&i| v[i].abs() > 0.15)
        .map(|i| format!("{:+.2} ln {}", sign * v[i], coords[i].def.name))
        .collect();
    (None, terms.join(" "))
}

/// Fits one group from `base`. Directions of parameter space the data do not determine (a
/// parameter without influence, or a combination such as a common scale of Kb, b and gamma1²
/// that only moves the unobserved heave) are found from the covariance, held (at `base`'s value,
/// or where the fit had taken them: `opts.hold`), and the rest is fitted again. The default
/// bounds are around the `prior`, the caller's start.
pub(super) fn fit_group(
    (prior, base): (&Params, &Params),
    group: &Group,
    experiments: &[Experiment],
    opts: &Options,
) -> Result<(Params, GroupResult), Error> {
    let defs = &group.params;
    let n = defs.len();
    let len = residual_count(group, experiments);
    let coords = Coordinate::of(defs, base);
    // counted among the fits running while it runs: their Jacobians share the cores
    let _running = lm::running();
    let weighed = (experiments, opts.weighting);
    let problem = Problem::new(base, &coords, group, weighed, opts.rtol, len);
    // for the covariance: tighter simulations (see `polish`)
    let precise = Problem::new(
        base,
        &coords,
        group,
        weighed,
        opts.rtol * COVARIANCE_RTOL_FACTOR,
        len,
    );
    let x0: Vec<f64> = coords.iter().map(|c| c.to_x((c.def.get)(base))).collect();
    let bounds = parameter_bounds(&coords, prior, opts);
    let (lo, hi) = coordinate_bounds(&coords, &bounds);
    let mut held: Vec<Held> = Vec::new();
    let mut iterations = 0;
    let mut out_of_budget = false;
    // the fit stops where the noise can no longer tell a step (see NOISE_TELL)
    let lm_opts = lm::Options {
        ftol: opts.lm.ftol.max(NOISE_TELL / len as f64),
        ..opts.lm.clone()
    };
    // where the last fit ended: a refit after holding a direction starts there
    let mut x_last = x0.clone();
    // where the held directions are held: each at the start, or where the fit had taken it
    let mut anchor = x0.clone();
    loop {
        let directions: Vec<DVector<f64>> = held.iter().map(|h| h.v.clone()).collect();
        let basis = complement(n, &directions);
        let reduced = Reduced {
            inner: &problem,
            anchor: &anchor,
            basis: &basis,
            lo: &lo,
            hi: &hi,
        };
        let m = basis.ncols();
        if m == 0 {
            let report = held_report(&held, &coords);
            let active = report.unfixed(&coords);
            let fitted = fitted_params(base, &coords, &bounds, &anchor, &active, &report)?;
            return Ok((
                fitted,
                GroupResult {
                    iterations,
                    simulations: simulations(&problem, &precise),
                    out_of_budget,
                    ..GroupResult::all_held(report)
                },
            ));
        }
        let (z_lo, z_hi) = reduced.z_bounds();
        let z_start = reduced.start_from(&x_last, &z_lo, &z_hi);
        let sol = optimise(
            &reduced,
            &z_start,
            (&z_lo, &z_hi),
            &lm_opts,
            opts.iteration_budget,
            (&mut iterations, &mut out_of_budget),
        )?;
        let sharp = Reduced {
            inner: &precise,
            ..reduced
        };
        let polished = polish(&sharp, sol.x.clone(), (&z_lo, &z_hi), opts)?;
        let x = sharp.x_of(&polished.z);
        let covariance = |j: &DMatrix<f64>| {
            sandwich_covariance(j, &polished.residuals, experiments, &group.channels)
        };
        let (jtj, cov_z) = covariance(&polished.jacobian);
        if let Some(first) = next_to_hold(cov_z.as_ref(), jtj, &basis, &coords) {
            // held where the fit reached, the point stays: what the data leave undetermined
            // beside it is judged there at once; held at the start, the point moves back
            // along it, and the next is judged after a fit from there
            match opts.hold {
                Hold::Reached => {
                    anchor = x.clone();
                    let at = (&polished.jacobian, &basis, directions.as_slice());
                    for (v, reason) in hold_undetermined(first, at, &coords, covariance) {
                        held.push(Held {
                            v,
                            reason,
                            at: Hold::Reached,
                        });
                    }
                }
                Hold::Start | Hold::Prior => {
                    let (v, reason) = first;
                    let back = back_to_start(&x, &x0, &v, &directions);
                    // a parameter the data push against its bound is not undetermined: its
                    // column of J is one-sided there (zero where the clamp holds it), and back
                    // at the start the fit could cost ten times as much; one that wandered
                    // there along a flat direction goes back
                    let limited = (opts.hold == Hold::Start)
                        .then(|| at_bound(&v, &x, (&lo, &hi)))
                        .flatten()
                        .filter(|_| costs_more(&precise, &back, &polished.residuals, m));
                    let held_here = match limited {
                        Some(j) => {
                            anchor = x.clone();
                            Held {
                                reason: format!(
                                    "{reason}; at its bound {:.6e}, where the data would take \
                                     it further: held there",
                                    value_at(&coords, &bounds, j, x[j])
                                ),
                                v,
                                at: Hold::Reached,
                            }
                        }
                        None => {
                            // every direction at the start while none is held at a bound
                            anchor = match held.iter().any(|h| h.at == Hold::Reached) {
                                true => back,
                                false => x0.clone(),
                            };
                            Held {
                                v,
                                reason,
                                at: Hold::Start,
                            }
                        }
                    };
                    held.push(held_here);
                }
            }
            x_last = x;
            continue;
        }
        // (where JᵀJ is singular, its weakest direction lies in what `basis` spans: held above)
        let cov = cov_z.expect("checked above");
        let cov_x = &basis * cov * basis.transpose();
        let report = held_report(&held, &coords);
        let (fitted, result) = determined(base, &coords, &bounds, &x, &cov_x, report)?;
        return Ok((
            fitted,
            GroupResult {
                iterations,
                simulations: simulations(&problem, &precise),
                out_of_budget,
                ..result
            },
        ));
    }
}

/// The coordinate whose axis the direction `v` is, where `x` sits at one of its bounds.
fn at_bound(v: &DVector<f64>, x: &[f64], (lo, hi): (&[f64], &[f64])) -> Option<usize> {
    let j = v.iamax();
    let alone = (0..v.len()).all(|i| i == j || v[i] == 0.0);
    let near = |b: f64| (x[j] - b).abs() <= 1e-12 * (1.0 + b.abs());
    (alone && (near(lo[j]) || near(hi[j]))).then_some(j)
}

/// Whether the point `back` fits worse than the fit's point (its `residuals`, `m` coordinates
/// fitted) by more than the noise explains: χ²₁(95 %) = 3.84 times the residual variance. Where
/// the model cannot run at `back`, it does.
fn costs_more(problem: &Problem, back: &[f64], residuals: &DVector<f64>, m: usize) -> bool {
    use lm::Residuals;
    let mut r = vec![0.0; problem.count()];
    if problem.eval(back, &mut r).is_err() {
        return true;
    }
    let here = residuals.norm_squared();
    let variance = here / residuals.len().saturating_sub(m).max(1) as f64;
    r.iter().map(|v| v * v).sum::<f64>() - here > CHI2_1_95 * variance
}

/// The 95 % quantile of χ² with one degree of freedom.
const CHI2_1_95: f64 = 3.841;

/// A direction of parameter space a group's fit holds, why, and where.
struct Held {
    v: DVector<f64>,
    reason: String,
    at: Hold,
}

/// The point `x` with its component along `v` (less what the directions `held` before take of
/// it) moved back to the start `x0`'s: `v` held at the start, the others where `x` has them.
fn back_to_start(x: &[f64], x0: &[f64], v: &DVector<f64>, held: &[DVector<f64>]) -> Vec<f64> {
    let mut u = v.clone();
    for q in orthonormal(held) {
        u -= &q * q.dot(v);
    }
    let u = u.normalize();
    let back: f64 = (0..x.len()).map(|i| u[i] * (x0[i] - x[i])).sum();
    (0..x.len()).map(|i| x[i] + back * u[i]).collect()
}

/// One run of the optimiser from `z_start` within what is left of the iteration `budget`: adds
/// its iterations to the count and notes whether the budget ran out before it converged.
fn optimise(
    reduced: &Reduced<'_, '_>,
    z_start: &[f64],
    (z_lo, z_hi): (&[f64], &[f64]),
    lm_opts: &lm::Options,
    budget: Option<usize>,
    (iterations, out_of_budget): (&mut usize, &mut bool),
) -> Result<lm::Solution, Error> {
    let left = budget.map_or(usize::MAX, |b| b.saturating_sub(*iterations));
    let run = lm::Options {
        max_iterations: lm_opts.max_iterations.min(left),
        ..lm_opts.clone()
    };
    let sol = lm::minimize(reduced, z_start, z_lo, z_hi, &run)?;
    *iterations += sol.iterations;
    *out_of_budget |= !sol.converged && left < lm_opts.max_iterations && sol.iterations == left;
    Ok(sol)
}

/// The directions to hold where a fit reached, `first` (the worst-determined, with its reason)
/// and each one the data then leave undetermined in turn, judged on the conditional covariance
/// at the same point: the Jacobian `j` (in the coordinates of `basis`, beside the directions
/// `held` before) restricted to what the directions held so far leave (book/src/identify.md,
/// "Parameters the data do not determine"). Holding one at a time, a fit and a polish ran
/// before each next, and moved the point by a few iterations at most.
fn hold_undetermined(
    first: (DVector<f64>, String),
    (j, basis, held): (&DMatrix<f64>, &DMatrix<f64>, &[DVector<f64>]),
    coords: &[Coordinate],
    covariance: impl Fn(&DMatrix<f64>) -> (DMatrix<f64>, Option<DMatrix<f64>>),
) -> Vec<(DVector<f64>, String)> {
    // the Jacobian in the parameters' coordinates, on the span of `basis` (orthonormal columns)
    let j_x = j * basis.transpose();
    let mut found = vec![first];
    loop {
        let all: Vec<DVector<f64>> = (held.iter().cloned())
            .chain(found.iter().map(|f| f.0.clone()))
            .collect();
        let rest = complement(coords.len(), &all);
        if rest.ncols() == 0 {
            return found;
        }
        let (jtj, cov) = covariance(&(&j_x * &rest));
        match next_to_hold(cov.as_ref(), jtj, &rest, coords) {
            Some(next) => found.push(next),
            None => return found,
        }
    }
}

/// The worst-determined direction (see [`worst_direction`]) as it is held, with its reason, unless
/// it is held already but for rounding (what `basis` spans reaches it by less than [`HELD`]): a
/// direction held again would change nothing, and the fit would hold it without end.
fn next_to_hold(
    cov_z: Option<&DMatrix<f64>>,
    jtj: DMatrix<f64>,
    basis: &DMatrix<f64>,
    coords: &[Coordinate],
) -> Option<(DVector<f64>, String)> {
    worst_direction(cov_z, jtj, basis, coords)
        .map(|(v, reason)| (snapped_to_single(v).normalize(), reason))
        .filter(|(v, _)| (basis.transpose() * v).norm() > HELD)
}

/// `v`, or where it lies mostly along one parameter exactly that parameter's axis: it holds
/// that parameter (when several parameters do nothing at all, their null space is entered one
/// at a time).
fn snapped_to_single(mut v: DVector<f64>) -> DVector<f64> {
    let n = v.len();
    let j = v.iamax();
    if v[j].abs() > SINGLE {
        v = DVector::from_fn(n, |i, _| if i == j { 1.0 } else { 0.0 });
    }
    v
}

impl<'a> Problem<'a> {
    /// The residuals of `group`'s channels in `experiments` (`len` of them) weighted by
    /// `weighting`, its parameters moved in `coords` from `base`, simulated to `rtol`.
    fn new(
        base: &'a Params,
        coords: &[Coordinate],
        group: &Group,
        (experiments, weighting): (&'a [Experiment], Weighting),
        rtol: f64,
        len: usize,
    ) -> Self {
        Problem {
            base,
            coords: coords.to_vec(),
            channels: group.channels.clone(),
            experiments,
            factors: experiments
                .iter()
                .map(|e| {
                    let factor = |&c: &Channel| e.residual_factor(c, weighting);
                    group.channels.iter().map(factor).collect()
                })
                .collect(),
            rtol,
            len,
            counter: Default::default(),
        }
    }
}

impl Reduced<'_, '_> {
    /// The last fit's point `x_last` without its component along the held directions, in z.
    fn start_from(&self, x_last: &[f64], z_lo: &[f64], z_hi: &[f64]) -> Vec<f64> {
        let (n, m) = self.basis.shape();
        (0..m)
            .map(|k| {
                let z: f64 = (0..n)
                    .map(|i| self.basis[(i, k)] * (x_last[i] - self.anchor[i]))
                    .sum();
                z.clamp(z_lo[k], z_hi[k])
            })
            .collect()
    }
}

impl GroupResult {
    /// Every direction held, nothing estimated: the held ones in words, with their reasons
    /// (no iterations or simulations counted yet).
    fn all_held(report: HeldReport) -> Self {
        GroupResult {
            estimates: vec![],
            not_identifiable: report.not_identifiable,
            held_combinations: report.held_combinations,
            names: vec![],
            coords: vec![],
            covariance: DMatrix::zeros(0, 0),
            iterations: 0,
            simulations: 0,
            out_of_budget: false,
        }
    }
}

/// The fitted parameters and the result once every direction left is determined: the
/// parameters not held single (`report.fixed`) estimated at `x` with covariance `cov_x` (no
/// iterations or simulations counted yet).
fn determined(
    base: &Params,
    coords: &[Coordinate],
    bounds: &[(f64, f64)],
    x: &[f64],
    cov_x: &DMatrix<f64>,
    report: HeldReport,
) -> Result<(Params, GroupResult), Error> {
    let active = report.unfixed(coords);
    let fitted = fitted_params(base, coords, bounds, x, &active, &report)?;
    let HeldReport {
        not_identifiable,
        held_combinations,
        ..
    } = report;
    let estimates = estimates(coords, bounds, x, cov_x, &active);
    let names = active
        .iter()
        .map(|&c| coords[c].def.name.to_string())
        .collect();
    let active_coords = active.iter().map(|&c| coords[c]).collect();
    let covariance = DMatrix::from_fn(active.len(), active.len(), |a, b| {
        cov_x[(active[a], active[b])]
    });
    Ok((
        fitted,
        GroupResult {
            estimates,
            not_identifiable,
            held_combinations,
            names,
            coords: active_coords,
            covariance,
            iterations: 0,
            simulations: 0,
            out_of_budget: false,
        },
    ))
}

/// Rows of the group's residual vector: one per sample of each channel an experiment measures.
fn residual_count(group: &Group, experiments: &[Experiment]) -> usize {
    experiments
        .iter()
        .map(|e| {
            group
                .channels
                .iter()
                .filter(|&&c| e.measured(c).is_some())
                .count()
                * e.t.len()
        })
        .sum()
}

/// Simulations run so far by the fit's problem and the covariance's tighter one together.
fn simulations(problem: &Problem<'_>, precise: &Problem<'_>) -> usize {
    problem.counter.load(std::sync::atomic::Ordering::Relaxed)
        + precise.counter.load(std::sync::atomic::Ordering::Relaxed)
}

/// The bounds of each parameter: the caller's, or a default by the parameter's rule around its
/// `prior` value.
fn parameter_bounds(coords: &[Coordinate], prior: &Params, opts: &Options) -> Vec<(f64, f64)> {
    coords
        .iter()
        .map(|c| {
            let prior = (c.def.get)(prior);
            let default = match c.def.rule {
                Rule::Positive | Rule::Limit => (prior / 20.0, prior * 20.0),
                Rule::Weight => (0.0, f64::INFINITY),
                Rule::NonNegative => (
                    0.0,
                    if prior > 0.0 {
                        prior * 20.0
                    } else {
                        f64::INFINITY
                    },
                ),
                Rule::Finite => (f64::NEG_INFINITY, f64::INFINITY),
                // a choice among forms is never fitted
                Rule::Index(_) => (prior, prior),
            };
            opts.bounds.get(c.def.name).copied().unwrap_or(default)
        })
        .collect()
}

/// The parameters' bounds in the fit's coordinates (lower, upper); an infinite one stays so.
fn coordinate_bounds(coords: &[Coordinate], bounds: &[(f64, f64)]) -> (Vec<f64>, Vec<f64>) {
    coords
        .iter()
        .zip(bounds)
        .map(|(c, &(l, h))| {
            (
                if l.is_finite() { c.to_x(l) } else { l },
                if h.is_finite() { c.to_x(h) } else { h },
            )
        })
        .unzip()
}

/// Parameter `c` at coordinate `x`: a value at its bound is the bound itself, not
/// exp(ln(bound)) a rounding outside.
fn value_at(coords: &[Coordinate], bounds: &[(f64, f64)], c: usize, x: f64) -> f64 {
    coords[c].to_p(x).clamp(bounds[c].0, bounds[c].1)
}

/// Polishes the optimiser's `z` with Gauss–Newton on the sensitivities of tighter simulations,
/// which also gives the covariance: Kb and gamma1 correlate to 0.999, and forward differences
/// at the optimiser's tolerance misjudge the gradient and the information along that valley.
fn polish(
    sharp: &Reduced<'_, '_>,
    mut z: Vec<f64>,
    (z_lo, z_hi): (&[f64], &[f64]),
    opts: &Options,
) -> Result<Polished, Error> {
    let m = z.len();
    let mut r = lm::evaluate(sharp, &z)?;
    let mut j = polish_jacobian(sharp, (&z, &r), lm::share())?;
    for _ in 0..GN_POLISH {
        lm::check_deadline(opts.lm.deadline)?;
        let Some(step) = (j.transpose() * &j)
            .cholesky()
            .map(|c| c.solve(&(-(j.transpose() * &r))))
        else {
            break;
        };
        let mut z_new: Vec<f64> = (0..m)
            .map(|k| (z[k] + step[k]).clamp(z_lo[k], z_hi[k]))
            .collect();
        lm::Residuals::project(sharp, &mut z_new);
        match lm::evaluate(sharp, &z_new) {
            Ok(r_new) if r_new.norm_squared() < r.norm_squared() => {
                (z, r) = (z_new, r_new);
                j = polish_jacobian(sharp, (&z, &r), lm::share())?;
                if step.amax() < 1e-8 {
                    break;
                }
            }
            _ => break,
        }
    }
    Ok(Polished {
        z,
        residuals: r,
        jacobian: j,
    })
}

/// Where the polish ended: the point, its residuals and its Jacobian.
struct Polished {
    z: Vec<f64>,
    residuals: DVector<f64>,
    jacobian: DMatrix<f64>,
}

/// JᵀJ and the covariance of the least-squares estimate with per-channel noise levels σ_c from
/// the residuals (as the fit weighs them: a weighting's factor scales a channel's rows of J and
/// its σ_c alike): the sandwich (JᵀJ)⁻¹ JᵀΣJ (JᵀJ)⁻¹ in the reduced coordinates
/// (`None` where JᵀJ is singular).
fn sandwich_covariance(
    j: &DMatrix<f64>,
    residuals: &DVector<f64>,
    experiments: &[Experiment],
    channels: &[Channel],
) -> (DMatrix<f64>, Option<DMatrix<f64>>) {
    let m = j.ncols();
    let mut sigma2 = Vec::with_capacity(j.nrows());
    let mut k = 0;
    for e in experiments {
        for &c in channels {
            if e.measured(c).is_some() {
                let rows = e.t.len();
                let var = residuals.rows(k, rows).norm_squared() / rows as f64;
                sigma2.extend(std::iter::repeat_n(var, rows));
                k += rows;
            }
        }
    }
    let jtj = j.transpose() * j;
    let cov_z = jtj.clone().try_inverse().map(|inv| {
        let mut meat = DMatrix::zeros(m, m);
        for (row, s2) in j.row_iter().zip(&sigma2) {
            meat += row.transpose() * row * *s2;
        }
        &inv * meat * &inv
    });
    (jtj, cov_z)
}

/// The worst-determined direction, if its 95 % interval is wider than ×/÷ 1.5, with the reason
/// it is held. Weights of a series are not held for a wide interval: neighbours of a spectrum
/// share what the data tell of them, the sum is what is judged, and 0 is a value a weight may
/// take (book/src/identify.md, "Parameters the data do not determine"); the other parameters
/// are judged on their marginal covariance.
fn worst_direction(
    cov_z: Option<&DMatrix<f64>>,
    jtj: DMatrix<f64>,
    basis: &DMatrix<f64>,
    coords: &[Coordinate],
) -> Option<(DVector<f64>, String)> {
    let n = coords.len();
    match cov_z {
        None => {
            let eig = jtj.symmetric_eigen();
            let (kmin, _) = eig.eigenvalues.argmin();
            Some((
                basis * eig.eigenvectors.column(kmin),
                "the measured outputs do not depend on it".to_string(),
            ))
        }
        Some(cov) => {
            // a parameter held alone has no variance but the rounding of `basis`, which a
            // direction the data leave undetermined beside it would lend it
            let judged: Vec<usize> = (0..n)
                .filter(|&i| coords[i].def.rule != Rule::Weight && basis.row(i).norm() > HELD)
                .collect();
            let cov_x = basis * cov * basis.transpose();
            let eig = (!judged.is_empty()).then(|| {
                cov_x
                    .select_rows(&judged)
                    .select_columns(&judged)
                    .symmetric_eigen()
            });
            eig.as_ref()
                .map(|eig| eig.eigenvalues.argmax())
                .map(|(kmax, var)| (kmax, 1.96 * var.max(0.0).sqrt()))
                .filter(|&(_, half)| half > MAX_LOG_HALF_WIDTH)
                .map(|(kmax, half)| {
                    let vectors = &eig.as_ref().expect("judged above").eigenvectors;
                    let mut v = DVector::zeros(n);
                    for (k, &i) in judged.iter().enumerate() {
                        v[i] = vectors[(k, kmax)];
                    }
                    (
                        v,
                        format!(
                            "its 95 % interval would span a factor of {:.3e}",
                            (2.0 * half).exp()
                        ),
                    )
                })
        }
    }
}

/// The held directions as a group's result reports them.
struct HeldReport {
    /// Each held direction in words, with the reason it is held.
    not_identifiable: Vec<(String, String)>,
    /// The weights of each held combination of several parameters.
    held_combinations: Vec<Vec<(String, f64)>>,
    /// The names of the single parameters held, and where.
    fixed: Vec<(String, Hold)>,
}

impl HeldReport {
    /// The coordinates not held single: estimated, or in a held combination.
    fn unfixed(&self, coords: &[Coordinate]) -> Vec<usize> {
        (0..coords.len())
            .filter(|&c| !self.fixed.iter().any(|(f, _)| f == coords[c].def.name))
            .collect()
    }
}

/// The held directions in words, the held combinations' weights, and the single parameters held.
fn held_report(held: &[Held], coords: &[Coordinate]) -> HeldReport {
    let mut not_identifiable = Vec::new();
    let mut held_combinations = Vec::new();
    let mut fixed = Vec::new();
    for h in held {
        let (single, text) = describe(&h.v, coords);
        if let Some(name) = single {
            fixed.push((name.clone(), h.at));
            not_identifiable.push((name, h.reason.clone()));
        } else {
            held_combinations.push(
                coords
                    .iter()
                    .zip(h.v.iter())
                    .map(|(c, w)| (c.def.name.to_string(), *w))
                    .collect(),
            );
            not_identifiable.push((
                format!("combination {text}"),
                format!(
                    "{}; held {}, so the parameters in it are estimated relative to that",
                    h.reason,
                    h.at.at()
                ),
            ));
        }
    }
    HeldReport {
        not_identifiable,
        held_combinations,
        fixed,
    }
}

/// `base` with the fit's values at `x` set: the `active` parameters, and those held single
/// where the fit had taken them; one held at the start keeps its start value exactly (not
/// exp(ln(value))).
fn fitted_params(
    base: &Params,
    coords: &[Coordinate],
    bounds: &[(f64, f64)],
    x: &[f64],
    active: &[usize],
    report: &HeldReport,
) -> Result<Params, Error> {
    let reached = |c: usize| {
        (report.fixed.iter()).any(|(f, at)| f == coords[c].def.name && *at == Hold::Reached)
    };
    let mut fitted = base.clone();
    for c in (0..coords.len()).filter(|&c| active.contains(&c) || reached(c)) {
        fitted.set(coords[c].def.name, value_at(coords, bounds, c, x[c]))?;
    }
    Ok(fitted)
}

/// Each `active` parameter's name, value, standard error and 95 % interval from the covariance
/// `cov_x` in the fit's coordinates (an interval ×/÷ in log space, ± otherwise).
fn estimates(
    coords: &[Coordinate],
    bounds: &[(f64, f64)],
    x: &[f64],
    cov_x: &DMatrix<f64>,
    active: &[usize],
) -> Vec<(String, f64, f64, (f64, f64))> {
    active
        .iter()
        .map(|&c| {
            let coord = coords[c];
            let value = value_at(coords, bounds, c, x[c]);
            let se_x = cov_x[(c, c)].max(0.0).sqrt();
            let (se, ci) = if coord.log {
                (
                    value * se_x,
                    (value * (-1.96 * se_x).exp(), value * (1.96 * se_x).exp()),
                )
            } else {
                let se = se_x * coord.scale;
                (se, (value - 1.96 * se, value + 1.96 * se))
            };
            (coord.def.name.to_string(), value, se, ci)
        })
        .collect()
}
