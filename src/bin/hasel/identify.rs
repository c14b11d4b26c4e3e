//! `hasel identify` and `hasel synth`.

use std::path::PathBuf;

use hasel_fmu::identify::synth::{self, DATA_RTOL, Sensor, Spec};
use hasel_fmu::identify::{self, Options, Weighting, report};
use hasel_fmu::io::csv::write_atomic;

use hasel_fmu::diagnose::hidden::{self, Truth};
use hasel_fmu::model::Params;

use crate::common::{ConditionArgs, InputArgs, columns, load_params, read_all};
use crate::error::Error;

/// A parameter file over the defaults with `--set NAME=VALUE` overrides, validated.
fn given_params(file: &Option<PathBuf>, set: &[String]) -> Result<Params, Error> {
    let mut params = load_params(file)?;
    for s in set {
        let (name, value) = s
            .split_once('=')
            .ok_or_else(|| Error::flag("set", s, "expected NAME=VALUE"))?;
        let v: f64 = value
            .trim()
            .parse()
            .map_err(|_| Error::flag("set", s, format!("'{value}' is not a number")))?;
        params
            .set(name.trim(), v)
            .map_err(|e| Error::flag("set", s, e.to_string()))?;
    }
    params.validate()?;
    Ok(params)
}

#[derive(clap::Args)]
pub struct Args {
    /// Estimation experiments: CSV with t,U1,U2,U3 and any of h1..h3, tip_x, tip_y, tip_z
    #[arg(required = true, value_name = "EXPERIMENT.csv")]
    experiments: Vec<PathBuf>,
    /// Validation experiments (fits only, not used to estimate)
    #[arg(long, num_args = 1.., value_name = "EXPERIMENT.csv")]
    validate: Vec<PathBuf>,
    /// Output folder: identification.json, fitted.toml, report.md and figures
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Starting parameters (a parameter file over the defaults)
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
    /// Parameters to estimate, comma separated (default Kb, b, gamma1, gamma2 of each actuator)
    #[arg(long, value_delimiter = ',', value_name = "NAME,NAME,...")]
    free: Vec<String>,
    /// Bounds of a parameter, NAME=LO:HI (default [start/20, start*20])
    #[arg(long = "bound", value_name = "NAME=LO:HI")]
    bounds: Vec<String>,
    /// How the outputs' residuals count: equal (each in its own unit, as the paper fits) or
    /// noise (each over the noise its record shows: for outputs of unequal noise, such as
    /// heights and the tip, or a quiet actuator beside loud ones)
    #[arg(long, default_value = "equal", value_parser = ["equal", "noise"])]
    weigh: String,
    #[command(flatten)]
    conditions: ConditionArgs,
}

#[derive(clap::Args)]
// the fields' docs are their --help text, which gives units in brackets
#[allow(rustdoc::broken_intra_doc_links)]
pub struct SynthArgs {
    #[command(flatten)]
    input: InputArgs,
    /// The true parameters (a parameter file over the defaults)
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
    /// Override one true parameter, NAME=VALUE (repeatable)
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Measurement noise: standard deviation as a fraction of each output's range (default 0,
    /// or the hidden case's 0.5-2 % with --effect)
    #[arg(long)]
    noise: Option<f64>,
    // the help lists the hidden cases from the registry of families
    #[arg(long, value_name = "NAME", conflicts_with_all = ["params", "set"], help = effect_help())]
    effect: Option<String>,
    /// With --effect: the seed of the hidden case (the device); experiments of one device share
    /// it and differ in --seed
    #[arg(long, default_value_t = 1, requires = "effect")]
    case: u64,
    /// Recorded outputs: h (h1..h3) or tip (tip_x, tip_y, as the paper's laser)
    #[arg(long, default_value = "h", value_parser = ["h", "tip"])]
    columns: String,
    /// Seed of the measurement noise
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[arg(long, default_value_t = 10.0)]
    t_end: f64,
    /// Sample interval [s]
    #[arg(long, default_value_t = 1e-3)]
    dt: f64,
    /// The logger starts this long after the drive [s]: a record that starts mid-run, its time
    /// column going on from there (the device is driven from rest at 0)
    #[arg(long, default_value_t = 0.0, value_name = "SECONDS")]
    record_from: f64,
    /// A first-order lag of the sensor [s], before the noise
    #[arg(long, default_value_t = 0.0, value_name = "SECONDS")]
    sensor_lag: f64,
    #[arg(long, value_name = "FILE.csv")]
    out: PathBuf,
}

pub fn run(a: Args) -> Result<(), Error> {
    let start = load_params(&a.params)?;
    let estimation = read_all(&a.experiments)?;
    let validation = read_all(&a.validate)?;
    let mut opts = Options {
        conditions: Some(a.conditions.choice(&start)?),
        weighting: Weighting::from_name(&a.weigh)
            .ok_or_else(|| Error::flag("weigh", &a.weigh, "expected equal or noise"))?,
        ..Options::default()
    };
    if !a.free.is_empty() {
        opts.free = a.free.clone();
    }
    for b in &a.bounds {
        let (name, range) = b
            .split_once('=')
            .ok_or_else(|| Error::flag("bound", b, "expected NAME=LO:HI"))?;
        let (lo, hi) = range
            .split_once(':')
            .ok_or_else(|| Error::flag("bound", b, "expected NAME=LO:HI"))?;
        let num = |s: &str| {
            s.trim()
                .parse::<f64>()
                .map_err(|_| Error::flag("bound", b, format!("'{s}' is not a number")))
        };
        opts.bounds
            .insert(name.trim().to_string(), (num(lo)?, num(hi)?));
    }
    let id = identify::identify(&start, &estimation, &validation, &opts)?;
    report::write(&a.out, &id, &estimation, &validation)?;
    say!(
        "identified in {:.2} s: {} iterations, {} simulations",
        id.seconds,
        id.iterations,
        id.simulations
    );
    for e in id.estimates.iter().filter(|e| e.estimated) {
        let (lo, hi) = e.ci95.expect("estimated");
        say!(
            "  {:<10} {:>12.6} (start {:.6}), 95 % interval [{:.6}, {:.6}]",
            e.name,
            e.value,
            e.prior,
            lo,
            hi
        );
    }
    for (n, reason) in &id.not_identifiable {
        say!("  {n:<10} not identifiable from these data, held at its start value: {reason}");
    }
    for (title, fits) in [
        ("estimation", &id.estimation),
        ("validation", &id.validation),
    ] {
        for f in fits.iter() {
            let list: Vec<String> = f
                .fits
                .iter()
                .map(|(c, v)| format!("{c} {v:.1} %"))
                .collect();
            say!("  fit on {} ({title}): {}", f.experiment, list.join(", "));
        }
    }
    say!(
        "wrote {}, fitted.toml, report.md",
        a.out.join("identification.json").display()
    );
    Ok(())
}

/// `--effect`'s help: hide a mechanism of the library, one of their second forms, one outside
/// the library, or two at once.
fn effect_help() -> String {
    let names = |kind: fn(&Truth) -> bool| {
        let all = Truth::all().into_iter().filter(kind);
        all.map(|t| t.name()).collect::<Vec<_>>().join(", ")
    };
    format!(
        "Hide a mechanism in the data, in a form that differs from the library's term: an effect of the library ({}), a further form of one ({}), `vibration` or `supply_ripple` (outside the library), `none`, or two at once ({}); with the base parameters Kb, b, gamma1, gamma2 off by up to 20 %, all drawn from --case",
        names(|t| matches!(t, Truth::Effect(_))),
        names(|t| matches!(t, Truth::Variant(..))),
        names(|t| matches!(t, Truth::Two(_))),
    )
}

pub fn synth(a: SynthArgs) -> Result<(), Error> {
    let (input, _) = a.input.input()?;
    if let Some(noise) = a.noise.filter(|n| !(n.is_finite() && *n >= 0.0)) {
        return Err(Error::flag("noise", noise, "must be >= 0"));
    }
    let columns = columns(&a.columns);
    let spec = match &a.effect {
        Some(name) => {
            let truth = Truth::from_name(name).ok_or_else(|| {
                Error::flag(
                    "effect",
                    name,
                    "not a hidden case (an effect of the library, one of its second forms such as `coupling_tilt`, a pair such as `coupling_tilt+creep`, `vibration`, `supply_ripple` or `none`)",
                )
            })?;
            let mut hidden = hidden::hide(truth, a.case)?;
            if let Some(noise) = a.noise {
                hidden.noise = noise;
            }
            say!("hidden: {}", hidden.description);
            hidden.spec(input, a.t_end, a.dt, columns, a.seed)?
        }
        None => Spec {
            input,
            drive: None,
            vibration: None,
            params: given_params(&a.params, &a.set)?,
            t_end: a.t_end,
            dt: a.dt,
            noise: a.noise.unwrap_or(0.0),
            sensor: Sensor::IDEAL,
            columns,
            seed: a.seed,
            rtol: DATA_RTOL,
            record_from: 0.0,
        },
    };
    let spec = Spec {
        record_from: a.record_from,
        sensor: Sensor {
            lag: a.sensor_lag,
            ..spec.sensor
        },
        ..spec
    };
    let (header, rows) = synth::synthesize(&spec)?;
    let n = rows.len();
    write_atomic(&a.out, &header, &rows)?;
    say!(
        "wrote {} ({n} samples, {})",
        a.out.display(),
        header.join(",")
    );
    Ok(())
}
