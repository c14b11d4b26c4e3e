//! Parameter files: TOML with flat keys named as the FMU's parameters (`Kb_1 = 0.305`). A file
//! may hold any subset; the others keep their defaults. Every key and value is checked, and an
//! error names the file, the line and the column.

use std::path::Path;

use super::file::{FileError, write_text_atomic};
use crate::model::Params;
use crate::model::params::{ParamError, parameters};

/// 1-based line and column of byte offset `at` in `text`.
fn line_col(text: &str, at: usize) -> (usize, usize) {
    let before = &text[..at.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

fn located(
    path: &Path,
    text: &str,
    at: usize,
    column_name: Option<&str>,
    message: String,
) -> FileError {
    let (line, col) = line_col(text, at);
    let column = column_name.map_or_else(|| col.to_string(), |n| format!("{col} ({n})"));
    FileError::at(path, line, Some(column), message)
}

/// Reads a parameter file over the defaults.
pub fn read(path: &Path) -> Result<Params, FileError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| FileError::new(path, format!("cannot read: {e}")))?;
    parse(path, &text, Params::default())
}

/// Applies the parameters in `text` (the contents of `path`) over `base`.
pub fn parse(path: &Path, text: &str, base: Params) -> Result<Params, FileError> {
    let mut params = base;
    for (key, v, at) in numbers(path, text)? {
        params.set(&key, v).map_err(|e| match e {
            ParamError::Unknown { .. } => located(
                path,
                text,
                at,
                Some(&key),
                format!("unknown parameter '{key}' (`hasel params` lists them)"),
            ),
            invalid => located(path, text, at, Some(&key), invalid.to_string()),
        })?;
    }
    let spans = key_spans(text);
    params.validate().map_err(|e| {
        let name = match &e {
            ParamError::Invalid { name, .. } | ParamError::Unknown { name } => name.clone(),
        };
        match spans.iter().find(|(k, _)| *k == name) {
            Some((_, at)) => located(path, text, *at, Some(&name), e.to_string()),
            None => FileError::new(path, e.to_string()),
        }
    })?;
    Ok(params)
}

/// The flat `key = number` assignments of the TOML `text` (the contents of `path`), each with
/// the byte offset of its key.
fn numbers(path: &Path, text: &str) -> Result<Vec<(String, f64, usize)>, FileError> {
    let table: toml::Spanned<toml::Table> = toml::from_str(text).map_err(|e| {
        let at = e.span().map_or(0, |s| s.start);
        located(
            path,
            text,
            at,
            None,
            format!("not valid TOML: {}", e.message()),
        )
    })?;
    let spans = key_spans(text);
    table
        .get_ref()
        .iter()
        .map(|(key, value)| {
            let at = spans
                .iter()
                .find(|(k, _)| k == key)
                .map_or(0, |(_, at)| *at);
            match value {
                toml::Value::Float(f) => Ok((key.clone(), *f, at)),
                toml::Value::Integer(i) => Ok((key.clone(), *i as f64, at)),
                other => Err(located(
                    path,
                    text,
                    at,
                    Some(key),
                    format!("{key} must be a number, not {}", other.type_str()),
                )),
            }
        })
        .collect()
}

/// A start file (`--start FILE.toml`): the heights `h1`, `h2`, `h3` \[m\] at a record's first
/// sample, each given, finite and within ±Lv/2 of the parameters `params`.
pub fn read_heights(path: &Path, params: &Params) -> Result<[f64; 3], FileError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| FileError::new(path, format!("cannot read: {e}")))?;
    parse_heights(path, &text, params)
}

/// The heights of the start file `text` (the contents of `path`); `pub` for the fuzz target
/// and its replay (tests/fuzz), which feed it text without a file.
pub fn parse_heights(path: &Path, text: &str, params: &Params) -> Result<[f64; 3], FileError> {
    let mut h = [None; 3];
    for (key, v, at) in numbers(path, text)? {
        let Some(i) = ["h1", "h2", "h3"].iter().position(|k| *k == key) else {
            return Err(located(
                path,
                text,
                at,
                Some(&key),
                format!("unknown key '{key}': a start file gives h1, h2 and h3 [m]"),
            ));
        };
        if !(v.is_finite() && v.abs() < 0.5 * params.lv) {
            return Err(located(
                path,
                text,
                at,
                Some(&key),
                format!(
                    "{key} = {v}: a height must be finite and within +-Lv/2 = {}",
                    0.5 * params.lv
                ),
            ));
        }
        h[i] = Some(v);
    }
    match h {
        [Some(a), Some(b), Some(c)] => Ok([a, b, c]),
        _ => Err(FileError::new(
            path,
            "a start file gives all of h1, h2 and h3 [m]",
        )),
    }
}

/// Byte offsets of the top-level `key =` assignments (the TOML parser's spans cover values).
fn key_spans(text: &str) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let trimmed = line.trim_start();
        if let Some(eq) = trimmed.find('=') {
            let key = trimmed[..eq].trim().trim_matches('"').to_string();
            out.push((key, offset + (line.len() - trimmed.len())));
        }
        offset += line.len();
    }
    out
}

/// The parameters as a TOML document, every parameter with its unit and description.
pub fn to_toml(params: &Params) -> String {
    let mut text = String::from(
        "# HASEL platform parameters (SI units); any subset may be given, the rest keep their defaults\n",
    );
    for d in parameters() {
        let value = (d.get)(params);
        text.push_str(&format!(
            "{} = {:?}  # [{}] {}\n",
            d.name, value, d.unit, d.description
        ));
    }
    text
}

/// Writes the parameters atomically.
pub fn write(path: &Path, params: &Params) -> Result<(), FileError> {
    write_text_atomic(path, &to_toml(params))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_str(text: &str) -> Result<Params, FileError> {
        parse(Path::new("p.toml"), text, Params::default())
    }

    #[test]
    fn round_trips_every_parameter_exactly() {
        let mut p = Params::default();
        p.set("Kb_2", 0.3123456789012345).unwrap();
        p.set("L", 0.0612).unwrap();
        assert_eq!(parse_str(&to_toml(&p)).unwrap(), p);
    }

    #[test]
    fn a_subset_overrides_the_defaults() {
        let p = parse_str("b_1 = 0.2\nK_3 = 1\n").unwrap();
        assert_eq!(p.act[0].b, 0.2);
        assert_eq!(p.act[2].k, 1.0);
        assert_eq!(p.act[1].b, Params::default().act[1].b);
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse_str("b_1 = 0.2\n  C1_2 = -1e-10\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "p.toml:2, column 3 (C1_2): parameter C1_2 = -1e-10: must be finite and > 0"
        );
        let e = parse_str("Kb_1 = 0.3\nKb_9 = 1\n").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("p.toml:2, column 1 (Kb_9): unknown parameter 'Kb_9'"),
            "{e}"
        );
        let e = parse_str("Kb_1 = \"x\"\n").unwrap_err();
        assert!(
            e.to_string().contains("Kb_1 must be a number, not string"),
            "{e}"
        );
        let e = parse_str("Kb_1 = \n").unwrap_err();
        assert!(e.to_string().starts_with("p.toml:1, column"), "{e}");
        assert!(e.to_string().contains("not valid TOML"), "{e}");
        let e = parse_str("Lp = 0.011\n").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("p.toml:1, column 1 (Lp): parameter Lp"),
            "{e}"
        );
    }
}
