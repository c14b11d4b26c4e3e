//! What the integration tests that run the `hasel` binary share: running it, a scratch folder
//! of their own, and reading what it said.
// each test file is its own crate and uses a part of these
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `hasel` binary built with the tests.
pub fn hasel(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hasel"))
        .args(args)
        .output()
        .expect("hasel runs")
}

/// An empty folder of this test process, named after the test file and `name`.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "hasel-{}-{}-{name}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Holds the part of the document `path` between `<!-- generated: NAME -->` and
/// `<!-- /generated: NAME -->` to `text`, what the code generates; with `HASEL_BLESS=1` in the
/// environment it writes `text` there instead.
pub fn generated_section(path: &Path, name: &str, text: &str) {
    let doc = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (open, close) = (
        format!("<!-- generated: {name} -->\n"),
        format!("<!-- /generated: {name} -->"),
    );
    let (Some(start), Some(end)) = (doc.find(&open), doc.find(&close)) else {
        panic!("{}: no `{open}` … `{close}`", path.display());
    };
    let start = start + open.len();
    if std::env::var_os("HASEL_BLESS").is_some() {
        let new = format!("{}{text}{}", &doc[..start], &doc[end..]);
        std::fs::write(path, new).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    } else {
        assert!(
            doc[start..end] == *text,
            "{}: the part `{name}` is not what the code generates; `HASEL_BLESS=1 cargo test` rewrites it\n\
             --- in the file:\n{}\n--- generated:\n{text}",
            path.display(),
            &doc[start..end]
        );
    }
}
