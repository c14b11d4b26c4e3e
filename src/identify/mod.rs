//! Nonlinear grey-box identification as in the paper: Levenberg–Marquardt on the simulation
//! (output) error over all estimation experiments at once, NRMSE fits on estimation and
//! validation data, standard errors and 95 % intervals from the covariance, and an honest list
//! of the parameters the data cannot determine (held at their prior).

pub mod experiment;
pub mod fit;
pub mod lm;
pub mod report;
pub mod synth;

use std::collections::BTreeMap;
use std::time::Instant;

use nalgebra::{DMatrix, DVector};

use crate::model::params::{ParamDef, Rule, parameter};
use crate::model::{Params, Platform};
use crate::simulation::{Sample, Simulator};
pub use experiment::{Channel, Experiment};

/// The parameters the spec shows to be practically identifiable from h or tip data.
pub fn default_free() -> Vec<String> {
    ["Kb", "b", "gamma1", "gamma2"]
        .iter()
        .flat_map(|p| (1..=3).map(move |i| format!("{p}_{i}")))
        .collect()
}

/// Settings of an identification.
#[derive(Clone, Debug)]
pub struct Options {
    /// Names of the parameters to estimate.
    pub free: Vec<String>,
    /// Bounds per parameter; default [prior/20, prior·20] for positive parameters.
    pub bounds: BTreeMap<String, (f64, f64)>,
    /// Relative tolerance of the simulations: tight, so that finite differences of the
    /// outputs see the parameters and not the step-size control.
    pub rtol: f64,
    pub lm: lm::Options,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            free: default_free(),
            bounds: BTreeMap::new(),
            rtol: 1e-8,
            lm: lm::Options {
                fd_step: 1e-4,
                ..lm::Options::default()
            },
        }
    }
}

/// One parameter's outcome.
#[derive(Clone, Debug)]
pub struct Estimate {
    pub name: String,
    pub value: f64,
    pub prior: f64,
    /// Asked to be estimated.
    pub free: bool,
    /// Estimated (free and determined by the data).
    pub estimated: bool,
    pub std_error: Option<f64>,
    pub ci95: Option<(f64, f64)>,
}

/// Fits of one experiment: per channel, and the 2-D tip fit where X and Y are measured.
#[derive(Clone, Debug)]
pub struct ExperimentFit {
    pub experiment: String,
    pub fits: Vec<(String, f64)>,
}

/// The outcome of an identification.
#[derive(Clone, Debug)]
pub struct Identification {
    pub params: Params,
    pub estimates: Vec<Estimate>,
    /// Free parameters (or combinations) the data cannot determine, with the reason.
    pub not_identifiable: Vec<(String, String)>,
    /// Combinations of log-parameters held at their start value: (name, weight) of a unit
    /// direction in log-parameter space along which the data carry no information.
    pub held_combinations: Vec<Vec<(String, f64)>>,
    /// Correlation of the estimated parameters (names, matrix).
    pub correlation: (Vec<String>, DMatrix<f64>),
    pub estimation: Vec<ExperimentFit>,
    pub validation: Vec<ExperimentFit>,
    /// Fits of the starting parameters on the estimation data, for comparison.
    pub estimation_before: Vec<ExperimentFit>,
    pub iterations: usize,
    pub simulations: usize,
    pub seconds: f64,
    /// Simulated outputs at the fitted parameters, estimation then validation experiments.
    pub simulated: Vec<Vec<Sample>>,
}

/// Simulates `exp` from rest with `params`, sampled at the experiment's times.
pub fn simulate(params: &Params, exp: &Experiment, rtol: f64) -> Result<Vec<Sample>, String> {
    let model = Platform::new(params.clone()).map_err(|e| e.to_string())?;
    let mut sim = Simulator::new(model, exp.t[0], rtol).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(exp.t.len());
    sim.run_at(&exp.input, &exp.t, |s| out.push(*s))
        .map_err(|e| format!("{}: {e}", exp.name))?;
    Ok(out)
}

/// NRMSE fits of simulated outputs against one experiment.
pub fn fits(exp: &Experiment, sim: &[Sample]) -> ExperimentFit {
    let mut out: Vec<(String, f64)> = exp
        .channels
        .iter()
        .map(|(c, y)| {
            let s: Vec<f64> = sim.iter().map(|s| c.of(s)).collect();
            (c.name().to_string(), fit::nrmse_fit(y, &s))
        })
        .collect();
    if let (Some(x), Some(y)) = (exp.measured(Channel::Tip(0)), exp.measured(Channel::Tip(1))) {
        let sx: Vec<f64> = sim.iter().map(|s| s.tip[0]).collect();
        let sy: Vec<f64> = sim.iter().map(|s| s.tip[1]).collect();
        out.push(("tip_xy".into(), fit::nrmse_fit_2d(x, y, &sx, &sy)));
    }
    ExperimentFit {
        experiment: exp.name.clone(),
        fits: out,
    }
}

/// How a parameter is moved by the optimiser: in log space when it must be positive.
#[derive(Clone, Copy)]
struct Coordinate {
    def: &'static ParamDef,
    log: bool,
    scale: f64,
}

impl Coordinate {
    fn new(def: &'static ParamDef, prior: f64) -> Coordinate {
        Coordinate {
            def,
            log: def.rule != Rule::Finite && prior > 0.0,
            scale: prior.abs().max(1e-300),
        }
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
    rtol: f64,
    len: usize,
    counter: std::sync::atomic::AtomicUsize,
}

impl Problem<'_> {
    fn params_at(&self, x: &[f64]) -> Result<Params, String> {
        let mut p = self.base.clone();
        for (c, &xi) in self.coords.iter().zip(x) {
            p.set(c.def.name, c.to_p(xi)).map_err(|e| e.to_string())?;
        }
        Ok(p)
    }
}

impl lm::Residuals for Problem<'_> {
    fn count(&self) -> usize {
        self.len
    }
    fn eval(&self, x: &[f64], r: &mut [f64]) -> Result<(), String> {
        let p = self.params_at(x)?;
        let mut k = 0;
        for exp in self.experiments {
            let sim = simulate(&p, exp, self.rtol)?;
            self.counter
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            for &c in &self.channels {
                if let Some(y) = exp.measured(c) {
                    for (s, m) in sim.iter().zip(y) {
                        r[k] = c.of(s) - m;
                        k += 1;
                    }
                }
            }
        }
        Ok(())
    }
}

/// A group of parameters fitted together against some channels.
struct Group {
    params: Vec<&'static ParamDef>,
    channels: Vec<Channel>,
}

/// Actuators are fitted separately when only heights are measured and every free parameter
/// belongs to one actuator (the model is decoupled); otherwise all at once.
fn groups(free: &[&'static ParamDef], experiments: &[Experiment]) -> Vec<Group> {
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

/// Central-difference step (in log parameters) of the covariance Jacobian.
const COVARIANCE_FD_STEP: f64 = 1e-3;

/// Gauss–Newton iterations at most in the polish.
const GN_POLISH: usize = 10;

/// Half-width in log space of the widest 95 % interval an estimate may have and still count as
/// determined by the data: ×/÷ 1.5.
const MAX_LOG_HALF_WIDTH: f64 = 0.405;

struct GroupResult {
    estimates: Vec<(String, f64, f64, (f64, f64))>, // name, value, std error, ci95
    not_identifiable: Vec<(String, String)>,
    held_combinations: Vec<Vec<(String, f64)>>,
    names: Vec<String>,
    covariance: DMatrix<f64>,
    iterations: usize,
    simulations: usize,
}

/// The group's problem seen in reduced coordinates z: x = x0 + B z, clamped to the bounds.
/// The columns of B span the directions the data determine; the others stay at the start.
struct Reduced<'a, 'b> {
    inner: &'a Problem<'b>,
    x0: &'a [f64],
    basis: &'a DMatrix<f64>,
    lo: &'a [f64],
    hi: &'a [f64],
}

impl Reduced<'_, '_> {
    fn x_of(&self, z: &[f64]) -> Vec<f64> {
        (0..self.x0.len())
            .map(|i| {
                (self.x0[i] + (0..z.len()).map(|k| self.basis[(i, k)] * z[k]).sum::<f64>())
                    .clamp(self.lo[i], self.hi[i])
            })
            .collect()
    }
}

impl lm::Residuals for Reduced<'_, '_> {
    fn count(&self) -> usize {
        self.inner.len
    }
    fn eval(&self, z: &[f64], r: &mut [f64]) -> Result<(), String> {
        self.inner.eval(&self.x_of(z), r)
    }
}

/// An orthonormal basis of the complement of the directions `held` in Rⁿ.
fn complement(n: usize, held: &[DVector<f64>]) -> DMatrix<f64> {
    // Gram–Schmidt on the held directions, then the projector onto what is left
    let mut ortho: Vec<DVector<f64>> = Vec::new();
    for v in held {
        let mut w = v.clone();
        for q in &ortho {
            w -= q * q.dot(v);
        }
        if w.norm() > 1e-9 {
            ortho.push(w.normalize());
        }
    }
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

/// Fits one group. Directions of parameter space the data do not determine (a parameter
/// without influence, or a combination such as a common scale of Kb, b and gamma1² that only
/// moves the unobserved heave) are found from the covariance, held at the start value, and the
/// rest is fitted again.
fn fit_group(
    base: &Params,
    group: &Group,
    experiments: &[Experiment],
    opts: &Options,
) -> Result<(Params, GroupResult), String> {
    let defs = &group.params;
    let n = defs.len();
    let len: usize = experiments
        .iter()
        .map(|e| {
            group
                .channels
                .iter()
                .filter(|&&c| e.measured(c).is_some())
                .count()
                * e.t.len()
        })
        .sum();
    let coords: Vec<Coordinate> = defs
        .iter()
        .map(|d| Coordinate::new(d, (d.get)(base)))
        .collect();
    let problem = Problem {
        base,
        coords: coords.clone(),
        channels: group.channels.clone(),
        experiments,
        rtol: opts.rtol,
        len,
        counter: Default::default(),
    };
    // for the covariance: tighter simulations (see below)
    let precise = Problem {
        base,
        coords: coords.clone(),
        channels: group.channels.clone(),
        experiments,
        rtol: opts.rtol * 1e-2,
        len,
        counter: Default::default(),
    };
    let x0: Vec<f64> = coords.iter().map(|c| c.to_x((c.def.get)(base))).collect();
    let (lo, hi): (Vec<f64>, Vec<f64>) = coords
        .iter()
        .map(|c| {
            let prior = (c.def.get)(base);
            let default = match c.def.rule {
                Rule::Positive => (prior / 20.0, prior * 20.0),
                Rule::NonNegative => (
                    0.0,
                    if prior > 0.0 {
                        prior * 20.0
                    } else {
                        f64::INFINITY
                    },
                ),
                Rule::Finite => (f64::NEG_INFINITY, f64::INFINITY),
            };
            let (l, h) = opts.bounds.get(c.def.name).copied().unwrap_or(default);
            (
                if l.is_finite() { c.to_x(l) } else { l },
                if h.is_finite() { c.to_x(h) } else { h },
            )
        })
        .unzip();
    let mut held: Vec<DVector<f64>> = Vec::new();
    let mut reasons: Vec<String> = Vec::new();
    let mut iterations = 0;
    loop {
        let basis = complement(n, &held);
        let reduced = Reduced {
            inner: &problem,
            x0: &x0,
            basis: &basis,
            lo: &lo,
            hi: &hi,
        };
        let m = basis.ncols();
        if m == 0 {
            let simulations = problem.counter.load(std::sync::atomic::Ordering::Relaxed)
                + precise.counter.load(std::sync::atomic::Ordering::Relaxed);
            let not_identifiable = held
                .iter()
                .zip(&reasons)
                .map(|(v, r)| (describe(v, &coords).1, r.clone()))
                .collect();
            return Ok((
                base.clone(),
                GroupResult {
                    estimates: vec![],
                    not_identifiable,
                    held_combinations: vec![],
                    names: vec![],
                    covariance: DMatrix::zeros(0, 0),
                    iterations,
                    simulations,
                },
            ));
        }
        let sol = lm::minimize(
            &reduced,
            &vec![0.0; m],
            &vec![f64::NEG_INFINITY; m],
            &vec![f64::INFINITY; m],
            &opts.lm,
        )?;
        iterations += sol.iterations;
        // polish with Gauss–Newton on a central-difference Jacobian of tighter simulations, which
        // also gives the covariance: Kb and gamma1 correlate to 0.999, and forward differences
        // at the optimiser's tolerance misjudge the gradient and the information along that valley
        let sharp = Reduced {
            inner: &precise,
            ..reduced
        };
        let mut z = sol.x.clone();
        let mut r = lm::evaluate(&sharp, &z)?;
        let mut j = lm::jacobian_central(&sharp, &z, COVARIANCE_FD_STEP, opts.lm.threads)?;
        for _ in 0..GN_POLISH {
            let Some(step) = (j.transpose() * &j)
                .cholesky()
                .map(|c| c.solve(&(-(j.transpose() * &r))))
            else {
                break;
            };
            let z_new: Vec<f64> = z.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            match lm::evaluate(&sharp, &z_new) {
                Ok(r_new) if r_new.norm_squared() < r.norm_squared() => {
                    (z, r) = (z_new, r_new);
                    j = lm::jacobian_central(&sharp, &z, COVARIANCE_FD_STEP, opts.lm.threads)?;
                    if step.amax() < 1e-8 {
                        break;
                    }
                }
                _ => break,
            }
        }
        let x = sharp.x_of(&z);
        let residuals = r;
        // covariance of the unweighted least-squares estimate with per-channel noise levels
        // σ_c from the residuals: the sandwich (JᵀJ)⁻¹ JᵀΣJ (JᵀJ)⁻¹ in the reduced coordinates
        let mut sigma2 = Vec::with_capacity(j.nrows());
        let mut k = 0;
        for e in experiments {
            for &c in &group.channels {
                if e.measured(c).is_some() {
                    let rows = e.t.len();
                    let var = residuals.rows(k, rows).norm_squared() / rows as f64;
                    sigma2.extend(std::iter::repeat_n(var, rows));
                    k += rows;
                }
            }
        }
        let jtj = j.transpose() * &j;
        let cov_z = jtj.clone().try_inverse().map(|inv| {
            let mut meat = DMatrix::zeros(m, m);
            for (row, s2) in j.row_iter().zip(&sigma2) {
                meat += row.transpose() * row * *s2;
            }
            &inv * meat * &inv
        });
        // the worst-determined direction, if its 95 % interval is wider than ×/÷ 1.5
        let worst = match &cov_z {
            None => {
                let eig = jtj.symmetric_eigen();
                let (kmin, _) = eig.eigenvalues.argmin();
                Some((
                    eig.eigenvectors.column(kmin).into_owned(),
                    "the measured outputs do not depend on it".to_string(),
                ))
            }
            Some(cov) => {
                let eig = cov.clone().symmetric_eigen();
                let (kmax, var) = eig.eigenvalues.argmax();
                let half = 1.96 * var.max(0.0).sqrt();
                (half > MAX_LOG_HALF_WIDTH).then(|| {
                    (
                        eig.eigenvectors.column(kmax).into_owned(),
                        format!(
                            "its 95 % interval would span a factor of {:.3e}",
                            (2.0 * half).exp()
                        ),
                    )
                })
            }
        };
        if let Some((u, reason)) = worst {
            let mut v = &basis * u;
            // a direction mostly along one parameter holds exactly that parameter (when several
            // parameters do nothing at all, their null space is entered one at a time)
            let j = v.iamax();
            if v[j].abs() > SINGLE {
                v = DVector::from_fn(n, |i, _| if i == j { 1.0 } else { 0.0 });
            }
            held.push(v.normalize());
            reasons.push(reason);
            continue;
        }
        let cov = cov_z.expect("checked above");
        let cov_x = &basis * cov * basis.transpose();
        let mut not_identifiable = Vec::new();
        let mut held_combinations = Vec::new();
        let mut fixed = Vec::new();
        for (v, r) in held.iter().zip(&reasons) {
            let (single, text) = describe(v, &coords);
            if let Some(name) = single {
                fixed.push(name.clone());
                not_identifiable.push((name, r.clone()));
            } else {
                held_combinations.push(
                    coords
                        .iter()
                        .zip(v.iter())
                        .map(|(c, w)| (c.def.name.to_string(), *w))
                        .collect(),
                );
                not_identifiable.push((format!("combination {text}"), format!("{r}; held at its start value, so the parameters in it are estimated relative to that")));
            }
        }
        let active: Vec<usize> = (0..n)
            .filter(|&c| !fixed.iter().any(|f| f == coords[c].def.name))
            .collect();
        // held parameters keep their start value exactly (not exp(ln(value)))
        let mut fitted = base.clone();
        for &c in &active {
            fitted
                .set(coords[c].def.name, coords[c].to_p(x[c]))
                .map_err(|e| e.to_string())?;
        }
        let estimates = active
            .iter()
            .map(|&c| {
                let coord = coords[c];
                let value = coord.to_p(x[c]);
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
            .collect();
        let names = active
            .iter()
            .map(|&c| coords[c].def.name.to_string())
            .collect();
        let covariance = DMatrix::from_fn(active.len(), active.len(), |a, b| {
            cov_x[(active[a], active[b])]
        });
        let simulations = problem.counter.load(std::sync::atomic::Ordering::Relaxed)
            + precise.counter.load(std::sync::atomic::Ordering::Relaxed);
        return Ok((
            fitted,
            GroupResult {
                estimates,
                not_identifiable,
                held_combinations,
                names,
                covariance,
                iterations,
                simulations,
            },
        ));
    }
}

/// Identifies the free parameters on `estimation` from `start`, and reports fits on
/// `estimation` and `validation`.
pub fn identify(
    start: &Params,
    estimation: &[Experiment],
    validation: &[Experiment],
    opts: &Options,
) -> Result<Identification, String> {
    let began = Instant::now();
    if estimation.is_empty() {
        return Err("no estimation experiment".into());
    }
    let mut free: Vec<&'static ParamDef> = Vec::new();
    for name in &opts.free {
        let d = parameter(name)
            .ok_or_else(|| format!("unknown parameter '{name}' in the free list"))?;
        if !free.iter().any(|f| f.name == d.name) {
            free.push(d);
        }
    }
    for (name, (lo, hi)) in &opts.bounds {
        let prior = start.get(name).map_err(|e| e.to_string())?;
        if !(lo < hi && (*lo..=*hi).contains(&prior)) {
            return Err(format!(
                "bounds of {name}: [{lo}, {hi}] must be increasing and contain the start value {prior}"
            ));
        }
    }
    let estimation_before = estimation
        .iter()
        .map(|e| simulate(start, e, opts.rtol).map(|s| fits(e, &s)))
        .collect::<Result<Vec<_>, _>>()?;

    let mut params = start.clone();
    let (mut iterations, mut simulations) = (0, estimation.len());
    let mut estimated: Vec<(String, f64, f64, (f64, f64))> = Vec::new();
    let mut not_identifiable = Vec::new();
    let mut held_combinations = Vec::new();
    let mut blocks: Vec<(Vec<String>, DMatrix<f64>)> = Vec::new();
    for group in groups(&free, estimation) {
        let (fitted, r) = fit_group(start, &group, estimation, opts)?;
        for d in &group.params {
            params
                .set(d.name, (d.get)(&fitted))
                .map_err(|e| e.to_string())?;
        }
        iterations += r.iterations;
        simulations += r.simulations;
        estimated.extend(r.estimates);
        not_identifiable.extend(r.not_identifiable);
        held_combinations.extend(r.held_combinations);
        blocks.push((r.names, r.covariance));
    }

    // correlation over all estimated parameters (zero between separately fitted groups)
    let names: Vec<String> = blocks.iter().flat_map(|(n, _)| n.clone()).collect();
    let mut corr = DMatrix::zeros(names.len(), names.len());
    let mut o = 0;
    for (n, cov) in &blocks {
        for a in 0..n.len() {
            for b in 0..n.len() {
                corr[(o + a, o + b)] = cov[(a, b)] / (cov[(a, a)] * cov[(b, b)]).sqrt();
            }
        }
        o += n.len();
    }

    let estimates = crate::model::params::parameters()
        .map(|d| {
            let found = estimated.iter().find(|e| e.0 == d.name);
            Estimate {
                name: d.name.to_string(),
                value: (d.get)(&params),
                prior: (d.get)(start),
                free: free.iter().any(|f| f.name == d.name),
                estimated: found.is_some(),
                std_error: found.map(|e| e.2),
                ci95: found.map(|e| e.3),
            }
        })
        .collect();
    let mut simulated = Vec::new();
    let mut fit_all = |exps: &[Experiment]| -> Result<Vec<ExperimentFit>, String> {
        exps.iter()
            .map(|e| {
                let s = simulate(&params, e, opts.rtol)?;
                let f = fits(e, &s);
                simulated.push(s);
                Ok(f)
            })
            .collect()
    };
    let estimation_fits = fit_all(estimation)?;
    let validation_fits = fit_all(validation)?;
    simulations += estimation.len() + validation.len();
    Ok(Identification {
        params,
        estimates,
        not_identifiable,
        held_combinations,
        correlation: (names, corr),
        estimation: estimation_fits,
        validation: validation_fits,
        estimation_before,
        iterations,
        simulations,
        seconds: began.elapsed().as_secs_f64(),
        simulated,
    })
}
