//! Many simulations of drawn parameter sets on all cores, and the median and 2.5/97.5 % bands of
//! every output at every output time.

use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::{Posterior, SampleError, UncertaintyError};
use crate::io::csv::Table;
use crate::io::file::write_text_atomic;
use crate::model::Platform;
use crate::plot::{self, Band, Panel, Series};
use crate::simulation::{Input, Simulator};

/// The outputs of the study, as in the FMU.
pub const OUTPUTS: [&str; 6] = ["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"];

/// The probabilities of the bands' edges and middle.
const LOWER: f64 = 0.025;
const MEDIAN: f64 = 0.5;
const UPPER: f64 = 0.975;

/// The most memory the kept outputs of a study may take [bytes].
const MAX_BYTES: f64 = 8e9;

/// How a study runs.
#[derive(Clone, Debug)]
pub struct Settings {
    pub samples: usize,
    pub seed: u64,
    /// Worker threads (at least 1).
    pub threads: usize,
    pub t_end: f64,
    /// Output interval \[s\].
    pub dt: f64,
    pub rtol: f64,
}

/// What a study gives.
#[derive(Clone, Debug)]
pub struct Bands {
    pub t: Vec<f64>,
    /// Per time: the inputs.
    pub u: Vec<[f64; 3]>,
    /// Per time and output ([`OUTPUTS`]): 2.5 % quantile, median, 97.5 % quantile.
    pub lower: Vec<[f64; 6]>,
    pub median: Vec<[f64; 6]>,
    pub upper: Vec<[f64; 6]>,
    /// The parameter sets drawn, by sample index: the estimated parameters' values
    /// ([`Posterior::names`]).
    pub draws: Vec<Vec<f64>>,
    /// Samples whose draw or simulation failed, with the reason; left out of the bands.
    pub failed: Vec<(usize, SampleError)>,
}

/// The quantile `p` of sorted `v` (linear between order statistics: numpy's default).
pub fn quantile(v: &[f64], p: f64) -> f64 {
    let h = (v.len() - 1) as f64 * p;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(v.len() - 1);
    v[lo] + (h - lo as f64) * (v[hi] - v[lo])
}

/// One sample: its parameter values and outputs per time.
fn one(
    posterior: &Posterior,
    input: &Input,
    s: &Settings,
    index: usize,
) -> (Vec<f64>, Result<Vec<[f64; 6]>, SampleError>) {
    let values = posterior.values_at(&posterior.draw_coordinates(s.seed, index as u64));
    let run = || -> Result<Vec<[f64; 6]>, SampleError> {
        let params = posterior.params_at(&values)?;
        let model = Platform::new(params)?;
        let mut sim = Simulator::new(model, 0.0, s.rtol)?;
        let mut out = Vec::new();
        sim.run(input, s.t_end, s.dt, |p| {
            out.push([p.h[0], p.h[1], p.h[2], p.tip[0], p.tip[1], p.tip[2]])
        })?;
        Ok(out)
    };
    let outcome = run();
    (values, outcome)
}

/// Runs `settings.samples` draws of `posterior` through `input` on `settings.threads` threads,
/// calling `progress` after each sample. The result depends on the seed and not on the number
/// of threads: sample k's parameters come from (seed, k) alone, and the quantiles are taken
/// over the samples in index order.
pub fn run(
    posterior: &Posterior,
    input: &Input,
    settings: &Settings,
    progress: &(dyn Fn() + Sync),
) -> Result<Bands, UncertaintyError> {
    let s = settings;
    if s.samples < 2 {
        return Err(UncertaintyError::Setting(format!(
            "--samples {}: need at least 2 for bands",
            s.samples
        )));
    }
    if !(s.t_end.is_finite() && s.t_end > 0.0) {
        return Err(UncertaintyError::Setting(format!(
            "--t-end {}: must be > 0",
            s.t_end
        )));
    }
    if !(s.dt.is_finite() && s.dt > 0.0) {
        return Err(UncertaintyError::Setting(format!(
            "--dt {}: must be > 0",
            s.dt
        )));
    }
    // every sample's outputs are kept for the quantiles: refuse what memory cannot hold
    let times = (s.t_end / s.dt * (1.0 + 1e-12)).floor() + 1.0;
    let bytes = times * s.samples as f64 * (OUTPUTS.len() * 8) as f64;
    if bytes > MAX_BYTES {
        return Err(UncertaintyError::Setting(format!(
            "{} samples of {times} output times would keep {:.1} GB of outputs (at most {:.0} GB): \
             fewer samples, a shorter --t-end or a coarser --dt",
            s.samples,
            bytes / 1e9,
            MAX_BYTES / 1e9
        )));
    }
    // the time grid and inputs, as every sample's run has them
    let last = times as usize - 1;
    let t: Vec<f64> = (0..=last).map(|k| (k as f64 * s.dt).min(s.t_end)).collect();
    let u: Vec<[f64; 3]> = t.iter().map(|&ti| input.value(ti)).collect();

    type Outcome = (Vec<f64>, Result<Vec<[f64; 6]>, SampleError>);
    let results: Mutex<Vec<Option<Outcome>>> = Mutex::new(vec![None; s.samples]);
    let next = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for _ in 0..s.threads.clamp(1, s.samples) {
            scope.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    if k >= s.samples {
                        break;
                    }
                    let outcome = one(posterior, input, s, k);
                    if let Ok(mut r) = results.lock() {
                        r[k] = Some(outcome);
                    }
                    progress();
                }
            });
        }
    });
    let results = results
        .into_inner()
        .map_err(|_| UncertaintyError::Setting("a sample's thread failed".into()))?;

    let mut draws = Vec::with_capacity(s.samples);
    let mut failed = Vec::new();
    let mut ok: Vec<Vec<[f64; 6]>> = Vec::new();
    for (k, r) in results.into_iter().enumerate() {
        let (values, outcome) = r.unwrap_or((Vec::new(), Err(SampleError::NotRun)));
        draws.push(values);
        match outcome {
            Ok(out) if out.len() == t.len() => ok.push(out),
            Ok(out) => failed.push((
                k,
                SampleError::ShortRun {
                    got: out.len(),
                    expected: t.len(),
                },
            )),
            Err(e) => failed.push((k, e)),
        }
    }
    if let (true, Some((sample, reason))) = (ok.is_empty(), failed.first().cloned()) {
        return Err(UncertaintyError::AllFailed {
            samples: s.samples,
            sample,
            reason,
        });
    }
    let (mut lower, mut median, mut upper) = (
        vec![[0.0; 6]; t.len()],
        vec![[0.0; 6]; t.len()],
        vec![[0.0; 6]; t.len()],
    );
    let mut column = vec![0.0; ok.len()];
    for k in 0..t.len() {
        for j in 0..OUTPUTS.len() {
            for (c, out) in column.iter_mut().zip(&ok) {
                *c = out[k][j];
            }
            column.sort_by(f64::total_cmp);
            lower[k][j] = quantile(&column, LOWER);
            median[k][j] = quantile(&column, MEDIAN);
            upper[k][j] = quantile(&column, UPPER);
        }
    }
    Ok(Bands {
        t,
        u,
        lower,
        median,
        upper,
        draws,
        failed,
    })
}

impl Bands {
    /// The header of the bands CSV: `t,U1,U2,U3`, then per output `_p2.5`, `_median`, `_p97.5`.
    pub fn header() -> Vec<String> {
        let mut h: Vec<String> = ["t", "U1", "U2", "U3"].map(String::from).to_vec();
        for o in OUTPUTS {
            h.extend([
                format!("{o}_p2.5"),
                format!("{o}_median"),
                format!("{o}_p97.5"),
            ]);
        }
        h
    }

    /// The bands as CSV text, every number in the shortest form that reads back to the same
    /// bits.
    pub fn to_csv(&self) -> String {
        let mut text = Self::header().join(",");
        text.push('\n');
        for k in 0..self.t.len() {
            let mut row = vec![self.t[k]];
            row.extend(self.u[k]);
            for j in 0..OUTPUTS.len() {
                row.extend([self.lower[k][j], self.median[k][j], self.upper[k][j]]);
            }
            text.push_str(&join(&row));
            text.push('\n');
        }
        text
    }

    /// The drawn parameter sets as CSV: `sample`, then every parameter of the identification
    /// (the estimated ones as drawn, the rest at their value), so each row is a complete
    /// parameter set for the FMU. Failed samples are marked in `failed` (1) with their reason
    /// left to the command's report.
    fn draws_csv(&self, posterior: &Posterior) -> String {
        let all: Vec<&'static str> = crate::model::params::parameters().map(|d| d.name).collect();
        let mut text = format!("sample,failed,{}\n", all.join(","));
        for (k, values) in self.draws.iter().enumerate() {
            let mut p = posterior.center.clone();
            for (name, v) in posterior.names.iter().zip(values) {
                // a value a parameter's rule refuses stays at the center: its sample failed
                let _ = p.set(name, *v);
            }
            let failed = self.failed.iter().any(|(i, _)| *i == k);
            let row: Vec<f64> = all.iter().map(|n| p.get(n).unwrap_or(f64::NAN)).collect();
            text.push_str(&format!("{k},{},{}\n", u8::from(failed), join(&row)));
        }
        text
    }

    /// Writes the bands CSV.
    pub fn write_csv(&self, path: &Path) -> Result<(), UncertaintyError> {
        write_text_atomic(path, &self.to_csv()).map_err(|e| UncertaintyError::Output(e.to_string()))
    }

    /// Writes the drawn parameter sets.
    pub fn write_draws(&self, path: &Path, posterior: &Posterior) -> Result<(), UncertaintyError> {
        write_text_atomic(path, &self.draws_csv(posterior))
            .map_err(|e| UncertaintyError::Output(e.to_string()))
    }

    /// The figure: per output (those `data` measures, else all), the median with its 95 % band
    /// and the measured values of `data` (a table with columns named as the outputs) above,
    /// and below the same less the median, where a band narrower than the signal shows.
    /// Returns the panels, their bands, and the number of columns.
    pub fn panels(&self, data: Option<&Table>) -> (Vec<Panel>, Vec<Vec<Band>>, usize) {
        let um = 1e6;
        let measured = |name: &str| data.and_then(|d| Some((d, d.find("t")?, d.find(name)?)));
        let shown: Vec<usize> = if OUTPUTS.iter().any(|o| measured(o).is_some()) {
            (0..OUTPUTS.len())
                .filter(|&j| measured(OUTPUTS[j]).is_some())
                .collect()
        } else {
            (0..OUTPUTS.len()).collect()
        };
        let (mut top, mut top_bands, mut bottom, mut bottom_bands) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for &j in &shown {
            let name = OUTPUTS[j];
            let median_at = |t: f64| {
                // the median at a measured time: the output grid's nearest point
                let k = self.t.partition_point(|&x| x < t).min(self.t.len() - 1);
                let k = if k > 0 && (t - self.t[k - 1]).abs() < (self.t[k] - t).abs() {
                    k - 1
                } else {
                    k
                };
                ((self.t[k] - t).abs() <= 1e-9 * t.abs().max(1.0)).then_some(self.median[k][j])
            };
            let line = |shift: bool| Series {
                label: "median".into(),
                points: self
                    .t
                    .iter()
                    .zip(&self.median)
                    .map(|(t, m)| (*t, if shift { 0.0 } else { m[j] * um }))
                    .collect(),
                color: 1,
                dots: false,
            };
            let band = |shift: bool| Band {
                label: "95 % band".into(),
                points: (0..self.t.len())
                    .map(|k| {
                        let m = if shift { self.median[k][j] } else { 0.0 };
                        (
                            self.t[k],
                            (self.lower[k][j] - m) * um,
                            (self.upper[k][j] - m) * um,
                        )
                    })
                    .collect(),
                color: 1,
            };
            let mut series = vec![line(false)];
            let mut deviations = vec![line(true)];
            if let Some((table, ct, cy)) = measured(name) {
                series.push(Series {
                    label: "measured".into(),
                    points: table.rows.iter().map(|r| (r[ct], r[cy] * um)).collect(),
                    color: 3,
                    dots: true,
                });
                deviations.push(Series {
                    label: "measured - median".into(),
                    points: table
                        .rows
                        .iter()
                        .filter_map(|r| Some((r[ct], (r[cy] - median_at(r[ct])?) * um)))
                        .collect(),
                    color: 3,
                    dots: true,
                });
            }
            top.push(Panel {
                title: format!("{name}: median and 95 % band"),
                x_label: "t [s]".into(),
                y_label: format!("{name} [um]"),
                series,
                equal_axes: false,
            });
            top_bands.push(vec![band(false)]);
            bottom.push(Panel {
                title: format!("{name} less the median"),
                x_label: "t [s]".into(),
                y_label: format!("{name} - median [um]"),
                series: deviations,
                equal_axes: false,
            });
            bottom_bands.push(vec![band(true)]);
        }
        let columns = shown.len();
        top.extend(bottom);
        top_bands.extend(bottom_bands);
        (top, top_bands, columns)
    }

    /// Draws the figure of [`Bands::panels`].
    pub fn draw(&self, path: &Path, data: Option<&Table>) -> Result<(), UncertaintyError> {
        let (panels, bands, columns) = self.panels(data);
        plot::draw_with_bands(path, &panels, &bands, columns, (480 * columns as u32, 820))
            .map_err(|e| UncertaintyError::Output(e.to_string()))
    }
}

/// Numbers joined by commas, each in Rust's shortest round-trip form.
fn join(row: &[f64]) -> String {
    row.iter()
        .map(|v| format!("{v:e}"))
        .collect::<Vec<_>>()
        .join(",")
}
