//! Nonlinear grey-box identification as in the paper.
//!
//! Nonlinear grey-box identification as in the paper: Levenberg–Marquardt on the simulation
//! (output) error over all estimation experiments at once, NRMSE fits on estimation and
//! validation data, standard errors and 95 % intervals from the covariance, and an honest list
//! of the parameters the data cannot determine (held at their prior).
//!
//! Data files, fit metric and outputs: [book/src/identify.md](identify.md).

pub mod conditions;
mod error;
pub mod experiment;
pub mod fit;
mod group;
pub mod lm;
pub mod report;
pub mod synth;

use std::collections::BTreeMap;
use std::time::Instant;

use nalgebra::DMatrix;

use crate::model::params::{ParamDef, parameter};
use crate::model::{Params, Platform};
use crate::simulation::{DEFAULT_RTOL, Sample, Simulator};
pub use error::Error;
pub use experiment::{Channel, Conditions, Experiment, Weighting};
pub use group::orthonormal;
use group::{fit_group, groups};

/// The parameters practically identifiable from h or tip data (book/src/model.md, "Facts that
/// shape the implementation").
pub fn default_free() -> Vec<String> {
    ["Kb", "b", "gamma1", "gamma2"]
        .iter()
        .flat_map(|p| (1..=3).map(move |i| format!("{p}_{i}")))
        .collect()
}

/// Relative tolerance of the simulations of an identification: 100 times
/// tighter than the default, so that finite differences of the outputs see the parameters and
/// not the step-size control.
pub const FIT_RTOL: f64 = DEFAULT_RTOL * 1e-2;

/// Settings of an identification.
#[derive(Clone, Debug)]
pub struct Options {
    /// Names of the parameters to estimate.
    pub free: Vec<String>,
    /// Bounds per parameter; default [prior/20, prior·20] for positive parameters.
    pub bounds: BTreeMap<String, (f64, f64)>,
    /// Relative tolerance of the simulations (default [`FIT_RTOL`]).
    pub rtol: f64,
    pub lm: lm::Options,
    /// Levenberg–Marquardt iterations a group's fit may take in all, over its runs after
    /// holding undetermined directions (each run also stops at `lm.max_iterations`); `None`:
    /// no limit beyond that. Where it runs out the fit ends where it got to, converged or not.
    pub iteration_budget: Option<usize>,
    /// Where a direction the data do not determine is held.
    pub hold: Hold,
    /// What to estimate of each record's conditions (its start, its sensor's lag), or `None`:
    /// the experiments' conditions as they are.
    pub conditions: Option<conditions::Choice>,
    /// How each channel's residuals count, in the fit and in the conditions' estimate.
    pub weighting: Weighting,
}

/// Where a group's fit holds a direction of parameter space the data do not determine
/// (book/src/identify.md, "How `hasel identify` estimates").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hold {
    /// At the start value: the prior, which the data cannot improve on along it (a parameter
    /// the data push against its bound is held there instead: not undetermined, but limited).
    Start,
    /// Where the fit had taken it when it was found: for a start that is a guess, such as a
    /// diagnosis's refit, where holding it at the start would undo what the fit had gained.
    Reached,
    /// At the start value, every direction, a parameter the data push against its bound too:
    /// a diagnosis's paper model, where that push is a symptom of what the model lacks, left
    /// for the rounds to find (book/src/diagnose.md, workflow step 1).
    Prior,
}

impl Hold {
    /// Where, in words.
    pub fn at(self) -> &'static str {
        match self {
            Hold::Start | Hold::Prior => "at its start value",
            Hold::Reached => "where the fit had taken it",
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            free: default_free(),
            bounds: BTreeMap::new(),
            rtol: FIT_RTOL,
            lm: lm::Options {
                fd_step: 1e-4,
                ..lm::Options::default()
            },
            iteration_budget: None,
            hold: Hold::Start,
            conditions: Some(conditions::Choice::default()),
            weighting: Weighting::Equal,
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

/// The covariance of the estimates in the coordinates the fit moved them in: `ln p` for a
/// parameter that must be positive, `p` itself otherwise (the fit's `p` over a scale, scaled back).
/// Block-diagonal over separately fitted groups; singular along held combinations.
#[derive(Clone, Debug)]
pub struct Covariance {
    pub names: Vec<String>,
    /// Per parameter: true for `ln p`, false for `p`.
    pub log: Vec<bool>,
    pub matrix: DMatrix<f64>,
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
    /// Covariance of the estimated parameters, in the fit's coordinates.
    pub covariance: Covariance,
    pub estimation: Vec<ExperimentFit>,
    pub validation: Vec<ExperimentFit>,
    /// Fits of the starting parameters on the estimation data, for comparison.
    pub estimation_before: Vec<ExperimentFit>,
    pub iterations: usize,
    pub simulations: usize,
    /// A group's fit ended unconverged at `Options::iteration_budget`.
    pub out_of_budget: bool,
    pub seconds: f64,
    /// Simulated outputs at the fitted parameters, estimation then validation experiments.
    pub simulated: Vec<Vec<Sample>>,
    /// The conditions estimated for each record, estimation then validation experiments;
    /// empty where they were kept as given (`Options::conditions` = `None`).
    pub conditions: Vec<conditions::Found>,
    /// How the fit counted each output's residuals.
    pub weighting: Weighting,
}

impl Identification {
    /// The fits on the held-out records: the validation ones, or the estimation ones where
    /// there are none (a single record is then its own held-out one), with the index of the
    /// first of them among all records.
    pub fn held_out(&self) -> (usize, &[ExperimentFit]) {
        if self.validation.is_empty() {
            (0, &self.estimation)
        } else {
            (self.estimation.len(), &self.validation)
        }
    }
}

/// Simulates `exp` with `params` under its conditions (from its start, sampled where its
/// sensor lags to), the samples stamped with the experiment's times.
pub fn simulate(params: &Params, exp: &Experiment, rtol: f64) -> Result<Vec<Sample>, Error> {
    let model = Platform::new(params.clone())?;
    let times = exp.sensed_times();
    let in_experiment = |source| Error::Experiment {
        experiment: exp.name.clone(),
        source,
    };
    let mut sim = Simulator::starting(model, &exp.conditions.start, &exp.input, times[0], rtol)
        .map_err(in_experiment)?;
    let mut out = Vec::with_capacity(exp.t.len());
    sim.run_at(&exp.input, &times, |s| out.push(*s))
        .map_err(in_experiment)?;
    for (s, &t) in out.iter_mut().zip(&exp.t) {
        s.t = t;
    }
    Ok(out)
}

/// NRMSE fits of simulated outputs against one experiment, on its samples after the lead-in.
pub fn fits(exp: &Experiment, sim: &[Sample]) -> ExperimentFit {
    let (k, sim) = (exp.lead_in, &sim[exp.lead_in..]);
    let mut out: Vec<(String, f64)> = exp
        .channels
        .iter()
        .map(|(c, y)| {
            let s: Vec<f64> = sim.iter().map(|s| c.of(s)).collect();
            (c.name().to_string(), fit::nrmse_fit(&y[k..], &s))
        })
        .collect();
    if let (Some(x), Some(y)) = (exp.measured(Channel::Tip(0)), exp.measured(Channel::Tip(1))) {
        let sx: Vec<f64> = sim.iter().map(|s| s.tip[0]).collect();
        let sy: Vec<f64> = sim.iter().map(|s| s.tip[1]).collect();
        out.push((
            "tip_xy".into(),
            fit::nrmse_fit_2d(&x[k..], &y[k..], &sx, &sy),
        ));
    }
    ExperimentFit {
        experiment: exp.name.clone(),
        fits: out,
    }
}

/// Rounds of conditions and fit at most (book/src/identify.md, "The order of estimation").
const CONDITION_ROUNDS: usize = 4;

/// Rounds in a refinement, which starts from conditions found before (a diagnosis's refit): the
/// first adds the candidate's own states to the start, the second lets the start and the
/// parameters settle against each other. With one, a creep spectrum's 18 slow states stayed
/// loaded for the weights before the fit, and a creep in two branches recorded mid-run lost to
/// the hysteresis plays (book/src/hidden-effects.md, "On a lab's protocols").
const REFINED_ROUNDS: usize = 2;

/// The fits of `params` on `exps`.
fn fits_at(params: &Params, exps: &[Experiment], rtol: f64) -> Result<Vec<ExperimentFit>, Error> {
    exps.iter()
        .map(|e| simulate(params, e, rtol).map(|s| fits(e, &s)))
        .collect()
}

/// Identifies the free parameters on `estimation` from `start`, and reports fits on
/// `estimation` and `validation`. Where `opts.conditions` asks, each record's conditions are
/// estimated beside the parameters (book/src/identify.md, "Records that start mid-run"):
/// at the start parameters, and again at the fitted ones, with a second fit from there when
/// they moved.
pub fn identify(
    start: &Params,
    estimation: &[Experiment],
    validation: &[Experiment],
    opts: &Options,
) -> Result<Identification, Error> {
    let Some(choice) = opts.conditions else {
        return fit(start, start, estimation, validation, opts);
    };
    let began = Instant::now();
    let found = |p: &Params, exps: &[Experiment], c: conditions::Choice| -> Result<Vec<_>, _> {
        exps.iter()
            .map(|e| conditions::estimate(p, e, c, (opts.rtol, opts.weighting)))
            .collect()
    };
    let under = |exps: &[Experiment], found: &[conditions::Found]| -> Vec<Experiment> {
        exps.iter()
            .zip(found)
            .map(|(e, f)| Experiment {
                conditions: f.conditions.clone(),
                ..e.clone()
            })
            .collect()
    };
    // the start parameters are a guess: the lag, a fraction of a sample, waits for the fit,
    // and so does the detection of a start mid-run (the rest heights move with the
    // parameters: a device 20 % off the guess rests elsewhere): the first fit is under the
    // records' conditions as they come (at rest, unless found before)
    let first = conditions::Choice {
        lag: match choice.lag {
            conditions::LagChoice::Estimate => conditions::LagChoice::Stated(0.0),
            asked => asked,
        },
        start: match choice.start {
            conditions::StartChoice::Auto | conditions::StartChoice::Refined => {
                conditions::StartChoice::Kept
            }
            stated => stated,
        },
    };
    let mut est = under(estimation, &found(start, estimation, first)?);
    let mut val = validation.to_vec();
    let mut id = fit(start, start, &est, &val, opts)?;
    // the start and the parameters pull on each other (a start off by a micrometre is a slow
    // transient the parameters would bend to): conditions and fit alternate until the
    // conditions stand still
    let mut settled = Vec::new();
    let rounds = match choice.start {
        conditions::StartChoice::Refined => REFINED_ROUNDS,
        _ => CONDITION_ROUNDS,
    };
    // whether the parameters were fitted after the conditions were last found
    let mut fitted_last = true;
    for _ in 0..rounds {
        let all: Vec<Experiment> = est.iter().chain(&val).cloned().collect();
        settled = found(&id.params, &all, choice)?;
        let moved = settled
            .iter()
            .zip(&all)
            .any(|(f, e)| conditions::moved(&e.conditions, &f.conditions));
        if !moved {
            fitted_last = false;
            break;
        }
        let (e, v) = settled.split_at(estimation.len());
        (est, val) = (under(estimation, e), under(validation, v));
        let (iterations, simulations) = (id.iterations, id.simulations);
        let before = std::mem::take(&mut id.estimation_before);
        // from where the last fit ended (which held what the data leave undetermined), with
        // the default bounds around the caller's start still
        id = fit(start, &id.params, &est, &val, opts)?;
        // the start's fits under the conditions found, for comparison only: where the start
        // cannot be simulated under them (an effect's states estimated at the fit, which the
        // start's parameters drive elsewhere), the ones found before stand
        id.estimation_before = fits_at(start, &est, opts.rtol).unwrap_or(before);
        id.iterations += iterations;
        id.simulations += simulations;
    }
    if fitted_last && !val.is_empty() {
        validated_under_fit(&mut id, &mut settled, &val, choice, opts)?;
    }
    id.seconds = began.elapsed().as_secs_f64();
    id.conditions = settled;
    Ok(id)
}

/// The held-out records `val` judged under conditions found at the fitted parameters
/// (book/src/identify.md, "The order of estimation", step 5): the last fit moved the parameters
/// after their conditions were found, and a start mid-run found for other parameters (a
/// creep's loaded branches, the angles) would charge the model with its stale start.
fn validated_under_fit(
    id: &mut Identification,
    settled: &mut [conditions::Found],
    val: &[Experiment],
    choice: conditions::Choice,
    opts: &Options,
) -> Result<(), Error> {
    let (first, rtol) = (id.estimation.len(), opts.rtol);
    for (k, e) in val.iter().enumerate() {
        let f = conditions::estimate(&id.params, e, choice, (rtol, opts.weighting))?;
        let under = Experiment {
            conditions: f.conditions.clone(),
            ..e.clone()
        };
        let sim = simulate(&id.params, &under, rtol)?;
        id.validation[k] = fits(&under, &sim);
        id.simulated[first + k] = sim;
        if let Some(s) = settled.get_mut(first + k) {
            *s = f;
        }
        id.simulations += 1;
    }
    Ok(())
}

/// The free parameters named in `opts`, each once.
fn free_params(opts: &Options) -> Result<Vec<&'static ParamDef>, Error> {
    let mut free: Vec<&'static ParamDef> = Vec::new();
    for name in &opts.free {
        let d = parameter(name).ok_or_else(|| Error::UnknownFree(name.clone()))?;
        if !free.iter().any(|f| f.name == d.name) {
            free.push(d);
        }
    }
    Ok(free)
}

/// Each bound in `opts` a proper interval holding the start value.
fn check_bounds(start: &Params, opts: &Options) -> Result<(), Error> {
    for (name, (lo, hi)) in &opts.bounds {
        let prior = start.get(name)?;
        if !(lo < hi && (*lo..=*hi).contains(&prior)) {
            return Err(Error::Bounds {
                name: name.clone(),
                lo: *lo,
                hi: *hi,
                start: prior,
            });
        }
    }
    Ok(())
}

/// A group's estimated parameters, their fit's coordinates and their covariance in them.
type Block = (Vec<String>, Vec<group::Coordinate>, DMatrix<f64>);

/// The names, correlation and covariance over all estimated parameters from the groups'
/// `blocks` (zero between separately fitted groups).
fn joined_covariance(blocks: &[Block]) -> (Vec<String>, DMatrix<f64>, Covariance) {
    let names: Vec<String> = blocks.iter().flat_map(|(n, _, _)| n.clone()).collect();
    let mut corr = DMatrix::zeros(names.len(), names.len());
    let mut covariance = Covariance {
        names: names.clone(),
        log: Vec::with_capacity(names.len()),
        matrix: DMatrix::zeros(names.len(), names.len()),
    };
    let mut o = 0;
    for (n, coords, cov) in blocks {
        // the fit's coordinate of each parameter: ln p, or p over a scale (scaled back to p)
        let unit = |c: &group::Coordinate| if c.log { 1.0 } else { c.scale };
        for a in 0..n.len() {
            for b in 0..n.len() {
                corr[(o + a, o + b)] = cov[(a, b)] / (cov[(a, a)] * cov[(b, b)]).sqrt();
                covariance.matrix[(o + a, o + b)] =
                    cov[(a, b)] * unit(&coords[a]) * unit(&coords[b]);
            }
        }
        covariance.log.extend(coords.iter().map(|c| c.log));
        o += n.len();
    }
    (names, corr, covariance)
}

/// Every parameter of the model at `params` beside its `start`: whether free, and the
/// standard error and interval of those `estimated`.
fn estimates(
    params: &Params,
    start: &Params,
    free: &[&'static ParamDef],
    estimated: &[(String, f64, f64, (f64, f64))],
) -> Vec<Estimate> {
    crate::model::params::parameters()
        .map(|d| {
            let found = estimated.iter().find(|e| e.0 == d.name);
            Estimate {
                name: d.name.to_string(),
                value: (d.get)(params),
                prior: (d.get)(start),
                free: free.iter().any(|f| f.name == d.name),
                estimated: found.is_some(),
                std_error: found.map(|e| e.2),
                ci95: found.map(|e| e.3),
            }
        })
        .collect()
}

/// Fits the free parameters on `estimation` from `from` under the experiments' conditions, with
/// `prior` the start the caller gave: the default bounds are around it and the estimates are
/// shown beside it; a direction the data do not determine is held at `from`
/// ([`Hold::Start`], [`Hold::Prior`]), where a fit before this one had held it.
fn fit(
    prior: &Params,
    from: &Params,
    estimation: &[Experiment],
    validation: &[Experiment],
    opts: &Options,
) -> Result<Identification, Error> {
    let began = Instant::now();
    if estimation.is_empty() {
        return Err(Error::NoEstimationExperiment);
    }
    let free = free_params(opts)?;
    check_bounds(prior, opts)?;
    let estimation_before = fits_at(from, estimation, opts.rtol)?;

    let mut params = from.clone();
    let (mut iterations, mut simulations) = (0, estimation.len());
    let mut out_of_budget = false;
    let mut estimated: Vec<(String, f64, f64, (f64, f64))> = Vec::new();
    let mut not_identifiable = Vec::new();
    let mut held_combinations = Vec::new();
    let mut blocks: Vec<Block> = Vec::new();
    let groups = groups(&free, estimation);
    // each group is fitted from `from` on its own: side by side, in threads
    let fitted_groups: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = groups
            .iter()
            .map(|g| s.spawn(|| fit_group((prior, from), g, estimation, opts)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a group's fit does not panic"))
            .collect()
    });
    for (group, fitted) in groups.iter().zip(fitted_groups) {
        let (fitted, r) = fitted?;
        for d in &group.params {
            params.set(d.name, (d.get)(&fitted))?;
        }
        iterations += r.iterations;
        simulations += r.simulations;
        out_of_budget |= r.out_of_budget;
        estimated.extend(r.estimates);
        not_identifiable.extend(r.not_identifiable);
        held_combinations.extend(r.held_combinations);
        blocks.push((r.names, r.coords, r.covariance));
    }

    let (names, corr, covariance) = joined_covariance(&blocks);
    let estimates = estimates(&params, prior, &free, &estimated);
    let mut simulated = Vec::new();
    let mut fit_all = |exps: &[Experiment]| -> Result<Vec<ExperimentFit>, Error> {
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
        covariance,
        estimation: estimation_fits,
        validation: validation_fits,
        estimation_before,
        iterations,
        simulations,
        out_of_budget,
        seconds: began.elapsed().as_secs_f64(),
        simulated,
        conditions: Vec::new(),
        weighting: opts.weighting,
    })
}
