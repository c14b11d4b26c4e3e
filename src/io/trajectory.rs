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
    let rows: Vec<[f64; 10]> = samples
        .iter()
        .map(|s| {
            let [u1, u2, u3] = s.u;
            let [h1, h2, h3] = s.h;
            let [x, y, z] = s.tip;
            [s.t, u1, u2, u3, h1, h2, h3, x, y, z]
        })
        .collect();
    write_atomic(path, &COLUMNS, &rows)
}
