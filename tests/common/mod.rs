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
