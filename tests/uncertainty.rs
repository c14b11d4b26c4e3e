//! `hasel simulate --samples N --uncertainty identification.json`: the same seed gives the same
//! bands and draws whatever the number of threads; a bad identification file is named with what
//! is wrong, and nothing is written.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{hasel, s, scratch};

fn ok(o: Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// A small synthetic identification: 2 s of the paper's sine at 10 ms, 1 % noise.
fn identification(dir: &Path) -> PathBuf {
    let est = dir.join("est.csv");
    ok(hasel(&[
        "synth",
        "--t-end",
        "2",
        "--dt",
        "1e-2",
        "--noise",
        "0.01",
        "--seed",
        "3",
        "--out",
        s(&est),
    ]));
    let fit = dir.join("fit");
    ok(hasel(&["identify", s(&est), "--out", s(&fit)]));
    fit.join("identification.json")
}

fn bands(id: &Path, out: &Path, draws: &Path, threads: &str, seed: &str) -> String {
    ok(hasel(&[
        "simulate",
        "--samples",
        "8",
        "--uncertainty",
        s(id),
        "--seed",
        seed,
        "--threads",
        threads,
        "--t-end",
        "0.5",
        "--dt",
        "1e-2",
        "--out",
        s(out),
        "--draws",
        s(draws),
    ]))
}

#[test]
fn the_same_seed_gives_the_same_bands_with_one_thread_and_with_two() {
    let dir = scratch("threads");
    let id = identification(&dir);
    let read = |p: &PathBuf| std::fs::read_to_string(p).unwrap();
    let f = |n: &str| dir.join(n);
    let said = bands(&id, &f("one.csv"), &f("one_draws.csv"), "1", "7");
    assert!(said.contains("8 samples of 12 parameters"), "{said}");
    bands(&id, &f("two.csv"), &f("two_draws.csv"), "2", "7");
    bands(&id, &f("other.csv"), &f("other_draws.csv"), "2", "8");
    assert_eq!(read(&f("one.csv")), read(&f("two.csv")));
    assert_eq!(read(&f("one_draws.csv")), read(&f("two_draws.csv")));
    assert_ne!(read(&f("one.csv")), read(&f("other.csv")));
    let text = read(&f("one.csv"));
    let mut lines = text.lines();
    assert!(
        lines
            .next()
            .unwrap()
            .starts_with("t,U1,U2,U3,h1_p2.5,h1_median,h1_p97.5,h2_p2.5")
    );
    assert_eq!(lines.count(), 51);
    // the drawn sets: one row per sample, every parameter, the estimated ones varied
    let draws = read(&f("one_draws.csv"));
    let rows: Vec<&str> = draws.lines().collect();
    assert!(rows[0].starts_with("sample,failed,K_1,"));
    assert_eq!(rows.len(), 9);
    assert_ne!(rows[1].split(',').nth(5), rows[2].split(',').nth(5)); // Kb_1
}

#[test]
fn a_bad_identification_file_is_named_and_nothing_is_written() {
    let dir = scratch("bad");
    let out = dir.join("bands.csv");
    let run = |id: &Path| {
        hasel(&[
            "simulate",
            "--samples",
            "4",
            "--uncertainty",
            s(id),
            "--t-end",
            "0.2",
            "--out",
            s(&out),
        ])
    };
    let cases = [
        ("not json", "{", "not JSON"),
        ("no parameters", "{}", "no \"parameters\" object"),
        (
            "bad matrix",
            r#"{"parameters": {"Kb_1": {"value": 0.3, "estimated": true}},
                "covariance": {"parameters": ["Kb_1"], "coordinates": ["ln"], "matrix": [[1, 2]]}}"#,
            "covariance.matrix row 1: expected 1 numbers",
        ),
        (
            "bad value",
            r#"{"parameters": {"Kb_1": {"value": -0.3}}}"#,
            "parameters.Kb_1: parameter Kb_1 = -3e-1: must be finite and > 0",
        ),
    ];
    for (what, text, message) in cases {
        let id = dir.join("identification.json");
        std::fs::write(&id, text).unwrap();
        let o = run(&id);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{what}");
        assert!(
            err.contains(&format!("{}: ", id.display())),
            "{what}: {err}"
        );
        assert!(err.contains(message), "{what}: {err}");
        assert!(!out.exists(), "{what}: wrote {}", out.display());
    }
    let o = run(&dir.join("missing.json"));
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing.json: cannot read"));
    // --samples needs --uncertainty
    let o = hasel(&["simulate", "--samples", "4"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--uncertainty"));
}
