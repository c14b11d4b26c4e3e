//! Files in general: the error that names the file, the line and the column, and writes that
//! never leave a half-written file (a temporary file in the same folder, renamed into place).

use std::path::{Path, PathBuf};

/// Where in which file something is wrong, and what.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error(
    "{}{}{}: {message}",
    .path.display(),
    .line.map(|l| format!(":{l}")).unwrap_or_default(),
    .column.as_ref().map(|c| format!(", column {c}")).unwrap_or_default()
)]
pub struct FileError {
    pub path: PathBuf,
    /// 1-based line, when the problem has one.
    pub line: Option<usize>,
    /// Column name or 1-based number, when the problem has one.
    pub column: Option<String>,
    pub message: String,
}

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
    let mut file = AtomicFile::create(path)?;
    parts.iter().try_for_each(|part| file.write(part))?;
    file.commit()
}

/// A file written under a temporary name in its folder and renamed into place by
/// [`AtomicFile::commit`]: readers see the old file or the whole new one, never part of it.
/// Dropped uncommitted (an error, a panic), it removes its temporary file.
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    /// `None` once committed.
    file: Option<std::fs::File>,
}

impl AtomicFile {
    /// Creates the folder if needed and the temporary file beside `path`.
    pub fn create(path: &Path) -> Result<AtomicFile, FileError> {
        let dir = path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir)
            .map_err(|e| FileError::new(path, format!("cannot create folder: {e}")))?;
        let name = path
            .file_name()
            .ok_or_else(|| FileError::new(path, "not a file path"))?;
        if path.is_dir() {
            return Err(FileError::new(path, "is a folder: name a file in it"));
        }
        let tmp = dir.join(format!(
            ".{}.tmp{}",
            name.to_string_lossy(),
            std::process::id()
        ));
        let file = std::fs::File::create(&tmp)
            .map_err(|e| FileError::new(path, format!("cannot write: {e}")))?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            tmp,
            file: Some(file),
        })
    }

    /// Appends `bytes`.
    pub fn write(&mut self, bytes: &[u8]) -> Result<(), FileError> {
        use std::io::Write;
        let file = self
            .file
            .as_mut()
            .expect("an AtomicFile is written before its commit");
        file.write_all(bytes)
            .map_err(|e| FileError::new(&self.path, format!("cannot write: {e}")))
    }

    /// Closes the file and renames it into place.
    pub fn commit(mut self) -> Result<(), FileError> {
        drop(self.file.take());
        if replace_file(&self.tmp, &self.path) {
            return Ok(());
        }
        std::fs::rename(&self.tmp, &self.path).map_err(|e| {
            let _ = std::fs::remove_file(&self.tmp);
            FileError::new(&self.path, format!("cannot move into place: {e}"))
        })
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.file.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Puts `tmp` in place of the regular file `path` by swapping the two (renameat2 with
/// RENAME_EXCHANGE), then removes the old file, now at `tmp`; false, having changed nothing,
/// where that cannot be done (no file at `path`, a file system without the flag).
///
/// Why not a plain rename: ext4, with its default `auto_da_alloc`, writes a file renamed over
/// another to the disk inside the rename, so replacing a 2 MB trajectory cost a millisecond
/// more than writing a new one. The swap is as atomic for readers (they see the old file or
/// the whole new one); like a first write, it leaves the write-back to the kernel.
#[cfg(target_os = "linux")]
fn replace_file(tmp: &Path, path: &Path) -> bool {
    use std::ffi::CString;
    use std::os::unix::ffi::OsStrExt;
    let is_file = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_file());
    let (Ok(from), Ok(to)) = (
        CString::new(tmp.as_os_str().as_bytes()),
        CString::new(path.as_os_str().as_bytes()),
    ) else {
        return false;
    };
    // The system call rather than glibc's wrapper, which is newer (2.28) than the glibc the
    // FMU library is built against (2.17). SAFETY: two NUL-terminated paths that live across
    // the call.
    let swapped = is_file
        && unsafe {
            libc::syscall(
                libc::SYS_renameat2,
                libc::AT_FDCWD,
                from.as_ptr(),
                libc::AT_FDCWD,
                to.as_ptr(),
                libc::RENAME_EXCHANGE,
            )
        } == 0;
    if swapped {
        let _ = std::fs::remove_file(tmp);
    }
    swapped
}

/// Elsewhere (macOS, Windows) there is no such swap to try: [`AtomicFile::commit`] renames, which
/// replaces the file atomically there too (rename(2) on macOS, `MoveFileExW` with
/// `MOVEFILE_REPLACE_EXISTING` on Windows).
#[cfg(not(target_os = "linux"))]
fn replace_file(_tmp: &Path, _path: &Path) -> bool {
    false
}

/// The names in folder `dir`, for tests that no temporary file is left behind.
#[cfg(test)]
pub(crate) fn file_names(dir: &Path) -> Vec<std::ffi::OsString> {
    let mut names: Vec<_> = std::fs::read_dir(dir)
        .expect("a readable folder")
        .map(|e| e.expect("a readable entry").file_name())
        .collect();
    names.sort();
    names
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_replaced_file_has_the_new_text_and_no_temporary_beside_it() {
        let dir = std::env::temp_dir().join(format!("hasel-file-{}", std::process::id()));
        let path = dir.join("out.txt");
        write_text_atomic(&path, "first\n").unwrap();
        write_text_atomic(&path, "second\n").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "second\n");
        assert_eq!(file_names(&dir), ["out.txt"]);
        let e = write_text_atomic(&dir, "x").unwrap_err();
        assert!(
            e.to_string().ends_with("is a folder: name a file in it"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
