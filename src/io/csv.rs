//! Numeric CSV tables with a header row: read with errors that name the file, the line and the
//! column; written atomically (through [`super::file`], so nothing is half-written).

use std::path::{Path, PathBuf};

use super::file::{FileError, write_parts_atomic};

/// A numeric table: column names and rows of equal length.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub path: PathBuf,
    pub header: Vec<String>,
    pub rows: Vec<Vec<f64>>,
    /// 1-based file line of each row, for messages about a row.
    pub lines: Vec<usize>,
}

impl Table {
    /// Reads `path`: a header of names, then rows of finite numbers; blank lines and lines
    /// starting with `#` are skipped.
    pub fn read(path: &Path) -> Result<Table, FileError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| FileError::new(path, format!("cannot read: {e}")))?;
        Table::parse(path, &text)
    }

    pub fn parse(path: &Path, text: &str) -> Result<Table, FileError> {
        let mut lines = text.lines().enumerate().filter(|(_, l)| {
            let l = l.trim();
            !l.is_empty() && !l.starts_with('#')
        });
        let (header_no, header_line) = lines
            .next()
            .ok_or_else(|| FileError::new(path, "empty file: expected a header row"))?;
        let header: Vec<String> = header_line
            .split(',')
            .map(|s| s.trim().to_string())
            .collect();
        for (c, name) in header.iter().enumerate() {
            if name.is_empty() {
                return Err(FileError::at(
                    path,
                    header_no + 1,
                    Some((c + 1).to_string()),
                    "empty column name in the header",
                ));
            }
            if header[..c].contains(name) {
                return Err(FileError::at(
                    path,
                    header_no + 1,
                    Some(name.clone()),
                    "column appears twice in the header",
                ));
            }
        }
        let mut rows = Vec::new();
        let mut line_nos = Vec::new();
        for (no, line) in lines {
            let fields: Vec<&str> = line.split(',').collect();
            if fields.len() != header.len() {
                return Err(FileError::at(
                    path,
                    no + 1,
                    None,
                    format!("{} fields, the header has {}", fields.len(), header.len()),
                ));
            }
            let mut row = Vec::with_capacity(fields.len());
            for (c, f) in fields.iter().enumerate() {
                let v: f64 = f.trim().parse().map_err(|_| {
                    FileError::at(
                        path,
                        no + 1,
                        Some(header[c].clone()),
                        format!("'{}' is not a number", f.trim()),
                    )
                })?;
                if !v.is_finite() {
                    return Err(FileError::at(
                        path,
                        no + 1,
                        Some(header[c].clone()),
                        format!("{v} is not a finite number"),
                    ));
                }
                row.push(v);
            }
            rows.push(row);
            line_nos.push(no + 1);
        }
        Ok(Table {
            path: path.to_path_buf(),
            header,
            rows,
            lines: line_nos,
        })
    }

    /// Index of the column `name`, if present.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The column `name`, or an error naming the file and the missing column.
    pub fn column(&self, name: &str) -> Result<Vec<f64>, FileError> {
        let c = self.find(name).ok_or_else(|| FileError {
            path: self.path.clone(),
            line: Some(1),
            column: Some(name.into()),
            message: format!("missing column (the header has {})", self.header.join(",")),
        })?;
        Ok(self.rows.iter().map(|r| r[c]).collect())
    }

    /// Checks that column `name` increases strictly from row to row.
    pub fn check_increasing(&self, name: &str) -> Result<(), FileError> {
        let values = self.column(name)?;
        for k in 1..values.len() {
            if values[k] <= values[k - 1] {
                return Err(FileError::at(
                    &self.path,
                    self.lines[k],
                    Some(name.into()),
                    format!(
                        "{} does not increase (previous row: {})",
                        values[k],
                        values[k - 1]
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Writes a table to `path` through a temporary file in the same folder, renamed into place.
/// Each number is written in its shortest form that parses back to the same `f64` (zmij's
/// shortest round-trip conversion), without allocation per row or per number. A long table is
/// formatted in consecutive slices on the machine's threads (formatting is nine tenths of
/// writing a trajectory), then written in order.
pub fn write_atomic<R: AsRef<[f64]> + Sync>(
    path: &Path,
    header: &[&str],
    rows: &[R],
) -> Result<(), FileError> {
    let mut head = header.join(",").into_bytes();
    head.push(b'\n');
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let slices = threads.min(rows.len() / ROWS_PER_THREAD).max(1);
    let per = rows.len().div_ceil(slices).max(1);
    let bodies: Vec<Vec<u8>> = if slices == 1 {
        vec![format_rows(rows)]
    } else {
        std::thread::scope(|s| {
            let handles: Vec<_> = rows
                .chunks(per)
                .map(|chunk| s.spawn(|| format_rows(chunk)))
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("formatting numbers does not panic"))
                .collect()
        })
    };
    let parts: Vec<&[u8]> = std::iter::once(head.as_slice())
        .chain(bodies.iter().map(Vec::as_slice))
        .collect();
    write_parts_atomic(path, &parts)
}

/// Fewest rows worth a thread of their own (a thread costs tens of microseconds; a row about
/// 0.3 µs).
const ROWS_PER_THREAD: usize = 2_000;

/// The rows as CSV lines, into one buffer.
fn format_rows<R: AsRef<[f64]>>(rows: &[R]) -> Vec<u8> {
    let width = rows.first().map_or(0, |r| r.as_ref().len());
    let mut text = Vec::with_capacity(rows.len() * width * BYTES_PER_NUMBER);
    let mut number = zmij::Buffer::new();
    for row in rows {
        format_row(&mut text, &mut number, row.as_ref());
    }
    text
}

/// Room for a number and its separator in the common case (sign, 17 digits, point, exponent,
/// comma).
pub const BYTES_PER_NUMBER: usize = 24;

/// Appends `row` to `text` as one CSV line, each number in its shortest round-trip form
/// (formatted in `number`, which the caller keeps across rows).
pub fn format_row(text: &mut Vec<u8>, number: &mut zmij::Buffer, row: &[f64]) {
    for (k, v) in row.iter().enumerate() {
        if k > 0 {
            text.push(b',');
        }
        text.extend_from_slice(number.format(*v).as_bytes());
    }
    text.push(b'\n');
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Table, FileError> {
        Table::parse(Path::new("x.csv"), text)
    }

    #[test]
    fn errors_name_file_line_and_column() {
        let e = parse("t,U1\n0,1\n0.1,abc\n").unwrap_err();
        assert_eq!(e.to_string(), "x.csv:3, column U1: 'abc' is not a number");
        let e = parse("t,U1\n0,1,2\n").unwrap_err();
        assert_eq!(e.to_string(), "x.csv:2: 3 fields, the header has 2");
        let e = parse("t,U1\n0,nan\n").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("x.csv:2, column U1: NaN is not a finite number")
        );
        let t = parse("# comment\nt,U1\n0,1\n0,2\n").unwrap();
        assert_eq!(
            t.check_increasing("t").unwrap_err().to_string(),
            "x.csv:4, column t: 0 does not increase (previous row: 0)"
        );
        assert!(
            t.column("U2")
                .unwrap_err()
                .to_string()
                .contains("column U2: missing column")
        );
        assert!(parse("").is_err());
        assert!(parse("t,t\n").unwrap_err().to_string().contains("twice"));
    }

    #[test]
    fn written_numbers_read_back_bit_for_bit() {
        let dir = std::env::temp_dir().join(format!("hasel-csv-{}", std::process::id()));
        let path = dir.join("t.csv");
        let values = [
            0.0,
            -0.0,
            1.0 / 3.0,
            -1.3105600766481524e-6,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            0.1 + 0.2,
            123456789.0,
        ];
        // the values, then enough rows to be formatted in slices on several threads, which
        // must come back in order
        let rows: Vec<[f64; 3]> = values
            .iter()
            .map(|&v| [v, -v, v * 1e-9])
            .chain(
                (0..3 * ROWS_PER_THREAD)
                    .map(|k| [k as f64, (k as f64).sqrt(), 1.0 / (k as f64 + 0.5)]),
            )
            .collect();
        write_atomic(&path, &["a", "b", "c"], &rows).unwrap();
        let back = Table::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(back.header, ["a", "b", "c"]);
        for (got, want) in back.rows.iter().zip(&rows) {
            let bits = |r: &[f64]| r.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(got), bits(want));
        }
    }
}
