//! Files in general: the error that names the file, the line and the column, and writes that
//! never leave a half-written file (a temporary file in the same folder, renamed into place).

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in which file something is wrong, and what.
#[derive(Clone, Debug, PartialEq)]
pub struct FileError {
    pub path: PathBuf,
    /// 1-based line, when the problem has one.
    pub line: Option<usize>,
    /// Column name or 1-based number, when the problem has one.
    pub column: Option<String>,
    pub message: String,
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        if let Some(c) = &self.column {
            write!(f, ", column {c}")?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for FileError {}

impl FileError {
    pub fn new(path: &Path, message: impl Into<String>) -> FileError {
        FileError {
            path: path.to_path_buf(),
            line: None,
            column: None,
            message: message.into(),
        }
    }
    pub fn at(
        path: &Path,
        line: usize,
        column: Option<String>,
        message: impl Into<String>,
    ) -> FileError {
        FileError {
            path: path.to_path_buf(),
            line: Some(line),
            column,
            message: message.into(),
        }
    }
}

/// Writes `text` to `path` through a temporary file renamed into place.
pub fn write_text_atomic(path: &Path, text: &str) -> Result<(), FileError> {
    write_bytes_atomic(path, text.as_bytes())
}

/// Writes `bytes` to `path` through a temporary file renamed into place.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    write_parts_atomic(path, &[bytes])
}

/// [`write_bytes_atomic`] of the concatenation of `parts`, written one after the other.
pub fn write_parts_atomic(path: &Path, parts: &[&[u8]]) -> Result<(), FileError> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)
        .map_err(|e| FileError::new(path, format!("cannot create folder: {e}")))?;
    let name = path
        .file_name()
        .ok_or_else(|| FileError::new(path, "not a file path"))?;
    let tmp = dir.join(format!(
        ".{}.tmp{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let written = std::fs::File::create(&tmp).and_then(|mut f| {
        use std::io::Write;
        parts.iter().try_for_each(|part| f.write_all(part))
    });
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(FileError::new(path, format!("cannot write: {e}")));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        FileError::new(path, format!("cannot move into place: {e}"))
    })
}
