//! `diagnosis.json`, `report.md` with its figures, and `fitted.toml` (the model with the
//! named effects, ready for `hasel simulate` and `hasel fmu --params`).

use std::fmt::Write as _;
use std::path::Path;

use serde_json::{Map, Value, json};

use super::analysis::Disagreement;
use super::{Candidate, Diagnosis, Refit, Remaining, Round, Verdict};
use crate::identify::report::{
    conditions_json, conditions_section, fits_json, residual_series, round,
};
use crate::io::file::{FileError, write_text_atomic};
use crate::io::params_file;
use crate::model::Effect;
use crate::model::effects::FittedLaw;
use crate::plot::{self, Panel, Series};

fn candidate_json(c: &Candidate) -> Value {
    let mut v =
        json!({ "effect": c.effect.name(), "form": c.form.name, "score": round(c.score, 4) });
    if !c.forms_tried.is_empty() {
        v["forms_tried"] = c
            .forms_tried
            .iter()
            .map(|t| match &t.outcome {
                Ok((d, _)) => json!({"form": t.form.name, "delta_bic": round(*d, 1)}),
                Err(e) => json!({"form": t.form.name, "refit_error": e}),
            })
            .collect();
    }
    if let Some(r) = &c.refit {
        v["delta_bic"] = json!(round(r.delta_bic, 1));
        v["fit_gain"] = json!(round(r.fit_gain, 2));
        v["gap_closed"] = json!(round(r.gap_closed, 3));
        v["interval"] = r.interval.as_ref().map_or(
            Value::Null,
            |(n, lo, hi)| json!({"parameter": n, "ci95": [lo, hi]}),
        );
        if let Some((lr, quantile)) = r.likelihood_ratio {
            v["likelihood_ratio"] =
                json!({"statistic": round(lr, 1), "chi2_95": round(quantile, 2)});
        }
        v["passes"] = json!(r.passes());
        v["failed"] = json!(r.failed);
        v["iterations"] = json!(r.id.iterations);
        v["stopped_at_budget"] = json!(r.id.out_of_budget);
    } else if let Some(e) = &c.refit_error {
        v["refit_error"] = json!(e.to_string());
    } else {
        v["refit"] = json!("not refitted (lower screening score)");
    }
    v
}

fn disagreement_json(d: &Disagreement) -> Value {
    json!({
        "experiment": d.experiment,
        "output": d.channel.name(),
        "rms_um": round(d.rms * 1e6, 4),
        "noise_um": round(d.noise * 1e6, 4),
        "excess": round(d.excess, 4),
        "omega": round(d.omega, 4),
        "harmonics_um": d.harmonics.iter().map(|a| round(a * 1e6, 4)).collect::<Vec<_>>(),
        "drift_um": round(d.drift * 1e6, 4),
        "worst_window_s": [round(d.worst_window.0.0, 3), round(d.worst_window.0.1, 3)],
        "correlations": d.correlations.iter().map(|(n, c)| (n.clone(), json!(round(*c, 3)))).collect::<Map<_, _>>(),
        "off_harmonic": round(d.off_harmonic, 3),
    })
}

/// A fitted law drawn beside the textbook form nearest it, where that form has a curve on the
/// law's axes; a law of few points (a spectrum) as dots.
fn law_panel(effect: Effect, law: &FittedLaw) -> Panel {
    let mut series = vec![Series {
        label: "fitted".into(),
        points: law.points.clone(),
        color: 1,
        dots: law.points.len() <= TABLED_POINTS,
    }];
    let near = &law.textbook[law.nearest];
    if !near.points.is_empty() {
        series.push(Series {
            label: format!("{} {}", near.name, near.values),
            points: near.points.clone(),
            color: 0,
            dots: false,
        });
    }
    Panel {
        title: format!("{}: the fitted law", effect.name()),
        x_label: law.axes[0].into(),
        y_label: law.axes[1].into(),
        series,
        equal_axes: false,
    }
}

/// Where a remaining disagreement lies, in words.
fn where_it_remains(r: &Remaining) -> String {
    let d = &r.disagreement;
    let (k, a) = d
        .harmonics
        .iter()
        .enumerate()
        .fold((0, 0.0), |m, (k, &a)| if a > m.1 { (k, a) } else { m });
    let at = if k == 0 {
        "as an offset".to_string()
    } else {
        format!("at {k} x the drive ({:.1} rad/s)", k as f64 * d.omega)
    };
    format!(
        "{} on {}: {:.2} points below the noise floor; largest component {:.3} um {at}, drift {:.3} um, worst in {:.2}-{:.2} s, {:.0} % of the structured residual off the drive's harmonics",
        d.channel.name(),
        d.experiment,
        r.gap,
        a * 1e6,
        d.drift * 1e6,
        d.worst_window.0.0,
        d.worst_window.0.1,
        100.0 * d.off_harmonic
    )
}

/// The JSON of book/src/diagnose.md ("diagnosis.json"), and the evidence behind it.
pub fn to_json(d: &Diagnosis) -> Value {
    let effect_params: Map<String, Value> = d
        .forms
        .iter()
        .flat_map(|f| f.free.iter())
        .filter_map(|name| {
            let e = d.last.estimates.iter().find(|e| e.name == *name)?;
            Some((name.to_string(), json!({"value": e.value, "ci95": e.ci95.map(|(a, b)| vec![a, b]), "estimated": e.estimated})))
        })
        .collect();
    let as_map = |f: &std::collections::BTreeMap<String, f64>| -> Map<String, Value> {
        f.iter()
            .map(|(k, v)| (k.clone(), json!(round(*v, 2))))
            .collect()
    };
    json!({
        "verdict": d.verdict.name(),
        "effects": d.effects.iter().map(|e| e.name()).collect::<Vec<_>>(),
        "forms": d.forms.iter().map(|f| f.name).collect::<Vec<_>>(),
        "laws": laws_json(d),
        "ambiguous_between": d.ambiguous_between.iter().map(|e| e.name()).collect::<Vec<_>>(),
        "separating_experiment": d.separating_experiment,
        "separation": d.separation.iter().map(|s| json!({
            "experiment_exposing": s.effect.name(),
            "output": s.channel.name(),
            "difference_um": round(s.difference * 1e6, 4),
            "noise_um": round(s.noise * 1e6, 4),
            "separates": s.separates(),
        })).collect::<Vec<_>>(),
        "fit_before": as_map(&d.fits.before),
        "fit_after": as_map(&d.fits.after),
        "noise_floor_fit": as_map(&d.fits.held_out_floor),
        "fits_on": "held-out experiments",
        "candidates": d.rounds.first().map(|r| r.candidates.iter().map(candidate_json).collect::<Vec<_>>()).unwrap_or_default(),
        "rounds": d.rounds.iter().map(round_json).collect::<Vec<_>>(),
        "parameters": effect_params,
        "estimation": d.estimation,
        "held_out": d.held_out,
        "fits": {
            "before": { "estimation": fits_json(&d.base.estimation), "held_out": fits_json(&d.base.validation) },
            "after": { "estimation": fits_json(&d.last.estimation), "held_out": fits_json(&d.last.validation) },
        },
        "disagreement_before": d.before.iter().map(disagreement_json).collect::<Vec<_>>(),
        "disagreement_after": d.after.iter().map(disagreement_json).collect::<Vec<_>>(),
        "remaining": d.fits.remaining.iter().map(|r| json!({
            "experiment": r.disagreement.experiment,
            "output": r.disagreement.channel.name(),
            "below_noise_floor": round(r.gap, 2),
            "where": where_it_remains(r),
        })).collect::<Vec<_>>(),
        "conditions": conditions_json(&d.base.conditions),
        "outliers": d.outliers.iter().map(|o| json!({
            "experiment": o.experiment,
            "output": o.channel.name(),
            "count": o.times.len(),
            "times_s": o.times.iter().map(|t| round(*t, 4)).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "timing_s": d.timing.iter().map(|(s, t)| (s.clone(), json!(round(*t, 2)))).collect::<Map<_, _>>(),
    })
}

/// Each named effect's fitted law: its points and the textbook laws nearest it.
fn laws_json(d: &Diagnosis) -> Vec<Value> {
    d.effects
        .iter()
        .zip(&d.laws)
        .filter_map(|(e, law)| {
            let law = law.as_ref()?;
            Some(json!({
                "effect": e.name(),
                "what": law.what,
                "axes": law.axes,
                "points": law.points.iter().map(|&(x, y)| [x, y]).collect::<Vec<_>>(),
                "nearest": law.textbook[law.nearest].name,
                "distance": law.distance,
                "textbook": law.textbook.iter().map(|k| json!({
                    "name": k.name,
                    "values": k.values,
                    "distance": round(k.distance, 4),
                })).collect::<Vec<_>>(),
            }))
        })
        .collect()
}

/// One round of the search: the model it started from, what it added, its candidates, their
/// evidence weights and the revisits.
fn round_json(r: &Round) -> Value {
    json!({
        "effects_before": r.effects_before.iter().map(|e| e.name()).collect::<Vec<_>>(),
        "added": r.added.map(|e| e.name()),
        "added_form": r.added_form.map(|f| f.name),
        "provisional": r.provisional.map(|p| json!({
            "effect": p.form.effect.name(),
            "form": p.form.name,
            "kept": p.kept,
        })),
        "candidates": r.candidates.iter().map(candidate_json).collect::<Vec<_>>(),
        "evidence": r.evidence.iter().map(|(e, w)| json!({
            "effect": e.map_or("none", |e| e.name()),
            "weight": w,
        })).collect::<Vec<_>>(),
        "revisits": r.revisits.iter().map(|v| {
            let mut j = json!({
                "replaced": v.replaced.name(),
                "by": v.by.map(|f| f.effect.name()),
                "by_form": v.by.map(|f| f.name),
                "tied": v.tied,
                "swapped": v.swapped,
            });
            match &v.delta_bic {
                Ok(b) => j["delta_bic"] = json!(b),
                Err(e) => j["refit_error"] = json!(e),
            }
            j
        }).collect::<Vec<_>>(),
    })
}

/// One sentence on the answer.
fn headline(d: &Diagnosis) -> String {
    let names = |v: &[Effect]| {
        v.iter()
            .map(|e| format!("`{}` ({})", e.name(), e.mechanism()))
            .collect::<Vec<_>>()
            .join(", then ")
    };
    match d.verdict {
        Verdict::Effect => format!(
            "The missing effect: {}.",
            d.forms
                .iter()
                .map(|f| format!(
                    "`{}` in the form `{}` ({})",
                    f.effect.name(),
                    f.name,
                    f.effect.mechanism()
                ))
                .collect::<Vec<_>>()
                .join(", then ")
        ),
        Verdict::None => "No missing effect: the paper's model, re-identified, explains the data to the noise floor.".into(),
        Verdict::Ambiguous => format!(
            "Ambiguous: {} explain the data equally well. The experiment that tells them apart: {}.",
            names(&d.ambiguous_between),
            d.separating_experiment.as_deref().unwrap_or("")
        ),
        Verdict::Unexplained => "Unexplained: the disagreement is structured, beyond the noise, but no effect of the library explains it.".into(),
    }
}

fn disagreement_table(md: &mut String, ds: &[Disagreement]) {
    let _ = writeln!(
        md,
        "| experiment | output | residual RMS [um] | noise [um] | excess over noise | mean [um] | 1st / 2nd / 3rd harmonic [um] | drift [um] | worst window [s] | strongest correlation | off-harmonic share |\n|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for d in ds {
        let strongest = d
            .correlations
            .iter()
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .map(|(n, c)| format!("{n} {c:+.2}"))
            .unwrap_or_default();
        let h = |k: usize| d.harmonics.get(k).map_or(0.0, |a| a * 1e6);
        let _ = writeln!(
            md,
            "| {} | {} | {:.3} | {:.3} | {:.0} % | {:.3} | {:.3} / {:.3} / {:.3} | {:.3} | {:.2}–{:.2} | {} | {:.0} % |",
            d.experiment,
            d.channel.name(),
            d.rms * 1e6,
            d.noise * 1e6,
            100.0 * d.excess,
            h(0),
            h(1),
            h(2),
            h(3),
            d.drift * 1e6,
            d.worst_window.0.0,
            d.worst_window.0.1,
            strongest,
            100.0 * d.off_harmonic
        );
    }
}

/// The candidate's form, and the ΔBIC of every form refitted when there were several.
pub fn forms_cell(c: &Candidate) -> String {
    if c.forms_tried.len() < 2 {
        return format!("`{}`", c.form.name);
    }
    let tried: Vec<String> = c
        .forms_tried
        .iter()
        .map(|t| match &t.outcome {
            Ok((d, _)) => format!("{} ΔBIC {d:.1}", t.form.name),
            Err(e) => format!("{} failed: {e}", t.form.name),
        })
        .collect();
    format!("`{}` (of {})", c.form.name, tried.join(", "))
}

/// Where a refit was judged before it converged: its fit stopped at the iteration budget, so
/// its ΔBIC bounds the form's from above.
fn budget_note(r: &Refit) -> String {
    if r.id.out_of_budget {
        format!(" (stopped at the budget, {} iterations)", r.id.iterations)
    } else {
        String::new()
    }
}

/// A round's evidence weights in words, the model without a further effect as "no effect".
fn evidence_line(evidence: &[(Option<Effect>, f64)]) -> String {
    evidence
        .iter()
        .map(|(e, w)| format!("{} {:.3}", e.map_or("no effect", |e| e.name()), w))
        .collect::<Vec<_>>()
        .join(", ")
}

fn candidates_table(md: &mut String, cs: &[Candidate]) {
    let _ = writeln!(
        md,
        "| effect | form | screening score | ΔBIC (estimation) | held-out fit gain [points] | held-out gap closed | magnitude, 95 % interval | evidence |\n|---|---|---|---|---|---|---|---|"
    );
    for c in cs {
        match (&c.refit, &c.refit_error) {
            (Some(r), _) => {
                let interval = match (&r.interval, r.likelihood_ratio) {
                    (_, Some((lr, quantile))) => format!(
                        "held beside a base parameter; likelihood ratio {lr:.1} against the neutral value (95 %: {quantile:.1})"
                    ),
                    (Some((n, lo, hi)), None) => format!("{n} in [{lo:.4e}, {hi:.4e}]"),
                    (None, None) => "not determined".to_string(),
                };
                let _ = writeln!(
                    md,
                    "| {} | {} | {:.3} | {:.1}{} | {:+.2} | {:.0} % | {} | {} |",
                    c.effect.name(),
                    forms_cell(c),
                    c.score,
                    r.delta_bic,
                    budget_note(r),
                    r.fit_gain,
                    100.0 * r.gap_closed,
                    interval,
                    if r.passes() {
                        "passes every test".to_string()
                    } else {
                        r.failed.join("; ")
                    }
                );
            }
            (None, Some(e)) => {
                let _ = writeln!(
                    md,
                    "| {} | {} | {:.3} | | | | | refit failed: {e} |",
                    c.effect.name(),
                    forms_cell(c),
                    c.score
                );
            }
            (None, None) => {
                let _ = writeln!(
                    md,
                    "| {} | {} | {:.3} | | | | | not refitted (lower score) |",
                    c.effect.name(),
                    c.form.name,
                    c.score
                );
            }
        }
    }
}

/// Measured, before and after for each output of one experiment, and the residuals.
/// A law of at most this many points is tabled in the report (a spectrum); a longer one is a
/// curve, drawn.
const TABLED_POINTS: usize = 24;

/// The fitted law of each named effect that has one: its points, and the textbook forms with
/// how far each lies, the nearest first.
fn laws_section(md: &mut String, d: &Diagnosis) {
    for (e, law) in d.effects.iter().zip(&d.laws) {
        let Some(law) = law else { continue };
        let near = &law.textbook[law.nearest];
        let _ = writeln!(
            md,
            "## The fitted law of `{}`\n\n{}: nearest the textbook form **{}** ({}), {:.1} % away ({}).\n\n| {} | {} |\n|---|---|",
            e.name(),
            law.what,
            near.name,
            near.values,
            100.0 * near.distance,
            law.distance,
            law.axes[0],
            law.axes[1]
        );
        if law.points.len() <= TABLED_POINTS {
            for (x, y) in &law.points {
                let _ = writeln!(md, "| {x:.3} | {y:.4e} |");
            }
        } else {
            let _ = writeln!(
                md,
                "| … | {} points in report.json, drawn below |",
                law.points.len()
            );
        }
        let _ = writeln!(
            md,
            "\n| textbook form | fitted values | distance |\n|---|---|---|"
        );
        for k in &law.textbook {
            let _ = writeln!(
                md,
                "| {} | {} | {:.1} % |",
                k.name,
                k.values,
                100.0 * k.distance
            );
        }
        let _ = writeln!(md);
    }
}

fn figure(d: &Diagnosis, k: usize) -> Vec<Panel> {
    let um = 1e6;
    let exp = &d.experiments[k];
    let (before, after) = (&d.base.simulated[k], &d.last.simulated[k]);
    exp.channels
        .iter()
        .flat_map(|(c, y)| {
            let line = |label: &str, sim: &[crate::simulation::Sample], color| Series {
                label: label.into(),
                points: exp
                    .t
                    .iter()
                    .zip(sim)
                    .map(|(t, s)| (*t, c.of(s) * um))
                    .collect(),
                color,
                dots: false,
            };
            let resid = |label: &str, sim: &[crate::simulation::Sample], color| {
                residual_series(exp, *c, sim, label, color)
            };
            [
                Panel {
                    title: format!(
                        "{} {}: measured, paper's model, with effect",
                        exp.name,
                        c.name()
                    ),
                    x_label: "t [s]".into(),
                    y_label: "[um]".into(),
                    series: vec![
                        Series {
                            label: "measured".into(),
                            points: exp.t.iter().zip(y).map(|(t, v)| (*t, v * um)).collect(),
                            color: 3,
                            dots: true,
                        },
                        line("paper's model", before, 0),
                        line("with effect", after, 1),
                    ],
                    equal_axes: false,
                },
                Panel {
                    title: format!("{} {}: residuals before and after", exp.name, c.name()),
                    x_label: "t [s]".into(),
                    y_label: "[um]".into(),
                    series: vec![resid("before", before, 0), resid("after", after, 1)],
                    equal_axes: false,
                },
            ]
        })
        .collect()
}

fn fits_table(md: &mut String, d: &Diagnosis) {
    let _ = writeln!(
        md,
        "| experiment | role | output | paper's model [%] | with effect [%] | noise floor [%] |\n|---|---|---|---|---|---|"
    );
    let rows = d
        .base
        .estimation
        .iter()
        .chain(&d.base.validation)
        .zip(d.last.estimation.iter().chain(&d.last.validation));
    for (k, (b, a)) in rows.enumerate() {
        let role = if k == 0 { "estimation" } else { "held out" };
        for ((c, fb), (_, fa)) in b.fits.iter().zip(&a.fits) {
            let floor = d.fits.floor[k]
                .get(c)
                .map_or("".into(), |f| format!("{f:.2}"));
            let _ = writeln!(
                md,
                "| {} | {role} | {c} | {fb:.2} | {fa:.2} | {floor} |",
                b.experiment
            );
        }
    }
}

/// Writes `diagnosis.json`, `report.md`, its figures and `fitted.toml` into `dir`.
pub fn write(dir: &Path, d: &Diagnosis) -> Result<(), FileError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| FileError::new(dir, format!("cannot create folder: {e}")))?;
    let mut md = format!("# Diagnosis: {}\n\n{}\n\n", d.verdict.name(), headline(d));
    introduction(&mut md, d);
    let _ = writeln!(md, "## Where and how the paper's model disagreed\n");
    disagreement_table(&mut md, &d.before);
    let _ = writeln!(
        md,
        "\nExcess over noise: residual variance beyond the measurement noise (estimated from the samples' departures from their neighbours), relative to it; 0 % is the noise floor. Harmonics are of the drive frequency found in U1; the off-harmonic share is residual power neither at a harmonic nor slow.\n"
    );
    for (k, r) in d.rounds.iter().enumerate() {
        round_section(&mut md, k, r);
    }
    passing_rule(&mut md);
    if !d.effects.is_empty() {
        effects_section(&mut md, d);
    }
    laws_figure(dir, d, &mut md)?;
    let _ = writeln!(md, "## Fits before and after (NRMSE, MATLAB `compare`)\n");
    fits_table(&mut md, d);
    let _ = writeln!(md, "\n## Where the disagreement went\n");
    disagreement_table(&mut md, &d.after);
    if !d.fits.remaining.is_empty() {
        let _ = writeln!(md, "\n## What remains\n");
        for r in &d.fits.remaining {
            let _ = writeln!(md, "- {}", where_it_remains(r));
        }
    }
    conditions_section(&mut md, &d.base.conditions);
    outliers_section(&mut md, d);
    figures(dir, d, &mut md)?;
    let _ = writeln!(md, "## Time\n\n| stage | s |\n|---|---|");
    for (s, t) in &d.timing {
        let _ = writeln!(md, "| {s} | {t:.1} |");
    }
    let json = serde_json::to_string_pretty(&to_json(d)).expect("JSON of plain values");
    write_text_atomic(&dir.join("diagnosis.json"), &(json + "\n"))?;
    params_file::write(&dir.join("fitted.toml"), &d.last.params)?;
    write_text_atomic(&dir.join("report.md"), &md)
}

/// The report's opening lines: what was re-identified on which records, and what the
/// experiments that would separate two tied candidates would show.
fn introduction(md: &mut String, d: &Diagnosis) {
    let _ = writeln!(
        md,
        "The paper's model was re-identified (Kb, b, gamma1, gamma2 of each actuator) on `{}`; decisions use the held-out {}.\n",
        d.estimation,
        d.held_out
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for s in &d.separation {
        let _ = writeln!(
            md,
            "Simulated with both refitted models, the experiment exposing `{}` makes their {} differ by {:.3} µm RMS against a measurement noise of {:.3} µm: it {} them.\n",
            s.effect.name(),
            s.channel.name(),
            s.difference * 1e6,
            s.noise * 1e6,
            if s.separates() {
                "would separate"
            } else {
                "would not separate"
            }
        );
    }
}

/// One round of the search: its candidates, their evidence weights, what was added, and what
/// became of a provisional effect and of the earlier effects revisited.
fn round_section(md: &mut String, k: usize, r: &Round) {
    let _ = writeln!(
        md,
        "## Candidates, round {} (model with {})\n",
        k + 1,
        if r.effects_before.is_empty() {
            "no effect".to_string()
        } else {
            r.effects_before
                .iter()
                .map(|e| e.name())
                .collect::<Vec<_>>()
                .join(", ")
        }
    );
    candidates_table(md, &r.candidates);
    let _ = writeln!(
        md,
        "\nEvidence weights (Schwarz, from the estimation BIC): {}.",
        evidence_line(&r.evidence)
    );
    let _ = writeln!(
        md,
        "\n{}\n",
        match (r.added, r.added_form) {
            (Some(e), Some(f)) if !f.is_library() => format!(
                "Added: `{}` in the form `{}` (frees {}).",
                e.name(),
                f.name,
                f.free.join(", ")
            ),
            (Some(e), _) => format!("Added: `{}`, {}.", e.name(), e.form()),
            (None, _) if r.revisits.iter().any(|v| !v.tied && v.by.is_some_and(|f| f.effect == v.replaced)) => "Nothing added in this round, and the model still beyond its noise floor (the round ran for that): each earlier effect was tried in the forms of its family its round had not refitted (below).".into(),
            (None, _) if !r.revisits.is_empty() => "Nothing added in this round: its best candidate, failing only by leaving a held-out fit beyond the tolerance of its noise floor, was tried tentatively with the earlier effects revisited beside it (below), and none of them was replaced.".into(),
            (None, _) => "Nothing added in this round.".into(),
        }
    );
    if let Some(p) = r.provisional {
        let _ = writeln!(
            md,
            "No effect closes {:.0} % of the held-out gap: `{}` in the form `{}`, which closes at least {:.0} %, was added provisionally, to be kept only if the effects after it bring every held-out fit to within {} point(s) of its noise floor: {}.\n",
            100.0 * super::GAP_CLOSED,
            p.form.effect.name(),
            p.form.name,
            100.0 * super::PARTIAL_GAP,
            super::FIT_TOLERANCE,
            if p.kept {
                "kept"
            } else {
                "they did not, and it was dropped"
            }
        );
    }
    for v in &r.revisits {
        let against = match v.by {
            Some(f) if v.tied => format!(
                "its own family's form `{}`, which its round could not tell from the one chosen (within {} of BIC),",
                f.name,
                super::BIC_MARGIN
            ),
            Some(f) if f.effect == v.replaced => {
                format!(
                    "its own family's form `{}`, which its round had not refitted,",
                    f.name
                )
            }
            Some(f) => format!(
                "`{}` in the form `{}`, its round's runner-up,",
                f.effect.name(),
                f.name
            ),
            None => "the model without it".into(),
        };
        let tried = if v.by.is_none() && Some(v.replaced) == r.added {
            format!(
                "`{}`, this round's own, against the model without it, the earlier effects refitted from where the fit beside it put them",
                v.replaced.name()
            )
        } else {
            format!(
                "`{}` against {against} refitted beside the later effects",
                v.replaced.name()
            )
        };
        let _ = writeln!(
            md,
            "Revisited: {tried}: {}.\n",
            match (&v.delta_bic, v.swapped) {
                (Ok(b), true) if v.by.is_none() => format!("ΔBIC {b:.1}, dropped"),
                (Ok(b), true) if v.by.is_some_and(|f| f.effect == v.replaced) => {
                    format!("ΔBIC {b:.1}, the form takes the place of the one it had")
                }
                (Ok(b), true) => format!("ΔBIC {b:.1}, the runner-up takes its place"),
                (Ok(b), false) => format!("ΔBIC {b:.1}, kept"),
                (Err(e), _) => format!("the refit failed ({e}), kept"),
            }
        );
    }
}

/// The rule an effect must pass to be added, in words with the thresholds in force.
fn passing_rule(md: &mut String) {
    let _ = writeln!(
        md,
        "An effect passes when it lowers the BIC on the estimation data by more than {margin}, closes at least {:.0} % of the held-out gap to the noise floor, gains at least {gain} points of held-out fit (half the gap to the floor where that is less; a later effect only where it closes {:.0} % of that gap), and the 95 % interval of its magnitude excludes the neutral value. Of two that pass, the one with the lower BIC is added if it beats the other by {margin}, else the one with {gain} points more of held-out fit; otherwise the answer is `ambiguous`.\n",
        100.0 * super::GAP_CLOSED,
        100.0 * super::LATER_GAP_CLOSED,
        margin = super::BIC_MARGIN,
        gain = super::MIN_GAIN
    );
}

/// The named effects' parameters (estimate, 95 % interval) and their fitted laws.
fn effects_section(md: &mut String, d: &Diagnosis) {
    let _ = writeln!(
        md,
        "## The named effects and their parameters\n\n| effect | form | parameter | estimate | 95 % interval |\n|---|---|---|---|---|"
    );
    for f in &d.forms {
        let e = f.effect;
        let form = if f.is_library() {
            format!("`{}`: {}", f.name, e.form())
        } else {
            format!("`{}`", f.name)
        };
        for name in f.free {
            if let Some(est) = d.last.estimates.iter().find(|x| x.name == *name) {
                let ci = est
                    .ci95
                    .map_or("held (not determined)".to_string(), |(a, b)| {
                        format!("[{a:.4e}, {b:.4e}]")
                    });
                let _ = writeln!(
                    md,
                    "| {} | {} | {} | {:.4e} | {} |",
                    e.name(),
                    form,
                    name,
                    est.value,
                    ci
                );
            }
        }
    }
    let _ = writeln!(md);
    laws_section(md, d);
}

/// `laws.png`, a panel per named effect with a law to draw, and its link in the report.
fn laws_figure(dir: &Path, d: &Diagnosis, md: &mut String) -> Result<(), FileError> {
    let panels: Vec<Panel> = d
        .effects
        .iter()
        .zip(&d.laws)
        .filter_map(|(&e, law)| Some(law_panel(e, law.as_ref()?)))
        .collect();
    if !panels.is_empty() {
        plot::draw(
            &dir.join("laws.png"),
            &panels,
            panels.len(),
            (600 * panels.len() as u32, 400),
        )?;
        let _ = writeln!(md, "![the fitted laws](laws.png)\n");
    }
    Ok(())
}

/// The samples trimmed as outliers, per channel and experiment, if any.
fn outliers_section(md: &mut String, d: &Diagnosis) {
    if !d.outliers.is_empty() {
        let _ = writeln!(
            md,
            "\n## Outliers\n\nSamples departing from their neighbours by more than {} robust noise σ were trimmed (their rows left out of every fit):\n",
            super::analysis::OUTLIER_SIGMAS
        );
        for o in &d.outliers {
            let _ = writeln!(
                md,
                "- {} on {}: {} at {}",
                o.channel.name(),
                o.experiment,
                o.times.len(),
                o.times
                    .iter()
                    .map(|t| format!("{t:.3} s"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
}

/// `diagnosis_k.png`, one figure per experiment, and their links in the report.
fn figures(dir: &Path, d: &Diagnosis, md: &mut String) -> Result<(), FileError> {
    let _ = writeln!(md, "\n## Figures\n");
    for k in 0..d.experiments.len() {
        let file = format!("diagnosis_{k}.png");
        let panels = figure(d, k);
        let rows = panels.len() / 2;
        plot::draw(
            &dir.join(&file),
            &panels,
            2,
            (1200, 330 * rows.max(1) as u32),
        )?;
        let _ = writeln!(md, "![{}]({file})\n", d.experiments[k].name);
    }
    Ok(())
}
