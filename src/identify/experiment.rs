//! Measured experiments (book/src/identify.md, "Measured data files"): CSV with `t`,
//! `U1..U3` (the voltages as commanded) and any of `h1..h3`, `tip_x`, `tip_y`, `tip_z`. One file
//! is one experiment; a bad file gets an error naming the file, the line and the column.

use std::path::{Path, PathBuf};

use super::fit::noise_level;
use crate::io::csv::Table;
use crate::io::file::FileError;
use crate::simulation::{Input, Interpolation, Sample, Start};

/// A measured output channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Channel {
    H(usize),
    Tip(usize),
}

impl Channel {
    pub const ALL: [Channel; 6] = [
        Channel::H(0),
        Channel::H(1),
        Channel::H(2),
        Channel::Tip(0),
        Channel::Tip(1),
        Channel::Tip(2),
    ];

    /// The column name, as in the FMU's outputs.
    pub fn name(self) -> &'static str {
        match self {
            Channel::H(i) => ["h1", "h2", "h3"][i],
            Channel::Tip(i) => ["tip_x", "tip_y", "tip_z"][i],
        }
    }

    /// This channel's value in a simulated sample.
    pub fn of(self, s: &Sample) -> f64 {
        match self {
            Channel::H(i) => s.h[i],
            Channel::Tip(i) => s.tip[i],
        }
    }
}

/// How a fit counts each channel's residuals (book/src/identify.md, "How `hasel identify`
/// estimates").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Weighting {
    /// In each channel's own unit, as the paper fits.
    #[default]
    Equal,
    /// Each channel over the measurement noise its record shows ([`noise_level`]): residuals
    /// in units of noise, so that a quiet channel counts by what its noise allows and one
    /// pooled variance describes them all (what `hasel diagnose`'s BIC assumes).
    Noise,
}

impl Weighting {
    /// As `hasel identify --weigh` takes it and its report says it.
    pub fn name(self) -> &'static str {
        match self {
            Weighting::Equal => "equal",
            Weighting::Noise => "noise",
        }
    }

    /// The weighting named `name`, if any.
    pub fn from_name(name: &str) -> Option<Weighting> {
        [Weighting::Equal, Weighting::Noise]
            .into_iter()
            .find(|w| w.name() == name)
    }
}

/// The smallest noise a channel is taken to have, as a share of its spread: a record without
/// noise (a simulation) is weighed by its spread, not by its rounding.
const NOISE_FLOOR_SHARE: f64 = 1e-6;

/// Fewest samples and shortest duration an experiment may have: the slowest actuator settles
/// with a 0.42 s time constant, so a shorter record determines nothing.
const MIN_SAMPLES: usize = 50;
const MIN_DURATION: f64 = 1.0;

/// One experiment: its input and its measured channels at the sample times.
#[derive(Clone, Debug)]
pub struct Experiment {
    /// File name, the experiment's name in reports.
    pub name: String,
    pub path: PathBuf,
    pub t: Vec<f64>,
    /// The commanded voltages, replayed as a measured command: a spline through each smooth run
    /// of samples, held across a step (`Interpolation::Measured`).
    pub input: Input,
    pub channels: Vec<(Channel, Vec<f64>)>,
    /// Where the device stood at the first sample and the sensor's lag: the rest state and
    /// none as read, estimated by `identify::conditions`.
    pub conditions: Conditions,
    /// Samples before this one are a lead-in: the record's conditions are estimated on them
    /// alone, and they are not judged (book/src/diagnose.md, "A single record"). 0: every
    /// sample is judged, and the conditions are estimated on all of them.
    pub lead_in: usize,
}

/// How a record was taken beyond its samples (book/src/identify.md, "Records that start
/// mid-run" and "Sensor lag").
#[derive(Clone, Debug, PartialEq)]
pub struct Conditions {
    /// The state at the first sample.
    pub start: Start,
    /// The sensor's lag \[s\]: sample k holds the outputs at t_k − lag.
    pub lag: f64,
}

impl Default for Conditions {
    fn default() -> Self {
        Conditions {
            start: Start::Rest,
            lag: 0.0,
        }
    }
}

impl Experiment {
    pub fn read(path: &Path) -> Result<Experiment, FileError> {
        Experiment::from_table(&Table::read(path)?)
    }

    pub fn from_table(table: &Table) -> Result<Experiment, FileError> {
        let path = &table.path;
        let known = [
            "t", "U1", "U2", "U3", "h1", "h2", "h3", "tip_x", "tip_y", "tip_z",
        ];
        if let Some(c) = table.header.iter().find(|c| !known.contains(&c.as_str())) {
            return Err(FileError::at(
                path,
                1,
                Some(c.clone()),
                format!("unknown column (expected {})", known.join(",")),
            ));
        }
        let t = table.column("t")?;
        table.check_increasing("t")?;
        let u: [Vec<f64>; 3] = [
            table.column("U1")?,
            table.column("U2")?,
            table.column("U3")?,
        ];
        if t.len() < MIN_SAMPLES {
            return Err(FileError::new(
                path,
                format!(
                    "{} samples: an experiment needs at least {MIN_SAMPLES}",
                    t.len()
                ),
            ));
        }
        let duration = t[t.len() - 1] - t[0];
        if duration < MIN_DURATION {
            return Err(FileError::new(
                path,
                format!(
                    "{duration} s long: an experiment must last at least {MIN_DURATION} s to identify anything"
                ),
            ));
        }
        let has = |c: &str| table.find(c).is_some();
        if has("tip_x") != has("tip_y") {
            let missing = if has("tip_x") { "tip_y" } else { "tip_x" };
            return Err(FileError::at(
                path,
                1,
                Some(missing.into()),
                "missing column: tip_x and tip_y come together",
            ));
        }
        let mut channels = Vec::new();
        for ch in Channel::ALL {
            if has(ch.name()) {
                let values = table.column(ch.name())?;
                let range = values.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
                    - values.iter().fold(f64::INFINITY, |a, &b| a.min(b));
                if range <= 0.0 {
                    return Err(FileError::at(
                        path,
                        2,
                        Some(ch.name().into()),
                        "the output is constant: nothing to identify from it",
                    ));
                }
                channels.push((ch, values));
            }
        }
        if channels.is_empty() {
            return Err(FileError::at(
                path,
                1,
                None,
                "no output column: give h1..h3 and/or tip_x, tip_y",
            ));
        }
        let samples = (0..t.len()).map(|k| [u[0][k], u[1][k], u[2][k]]).collect();
        let input = Input::sampled(t.clone(), samples, Interpolation::Measured)
            .map_err(|e| FileError::new(path, e.to_string()))?;
        let name = path.file_name().map_or_else(
            || path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        Ok(Experiment {
            name,
            path: path.clone(),
            t,
            input,
            channels,
            conditions: Conditions::default(),
            lead_in: 0,
        })
    }

    /// This experiment with only the rows where `keep` holds (rows a recorder dropped, samples
    /// trimmed as outliers): the sampling becomes uneven, and the input is replayed through the
    /// commands at the rows kept.
    pub fn rows(&self, keep: &[bool]) -> Result<Experiment, FileError> {
        let kept = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .zip(keep)
                .filter(|(_, k)| **k)
                .map(|(x, _)| *x)
                .collect()
        };
        let t = kept(&self.t);
        if t.len() < MIN_SAMPLES {
            return Err(FileError::new(
                &self.path,
                format!(
                    "{} samples left: an experiment needs at least {MIN_SAMPLES}",
                    t.len()
                ),
            ));
        }
        let samples = t.iter().map(|&tk| self.input.value(tk)).collect();
        let input = Input::sampled(t.clone(), samples, Interpolation::Measured)
            .map_err(|e| FileError::new(&self.path, e.to_string()))?;
        Ok(Experiment {
            name: self.name.clone(),
            path: self.path.clone(),
            t,
            input,
            channels: self.channels.iter().map(|(c, v)| (*c, kept(v))).collect(),
            conditions: self.conditions.clone(),
            lead_in: keep[..self.lead_in].iter().filter(|k| **k).count(),
        })
    }

    /// The samples in `range` as a record of their own.
    pub fn samples_in(&self, range: std::ops::Range<usize>) -> Result<Experiment, FileError> {
        let keep: Vec<bool> = (0..self.t.len()).map(|j| range.contains(&j)).collect();
        self.rows(&keep)
    }

    /// The instants the samples show, t_k − lag: where the model is sampled.
    pub fn sensed_times(&self) -> Vec<f64> {
        self.t.iter().map(|t| t - self.conditions.lag).collect()
    }

    /// The factor on `channel`'s residuals under `weighting` (1 where it is not measured).
    pub fn residual_factor(&self, channel: Channel, weighting: Weighting) -> f64 {
        match (weighting, self.measured(channel)) {
            (Weighting::Noise, Some(y)) => {
                let mean = y.iter().sum::<f64>() / y.len() as f64;
                let spread =
                    (y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / y.len() as f64).sqrt();
                let noise = noise_level(&self.t, y)
                    .max(NOISE_FLOOR_SHARE * spread)
                    .max(f64::MIN_POSITIVE);
                1.0 / noise
            }
            _ => 1.0,
        }
    }

    /// The sum of the squared residuals of `sim` over the channels, each weighted by
    /// `weighting`: what a fit so weighted minimises.
    pub fn misfit(&self, sim: &[Sample], weighting: Weighting) -> f64 {
        self.channels
            .iter()
            .map(|(c, y)| {
                let rss = y
                    .iter()
                    .zip(sim)
                    .map(|(m, s)| (m - c.of(s)).powi(2))
                    .sum::<f64>();
                self.residual_factor(*c, weighting).powi(2) * rss
            })
            .sum()
    }

    /// The measured values of `channel`, if the experiment has it.
    pub fn measured(&self, channel: Channel) -> Option<&[f64]> {
        self.channels
            .iter()
            .find(|(c, _)| *c == channel)
            .map(|(_, v)| v.as_slice())
    }

    /// Whether the tip is measured in X and Y.
    #[cfg(test)]
    fn has_tip_xy(&self) -> bool {
        self.measured(Channel::Tip(0)).is_some() && self.measured(Channel::Tip(1)).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Experiment, FileError> {
        Experiment::from_table(&Table::parse(Path::new("e.csv"), text)?)
    }

    fn rows(n: usize, dt: f64, extra: &str) -> String {
        (0..n)
            .map(|k| {
                format!(
                    "{},1,2,3{}\n",
                    k as f64 * dt,
                    extra.replace('K', &k.to_string())
                )
            })
            .collect()
    }

    /// Weighted by noise, a channel counts in units of its noise σ: h1 alternates ±1 about a
    /// line (departures from the neighbours' line ±2, σ = 2/√1.5), h2 ±4 (four times that); a
    /// channel without noise is weighed by a millionth of its spread, not by its rounding.
    #[test]
    fn channels_weigh_by_their_noise() {
        let e = parse(&format!(
            "t,U1,U2,U3,h1,h2,h3\n{}",
            (0..100)
                .map(|k| {
                    let s = if k % 2 == 0 { 1.0 } else { -1.0 };
                    format!(
                        "{},1,2,3,{},{},{k}\n",
                        0.02 * k as f64,
                        k as f64 + s,
                        4.0 * s
                    )
                })
                .collect::<String>()
        ))
        .unwrap();
        let factor = |i| e.residual_factor(Channel::H(i), Weighting::Noise);
        assert!(
            (factor(0) - 1.5f64.sqrt() / 2.0).abs() < 1e-9,
            "{}",
            factor(0)
        );
        assert!((factor(1) / factor(0) - 0.25).abs() < 1e-9, "{}", factor(1));
        let spread = (((100.0f64 * 100.0) - 1.0) / 12.0).sqrt();
        assert!((factor(2) * NOISE_FLOOR_SHARE * spread - 1.0).abs() < 1e-6);
        assert_eq!(e.residual_factor(Channel::H(0), Weighting::Equal), 1.0);
        // simulated one off on every sample of every channel
        let sim: Vec<Sample> = (0..100)
            .map(|k| Sample {
                t: e.t[k],
                u: [1.0, 2.0, 3.0],
                h: [0, 1, 2].map(|i| e.channels[i].1[k] + 1.0),
                tip: [0.0; 3],
            })
            .collect();
        assert_eq!(e.misfit(&sim, Weighting::Equal), 300.0);
        let weighted = 100.0 * (factor(0).powi(2) + factor(1).powi(2) + factor(2).powi(2));
        assert!((e.misfit(&sim, Weighting::Noise) / weighted - 1.0).abs() < 1e-9);
    }

    #[test]
    fn reads_heights_and_tip() {
        let e = parse(&format!(
            "t,U1,U2,U3,h1,tip_x,tip_y\n{}",
            rows(100, 0.02, ",K,K,K")
        ))
        .unwrap();
        assert_eq!(
            e.channels.iter().map(|(c, _)| c.name()).collect::<Vec<_>>(),
            ["h1", "tip_x", "tip_y"]
        );
        assert!(e.has_tip_xy() && e.measured(Channel::Tip(2)).is_none());
    }

    #[test]
    fn uneven_sampling_is_read_and_rows_can_be_dropped() {
        let text: String = (0..200)
            .filter(|k| k % 5 != 2)
            .map(|k| format!("{},{k},0,0,{}\n", k as f64 * 0.01, k * k))
            .collect();
        let e = parse(&format!("t,U1,U2,U3,h1\n{text}")).unwrap();
        assert_eq!(e.t.len(), 160);
        assert!((e.input.value(0.31)[0] - 31.0).abs() < 1e-9);
        let keep: Vec<bool> = (0..160).map(|k| k % 2 == 0).collect();
        let half = e.rows(&keep).unwrap();
        assert_eq!(half.t.len(), 80);
        assert_eq!(half.measured(Channel::H(0)).unwrap()[1], 9.0);
        assert!((half.input.value(0.31)[0] - 31.0).abs() < 1e-6);
        let e = half.rows(&keep[..80]).unwrap_err();
        assert!(e.to_string().contains("40 samples left"), "{e}");
    }

    #[test]
    fn bad_files_are_located() {
        let e = parse(&format!("t,U1,U2,U3,h4\n{}", rows(100, 0.02, ",K"))).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("e.csv:1, column h4: unknown column"),
            "{e}"
        );
        let e = parse(&format!("t,U1,U3,h1\n{}", "0,1,2,3\n")).unwrap_err();
        assert!(e.to_string().contains("column U2: missing column"), "{e}");
        let e = parse(&format!("t,U1,U2,U3,h1\n{}", rows(10, 0.2, ",K"))).unwrap_err();
        assert!(e.to_string().contains("10 samples"), "{e}");
        let e = parse(&format!("t,U1,U2,U3,h1\n{}", rows(100, 0.001, ",K"))).unwrap_err();
        assert!(e.to_string().contains("must last at least 1 s"), "{e}");
        let e = parse(&format!("t,U1,U2,U3,tip_x\n{}", rows(100, 0.02, ",K"))).unwrap_err();
        assert!(
            e.to_string().contains("column tip_y: missing column"),
            "{e}"
        );
        let e = parse(&format!("t,U1,U2,U3,h2\n{}", rows(100, 0.02, ",5"))).unwrap_err();
        assert!(
            e.to_string().contains("column h2: the output is constant"),
            "{e}"
        );
        let e = parse(&format!("t,U1,U2,U3\n{}", rows(100, 0.02, ""))).unwrap_err();
        assert!(e.to_string().contains("no output column"), "{e}");
        let e = parse("t,U1,U2,U3,h1\n0,1,2,3,4\n0,1,2,3,5\n").unwrap_err();
        assert!(
            e.to_string()
                .contains("e.csv:3, column t: 0 does not increase"),
            "{e}"
        );
        let e = parse("t,U1,U2,U3,h1\n0,1,2,3,4\n0.1,1,nan,3,5\n").unwrap_err();
        assert!(
            e.to_string()
                .contains("e.csv:3, column U2: NaN is not a finite number"),
            "{e}"
        );
    }
}
