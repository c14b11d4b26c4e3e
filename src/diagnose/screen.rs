//! Ranking the candidates before refitting them: a score test. At the re-identified model,
//! each effect is switched on at a probe value and its change of the outputs is projected out
//! of what the base parameters can already do (their sensitivities); the share of the
//! residual that the rest explains is the effect's score, and the projection's coefficient
//! scales the probe into a starting value for the refit. Every form of an effect's family has
//! its own probes, which the family's module writes (book/src/diagnose.md, "Families of
//! forms"); a form is worth its explained share less the price of its dimensions, in the units
//! of the BIC (for a series of non-negative weights, the weights it uses).

use nalgebra::{DMatrix, DVector, Dyn, SVD};

use super::Error;
use super::analysis::noise_level;
use crate::identify::{self, Channel, Experiment, simulate};
use crate::model::effects::{Form, Probe, Scaling, nonnegative_least_squares};
use crate::model::linalg::bounded_svd;
use crate::model::{Effect, Params, Platform};
use crate::simulation::{SimError, Start};

/// Probes of every form of every family not yet in `params`, at values that change the response
/// by a few percent of its range at the paper's excitation (book/src/diagnose.md,
/// "Screening"): each family's own.
pub fn probes(params: &Params, u_peak: f64) -> Vec<Probe> {
    Effect::ALL
        .into_iter()
        .filter(|e| !e.is_active(&params.effects))
        .flat_map(|e| (e.family().probes)(params, u_peak))
        .collect()
}

/// The stacked outputs of `params` on `exp`, each channel divided by its weight.
fn outputs(
    params: &Params,
    exp: &Experiment,
    weights: &[(Channel, f64)],
    rtol: f64,
) -> Result<DVector<f64>, Error> {
    let sim = simulate(params, exp, rtol)?;
    let mut v = Vec::new();
    for &(c, w) in weights {
        v.extend(sim.iter().map(|s| c.of(s) / w));
    }
    Ok(DVector::from_vec(v))
}

/// How far from its probe value a magnitude's refit may start: a factor either way.
const MAGNITUDE_RANGE: f64 = 5.0;

/// The step of an effect's state at a start mid-run whose change of the outputs is its
/// direction, in the state's scale (a full stroke, 100 V): small enough to stay linear.
const START_STATE_STEP: f64 = 0.1;

/// A probe's outcome: its score and the start values it suggests.
pub struct Score {
    pub form: &'static Form,
    /// Share of the weighted residual the probe explains beyond the base parameters [0, 1].
    pub score: f64,
    /// What the form is worth: the weighted residual sum of squares it explains less ln N per
    /// parameter it frees, the drop of the BIC it predicts (book/src/diagnose.md,
    /// "Families of forms").
    pub worth: f64,
    pub start: Vec<(&'static str, f64)>,
}

/// The model at which the probes are scored: its weighted outputs and residual on one
/// experiment, and the directions in which its free parameters move the outputs.
pub struct Point<'a> {
    params: &'a Params,
    exp: &'a Experiment,
    /// Each channel divided by its noise level.
    weights: Vec<(Channel, f64)>,
    rtol: f64,
    y0: DVector<f64>,
    /// The directions in which the free parameters move the outputs, B, and its SVD.
    base_directions: DMatrix<f64>,
    base: SVD<f64, Dyn, Dyn>,
    /// The residual with what B can do projected out, r⊥ = r − B (B⁺ r).
    residual_perp: DVector<f64>,
}

/// The SVD of `m`, bounded in its iterations.
fn svd(m: DMatrix<f64>) -> Result<SVD<f64, Dyn, Dyn>, Error> {
    bounded_svd(m).ok_or(Error::Projection(
        "the SVD of the sensitivities did not converge",
    ))
}

/// `m` less its least-squares part in the columns of `a` (whose SVD is `a_svd`): m − A (A⁺ m).
fn off(
    a: &DMatrix<f64>,
    a_svd: &SVD<f64, Dyn, Dyn>,
    m: DMatrix<f64>,
) -> Result<DMatrix<f64>, Error> {
    let part = a * a_svd.solve(&m, 1e-12).map_err(Error::Projection)?;
    Ok(m - part)
}

impl<'a> Point<'a> {
    pub fn new(
        params: &'a Params,
        exp: &'a Experiment,
        free: &[String],
        rtol: f64,
    ) -> Result<Point<'a>, Error> {
        let weights: Vec<(Channel, f64)> = exp
            .channels
            .iter()
            .map(|(c, y)| (*c, noise_level(&exp.t, y).max(1e-15)))
            .collect();
        let y0 = outputs(params, exp, &weights, rtol)?;
        let mut measured = Vec::new();
        for ((_, y), (_, w)) in exp.channels.iter().zip(&weights) {
            measured.extend(y.iter().map(|v| v / w));
        }
        let residual = DVector::from_vec(measured) - &y0;
        let mut cols = Vec::new();
        for name in free {
            let v = params.get(name)?;
            let mut p = params.clone();
            let h = if v != 0.0 { 1e-3 * v } else { 1e-6 };
            p.set(name, v + h)?;
            cols.push(outputs(&p, exp, &weights, rtol)? - &y0);
        }
        let base_directions = DMatrix::from_columns(&cols);
        let base = svd(base_directions.clone())?;
        let residual_perp = &residual
            - &base_directions * base.solve(&residual, 1e-12).map_err(Error::Projection)?;
        Ok(Point {
            params,
            exp,
            weights,
            rtol,
            y0,
            base_directions,
            base,
            residual_perp,
        })
    }

    /// On a record that starts mid-run (book/src/diagnose.md, "Screening"), the directions
    /// in which the effects' states at the start move the outputs of the model with each of
    /// `probe`'s columns on: one per state, a step of START_STATE_STEP of its scale from where
    /// the states settle at the start's angles and first command. None from rest, or where the
    /// probed model has no effect states.
    fn start_state_directions(&self, probe: &Probe) -> Result<Option<DMatrix<f64>>, Error> {
        let Start::Settled { theta, .. } = self.exp.conditions.start else {
            return Ok(None);
        };
        let u0 = self.exp.input.value(self.exp.t[0]);
        let mut cols = Vec::new();
        for column in &probe.columns {
            let mut p = self.params.clone();
            for &(name, v) in column {
                p.set(name, v)?;
            }
            let model = Platform::new(p.clone())?;
            let x0 = model
                .settled_state(theta, &[], u0)
                .map_err(|e| identify::Error::from(SimError::from(e)))?;
            let slow = model.effect_states(&x0);
            let scales = model.effect_states(&model.state_scales());
            let mut exp = self.exp.clone();
            let mut outputs_from = |slow: Vec<f64>| {
                exp.conditions.start = Start::Settled { theta, slow };
                outputs(&p, &exp, &self.weights, self.rtol)
            };
            let y = outputs_from(slow.clone())?;
            for (k, scale) in scales.iter().enumerate() {
                let mut moved = slow.clone();
                moved[k] += START_STATE_STEP * scale;
                cols.push(outputs_from(moved)? - &y);
            }
        }
        Ok((!cols.is_empty()).then(|| DMatrix::from_columns(&cols)))
    }

    /// Whether the record starts mid-run, where a probe's states at the start are unknowns of
    /// its refit.
    pub fn mid_run(&self) -> bool {
        matches!(self.exp.conditions.start, Start::Settled { .. })
    }

    /// Scores `probe` here; with `start_states`, on a record that starts mid-run, beside the
    /// probe's states at the start.
    pub fn score(&self, probe: &Probe, start_states: bool) -> Result<Score, Error> {
        let mut cols = Vec::new();
        for column in &probe.columns {
            let mut p = self.params.clone();
            for &(name, v) in column {
                p.set(name, v)?;
            }
            cols.push(outputs(&p, self.exp, &self.weights, self.rtol)? - &self.y0);
        }
        let d = DMatrix::from_columns(&cols);
        // project out the base sensitivities, D⊥ = D − B (B⁺ D), and on a record that starts
        // mid-run the probe's own states at the start, which its refit estimates (N⊥ = N − B B⁺N;
        // D and r lose their parts in N⊥ too, which count as explained)
        let d_perp = off(&self.base_directions, &self.base, d)?;
        let directions = if start_states {
            self.start_state_directions(probe)?
        } else {
            None
        };
        let (d_perp, r_perp, start_states) = match directions {
            Some(n) => {
                let n_perp = off(&self.base_directions, &self.base, n)?;
                let n_svd = svd(n_perp.clone())?;
                let r = DMatrix::from_column_slice(
                    self.residual_perp.len(),
                    1,
                    self.residual_perp.as_slice(),
                );
                let r_off = off(&n_perp, &n_svd, r)?.column(0).into_owned();
                (off(&n_perp, &n_svd, d_perp)?, r_off, n_perp.ncols())
            }
            None => (d_perp, self.residual_perp.clone(), 0),
        };
        let r_perp = &r_perp;
        let coef = if probe.scaling == Scaling::Weights {
            nonnegative_least_squares(&d_perp, r_perp)
        } else {
            svd(d_perp.clone())?
                .solve(r_perp, 1e-9)
                .map_err(Error::Projection)?
        };
        // a form is worth what it explains where its refit starts: a magnitude within a factor
        // MAGNITUDE_RANGE of the probe's, where the probe's change pictures the form's; a limit
        // at the probe itself (a slew limit's distortion scaled to a fifth is no slew limit)
        let realized = match probe.scaling {
            Scaling::Magnitude => coef.map(|c| c.clamp(1.0 / MAGNITUDE_RANGE, MAGNITUDE_RANGE)),
            Scaling::Fixed => coef.map(|_| 1.0),
            _ => coef.clone(),
        };
        let total = self.residual_perp.norm_squared().max(1e-300);
        let explained = (total - (r_perp - &d_perp * &realized).norm_squared()).max(0.0);
        let start = start_values(probe, &coef, &realized);
        // an effect that can only act with one sign explains nothing against it
        let wrong_sign = match probe.scaling {
            Scaling::Magnitude => coef[0] <= 0.0,
            Scaling::Pairs => coef.max() <= 0.0,
            _ => false,
        };
        let explained = if wrong_sign { 0.0 } else { explained };
        let n = self.residual_perp.len() as f64;
        // a series is charged for the weights it uses, not for the length of its grid; the
        // states at a start mid-run as its refit's BIC charges them (`diagnose::unknowns`)
        let dimensions = start_states
            + match probe.scaling {
                Scaling::Weights => coef.iter().filter(|&&c| c > 0.0).count(),
                _ => probe.form.free.len(),
            };
        Ok(Score {
            form: probe.form,
            score: explained / total,
            worth: explained - dimensions as f64 * n.ln(),
            start,
        })
    }
}

/// The probe's settings scaled as the fit found them, where the form's refit starts: the
/// magnitudes as `realized`, signed amplitudes and weights as fitted (`coef`), a coupling's
/// pair stiffnesses relative to pair (1, 2).
fn start_values(
    probe: &Probe,
    coef: &DVector<f64>,
    realized: &DVector<f64>,
) -> Vec<(&'static str, f64)> {
    let mut start = Vec::new();
    if probe.scaling == Scaling::Pairs {
        // pair j's stiffness is k_c c_j; the weights are relative to pair (1, 2)
        let c = |j: usize| coef[j].max(0.05 * coef.max().max(1e-12));
        let k_c = probe.columns[0][0].1 * c(0);
        start = vec![
            ("k_c", k_c),
            ("w_c12", 1.0),
            ("w_c13", c(1) / c(0)),
            ("w_c23", c(2) / c(0)),
        ];
    }
    for (k, column) in probe
        .columns
        .iter()
        .enumerate()
        .filter(|_| probe.scaling != Scaling::Pairs)
    {
        for (i, &(name, v)) in column.iter().enumerate() {
            // the first setting of a column is its magnitude; the others (time constants,
            // saturation angles) are kept
            let value = match probe.scaling {
                Scaling::Magnitude if i == 0 => v * realized[k],
                Scaling::Signed | Scaling::Weights if i == 0 => v * coef[k],
                _ => v,
            };
            start.push((name, value));
        }
    }
    start
}
