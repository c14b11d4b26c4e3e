//! `hasel simulate` and `hasel params`.

use std::path::PathBuf;
use std::time::Instant;

use hasel_fmu::io::{params_file, trajectory};
use hasel_fmu::model::Platform;
use hasel_fmu::plot::{self, Panel, Series};
use hasel_fmu::simulation::{DEFAULT_RTOL, Sample, Simulator};
use indicatif::{ProgressBar, ProgressStyle};

use crate::common::{InputArgs, load_params};
use crate::error::Error;

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    input: InputArgs,
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
    let params = load_params(&a.params)?;
    let (input, default_end) = a.input.input()?;
    let t_end = a.t_end.unwrap_or(default_end);
    if !(t_end.is_finite() && t_end > 0.0) {
        return Err(Error::flag("t-end", t_end, "must be > 0"));
    }
    let model = Platform::new(params)?;
    let mut sim = Simulator::new(model, 0.0, a.rtol)?;

    let bar = (t_end >= 30.0).then(|| {
        let bar = ProgressBar::new((t_end * 1000.0) as u64);
        bar.set_style(
            ProgressStyle::with_template("{bar:40} {percent}% of simulated time, eta {eta}")
                .expect("valid template"),
        );
        bar
    });
    let started = Instant::now();
    let mut samples: Vec<Sample> = Vec::new();
    sim.run(&input, t_end, a.dt, |s| {
        if let Some(b) = &bar {
            b.set_position((s.t * 1000.0) as u64);
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
        let (lo, hi) = steady
            .iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(v), h.max(v))
            });
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
    if let Some(path) = &a.out {
        trajectory::write(path, &samples)?;
        say!("wrote {}", path.display());
    }
    if let Some(path) = &a.plot {
        plot::draw(path, &run_panels(&samples), 2, (1400, 560))?;
        say!("wrote {}", path.display());
    }
    Ok(())
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
