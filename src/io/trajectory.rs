//! Simulated trajectories as CSV: `t,U1,U2,U3,h1,h2,h3,tip_x,tip_y,tip_z` in SI units, the
//! columns of the reference data and of measured experiment files.

use std::path::Path;

use super::csv::write_atomic;
use super::file::FileError;
use crate::simulation::Sample;

pub const COLUMNS: [&str; 10] = [
    "t", "U1", "U2", "U3", "h1", "h2", "h3", "tip_x", "tip_y", "tip_z",
];

/// Writes `samples` to `path` atomically.
pub fn write(path: &Path, samples: &[Sample]) -> Result<(), FileError> {
    let rows = samples.iter().map(|s| {
        let mut r = vec![s.t];
        r.extend(s.u);
        r.extend(s.h);
        r.extend(s.tip);
        r
    });
    write_atomic(path, &COLUMNS, rows)
}
