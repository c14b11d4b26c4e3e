//! The reference trajectories of tests/data/reference/ (see its README), and the error of a
//! run against them.

use std::path::Path;

use hasel_fmu::io::csv::Table;
use hasel_fmu::simulation::Sample;

use crate::error::Error;

/// The reference trajectories of tests/data/reference/ (see its README), built into the
/// executable so that an installed `hasel bench` needs no source tree.
const EMBEDDED: [(&str, &str); 2] = [
    (
        "sine60_w3pi.csv",
        include_str!("../../../../tests/data/reference/sine60_w3pi.csv"),
    ),
    (
        "zoh1ms_sine60_w3pi.csv",
        include_str!("../../../../tests/data/reference/zoh1ms_sine60_w3pi.csv"),
    ),
];

/// The reference trajectory `name`: from `dir` when given, else the embedded copy.
pub fn reference(dir: Option<&Path>, name: &str) -> Result<Table, Error> {
    match dir {
        Some(dir) => Ok(Table::read(&dir.join(name))?),
        None => {
            let (_, text) = EMBEDDED
                .iter()
                .find(|(n, _)| *n == name)
                .ok_or_else(|| Error::NoEmbeddedReference(name.to_string()))?;
            Ok(Table::parse(Path::new(name), text)?)
        }
    }
}

/// Largest |Δh| and |Δtip| \[µm\] against a reference trajectory, over the rows both have;
/// `None` when its columns or times do not match the samples.
pub fn error_against(table: &Table, samples: &[Sample]) -> Option<(f64, f64)> {
    let cols: Vec<usize> = ["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"]
        .iter()
        .map(|c| table.find(c))
        .collect::<Option<_>>()?;
    let (mut dh, mut dtip): (f64, f64) = (0.0, 0.0);
    for (row, s) in table.rows.iter().zip(samples) {
        if (row[0] - s.t).abs() > 1e-9 {
            return None;
        }
        for i in 0..3 {
            dh = dh.max((row[cols[i]] - s.h[i]).abs());
            dtip = dtip.max((row[cols[3 + i]] - s.tip[i]).abs());
        }
    }
    Some((dh * 1e6, dtip * 1e6))
}
