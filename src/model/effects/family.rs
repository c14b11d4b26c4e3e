//! What a family of the effect library is (book/src/effects.md, "The effect library"):
//! the one description each family's module gives of itself, which the registry
//! ([`super::Effect::family`]) hands to everything else: the parameter table, the FMU, the
//! screening and separation of `hasel diagnose`, the hidden-mechanism generator, the CLI and the
//! documents. Its terms (energy, right-hand side, Jacobian, dissipation) are the module's
//! [`super::terms::Law`].

use nalgebra::{DMatrix, DVector};

use super::{Effect, EffectParams};
use crate::model::Params;
use crate::model::actuator::StateInfo;
use crate::model::linalg::bounded_svd;
use crate::model::params::ParamDef;

/// One family: a place in the model where a missing mechanism enters, with its forms.
pub struct Family {
    pub effect: Effect,
    /// The name in book/src/effects.md, the CLI and the reports.
    pub name: &'static str,
    /// The physical mechanism, in words.
    pub mechanism: &'static str,
    /// The library's term, as written in book/src/effects.md.
    pub form: &'static str,
    /// The forms of the family, the library form first (effects.md, each family's "Forms").
    pub forms: &'static [Form],
    /// The family's rows of the parameter table, magnitudes and settings.
    pub rows: &'static [ParamDef],
    /// Rows that choose among forms (an index no magnitude expresses); the table lists them
    /// after every family's `rows`.
    pub choices: &'static [ParamDef],
    /// Name, unit and meaning of the family's extra state (every stage shares them), if any.
    pub state: Option<StateInfo>,
    /// How many stages of that state the parameter table can switch on: the FMU's states.
    pub table_stages: usize,
    /// Is the family switched on by these parameters?
    pub is_active: fn(&EffectParams) -> bool,
    /// Switches every form the table reaches on at once, at values inside the model's domain
    /// (the FMU reads the model structure there).
    pub on: fn(&mut EffectParams),
    /// Further settings over `on` whose Jacobian structure differs from it (another circuit
    /// site): the FMU reads the structure there too.
    pub structures: &'static [fn(&mut EffectParams)],
    /// Whether the family delays the command on its way to the actuators, as a lag of the
    /// sensor does to the outputs of a nearly linear device.
    pub delays_the_command: bool,
    /// What the neutral value of the family's magnitude is, for its confidence interval.
    pub magnitude: Magnitude,
    /// The screening probes of every form, at the model `params` and the peak command \[V\]
    /// (book/src/diagnose.md, "Screening").
    pub probes: fn(&Params, f64) -> Vec<Probe>,
    /// The experiment that exposes the family (book/src/diagnose.md, "The decision rule").
    pub exposing: Exposing,
    /// The family hidden in a form unlike its library term, for synthetic data.
    pub hidden: Plant,
    /// Further hidden forms, by name (their names are hidden cases of the CLI).
    pub variants: &'static [(&'static str, Plant)],
    /// The family's fitted law at the model `params`, drawn over commands up to the peak
    /// command \[V\] where its variable is the command (book/src/diagnose.md, "The fitted
    /// law"); `None` for a family whose forms are its textbook terms (`no_law`) and for a
    /// form of the family the law does not describe (charge_drift's series stage).
    pub law: fn(&Params, f64) -> Option<FittedLaw>,
}

/// The `law` of a family whose forms are its textbook terms (delay, preload): nothing to draw.
pub fn no_law(_: &Params, _: f64) -> Option<FittedLaw> {
    None
}

/// A family's fitted law as the verdict shows it: its points against its variable, and the
/// textbook forms fitted to it with how far each lies.
#[derive(Clone, Debug, PartialEq)]
pub struct FittedLaw {
    /// The law and its fitted values, in words.
    pub what: String,
    /// Names and units of the points' two coordinates.
    pub axes: [&'static str; 2],
    pub points: Vec<(f64, f64)>,
    /// How the distance to a textbook form is measured, in words.
    pub distance: &'static str,
    /// The textbook forms fitted to the law, fewest parameters first.
    pub textbook: Vec<Textbook>,
    /// The one the law is nearest to: an index into `textbook` (see `nearest`).
    pub nearest: usize,
}

/// A textbook form fitted to a law.
#[derive(Clone, Debug, PartialEq)]
pub struct Textbook {
    pub name: &'static str,
    /// Its fitted values, in words.
    pub values: String,
    /// The form on the law's axes where it has a curve there (drawn beside the law), else empty.
    pub points: Vec<(f64, f64)>,
    /// How far the law lies from it (see [`FittedLaw::distance`]).
    pub distance: f64,
}

/// One form of a family: the parameters it frees (its magnitude first) and the settings that
/// select it (book/src/effects.md, each family's "Forms").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Form {
    pub effect: Effect,
    pub name: &'static str,
    pub free: &'static [&'static str],
    /// The parameters that switch the form on, any one of which is enough: its first free
    /// parameter, or each of interchangeable ones (the two stages of a second-order amplifier,
    /// the weights of the creep's spectrum), of which a fit may leave any near 0.
    pub magnitudes: &'static [&'static str],
    /// Parameters set to select the form, never fitted (e.g. `drift_site`).
    pub settings: &'static [(&'static str, f64)],
    /// Two magnitudes the outputs are symmetric in (two linear stages in cascade, whose order
    /// the outputs cannot see), or none: at equal values their sensitivities are one column,
    /// and a refit started there leaves them equal but for rounding.
    pub exchangeable: Option<(&'static str, &'static str)>,
    /// The form of the family this one refines: the same change of the outputs to first order
    /// in its magnitudes (a second stage, to first order in the times, is a longer first one),
    /// so the screening's linear projection cannot rank the two, however it scores them.
    pub refines: Option<&'static str>,
}

impl Form {
    /// A form whose first free parameter is its magnitude.
    pub const fn new(
        effect: Effect,
        name: &'static str,
        free: &'static [&'static str],
        settings: &'static [(&'static str, f64)],
    ) -> Form {
        Form {
            effect,
            name,
            free,
            magnitudes: free.split_at(1).0,
            settings,
            exchangeable: None,
            refines: None,
        }
    }

    /// The library form of `effect`.
    pub fn library(effect: Effect) -> &'static Form {
        &effect.forms()[0]
    }

    /// Is this the family's library form?
    pub fn is_library(&self) -> bool {
        self.name == self.effect.forms()[0].name
    }
}

/// The neutral value of a family's magnitude.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Magnitude {
    /// A positive magnitude, off at 0 (fitted in log coordinates).
    Positive,
    /// Magnitudes of either sign, off at 0; any one away from 0 is enough.
    Signed,
    /// A limit, off above the largest command (a limit above it clips nothing).
    Limit,
}

/// Effect parameter settings that switch a form of a family on, each giving one direction in
/// output space; several settings of one probe span a subspace (the preload's three torques,
/// the coupling's three pairs, the weights of the creep's spectrum).
pub struct Probe {
    pub form: &'static Form,
    pub columns: Vec<Vec<(&'static str, f64)>>,
    pub scaling: Scaling,
}

impl Probe {
    /// A probe of one setting, scaled as a positive magnitude, with the form's own settings.
    pub fn one(form: &'static Form, settings: Vec<(&'static str, f64)>) -> Probe {
        Probe {
            form,
            columns: vec![[settings, form.settings.to_vec()].concat()],
            scaling: Scaling::Magnitude,
        }
    }

    /// One column of `form`, its values kept as they are (a limit, whose change does not scale
    /// with any of its values).
    pub fn fixed(form: &'static Form, values: Vec<(&'static str, f64)>) -> Probe {
        Probe {
            form,
            columns: vec![[values, form.settings.to_vec()].concat()],
            scaling: Scaling::Fixed,
        }
    }
}

/// How a probe's first setting (its magnitude) becomes a start value.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Scaling {
    /// A positive magnitude, scaled by the projection coefficient (within ×/÷ 5).
    Magnitude,
    /// A magnitude of either sign, scaled by the coefficient.
    Signed,
    /// A limit (U_max, a slew rate): the probe's values are kept, and it is worth what it
    /// explains as it is.
    Fixed,
    /// Non-negative weights of a series (the creep's spectrum), column j switching weight j on
    /// alone: the start is each column's value times its coefficient of the non-negative least
    /// squares, 0 where that is 0, and the form's worth counts only the weights above 0.
    Weights,
    /// The coupling's pairs: column j switches pair j on alone at k_c; the start is
    /// k_c c_12 with the weights c_13 / c_12 and c_23 / c_12 (all kept positive).
    Pairs,
}

/// The experiment that exposes a family, at commands up to a peak U.
pub struct Exposing {
    /// What to do and why it exposes the family, in words.
    pub text: &'static str,
    pub drive: Drive,
    /// The record's length \[s\].
    pub t_end: f64,
}

/// A command of an exposing experiment, scaled to the peak command U.
pub enum Drive {
    /// Piecewise linear through (t \[s\], share of U) corners, the same on every actuator.
    Corners(&'static [(f64, f64)]),
    /// A sine of amplitude U at ω [rad/s] on the first actuator alone.
    Alone { omega: f64 },
    /// On every actuator, tones at these ω [rad/s], each of amplitude U/4, at the paper's
    /// phase of the actuator plus the tone's index.
    Multisine(&'static [f64]),
    /// A sine at ω [rad/s] on every actuator, of amplitude U/2 before `switch` \[s\] and U after.
    Levels { omega: f64, switch: f64 },
}

/// Plants a family's hidden form in `params`, its values drawn by `between(lo, hi)`.
pub type Plant = fn(&mut Params, &mut dyn FnMut(f64, f64) -> f64) -> Planted;

/// A planted mechanism.
pub struct Planted {
    /// The mechanism and its values, in words.
    pub text: String,
    /// A transport delay the data generator applies to the command, wandering around its mean
    /// as no parameter can: (mean \[s\], phase of the wander).
    pub wandering_delay: Option<(f64, f64)>,
}

impl Planted {
    pub fn text(text: String) -> Planted {
        Planted {
            text,
            wandering_delay: None,
        }
    }
}

/// A value drawn log-uniformly in [lo, hi] by `between`.
pub fn log_between(between: &mut dyn FnMut(f64, f64) -> f64, lo: f64, hi: f64) -> f64 {
    between(lo.ln(), hi.ln()).exp()
}

/// The mean bending stiffness Kb of the three actuators [N m/rad]: the scale of the
/// mechanical families' probes and hidden magnitudes.
pub fn mean_kb(params: &Params) -> f64 {
    params.act.iter().map(|a| a.kb).sum::<f64>() / 3.0
}

/// A textbook form within this distance of the closest, with fewer parameters, is the one named
/// nearest a law (a share of the law's scale).
const NEAREST_TOLERANCE: f64 = 0.01;

/// The textbook form named nearest a law: of the forms within [`NEAREST_TOLERANCE`] of the
/// closest, the one of fewest parameters (they come fewest first).
pub fn nearest(textbook: &[Textbook]) -> usize {
    let best = textbook
        .iter()
        .map(|k| k.distance)
        .fold(f64::INFINITY, f64::min);
    textbook
        .iter()
        .position(|k| k.distance <= best + NEAREST_TOLERANCE)
        .unwrap_or(0)
}

/// A textbook form to fit beside a law drawn as a curve: its name, its fitted values in words,
/// and its function of the law's variable.
pub type TextbookForm = (&'static str, String, Box<dyn Fn(f64) -> f64>);

impl FittedLaw {
    /// A law drawn as the curve `points` of its variable, beside textbook forms given as
    /// (name, fitted values, the form's function of the same variable), fewest parameters first;
    /// each form's distance is its RMS difference from the law over the points, relative to the
    /// law's RMS.
    pub fn of_curve(
        what: String,
        axes: [&'static str; 2],
        points: Vec<(f64, f64)>,
        forms: Vec<TextbookForm>,
    ) -> FittedLaw {
        let rms = |v: &mut dyn Iterator<Item = f64>| {
            let (s, n) = v.fold((0.0, 0), |(s, n), x| (s + x * x, n + 1));
            (s / n.max(1) as f64).sqrt()
        };
        let scale = rms(&mut points.iter().map(|p| p.1)).max(f64::MIN_POSITIVE);
        let textbook: Vec<Textbook> = forms
            .into_iter()
            .map(|(name, values, f)| {
                let drawn: Vec<(f64, f64)> = points.iter().map(|&(x, _)| (x, f(x))).collect();
                let diff = &mut drawn.iter().zip(&points).map(|(a, b)| a.1 - b.1);
                Textbook {
                    name,
                    values,
                    distance: rms(diff) / scale,
                    points: drawn,
                }
            })
            .collect();
        FittedLaw {
            what,
            axes,
            points,
            distance: "RMS difference over the drawn curve, relative to the law's RMS",
            nearest: nearest(&textbook),
            textbook,
        }
    }
}

/// The best non-negative multiple c of the shape `g` for the points of `curve` by least squares,
/// and its sum of squared errors: a textbook form's scale fitted to a law.
pub fn scaled_to(curve: &[(f64, f64)], g: &dyn Fn(f64) -> f64) -> (f64, f64) {
    let (gy, gg) = curve.iter().fold((0.0, 0.0), |(a, b), &(x, y)| {
        (a + g(x) * y, b + g(x) * g(x))
    });
    let c = if gg > 0.0 { (gy / gg).max(0.0) } else { 0.0 };
    let sse: f64 = curve.iter().map(|&(x, y)| (c * g(x) - y).powi(2)).sum();
    (c, sse)
}

/// Points of a law on [lo, hi], where it is drawn and compared.
pub fn sampled(lo: f64, hi: f64, f: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
    const POINTS: usize = 201;
    (0..POINTS)
        .map(|k| {
            let x = lo + (hi - lo) * k as f64 / (POINTS - 1) as f64;
            (x, f(x))
        })
        .collect()
}

/// The minimum of `cost` over [lo, hi] (lo > 0) in ln x: a textbook form's one scale fitted to
/// a law. A grid first (the cost of a clamp is flat wherever it clips nothing, where a
/// golden-section search alone drifts), then a golden-section search between the best point's
/// neighbours.
pub fn golden(lo: f64, hi: f64, cost: impl Fn(f64) -> f64) -> f64 {
    const GRID: usize = 64;
    let at = |k: usize| lo.ln() + (hi / lo).ln() * k as f64 / (GRID - 1) as f64;
    let best = (0..GRID)
        .min_by(|&i, &j| cost(at(i).exp()).total_cmp(&cost(at(j).exp())))
        .unwrap_or(0);
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (at(best.saturating_sub(1)), at((best + 1).min(GRID - 1)));
    let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
    let (mut fc, mut fd) = (cost(c.exp()), cost(d.exp()));
    while b - a > 1e-6 {
        if fc < fd {
            (b, d, fd) = (d, c, fc);
            c = b - r * (b - a);
            fc = cost(c.exp());
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + r * (b - a);
            fd = cost(d.exp());
        }
    }
    (0.5 * (a + b)).exp()
}

/// min |A x − b| over x ≥ 0, by Lawson and Hanson's active set: the weights of a non-negative
/// series (a creep's spectrum, its screening's start).
pub fn nonnegative_least_squares(a: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    let n = a.ncols();
    let mut x = DVector::zeros(n);
    let mut passive = vec![false; n];
    let tol = 1e-12 * a.norm() * b.norm();
    // each pass frees one coefficient; the inner loop drops the ones its solve makes negative
    for _ in 0..3 * n {
        let w = a.transpose() * (b - a * &x);
        let Some(j) = (0..n)
            .filter(|&j| !passive[j] && w[j] > tol)
            .max_by(|&i, &j| w[i].total_cmp(&w[j]))
        else {
            break;
        };
        passive[j] = true;
        // each inner pass sets one coefficient back to 0 (bounded: rounding must not spin it)
        for _ in 0..n {
            let idx: Vec<usize> = (0..n).filter(|&j| passive[j]).collect();
            let Some(svd) = bounded_svd(a.select_columns(&idx)) else {
                return x;
            };
            let z = svd.solve(b, 1e-12).expect("U and V were computed");
            if z.iter().all(|&v| v > 0.0) {
                for (k, &j) in idx.iter().enumerate() {
                    x[j] = z[k];
                }
                break;
            }
            // toward z as far as every coefficient stays ≥ 0; the one that reaches 0 leaves
            let alpha = idx
                .iter()
                .zip(z.iter())
                .filter(|&(_, &zk)| zk <= 0.0)
                .map(|(&j, &zk)| x[j] / (x[j] - zk))
                .fold(1.0f64, f64::min);
            for (k, &j) in idx.iter().enumerate() {
                x[j] += alpha * (z[k] - x[j]);
                if z[k] <= 0.0 && x[j] <= 1e-14 * x.amax().max(f64::MIN_POSITIVE) {
                    x[j] = 0.0;
                    passive[j] = false;
                }
            }
            if idx.iter().all(|&j| !passive[j]) {
                break;
            }
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nonnegative_least_squares_drops_what_would_be_negative() {
        // b = 2 a0 + 1 a1 exactly; a2 would take a negative share of the rest
        let a = DMatrix::from_row_slice(
            4,
            3,
            &[1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.5, 0.0, 1.0],
        );
        let b = &a.column(0) * 2.0 + a.column(1);
        let x = nonnegative_least_squares(&a, &b.into_owned());
        assert!(
            (x[0] - 2.0).abs() < 1e-12 && (x[1] - 1.0).abs() < 1e-12 && x[2] == 0.0,
            "{x}"
        );
        // against every column: 0
        let x = nonnegative_least_squares(&a, &DVector::from_element(4, -1.0));
        assert!(x.iter().all(|&v| v == 0.0), "{x}");
        // the unconstrained solution has a negative coefficient: held at 0, the rest refitted
        let b = &a.column(0) * 1.0 - &a.column(2) * 0.5;
        let x = nonnegative_least_squares(&a, &b.into_owned());
        assert!(x[2] == 0.0 && x[0] > 0.0, "{x}");
    }
}
