//! Sampled input files: CSV with columns `t,U1,U2,U3` (other columns are ignored, so a
//! measured experiment file can be replayed as an input).

use std::path::Path;

use super::csv::Table;
use super::file::FileError;
use crate::simulation::{Input, Interpolation};

/// Reads the sampled voltages of `path`; time must increase strictly.
pub fn read(path: &Path, interpolation: Interpolation) -> Result<Input, FileError> {
    let table = Table::read(path)?;
    from_table(&table, interpolation)
}

/// The sampled voltages of a table already read.
pub fn from_table(table: &Table, interpolation: Interpolation) -> Result<Input, FileError> {
    let t = table.column("t")?;
    let cols = [
        table.column("U1")?,
        table.column("U2")?,
        table.column("U3")?,
    ];
    if t.len() < 2 {
        return Err(FileError::new(
            &table.path,
            format!("{} data rows: an input needs at least 2 samples", t.len()),
        ));
    }
    table.check_increasing("t")?;
    let u = (0..t.len())
        .map(|k| [cols[0][k], cols[1][k], cols[2][k]])
        .collect();
    Input::sampled(t, u, interpolation).map_err(|e| FileError::new(&table.path, e.to_string()))
}
