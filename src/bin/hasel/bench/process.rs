//! `hasel bench`: the command as a user runs it, the whole process (start, integration,
//! sampling, the CSV, exit) with and without `--out`, and the CSV writing alone beside the
//! integration that made the rows.

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use hasel_fmu::io::file::FileError;
use hasel_fmu::io::trajectory;
use hasel_fmu::model::{Params, Platform};
use hasel_fmu::simulation::{DEFAULT_RTOL, Input, Simulator};

use super::timing::{best, best_after};
use crate::error::Error;

/// The command: 10 s of the paper's sine at 1 ms outputs.
const SIMULATE: [&str; 7] = [
    "simulate",
    "--sine",
    "60,9.42477796",
    "--t-end",
    "10",
    "--dt",
    "0.001",
];

/// Issue #14's yardstick: the Python implementation of the same model with SUNDIALS CVODE and
/// an analytic Jacobian, integration only, 10 s of the default excitation \[ms\] (measured by the
/// issue's author; the Python code is not part of this repository).
const PYTHON_CVODE_MS: f64 = 468.0;
/// The whole process with `--out` must be this many times faster than that.
const TARGET_SPEEDUP: f64 = 50.0;

/// Best wall time of `repeat` runs of this executable with `args`, each after `before` (not
/// timed).
fn process(repeat: usize, args: &[&str], before: impl FnMut()) -> Result<Duration, Error> {
    let exe = std::env::current_exe().map_err(Error::CurrentExe)?;
    best_after(repeat, before, || {
        let problem = match Command::new(&exe).args(args).output() {
            Ok(o) if o.status.success() => return Ok(()),
            Ok(o) => String::from_utf8_lossy(&o.stderr).into_owned(),
            Err(e) => e.to_string(),
        };
        Err(Error::Benchmark {
            command: format!("hasel {}", args.join(" ")),
            problem,
        })
    })
}

pub fn run(repeat: usize) -> Result<(), Error> {
    let dir = std::env::temp_dir().join(format!("hasel-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)
        .map_err(|e| FileError::new(&dir, format!("cannot create folder: {e}")))?;
    let csv = dir.join("run.csv");
    let result = measure(repeat, &csv);
    let _ = std::fs::remove_dir_all(&dir);
    result
}

fn measure(repeat: usize, csv: &Path) -> Result<(), Error> {
    let with_out: Vec<&str> = SIMULATE
        .iter()
        .copied()
        .chain(["--out", csv.to_str().unwrap_or("run.csv")])
        .collect();
    let remove = || {
        let _ = std::fs::remove_file(csv);
    };
    let quiet = process(repeat, &SIMULATE, || {})?;
    let new_file = process(repeat, &with_out, remove)?;
    let over_existing = process(repeat, &with_out, || {})?;

    let model = Platform::new(Params::default())?;
    let input = Input::sine(60.0, 9.42477796);
    let (integration, samples) = best(repeat, || {
        let mut sim = Simulator::new(model.clone(), 0.0, DEFAULT_RTOL).expect("valid model");
        let mut samples = Vec::with_capacity(10_001);
        sim.run(&input, 10.0, 1e-3, |s| samples.push(*s))
            .expect("the default run succeeds");
        samples
    });
    let write = |fresh: bool| -> Result<Duration, Error> {
        best_after(
            repeat,
            || {
                if fresh {
                    remove();
                }
            },
            || trajectory::write(csv, &samples).map_err(Error::from),
        )
    };
    let (writing, replacing) = (write(true)?, write(false)?);
    // what `hasel simulate --out` does: the rows formatted and written while they are computed
    let streamed = best_after(repeat, remove, || {
        let mut sim = Simulator::new(model.clone(), 0.0, DEFAULT_RTOL)?;
        let mut csv = trajectory::Stream::create(csv)?;
        sim.run(&input, 10.0, 1e-3, |s| csv.push(s))?;
        Ok::<_, Error>(csv.finish()?)
    })?;
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    say!(
        "hasel {} [--out run.csv], whole process, best of {repeat}",
        SIMULATE.join(" ")
    );
    let speedup = |d: Duration| PYTHON_CVODE_MS / ms(d);
    let slower = new_file.max(over_existing);
    say!(
        "  without --out {:.1} ms | with --out {:.1} ms ({:.1} ms over an existing run.csv): \
         {:.0}x / {:.0}x the Python run's {PYTHON_CVODE_MS} ms (target >= {TARGET_SPEEDUP}x: {})",
        ms(quiet),
        ms(new_file),
        ms(over_existing),
        speedup(new_file),
        speedup(over_existing),
        if speedup(slower) >= TARGET_SPEEDUP {
            "met"
        } else {
            "MISSED"
        },
    );
    say!(
        "  in the process: integration and sampling {:.2} ms; writing the {}-row CSV alone {:.2} ms \
         ({}), {:.2} ms over an existing file; the integration with the CSV written alongside, as `--out` does, {:.2} ms",
        ms(integration),
        samples.len(),
        ms(writing),
        if writing < integration {
            "less than the integration: met"
        } else {
            "more than the integration: MISSED"
        },
        ms(replacing),
        ms(streamed),
    );
    Ok(())
}
