//! What several commands share: the parameter file over the defaults, the input voltages of a
//! run, the experiment files, the recorded outputs.

use std::path::PathBuf;

use hasel_fmu::diagnose;
use hasel_fmu::identify::Experiment;
use hasel_fmu::identify::conditions::{Choice, LagChoice, StartChoice};
use hasel_fmu::identify::synth::Columns;
use hasel_fmu::io::{input_file, params_file};
use hasel_fmu::model::{Params, Platform, Reduction};
use hasel_fmu::simulation::input::PAPER_PHASES;
use hasel_fmu::simulation::{Input, Interpolation, Tone, check_rtol};

use crate::error::Error;

/// The parameters of `--params FILE.toml` over the defaults, or the defaults.
pub fn load_params(path: &Option<PathBuf>) -> Result<Params, Error> {
    match path {
        Some(p) => Ok(params_file::read(p)?),
        None => Ok(Params::default()),
    }
}

/// Which model of the platform a command builds (src/model/reduced.rs).
#[derive(clap::Args)]
pub struct ModelArgs {
    /// full (the paper's 15 states), quasi-static (the charges on their DC values: θ, l_p, p
    /// per actuator) or slow (also the momentum: θ per actuator), each with the effects' states
    #[arg(
        long = "model",
        default_value = "full",
        value_parser = clap::builder::PossibleValuesParser::new(Reduction::ALL.map(Reduction::name))
    )]
    model: String,
}

impl ModelArgs {
    /// The model chosen.
    pub fn reduction(&self) -> Result<Reduction, Error> {
        self.model
            .parse()
            .map_err(|e| Error::flag("model", &self.model, format!("{e}")))
    }

    /// The model chosen, built from `params`.
    pub fn build(&self, params: Params) -> Result<Platform, Error> {
        Ok(Platform::reduced(params, self.reduction()?)?)
    }
}

/// A diagnosis's options, with `rtol` in place of its tolerance where given (`--rtol`),
/// checked by the simulations' own rule before anything runs.
pub fn diagnose_options(rtol: Option<f64>) -> Result<diagnose::Options, Error> {
    let mut opts = diagnose::Options::default();
    if let Some(rtol) = rtol {
        check_rtol("--rtol", rtol)?;
        opts.rtol = rtol;
    }
    Ok(opts)
}

/// The experiment files, read and checked.
pub fn read_all(paths: &[PathBuf]) -> Result<Vec<Experiment>, Error> {
    paths.iter().map(|p| Ok(Experiment::read(p)?)).collect()
}

/// How the records were taken, shared by `identify` and `diagnose` (book/src/identify.md,
/// "Records that start mid-run" and "Sensor lag").
#[derive(clap::Args)]
// the fields' docs are their --help text, which gives units in brackets
#[allow(rustdoc::broken_intra_doc_links)]
pub struct ConditionArgs {
    /// Where each record starts: auto (estimated where the first sample is not the rest
    /// state's), rest, estimate, or FILE.toml giving the heights h1, h2, h3 [m] at the first
    /// sample
    #[arg(
        long,
        default_value = "auto",
        value_name = "auto|rest|estimate|FILE.toml"
    )]
    start: String,
    /// The sensor's lag: estimate (within 0-1 ms), or stated in seconds (0: none)
    #[arg(long, default_value = "estimate", value_name = "estimate|SECONDS")]
    lag: String,
}

impl ConditionArgs {
    /// What to estimate of the records' conditions, over the start parameters `params`.
    pub fn choice(&self, params: &Params) -> Result<Choice, Error> {
        let start = match self.start.as_str() {
            "auto" => StartChoice::Auto,
            "rest" => StartChoice::Rest,
            "estimate" => StartChoice::Estimate,
            file => StartChoice::Heights(params_file::read_heights(file.as_ref(), params)?),
        };
        let lag = match self.lag.as_str() {
            "estimate" => LagChoice::Estimate,
            text => match text.parse::<f64>() {
                Ok(v) if v.is_finite() && v >= 0.0 => LagChoice::Stated(v),
                _ => {
                    return Err(Error::flag(
                        "lag",
                        text,
                        "expected `estimate` or a lag in seconds >= 0",
                    ));
                }
            },
        };
        Ok(Choice { start, lag })
    }
}

/// The recorded outputs of `--columns h|tip`.
pub fn columns(name: &str) -> Columns {
    if name == "tip" {
        Columns::TipXy
    } else {
        Columns::Heights
    }
}

/// The input voltages of a run, shared by `simulate` and `synth`.
#[derive(clap::Args)]
// the fields' docs are their --help text, which gives units in brackets
#[allow(rustdoc::broken_intra_doc_links)]
pub struct InputArgs {
    /// The paper's excitation U0·sin(ω t + φ_i), φ = 0°, 120°, 240° [V, rad/s] (the default: 60,3π)
    #[arg(long, value_name = "U0,OMEGA", conflicts_with_all = ["offset_sine", "multisine", "input"])]
    sine: Option<String>,
    /// The unipolar excitation U0·(1 + sin(ω t + φ_i))/2 [V, rad/s]
    #[arg(long, value_name = "U0,OMEGA", conflicts_with_all = ["multisine", "input"])]
    offset_sine: Option<String>,
    /// A multisine: tones A:OMEGA[:PHASE] [V, rad/s, rad] separated by commas, each applied to
    /// the three actuators with the paper's phase offsets 0°, 120°, 240° added
    #[arg(long, value_name = "A:OMEGA[:PHASE],...", conflicts_with = "input")]
    multisine: Option<String>,
    /// Sampled voltages: CSV with columns t,U1,U2,U3 [s, V]
    #[arg(long, value_name = "FILE.csv")]
    pub input: Option<PathBuf>,
    /// How --input is read between samples: zoh (held, as a co-simulation master does),
    /// linear, pchip (monotone cubic) or spline (natural cubic, C², fastest for dense smooth data)
    #[arg(long, default_value = "zoh", value_parser = ["zoh", "linear", "pchip", "spline"])]
    interp: String,
}

impl InputArgs {
    /// The input and its natural end: the last sample of a file, else 10 s.
    pub fn input(&self) -> Result<(Input, f64), Error> {
        if let Some(path) = &self.input {
            let interpolation = match self.interp.as_str() {
                "linear" => Interpolation::Linear,
                "pchip" => Interpolation::Pchip,
                "spline" => Interpolation::Spline,
                _ => Interpolation::ZeroOrderHold,
            };
            let input = input_file::read(path, interpolation)?;
            let end = input.last_sample().unwrap_or(10.0);
            return Ok((input, end));
        }
        if let Some(s) = &self.offset_sine {
            let (u0, w) = pair("offset-sine", s)?;
            return Ok((Input::offset_sine(u0, w), 10.0));
        }
        if let Some(s) = &self.multisine {
            let [t1, t2, t3] = PAPER_PHASES.map(|phi| multisine(s, phi));
            return Ok((
                Input::Tones {
                    offset: [0.0; 3],
                    tones: [t1?, t2?, t3?],
                },
                10.0,
            ));
        }
        let (u0, w) = match &self.sine {
            Some(s) => pair("sine", s)?,
            None => (60.0, 3.0 * std::f64::consts::PI),
        };
        Ok((Input::sine(u0, w), 10.0))
    }
}

/// The tones of `--multisine`, shifted by the actuator's phase `phi`.
fn multisine(text: &str, phi: f64) -> Result<Vec<Tone>, Error> {
    text.split(',')
        .map(|tone| {
            let parts: Vec<f64> = tone
                .split(':')
                .map(|p| p.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
                .collect::<Option<_>>()
                .ok_or_else(|| {
                    Error::flag(
                        "multisine",
                        text,
                        format!("'{tone}' is not A:OMEGA[:PHASE] in numbers"),
                    )
                })?;
            match parts.as_slice() {
                [a, w] => Ok(Tone {
                    amplitude: *a,
                    omega: *w,
                    phase: phi,
                }),
                [a, w, p] => Ok(Tone {
                    amplitude: *a,
                    omega: *w,
                    phase: p + phi,
                }),
                _ => Err(Error::flag(
                    "multisine",
                    text,
                    format!("'{tone}' is not A:OMEGA[:PHASE]"),
                )),
            }
        })
        .collect()
}

/// The `U0,OMEGA` of `--sine` or `--offset-sine`.
fn pair(flag: &'static str, text: &str) -> Result<(f64, f64), Error> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let num = |s: &str| s.parse::<f64>().ok().filter(|v| v.is_finite());
    match parts.as_slice() {
        [a, b] => match (num(a), num(b)) {
            (Some(u0), Some(w)) => Ok((u0, w)),
            _ => Err(Error::flag(flag, text, "expected two numbers U0,OMEGA")),
        },
        _ => Err(Error::flag(flag, text, "expected U0,OMEGA")),
    }
}
