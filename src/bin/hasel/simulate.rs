//! `hasel simulate` and `hasel params`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use hasel_fmu::identify::fit::span;
use hasel_fmu::io::csv::Table;
use hasel_fmu::io::{params_file, trajectory};
use hasel_fmu::model::Reduction;
use hasel_fmu::plot::{self, Panel, Series};
use hasel_fmu::simulation::{DEFAULT_RTOL, Sample, Simulator};
use indicatif::{ProgressBar, ProgressStyle};

use crate::common::{InputArgs, ModelArgs, load_params};
use crate::error::Error;

#[derive(clap::Args)]
// the fields' docs are their --help text, which gives units in brackets
#[allow(rustdoc::broken_intra_doc_links)]
pub struct Args {
    #[command(flatten)]
    input: InputArgs,
    #[command(flatten)]
    model: ModelArgs,
    /// Parameter file (TOML, any subset of `hasel params`)
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
    /// End time [s] (default 10, or the last sample of --input)
    #[arg(long)]
    t_end: Option<f64>,
    /// Output sample interval [s]
    #[arg(long, default_value_t = 1e-3)]
    dt: f64,
    /// Relative tolerance of the integrator
    #[arg(long, default_value_t = DEFAULT_RTOL)]
    rtol: f64,
    /// Write t,U1,U2,U3,h1,h2,h3,tip_x,tip_y,tip_z (SI) here
    #[arg(long, value_name = "FILE.csv")]
    out: Option<PathBuf>,
    /// Draw h_i(t) and the tip's XY path here
    #[arg(long, value_name = "FILE.png")]
    plot: Option<PathBuf>,
    /// Prediction bands: run this many parameter sets drawn from --uncertainty on all cores;
    /// --out then gets the median and 2.5/97.5 % bands of every output, --plot their figure
    #[arg(long, value_name = "N", requires = "uncertainty")]
    samples: Option<usize>,
    /// The identification.json of `hasel identify` whose covariance the parameter sets are
    /// drawn from (in the fit's coordinates: ln p for positive parameters)
    #[arg(
        long,
        value_name = "DIR/identification.json",
        requires = "samples",
        conflicts_with = "params"
    )]
    uncertainty: Option<PathBuf>,
    /// Seed of the draw (default 1): sample k is seeded from (seed, k) alone
    #[arg(long, requires = "samples")]
    seed: Option<u64>,
    /// Threads for --samples (default: every core); the numbers do not depend on it
    #[arg(long, requires = "samples")]
    threads: Option<usize>,
    /// With --samples: write the drawn parameter sets here (sample, failed, every parameter)
    #[arg(long, value_name = "FILE.csv", requires = "samples")]
    draws: Option<PathBuf>,
}

#[derive(clap::Args)]
pub struct ParamsArgs {
    /// A parameter file to read over the defaults
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
    /// Write here instead of standard output
    #[arg(long, value_name = "FILE.toml")]
    out: Option<PathBuf>,
}

pub fn params(a: ParamsArgs) -> Result<(), Error> {
    let p = load_params(&a.params)?;
    match a.out {
        Some(path) => Ok(params_file::write(&path, &p)?),
        None => {
            say_raw!("{}", params_file::to_toml(&p));
            Ok(())
        }
    }
}

pub fn run(a: Args) -> Result<(), Error> {
    if let (Some(n), Some(id)) = (a.samples, &a.uncertainty) {
        return run_samples(&a, n, id);
    }
    let params = load_params(&a.params)?;
    let (input, default_end) = a.input.input()?;
    let t_end = a.t_end.unwrap_or(default_end);
    if !(t_end.is_finite() && t_end > 0.0) {
        return Err(Error::flag("t-end", t_end, "must be > 0"));
    }
    let model = a.model.build(params)?;
    let mut sim = Simulator::new(model, 0.0, a.rtol)?;

    let bar = (t_end >= 30.0).then(|| {
        let bar = ProgressBar::new((t_end * 1000.0) as u64);
        bar.set_style(
            ProgressStyle::with_template("{bar:40} {percent}% of simulated time, eta {eta}")
                .expect("valid template"),
        );
        bar
    });
    // the CSV is written while the run computes it (on a second core), and appears only
    // once the run has succeeded
    let mut csv = a
        .out
        .as_deref()
        .map(trajectory::Stream::create)
        .transpose()?;
    let started = Instant::now();
    let mut samples: Vec<Sample> = Vec::with_capacity(expected_samples(t_end, a.dt));
    sim.run(&input, t_end, a.dt, |s| {
        if let Some(b) = &bar {
            b.set_position((s.t * 1000.0) as u64);
        }
        if let Some(csv) = &mut csv {
            csv.push(s);
        }
        samples.push(*s);
    })?;
    let wall = started.elapsed();
    if let Some(b) = bar {
        b.finish_and_clear();
    }

    let stats = sim.stats();
    // strokes over the second half of the run, past the start-up transient
    let steady = &samples[samples.len() / 2..];
    let range = |f: &dyn Fn(&Sample) -> f64| {
        let (lo, hi) = span(steady.iter().map(f));
        (hi - lo) * 1e6
    };
    say!(
        "simulated {t_end} s in {:.1} ms: {} steps ({} rejected), {} f and {} Jacobian evaluations",
        wall.as_secs_f64() * 1e3,
        stats.accepted,
        stats.rejected,
        stats.rhs_evals,
        stats.jac_evals
    );
    say!(
        "second half of the run: peak-to-peak stroke h1/h2/h3 {:.1} / {:.1} / {:.1} um; tip path {:.1} x {:.1} um (X x Y)",
        range(&|s| s.h[0]),
        range(&|s| s.h[1]),
        range(&|s| s.h[2]),
        range(&|s| s.tip[0]),
        range(&|s| s.tip[1])
    );
    if let (Some(csv), Some(path)) = (csv, &a.out) {
        csv.finish()?;
        say!("wrote {}", path.display());
    }
    if let Some(path) = &a.plot {
        plot::draw(path, &run_panels(&samples), 2, (1400, 560))?;
        say!("wrote {}", path.display());
    }
    Ok(())
}

/// Samples of a run to `t_end` every `dt` (0, dt, ... and t_end), bounded so that a wild
/// request reserves no more than it would fill before its first report.
fn expected_samples(t_end: f64, dt: f64) -> usize {
    const MOST: f64 = 1e7;
    ((t_end / dt).ceil() + 1.0).clamp(1.0, MOST) as usize
}

/// h_i(t) and the tip's XY path.
pub fn run_panels(samples: &[Sample]) -> Vec<Panel> {
    let um = 1e6;
    let heights = (0..3)
        .map(|i| Series {
            label: format!("h{}", i + 1),
            points: samples.iter().map(|s| (s.t, s.h[i] * um)).collect(),
            color: i,
            dots: false,
        })
        .collect();
    vec![
        Panel {
            title: "Actuator heights".into(),
            x_label: "t [s]".into(),
            y_label: "h [um]".into(),
            series: heights,
            equal_axes: false,
        },
        Panel {
            title: "Antenna tip".into(),
            x_label: "tip x [um]".into(),
            y_label: "tip y [um]".into(),
            series: vec![Series {
                label: "tip path".into(),
                points: samples
                    .iter()
                    .map(|s| (s.tip[0] * um, s.tip[1] * um))
                    .collect(),
                color: 3,
                dots: false,
            }],
            equal_axes: true,
        },
    ]
}

/// `hasel simulate --samples N --uncertainty DIR/identification.json`: prediction bands.
fn run_samples(a: &Args, samples: usize, identification: &Path) -> Result<(), Error> {
    use hasel_fmu::uncertainty::{Posterior, bands};
    if a.model.reduction()? != Reduction::Full {
        return Err(Error::Usage(
            "--samples draws runs of the full model: leave out --model".into(),
        ));
    }
    let posterior = Posterior::read(identification)?;
    let (input, default_end) = a.input.input()?;
    // a measured experiment given as --input is drawn under the bands
    let data = match &a.input.input {
        Some(path) => Some(Table::read(path)?),
        None => None,
    };
    let threads = a
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        return Err(Error::flag("threads", 0, "need at least 1"));
    }
    let settings = bands::Settings {
        samples,
        seed: a.seed.unwrap_or(1),
        threads,
        t_end: a.t_end.unwrap_or(default_end),
        dt: a.dt,
        rtol: a.rtol,
    };
    let bar = ProgressBar::new(samples as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} samples, eta {eta}")
            .expect("valid template"),
    );
    let started = Instant::now();
    let result = bands::run(&posterior, &input, &settings, &|| bar.inc(1));
    bar.finish_and_clear();
    let b = result?;
    let wall = started.elapsed().as_secs_f64();
    say!(
        "{samples} samples of {} parameters (covariance of rank {}) from {}, seed {}, {threads} threads: {wall:.2} s, {:.1} runs/s",
        posterior.names.len(),
        posterior.rank(),
        identification.display(),
        settings.seed,
        samples as f64 / wall
    );
    if !b.failed.is_empty() {
        say!(
            "{} samples failed and are left out of the bands (sample {}: {})",
            b.failed.len(),
            b.failed[0].0,
            b.failed[0].1
        );
    }
    for (j, name) in bands::OUTPUTS.iter().enumerate() {
        let widest = (0..b.t.len())
            .map(|k| b.upper[k][j] - b.lower[k][j])
            .fold(0.0, f64::max);
        say!("  {name:<6} widest 95 % band {:.3} um", widest * 1e6);
    }
    // everything computed: now the files, each written whole or not at all
    if let Some(path) = &a.out {
        b.write_csv(path)?;
        say!("wrote {}", path.display());
    }
    if let Some(path) = &a.draws {
        b.write_draws(path, &posterior)?;
        say!("wrote {}", path.display());
    }
    if let Some(path) = &a.plot {
        b.draw(path, data.as_ref())?;
        say!("wrote {}", path.display());
    }
    Ok(())
}
