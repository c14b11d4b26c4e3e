//! Prediction uncertainty from an identification: drawn parameter sets and quantile bands.
//!
//! Prediction uncertainty from an identification: parameter sets drawn from the covariance that
//! `hasel identify` reports ([`Posterior`]), many simulations of them on all cores, and the
//! median and 2.5/97.5 % bands of every output over time ([`bands`]).
//!
//! The draw happens where the fit happened: each estimated parameter in its fit coordinate,
//! `ln p` for a parameter that must be positive and `p` otherwise (`identification.json`,
//! `covariance.coordinates`), as `x = x̂ + F ξ` with `F Fᵀ` the covariance and `ξ` standard
//! normal. Parameters the data did not determine keep their value; a held combination keeps its
//! value because the covariance is zero along it (checked when the file is read). Sample `k` of
//! seed `s` draws its `ξ` from its own stream, seeded from `(s, k)` alone, so a sample is the
//! same whichever thread runs it and however many run.

pub mod bands;

use std::path::{Path, PathBuf};

use nalgebra::{DMatrix, DVector};
use serde_json::Value;

use crate::identify::orthonormal;
use crate::identify::synth::Normal;
use crate::model::Params;
use crate::model::params::{ParamError, parameter};
use crate::simulation::SimError;

/// What can go wrong in an uncertainty study.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum UncertaintyError {
    /// The identification file cannot be read or is not what `hasel identify` writes.
    #[error("{}: {message}", .path.display())]
    Identification { path: PathBuf, message: String },
    /// A setting of the study is out of range.
    #[error("{0}")]
    Setting(String),
    /// Every sample failed; the first failure is given.
    #[error("all {samples} samples failed (sample {sample}: {reason})")]
    AllFailed {
        samples: usize,
        sample: usize,
        reason: SampleError,
    },
    /// A result file or figure could not be written.
    #[error("{0}")]
    Output(String),
}

/// Why one sample of a study has no outputs: it is left out of the bands, with this reason.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// The drawn parameters break a parameter's rule.
    #[error("{0}")]
    Parameters(#[from] ParamError),
    /// The simulation of the drawn model stopped.
    #[error("{0}")]
    Simulation(#[from] SimError),
    /// The run ended before the study's last output time.
    #[error("{got} output times, not {expected}")]
    ShortRun { got: usize, expected: usize },
    /// No thread took the sample (a thread that stopped before its end).
    #[error("not run")]
    NotRun,
}

/// Eigenvalues of the covariance below this fraction of the largest are taken as zero (the
/// held directions, and rounding).
const RANK_TOLERANCE: f64 = 1e-12;

/// A held combination counts as held when the covariance along it is below this fraction of
/// its largest eigenvalue (the file rounds the combination's weights to 4 digits).
const HELD_TOLERANCE: f64 = 1e-6;

/// The distribution of the parameters after an identification.
#[derive(Clone, Debug)]
pub struct Posterior {
    /// The file it was read from.
    pub path: PathBuf,
    /// Every parameter at its identified value (the defaults for any the file does not list).
    pub center: Params,
    /// The estimated parameters, which the draw moves.
    pub names: Vec<String>,
    /// Per estimated parameter: drawn in `ln p` (true) or `p` (false).
    pub log: Vec<bool>,
    /// The identified values in those coordinates.
    pub mean: Vec<f64>,
    /// `x = mean + factor · ξ`: n × r, r the rank of the covariance.
    factor: DMatrix<f64>,
    /// Held combinations: (parameter, weight in the fit coordinates).
    pub held: Vec<Vec<(String, f64)>>,
}

/// The 64-bit finaliser of SplitMix64: a bijection that scatters nearby inputs.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The seed of sample `index` of a study seeded `seed`: a function of the two alone.
fn sample_seed(seed: u64, index: u64) -> u64 {
    mix(mix(seed) ^ index)
}

impl Posterior {
    /// Reads `identification.json` as `hasel identify` writes it.
    pub fn read(path: &Path) -> Result<Posterior, UncertaintyError> {
        let fail = |m: String| UncertaintyError::Identification {
            path: path.to_path_buf(),
            message: m,
        };
        let text = std::fs::read_to_string(path).map_err(|e| fail(format!("cannot read: {e}")))?;
        Posterior::parse(path, &text)
    }

    /// The posterior of the JSON `text` (the contents of `path`); `pub` for the fuzz target and
    /// its replay (tests/fuzz), which feed it text without a file.
    pub fn parse(path: &Path, text: &str) -> Result<Posterior, UncertaintyError> {
        let fail = |m: String| UncertaintyError::Identification {
            path: path.to_path_buf(),
            message: m,
        };
        let json: Value = serde_json::from_str(text).map_err(|e| {
            fail(format!(
                "not JSON ({e}): expected the identification.json of `hasel identify`"
            ))
        })?;
        Posterior::from_json(path, &json)
    }

    /// The posterior described by `json`, read from `path` (for messages).
    pub fn from_json(path: &Path, json: &Value) -> Result<Posterior, UncertaintyError> {
        let fail = |m: String| UncertaintyError::Identification {
            path: path.to_path_buf(),
            message: m,
        };
        let (center, estimated) = read_parameters(json, &fail)?;
        let held = read_held(json, &fail)?;

        let (names, log, cov, exact) = match json.get("covariance") {
            Some(c) => {
                let (names, log, cov) = read_covariance(c, &fail)?;
                (names, log, cov, true)
            }
            None => {
                let (names, log, cov) = covariance_from_errors(json, &estimated, &fail)?;
                (names, log, cov, false)
            }
        };
        // found by fuzzing (tests/fuzz, identification_json): an empty matrix has no factor
        if names.is_empty() {
            return Err(fail(
                "covariance: no parameter to draw (a study draws the estimated parameters)".into(),
            ));
        }
        for (name, &l) in names.iter().zip(&log) {
            if !estimated.contains(name) {
                return Err(fail(format!(
                    "covariance: {name} is not an estimated parameter (\"estimated\": true in parameters)"
                )));
            }
            let v = center.get(name).expect("set above");
            if l && v <= 0.0 {
                return Err(fail(format!(
                    "covariance: {name} is drawn in ln p but its value is {v}"
                )));
            }
        }
        let mean: Vec<f64> = names
            .iter()
            .zip(&log)
            .map(|(n, &l)| {
                let v = center.get(n).expect("set above");
                if l { v.ln() } else { v }
            })
            .collect();

        let directions = held_directions(&held, &names);
        let factor = factor(&cov, &directions, exact, &fail)?;
        Ok(Posterior {
            path: path.to_path_buf(),
            center,
            names,
            log,
            mean,
            factor,
            held,
        })
    }

    /// The rank of the covariance: how many independent normals a draw takes.
    pub fn rank(&self) -> usize {
        self.factor.ncols()
    }

    /// Sample `index` of the study seeded `seed`, in the fit coordinates.
    pub fn draw_coordinates(&self, seed: u64, index: u64) -> Vec<f64> {
        let mut rng = Normal::new(sample_seed(seed, index));
        let xi = DVector::from_fn(self.rank(), |_, _| rng.sample());
        let dx = &self.factor * xi;
        self.mean
            .iter()
            .zip(dx.iter())
            .map(|(m, d)| m + d)
            .collect()
    }

    /// Sample `index` of the study seeded `seed`: every parameter, the estimated ones drawn.
    pub fn draw(&self, seed: u64, index: u64) -> Result<Params, ParamError> {
        self.params_at(&self.values_at(&self.draw_coordinates(seed, index)))
    }

    /// The estimated parameters' values at fit coordinates `x`.
    pub fn values_at(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(&self.log)
            .map(|(&xi, &l)| if l { xi.exp() } else { xi })
            .collect()
    }

    /// Every parameter, the estimated ones at `values` (checked).
    pub fn params_at(&self, values: &[f64]) -> Result<Params, ParamError> {
        let mut p = self.center.clone();
        for (name, &v) in self.names.iter().zip(values) {
            p.set(name, v)?;
        }
        p.validate()?;
        Ok(p)
    }
}

/// A covariance as read: parameter names, per name drawn in `ln p`, the matrix.
type Block = (Vec<String>, Vec<bool>, DMatrix<f64>);

/// The number `v` as `what` must be: present and finite.
fn number(
    v: Option<&Value>,
    what: &str,
    fail: &dyn Fn(String) -> UncertaintyError,
) -> Result<f64, UncertaintyError> {
    v.and_then(Value::as_f64)
        .filter(|x| x.is_finite())
        .ok_or_else(|| fail(format!("{what}: expected a finite number")))
}

/// The parameters of `json` (each known, each value valid) and the names of those estimated.
fn read_parameters(
    json: &Value,
    fail: &dyn Fn(String) -> UncertaintyError,
) -> Result<(Params, Vec<String>), UncertaintyError> {
    let params = json
        .get("parameters")
        .and_then(Value::as_object)
        .ok_or_else(|| {
            fail(
                "no \"parameters\" object: expected the identification.json of `hasel identify`"
                    .into(),
            )
        })?;
    let mut center = Params::default();
    let mut estimated = Vec::new();
    for (name, entry) in params {
        parameter(name).ok_or_else(|| fail(format!("parameters.{name}: unknown parameter")))?;
        let value = number(
            entry.get("value"),
            &format!("parameters.{name}.value"),
            fail,
        )?;
        center
            .set(name, value)
            .map_err(|e| fail(format!("parameters.{name}: {e}")))?;
        if entry.get("estimated").and_then(Value::as_bool) == Some(true) {
            estimated.push(name.clone());
        }
    }
    center
        .validate()
        .map_err(|e| fail(format!("parameters: {e}")))?;
    Ok((center, estimated))
}

/// The held combinations of `json`, each as its parameters' weights (none if absent).
fn read_held(
    json: &Value,
    fail: &dyn Fn(String) -> UncertaintyError,
) -> Result<Vec<Vec<(String, f64)>>, UncertaintyError> {
    Ok(match json.get("held_combinations") {
        None | Some(Value::Null) => Vec::new(),
        Some(Value::Array(list)) => list
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let o = c.as_object().ok_or_else(|| {
                    fail(format!("held_combinations[{k}]: expected {{name: weight}}"))
                })?;
                o.iter()
                    .map(|(n, w)| {
                        parameter(n).ok_or_else(|| {
                            fail(format!("held_combinations[{k}]: unknown parameter {n}"))
                        })?;
                        Ok((
                            n.clone(),
                            number(Some(w), &format!("held_combinations[{k}].{n}"), fail)?,
                        ))
                    })
                    .collect()
            })
            .collect::<Result<_, _>>()?,
        Some(_) => return Err(fail("held_combinations: expected a list".into())),
    })
}

/// The held combinations, as unit vectors over the estimated parameters `names`.
fn held_directions(held: &[Vec<(String, f64)>], names: &[String]) -> Vec<DVector<f64>> {
    let n = names.len();
    held.iter()
        .map(|c| {
            let v = DVector::from_fn(n, |i, _| {
                c.iter()
                    .find(|(name, _)| *name == names[i])
                    .map_or(0.0, |(_, w)| *w)
            });
            let norm = v.norm();
            if norm > 0.0 { v / norm } else { v }
        })
        .collect()
}

/// A factor L of the covariance (L Lᵀ = cov over its numerical rank), checked positive
/// semi-definite; an `exact` one (as `hasel identify` wrote it) checked singular along the held
/// `directions`, one from rounded correlations with them taken out.
fn factor(
    cov: &DMatrix<f64>,
    directions: &[DVector<f64>],
    exact: bool,
    fail: &dyn Fn(String) -> UncertaintyError,
) -> Result<DMatrix<f64>, UncertaintyError> {
    let n = cov.nrows();
    let eig = cov.clone().symmetric_eigen();
    let top = eig.eigenvalues.iter().fold(0.0_f64, |a, &b| a.max(b));
    if let Some(low) = eig
        .eigenvalues
        .iter()
        .copied()
        .find(|&l| l < -1e-9 * top.max(f64::MIN_POSITIVE))
    {
        return Err(fail(format!(
            "covariance: not positive semi-definite (eigenvalue {low:e}, largest {top:e})"
        )));
    }
    let keep: Vec<usize> = (0..n)
        .filter(|&k| eig.eigenvalues[k] > RANK_TOLERANCE * top)
        .collect();
    let mut factor = DMatrix::from_fn(n, keep.len(), |i, c| {
        eig.eigenvectors[(i, keep[c])] * eig.eigenvalues[keep[c]].sqrt()
    });
    if exact {
        // the covariance `hasel identify` wrote is singular along what it held
        for (k, v) in directions.iter().enumerate() {
            if v.norm() > 0.0 {
                let along = (v.transpose() * cov * v)[(0, 0)];
                if along > HELD_TOLERANCE * top {
                    return Err(fail(format!(
                        "covariance: variance {along:e} along held_combinations[{k}], which must be held (largest eigenvalue {top:e})"
                    )));
                }
            }
        }
    } else {
        // from rounded correlations: take the held directions out explicitly
        for q in &orthonormal(directions) {
            let along = q.transpose() * &factor;
            factor -= q * along;
        }
    }
    Ok(factor)
}

/// The `covariance` block: names, coordinates, and a symmetric matrix of finite numbers.
fn read_covariance(
    c: &Value,
    fail: &dyn Fn(String) -> UncertaintyError,
) -> Result<Block, UncertaintyError> {
    let names: Vec<String> = c
        .get("parameters")
        .and_then(Value::as_array)
        .and_then(|a| a.iter().map(|v| v.as_str().map(String::from)).collect())
        .ok_or_else(|| fail("covariance.parameters: expected a list of names".into()))?;
    let log: Vec<bool> = c
        .get("coordinates")
        .and_then(Value::as_array)
        .and_then(|a| {
            a.iter()
                .map(|v| match v.as_str() {
                    Some("ln") => Some(true),
                    Some("linear") => Some(false),
                    _ => None,
                })
                .collect()
        })
        .ok_or_else(|| {
            fail("covariance.coordinates: expected a list of \"ln\" or \"linear\"".into())
        })?;
    if log.len() != names.len() {
        return Err(fail(format!(
            "covariance: {} coordinates for {} parameters",
            log.len(),
            names.len()
        )));
    }
    let n = names.len();
    let rows = c
        .get("matrix")
        .and_then(Value::as_array)
        .ok_or_else(|| fail("covariance.matrix: expected a list of rows".into()))?;
    if rows.len() != n {
        return Err(fail(format!(
            "covariance.matrix: {} rows for {n} parameters",
            rows.len()
        )));
    }
    let mut m = DMatrix::zeros(n, n);
    for (r, row) in rows.iter().enumerate() {
        let row = row.as_array().filter(|a| a.len() == n).ok_or_else(|| {
            fail(format!(
                "covariance.matrix row {}: expected {n} numbers",
                r + 1
            ))
        })?;
        for (col, v) in row.iter().enumerate() {
            m[(r, col)] = v.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                fail(format!(
                    "covariance.matrix row {}, column {}: expected a finite number",
                    r + 1,
                    col + 1
                ))
            })?;
        }
    }
    for r in 0..n {
        for col in 0..r {
            let (a, b) = (m[(r, col)], m[(col, r)]);
            if (a - b).abs() > 1e-9 * (m[(r, r)] * m[(col, col)]).sqrt() {
                return Err(fail(format!(
                    "covariance.matrix: not symmetric at ({}, {}): {a:e} and {b:e}",
                    r + 1,
                    col + 1
                )));
            }
        }
    }
    Ok((names, log, m))
}

/// Older files have no `covariance` block: it is rebuilt from the standard errors and the
/// (rounded) correlations, in the coordinates the fit used (`ln p` for a parameter that must
/// be positive, at a positive start value).
fn covariance_from_errors(
    json: &Value,
    estimated: &[String],
    fail: &dyn Fn(String) -> UncertaintyError,
) -> Result<Block, UncertaintyError> {
    let corr = json.get("correlation").ok_or_else(|| {
        fail("neither \"covariance\" nor \"correlation\": nothing to draw from".into())
    })?;
    let (names, _, r) = read_covariance(
        &serde_json::json!({
            "parameters": corr.get("parameters").cloned().unwrap_or(Value::Null),
            "coordinates": corr.get("parameters").and_then(Value::as_array)
                .map(|a| vec!["ln"; a.len()]).unwrap_or_default(),
            "matrix": corr.get("matrix").cloned().unwrap_or(Value::Null),
        }),
        &|m| fail(m.replace("covariance", "correlation")),
    )?;
    let mut log = Vec::new();
    let mut se = Vec::new();
    for name in &names {
        if !estimated.contains(name) {
            return Err(fail(format!(
                "correlation: {name} is not an estimated parameter"
            )));
        }
        let entry = &json["parameters"][name.as_str()];
        let get = |k: &str| {
            entry
                .get(k)
                .and_then(Value::as_f64)
                .filter(|v| v.is_finite())
        };
        let (Some(value), Some(prior), Some(error)) =
            (get("value"), get("prior"), get("std_error"))
        else {
            return Err(fail(format!(
                "parameters.{name}: value, prior and std_error must be finite numbers"
            )));
        };
        let l = parameter(name).is_some_and(|d| d.rule.fitted_in_log(prior));
        log.push(l);
        // the file gives std_error = value · se(ln p) for a log coordinate
        se.push(if l { error / value } else { error });
    }
    let cov = DMatrix::from_fn(names.len(), names.len(), |a, b| r[(a, b)] * se[a] * se[b]);
    Ok((names, log, cov))
}

#[cfg(test)]
mod tests;
