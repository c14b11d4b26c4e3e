//! `hasel bench --diagnose`: the missing-effect workflow on data with hidden mechanisms (each
//! effect of the library in another form, no effect, a mechanism outside the library, two
//! effects at once), two 6 s experiments at 1 ms each or a lab protocol drawn per case,
//! optionally recorded as lab data (artifacts on top); prints every case, the confusion matrix
//! by family, the evidence weight of the hidden family, the held-out fits against the noise
//! floor, the spurious effects (named beside every hidden one), the share of two-effect cases
//! with both named and where the time goes.

use std::collections::BTreeMap;

use hasel_fmu::diagnose::hidden::{self, Truth};
use hasel_fmu::diagnose::{self, Options, Verdict};
use hasel_fmu::identify::synth::Columns;
use hasel_fmu::model::{Effect, Params};

use crate::error::Error;

/// Is `d` the answer the case expects: its effect, both effects of a pair in either order,
/// `none` without one, `unexplained` outside the library.
fn right(t: Truth, d: &diagnose::Diagnosis) -> bool {
    match t {
        Truth::Nothing => d.verdict == Verdict::None,
        Truth::Outside | Truth::Ripple => d.verdict == Verdict::Unexplained,
        _ => {
            let (mut want, mut got) = (t.effects(), d.effects.clone());
            want.sort();
            got.sort();
            d.verdict == Verdict::Effect && got == want
        }
    }
}

/// The hidden families of a case, as the confusion matrix rows them: the family, both of a
/// pair, `none`, or `outside` for a mechanism outside every family.
fn hidden_families(t: Truth) -> String {
    match t {
        Truth::Nothing => "none".into(),
        Truth::Outside | Truth::Ripple => "outside".into(),
        _ => {
            let mut names: Vec<&str> = t.effects().iter().map(|e| e.name()).collect();
            names.sort();
            names.join("+")
        }
    }
}

/// The evidence weight of the hidden family in the round that added it, or else in the first
/// that refitted it (a family that took an earlier one's place on a revisit), 0 where none did.
fn confidence(effect: Effect, d: &diagnose::Diagnosis) -> f64 {
    let weight = |r: &diagnose::Round| {
        r.evidence
            .iter()
            .find(|(e, _)| *e == Some(effect))
            .map(|e| e.1)
    };
    d.rounds
        .iter()
        .find(|r| r.added == Some(effect))
        .and_then(weight)
        .or_else(|| d.rounds.iter().find_map(weight))
        .unwrap_or(0.0)
}

/// The largest distance of a held-out fit below its noise floor \[points\].
fn worst_gap(d: &diagnose::Diagnosis) -> f64 {
    let (first, fits) = d.last.held_out();
    let floors = &d.fits.floor[first..];
    floors
        .iter()
        .zip(fits)
        .flat_map(|(floor, f)| {
            f.fits
                .iter()
                .filter_map(|(name, v)| floor.get(name).map(|floor| floor - v))
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

pub fn run(
    seeds: std::ops::RangeInclusive<u64>,
    columns: Columns,
    only: Option<String>,
    artifacts: bool,
    protocols: bool,
    reports: Option<std::path::PathBuf>,
    opts: Options,
) -> Result<(), Error> {
    say!(
        "diagnosis of hidden mechanisms: {} seed(s) per case ({}-{}), {columns:?} data{}, {}, simulated at rtol {:e}, target <= 30 s per diagnosis, median <= 5 s (issue #29)",
        seeds.clone().count(),
        seeds.start(),
        seeds.end(),
        if artifacts {
            " with lab artifacts (sensor lag, resolution, outliers, dropouts)"
        } else {
            ""
        },
        if protocols {
            "a lab protocol drawn per case"
        } else {
            "two 6 s experiments at 1 ms (3pi and 11 rad/s)"
        },
        opts.rtol
    );
    let mut tally = Tally::default();
    for truth in Truth::all() {
        // `--only coupling` runs every single case of the family, `--only coupling_tilt` one,
        // `--only two` every two-mechanism case
        let pair = matches!(truth, Truth::Two(_));
        if only.as_deref().is_some_and(|o| {
            o != truth.name()
                && truth.effect().is_none_or(|e| e.name() != o)
                && !(pair && o == "two")
        }) {
            continue;
        }
        for seed in seeds.clone() {
            let mut case = hidden::hide(truth, seed)?;
            if artifacts {
                case = case.with_artifacts(seed);
            }
            let mut protocol = "sines".to_string();
            if protocols {
                case = case.in_drawn_protocol(seed);
                protocol = case.protocol_label();
            }
            let exps = case.experiments(columns, seed)?;
            let d = diagnose::diagnose(&Params::default(), exps.clone(), &opts)?;
            if let Some(dir) = &reports {
                diagnose::report::write(&dir.join(format!("{}-{seed}", truth.name())), &d)?;
            }
            let got = d.answer();
            let ok = right(truth, &d);
            let seconds = d.timing.last().map_or(0.0, |t| t.1);
            let gap = worst_gap(&d);
            // a miss, or the right effects short of the floor: how near the truth comes
            let short = !ok || gap > diagnose::AT_FLOOR;
            let truth_gaps = match case.true_model() {
                Some(model) if short && !truth.effects().is_empty() => {
                    Some(diagnose::truth_gaps(&model, exps, &opts)?)
                }
                _ => None,
            };
            let weight = tally.count(truth, seed, &d, &protocol, (ok, seconds, gap), truth_gaps);
            let truth_gap = truth_gaps.map_or(String::new(), |g| {
                format!(
                    " | truth held {:.2}, refitted {:.2} below floor",
                    g.held, g.refitted
                )
            });
            let (before, after) = (&d.fits.before, &d.fits.after);
            let single = d.after.len() == 1;
            let floor: Vec<String> = d
                .after
                .iter()
                .filter(|x| single || x.experiment != d.estimation)
                .map(|x| format!("{:.1}", 100.0 * x.excess))
                .collect();
            let forms: Vec<&str> = d.forms.iter().map(|f| f.name).collect();
            say!(
                "  {:<26} seed {seed}: {:<28} {} {:5.1} s | {protocol}{weight}{truth_gap} | held-out fit {} -> {} | {gap:.2} below floor | excess after {} % | {} outlier(s) | {}",
                truth.name(),
                format!("{got} [{}]", forms.join("+")),
                if ok { "ok  " } else { "MISS" },
                seconds,
                fmt_fits(before),
                fmt_fits(after),
                floor.join("/"),
                d.outliers.iter().map(|o| o.times.len()).sum::<usize>(),
                case.description
            );
            say_rounds(&d);
            *tally
                .matrix
                .entry((hidden_families(truth), got))
                .or_default() += 1;
        }
    }
    tally.say(protocols);
    Ok(())
}

/// What the cases so far came to, for the closing lines.
#[derive(Default)]
struct Tally {
    times: Vec<f64>,
    spurious: usize,
    /// Effect cases named exactly: (worst held-out gap to the noise floor, case, its truth's
    /// gaps where the gap is beyond `AT_FLOOR`).
    gaps: Vec<(f64, String, Option<diagnose::TruthGaps>)>,
    matrix: BTreeMap<(String, String), usize>,
    /// The right family's evidence weight on each single-mechanism case.
    confidences: Vec<f64>,
    right_cases: usize,
    effect_cases: usize,
    effect_right: usize,
    pair_cases: usize,
    pair_right: usize,
    total: usize,
    slowest: f64,
    stages: BTreeMap<String, f64>,
    /// Per protocol (its drive, and whether recorded mid-run): (right, cases).
    by_protocol: BTreeMap<String, (usize, usize)>,
    /// Misses whose true model, refitted as a diagnosis fits, leaves a held-out fit beyond
    /// `FIT_TOLERANCE`: (case, its truth's gaps, the answer, whether a pair).
    beyond_truth: Vec<(String, diagnose::TruthGaps, String, bool)>,
}

impl Tally {
    /// Counts the diagnosis `d` of the case hiding `truth` (drawn from `seed`, recorded in
    /// `protocol`): whether it is right, its time and its worst held-out gap; returns the hidden
    /// family's evidence weight as the case's line shows it, if any. `truth_gaps`, where the
    /// case's truth was checked: a miss beyond its reach is counted apart.
    fn count(
        &mut self,
        truth: Truth,
        seed: u64,
        d: &diagnose::Diagnosis,
        protocol: &str,
        (ok, seconds, gap): (bool, f64, f64),
        truth_gaps: Option<diagnose::TruthGaps>,
    ) -> String {
        let pair = matches!(truth, Truth::Two(_));
        self.slowest = self.slowest.max(seconds);
        self.times.push(seconds);
        let mut weight = String::new();
        // an effect named beside every hidden one, a third beside a pair as a second beside one
        let hidden = truth.effects();
        let all_named = !hidden.is_empty() && hidden.iter().all(|e| d.effects.contains(e));
        self.spurious += (all_named && d.effects.len() > hidden.len()) as usize;
        if let Some(e) = truth.effect() {
            self.confidences.push(confidence(e, d));
            weight = format!(" | weight {:.3}", confidence(e, d));
        }
        let case = format!("{} seed {seed}", truth.name());
        if ok && !truth.effects().is_empty() {
            self.gaps.push((gap, case.clone(), truth_gaps));
        }
        if let Some(g) = truth_gaps.filter(|g| !ok && g.refitted > diagnose::FIT_TOLERANCE) {
            self.beyond_truth.push((case, g, d.answer(), pair));
        }
        for (stage, s) in &d.timing {
            let key = stage.split(" (round").next().unwrap_or(stage).to_string();
            *self.stages.entry(key).or_default() += s;
        }
        self.total += 1;
        self.right_cases += ok as usize;
        let score = self.by_protocol.entry(protocol.to_string()).or_default();
        score.0 += ok as usize;
        score.1 += 1;
        if pair {
            self.pair_cases += 1;
            self.pair_right += ok as usize;
        } else if truth.effect().is_some() {
            self.effect_cases += 1;
            self.effect_right += ok as usize;
        }
        weight
    }

    /// The closing lines: the confusion matrix, the evidence weights, the scores against
    /// their targets, the times, and with `protocols` the score per protocol.
    fn say(self, protocols: bool) {
        let Tally {
            mut times,
            spurious,
            mut gaps,
            matrix,
            mut confidences,
            right_cases,
            effect_cases,
            effect_right,
            pair_cases,
            pair_right,
            total,
            slowest,
            stages,
            by_protocol,
            beyond_truth,
        } = self;
        say!("confusion by family (hidden -> answer: count)");
        for ((t, a), n) in &matrix {
            say!("  {t:<26} -> {a:<28} {n}");
        }
        confidences.sort_by(f64::total_cmp);
        if let (Some(low), Some(median)) =
            (confidences.first(), confidences.get(confidences.len() / 2))
        {
            say!(
                "evidence weight of the hidden family (single mechanisms): median {median:.3}, lowest {low:.3}, >= 0.95 in {}/{}",
                confidences.iter().filter(|&&w| w >= 0.95).count(),
                confidences.len()
            );
        }
        times.sort_by(f64::total_cmp);
        let typical = times.get(times.len() / 2).copied().unwrap_or(0.0);
        say!(
            "right: {right_cases}/{total}; effect named exactly: {effect_right}/{effect_cases} (target >= 95 %); spurious effects beside the hidden ones: {spurious} (target 0)"
        );
        if pair_cases > 0 {
            say!(
                "two mechanisms, both named: {pair_right}/{pair_cases} ({:.0} %, target >= 85 %)",
                100.0 * pair_right as f64 / pair_cases as f64
            );
        }
        if !beyond_truth.is_empty() {
            let why = |g: &diagnose::TruthGaps| {
                if g.held > diagnose::FIT_TOLERANCE {
                    "even held, its start mid-run is not found"
                } else {
                    "the estimation record does not determine it"
                }
            };
            say!(
                "misses beyond the truth's reach: {} (the hidden model itself, fitted as a diagnosis fits the paper's model, leaves a held-out fit more than {} point below the noise floor): {}",
                beyond_truth.len(),
                diagnose::FIT_TOLERANCE,
                beyond_truth
                    .iter()
                    .map(|(c, g, a, _)| format!(
                        "{c} {:.2} points ({}), answered {a}",
                        g.refitted,
                        why(g)
                    ))
                    .collect::<Vec<_>>()
                    .join("; ")
            );
            let pairs = beyond_truth.iter().filter(|u| u.3).count();
            say!(
                "within the truth's reach: right {right_cases}/{}, effect named exactly {effect_right}/{}, both of two named {pair_right}/{}",
                total - beyond_truth.len(),
                effect_cases - (beyond_truth.len() - pairs),
                pair_cases - pairs
            );
        }
        gaps.sort_by(|a, b| b.0.total_cmp(&a.0));
        let floor = diagnose::AT_FLOOR;
        let within = gaps.iter().filter(|g| g.0 <= floor).count();
        say!(
            "held-out fit after the right effect(s) within {floor} points of the noise floor: {within}/{}{}",
            gaps.len(),
            gaps.first()
                .map(|(g, c, _)| format!("; farthest {g:.2} points below ({c})"))
                .unwrap_or_default()
        );
        let short: Vec<String> = gaps
            .iter()
            .filter(|g| g.0 > floor)
            .map(|(g, c, t)| {
                t.map_or(format!("{c} {g:.2} (no model truth)"), |t| {
                    format!(
                        "{c} {g:.2} (its truth held {:.2}, refitted {:.2})",
                        t.held, t.refitted
                    )
                })
            })
            .collect();
        if !short.is_empty() {
            say!(
                "  beyond {floor} points, with how far below the floor the hidden model itself leaves them: {}",
                short.join("; ")
            );
        }
        say!(
            "time per diagnosis: median {typical:.1} s ({}), slowest {slowest:.1} s ({})",
            if typical <= 5.0 { "met" } else { "MISSED" },
            if slowest <= 30.0 { "met" } else { "MISSED" }
        );
        if protocols {
            say!("right per protocol:");
            for (p, (ok, n)) in &by_protocol {
                say!("  {p:<24} {ok}/{n}");
            }
        }
        say!("time by stage over all cases:");
        for (stage, s) in &stages {
            say!("  {stage:<40} {s:8.1} s");
        }
    }
}

fn fmt_fits(f: &BTreeMap<String, f64>) -> String {
    f.iter()
        .map(|(k, v)| format!("{k} {v:.1}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Each round's candidates (the refitted with their evidence, the others with their score)
/// and the revisits of earlier effects.
fn say_rounds(d: &diagnose::Diagnosis) {
    for r in &d.rounds {
        for c in &r.candidates {
            if let Some(f) = &c.refit {
                say!(
                    "      {:<13} {:<17} score {:.3} dBIC {:9.1} gain {:6.2} gap {:5.2} {}",
                    c.effect.name(),
                    diagnose::report::forms_cell(c),
                    c.score,
                    f.delta_bic,
                    f.fit_gain,
                    f.gap_closed,
                    if f.passes() {
                        "passes".to_string()
                    } else {
                        f.failed.join("; ")
                    }
                );
            } else {
                say!(
                    "      {:<13} {:<17} score {:.3}{}",
                    c.effect.name(),
                    c.form.name,
                    c.score,
                    c.refit_error
                        .as_ref()
                        .map(|e| format!(" refit failed: {e}"))
                        .unwrap_or_default()
                );
            }
        }
        for v in &r.revisits {
            say!(
                "      revisit {} against {}: {}",
                v.replaced.name(),
                v.by.map_or("nothing".into(), |f| format!(
                    "{} [{}]",
                    f.effect.name(),
                    f.name
                )),
                match (&v.delta_bic, v.swapped) {
                    (Ok(b), s) => format!("dBIC {b:.1}, {}", if s { "swapped" } else { "kept" }),
                    (Err(e), _) => format!("refit failed: {e}"),
                }
            );
        }
    }
}
