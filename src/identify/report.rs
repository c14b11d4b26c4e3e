//! What `hasel identify` writes: `identification.json`, `fitted.toml` (a parameter file for
//! `hasel simulate` and `hasel fmu`), and `report.md` with its figures.

use std::fmt::Write as _;
use std::path::Path;

use serde_json::{Value, json};

use super::conditions::{Found, LAG_MAX};
use super::experiment::{Channel, Experiment, Weighting};
use super::{ExperimentFit, Identification};
use crate::io::file::{FileError, write_text_atomic};
use crate::io::params_file;
use crate::plot::{self, Panel, Series};
use crate::simulation::Sample;

/// Fits per experiment and output, to 0.01 points: `{experiment: {output: fit}}`.
pub(crate) fn fits_json(fits: &[ExperimentFit]) -> Value {
    Value::Object(
        fits.iter()
            .map(|f| {
                (
                    f.experiment.clone(),
                    Value::Object(
                        f.fits
                            .iter()
                            .map(|(c, v)| (c.clone(), json!(round(*v, 2))))
                            .collect(),
                    ),
                )
            })
            .collect(),
    )
}

/// `v` rounded to `digits` decimals, for the reports' JSON.
pub(crate) fn round(v: f64, digits: i32) -> f64 {
    let m = 10f64.powi(digits);
    (v * m).round() / m
}

/// The contents of `identification.json`.
pub fn to_json(id: &Identification) -> Value {
    let parameters: serde_json::Map<String, Value> = id
        .estimates
        .iter()
        .map(|e| {
            (
                e.name.clone(),
                json!({
                    "value": e.value,
                    "prior": e.prior,
                    "free": e.free,
                    "estimated": e.estimated,
                    "std_error": e.std_error,
                    "ci95": e.ci95.map(|(a, b)| [a, b]),
                }),
            )
        })
        .collect();
    let (names, corr) = &id.correlation;
    json!({
        "parameters": parameters,
        "not_identifiable": id.not_identifiable.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>(),
        "not_identifiable_reasons": id.not_identifiable.iter().map(|(n, r)| (n.clone(), json!(r))).collect::<serde_json::Map<_, _>>(),
        "held_combinations": id.held_combinations.iter().map(|dir| dir.iter().map(|(n, w)| (n.clone(), json!(round(*w, 4)))).collect::<serde_json::Map<_, _>>()).collect::<Vec<_>>(),
        "fit": { "estimation": fits_json(&id.estimation), "validation": fits_json(&id.validation) },
        "fit_before": { "estimation": fits_json(&id.estimation_before) },
        "correlation": {
            "parameters": names,
            "matrix": (0..names.len()).map(|r| (0..names.len()).map(|c| round(corr[(r, c)], 4)).collect::<Vec<_>>()).collect::<Vec<_>>(),
        },
        // full precision, for drawing parameter sets (`hasel simulate --uncertainty`)
        "covariance": {
            "parameters": id.covariance.names,
            "coordinates": id.covariance.log.iter().map(|&l| if l { "ln" } else { "linear" }).collect::<Vec<_>>(),
            "matrix": (0..id.covariance.names.len()).map(|r| (0..id.covariance.names.len()).map(|c| id.covariance.matrix[(r, c)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
        },
        "conditions": conditions_json(&id.conditions),
        "weighting": id.weighting.name(),
        "iterations": id.iterations,
        "simulations": id.simulations,
        "seconds": round(id.seconds, 3),
    })
}

/// Each record's conditions (book/src/identify.md, "Records that start mid-run"): how its
/// start was set, the heights there [µm], the sensor's lag and its standard error [ms].
pub(crate) fn conditions_json(found: &[Found]) -> Value {
    Value::Array(
        found
            .iter()
            .map(|f| {
                json!({
                    "experiment": f.experiment,
                    "start": f.start_how,
                    "start_heights_um": f.heights.map(|h| round(h * 1e6, 3)),
                    "sensor_lag_ms": round(f.conditions.lag * 1e3, 4),
                    "sensor_lag_se_ms": f.lag_se.map(|s| round(s * 1e3, 4)),
                })
            })
            .collect(),
    )
}

/// The section on the records' conditions, where they were estimated.
pub(crate) fn conditions_section(md: &mut String, found: &[Found]) {
    if found.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "
## How the records were taken

Estimated beside the model, as properties of the experiment (a lag within 0–{} ms is the sensor's):

| experiment | start | heights at the first sample [µm] | sensor lag [ms] |
|---|---|---|---|",
        LAG_MAX * 1e3
    );
    for f in found {
        let lag = match f.lag_se {
            Some(se) => format!("{:.3} ± {:.3}", f.conditions.lag * 1e3, 1.96 * se * 1e3),
            None => format!("{:.3} (stated)", f.conditions.lag * 1e3),
        };
        let _ = writeln!(
            md,
            "| {} | {} | {:.2} / {:.2} / {:.2} | {lag} |",
            f.experiment,
            f.start_how,
            f.heights[0] * 1e6,
            f.heights[1] * 1e6,
            f.heights[2] * 1e6
        );
    }
}

/// The residual (measured − simulated) of channel `c` over time \[µm\], as dots.
pub fn residual_series(
    exp: &Experiment,
    c: Channel,
    sim: &[Sample],
    label: &str,
    color: usize,
) -> Series {
    let y = exp.measured(c).unwrap_or(&[]);
    Series {
        label: label.into(),
        points: exp
            .t
            .iter()
            .zip(y)
            .zip(sim)
            .map(|((t, v), s)| (*t, (v - c.of(s)) * 1e6))
            .collect(),
        color,
        dots: true,
    }
}

/// Measured against simulated outputs of one experiment, the tip path, and the residuals.
fn experiment_panels(exp: &Experiment, sim: &[Sample], label: &str) -> Vec<Panel> {
    let um = 1e6;
    let mut panels = Vec::new();
    let mut measured_sim = Vec::new();
    let mut residuals = Vec::new();
    for (k, (c, y)) in exp.channels.iter().enumerate() {
        if *c == Channel::Tip(2) {
            continue;
        }
        measured_sim.push(Series {
            label: format!("{} measured", c.name()),
            points: exp.t.iter().zip(y).map(|(t, v)| (*t, v * um)).collect(),
            color: 3,
            dots: true,
        });
        measured_sim.push(Series {
            label: format!("{} {label}", c.name()),
            points: exp
                .t
                .iter()
                .zip(sim)
                .map(|(t, s)| (*t, c.of(s) * um))
                .collect(),
            color: k,
            dots: false,
        });
        residuals.push(residual_series(exp, *c, sim, c.name(), k));
    }
    panels.push(Panel {
        title: format!("{}: measured and {label}", exp.name),
        x_label: "t [s]".into(),
        y_label: "[um]".into(),
        series: measured_sim,
        equal_axes: false,
    });
    if let (Some(x), Some(y)) = (exp.measured(Channel::Tip(0)), exp.measured(Channel::Tip(1))) {
        panels.push(Panel {
            title: "Tip path".into(),
            x_label: "tip x [um]".into(),
            y_label: "tip y [um]".into(),
            series: vec![
                Series {
                    label: "measured".into(),
                    points: x.iter().zip(y).map(|(a, b)| (a * um, b * um)).collect(),
                    color: 3,
                    dots: true,
                },
                Series {
                    label: label.into(),
                    points: sim.iter().map(|s| (s.tip[0] * um, s.tip[1] * um)).collect(),
                    color: 0,
                    dots: false,
                },
            ],
            equal_axes: true,
        });
    }
    panels.push(Panel {
        title: "Residuals (measured - simulated)".into(),
        x_label: "t [s]".into(),
        y_label: "[um]".into(),
        series: residuals,
        equal_axes: false,
    });
    panels
}

fn fit_table(out: &mut String, title: &str, fits: &[ExperimentFit]) {
    let _ = writeln!(
        out,
        "\n**{title}**\n\n| experiment | output | fit [%] |\n|---|---|---|"
    );
    for f in fits {
        for (c, v) in &f.fits {
            let _ = writeln!(out, "| {} | {c} | {v:.2} |", f.experiment);
        }
    }
}

/// Writes `identification.json`, `fitted.toml`, `report.md` and the figures into `dir`.
pub fn write(
    dir: &Path,
    id: &Identification,
    estimation: &[Experiment],
    validation: &[Experiment],
) -> Result<(), FileError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| FileError::new(dir, format!("cannot create folder: {e}")))?;
    let mut md = String::from("# Identification report\n\n");
    let _ = writeln!(
        md,
        "Levenberg–Marquardt on the simulation error, {}: {} iterations, {} simulations, \
         {:.2} s. Estimation on {}; validation on {}.",
        match id.weighting {
            Weighting::Equal => "each output in its own unit",
            Weighting::Noise => "each output in units of the noise its record shows",
        },
        id.iterations,
        id.simulations,
        id.seconds,
        estimation
            .iter()
            .map(|e| e.name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        if validation.is_empty() {
            "none".into()
        } else {
            validation
                .iter()
                .map(|e| e.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        }
    );
    let _ = writeln!(
        md,
        "\n## Parameters\n\n| parameter | start | estimate | std. error | 95 % interval |\n|---|---|---|---|---|"
    );
    for e in id.estimates.iter().filter(|e| e.estimated) {
        let (lo, hi) = e.ci95.expect("estimated parameters have an interval");
        let _ = writeln!(
            md,
            "| {} | {:.5} | {:.5} | {:.2e} | [{:.5}, {:.5}] |",
            e.name,
            e.prior,
            e.value,
            e.std_error.unwrap_or(0.0),
            lo,
            hi
        );
    }
    if !id.not_identifiable.is_empty() {
        let _ = writeln!(
            md,
            "\nNot determined by these data, held at the start value:\n"
        );
        for (n, reason) in &id.not_identifiable {
            let _ = writeln!(md, "- `{n}`: {reason}");
        }
    }
    let _ = writeln!(
        md,
        "\nIntervals assume white measurement noise; correlated residuals make them too narrow."
    );
    conditions_section(&mut md, &id.conditions);
    let _ = writeln!(md, "\n## Fits (NRMSE, MATLAB `compare`)");
    fit_table(
        &mut md,
        "Estimation data, start parameters",
        &id.estimation_before,
    );
    fit_table(&mut md, "Estimation data, fitted", &id.estimation);
    if !validation.is_empty() {
        fit_table(&mut md, "Validation data, fitted", &id.validation);
    }
    let _ = writeln!(md, "\n## Figures\n");
    for (k, (exp, sim)) in estimation
        .iter()
        .chain(validation)
        .zip(&id.simulated)
        .enumerate()
    {
        let file = format!("fit_{k}.png");
        let panels = experiment_panels(exp, sim, "fitted");
        plot::draw(
            &dir.join(&file),
            &panels,
            panels.len(),
            (560 * panels.len() as u32, 480),
        )?;
        let role = if k < estimation.len() {
            "estimation"
        } else {
            "validation"
        };
        let _ = writeln!(md, "![{} ({role})]({file})\n", exp.name);
    }
    let json = serde_json::to_string_pretty(&to_json(id)).expect("JSON of plain values");
    write_text_atomic(&dir.join("identification.json"), &(json + "\n"))?;
    params_file::write(&dir.join("fitted.toml"), &id.params)?;
    write_text_atomic(&dir.join("report.md"), &md)
}
