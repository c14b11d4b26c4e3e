//! Files in and out: CSV tables and parameter files, read with clear errors, written whole.
//!
//! CSV tables and parameter files, with errors that name the file, the line
//! and the column, and writes that never leave a half-written file (`file`).

pub mod csv;
pub mod file;
pub mod input_file;
pub mod params_file;
pub mod trajectory;
