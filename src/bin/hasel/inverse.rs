//! `hasel inverse`: the heights that put the antenna tip on a path and the constant voltages
//! that hold each of them at equilibrium (book/src/model.md, "Inverse kinematics" and
//! "Statics"), the feedforward of a tip path.

use std::path::PathBuf;

use hasel_fmu::identify::fit::span;
use hasel_fmu::io::csv::{self, Table};
use hasel_fmu::model::Platform;
use hasel_fmu::model::kinematics::Inverse;
use hasel_fmu::model::statics::{FeedforwardError, StaticsError, feedforward};

use crate::common::load_params;
use crate::error::{Error, UnreachablePoint};

#[derive(clap::Args)]
// the fields' docs are their --help text, which gives units in brackets
#[allow(rustdoc::broken_intra_doc_links)]
pub struct Args {
    /// The tip path: CSV with columns t,tip_x,tip_y[,tip_z] [s, m] (tip_z for closed and exact)
    #[arg(long, value_name = "PATH.csv")]
    tip: PathBuf,
    /// The inverse kinematics: closed (the paper's closed form, approximate), exact (Newton on
    /// the forward kinematics) or xy (from tip_x, tip_y and --mean-height)
    #[arg(long, default_value = "exact", value_parser = ["closed", "exact", "xy"])]
    method: String,
    /// The platform's mean height for --method xy [m]
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    mean_height: Option<f64>,
    /// Parameter file (TOML, any subset of `hasel params`)
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
    /// Where to write t,h1,h2,h3,U1,U2,U3 [s, m, V]
    #[arg(long, value_name = "FILE.csv", default_value = "inverse.csv")]
    out: PathBuf,
}

pub fn run(a: Args) -> Result<(), Error> {
    let method = match (a.method.as_str(), a.mean_height) {
        ("xy", Some(h)) if h.is_finite() => Inverse::Xy { mean_height: h },
        ("xy", Some(h)) => return Err(Error::flag("mean-height", h, "must be a finite number")),
        ("xy", None) => {
            return Err(Error::Usage(
                "--method xy needs --mean-height H: the tip's X and Y leave the heave open".into(),
            ));
        }
        (m, Some(_)) => {
            return Err(Error::Usage(format!(
                "--mean-height is for --method xy; --method {m} takes tip_z from the path"
            )));
        }
        ("closed", None) => Inverse::ClosedForm,
        _ => Inverse::Exact,
    };
    let model = Platform::new(load_params(&a.params)?)?;
    let table = Table::read(&a.tip)?;
    table.check_increasing("t")?;
    let t = table.column("t")?;
    let x = table.column("tip_x")?;
    let y = table.column("tip_y")?;
    let z = match method {
        Inverse::Xy { .. } => vec![f64::NAN; t.len()],
        _ => table.column("tip_z")?,
    };
    let mut rows = Vec::with_capacity(t.len());
    let mut unreachable = Vec::new();
    for k in 0..t.len() {
        match feedforward(&model, method, [x[k], y[k], z[k]]) {
            Ok((h, u)) => rows.push(vec![t[k], h[0], h[1], h[2], u[0], u[1], u[2]]),
            // the same for every point: say it once
            Err(FeedforwardError::Statics(e @ StaticsError::Effects(_))) => return Err(e.into()),
            Err(why) => unreachable.push(UnreachablePoint {
                line: table.lines[k],
                t: t[k],
                why: why.to_string(),
            }),
        }
    }
    if !unreachable.is_empty() {
        return Err(Error::Unreachable {
            path: a.tip,
            total: t.len(),
            points: unreachable,
        });
    }
    let (h_min, h_max) = span(rows.iter().flat_map(|r| r[1..4].to_vec()));
    let (u_min, u_max) = span(rows.iter().flat_map(|r| r[4..7].to_vec()));
    let n = rows.len();
    csv::write_atomic(&a.out, &["t", "h1", "h2", "h3", "U1", "U2", "U3"], &rows)?;
    say!(
        "wrote {} ({n} points, --method {}): heights {:.3} .. {:.3} um, voltages {:.3} .. {:.3} V",
        a.out.display(),
        a.method,
        h_min * 1e6,
        h_max * 1e6,
        u_min,
        u_max
    );
    Ok(())
}
