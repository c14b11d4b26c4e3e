//! The `hasel` command line: outputs on success, and errors that name the file, line and
//! column with nothing written on failure.

mod common;

use std::path::Path;

use common::{hasel, s, scratch, stderr};
use hasel_fmu::io::csv::Table;
use hasel_fmu::model::{Params, Platform};

#[test]
fn simulate_writes_the_trajectory_and_the_figure() {
    let dir = scratch("ok");
    let (csv, png) = (dir.join("run.csv"), dir.join("run.png"));
    let o = hasel(&[
        "simulate",
        "--sine",
        "60,11",
        "--t-end",
        "0.5",
        "--out",
        s(&csv),
        "--plot",
        s(&png),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,U1,U2,U3,h1,h2,h3,tip_x,tip_y,tip_z"));
    assert_eq!(lines.count(), 501);
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
}

#[test]
fn an_unknown_model_is_refused_with_the_allowed_ones() {
    let o = hasel(&["simulate", "--model", "reduced", "--t-end", "0.1"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("'reduced'") && err.contains("--model"),
        "{err}"
    );
    assert!(err.contains("full, quasi-static, slow"), "{err}");
}

#[test]
fn a_reduced_model_runs_from_the_command_line() {
    let dir = scratch("slow");
    let csv = dir.join("run.csv");
    let o = hasel(&[
        "simulate",
        "--model",
        "slow",
        "--sine",
        "60,11",
        "--t-end",
        "0.2",
        "--out",
        s(&csv),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(Table::read(&csv).unwrap().rows.len(), 201);
}

#[test]
fn a_sampled_input_file_drives_the_run() {
    let dir = scratch("input");
    let input = dir.join("u.csv");
    std::fs::write(&input, "t,U1,U2,U3\n0,0,0,0\n0.1,50,0,0\n0.2,50,20,0\n").unwrap();
    let out = dir.join("run.csv");
    let o = hasel(&[
        "simulate",
        "--input",
        s(&input),
        "--interp",
        "pchip",
        "--dt",
        "0.01",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // the run ends at the last sample by default
    assert_eq!(
        std::fs::read_to_string(&out).unwrap().lines().count(),
        1 + 21
    );
}

#[test]
fn a_bad_input_file_is_located_and_nothing_is_written() {
    let dir = scratch("badinput");
    let input = dir.join("u.csv");
    std::fs::write(&input, "t,U1,U2,U3\n0,0,0,0\n0.1,5,x,0\n").unwrap();
    let out = dir.join("run.csv");
    let o = hasel(&["simulate", "--input", s(&input), "--out", s(&out)]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains(&format!(
            "{}:3, column U2: 'x' is not a number",
            input.display()
        )),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());

    std::fs::write(&input, "t,U1,U3\n0,0,0\n0.1,5,0\n").unwrap();
    let o = hasel(&["simulate", "--input", s(&input)]);
    assert!(
        stderr(&o).contains("column U2: missing column"),
        "{}",
        stderr(&o)
    );

    std::fs::write(&input, "t,U1,U2,U3\n0,0,0,0\n0,5,0,0\n").unwrap();
    let o = hasel(&["simulate", "--input", s(&input)]);
    assert!(
        stderr(&o).contains(":3, column t: 0 does not increase"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_bad_parameter_file_is_located() {
    let dir = scratch("badparams");
    let params = dir.join("p.toml");
    std::fs::write(&params, "Kb_1 = 0.3\nC1_2 = -2e-10\n").unwrap();
    let o = hasel(&["simulate", "--params", s(&params), "--t-end", "0.1"]);
    assert!(!o.status.success());
    let msg = stderr(&o);
    assert!(
        msg.contains(&format!(
            "{}:2, column 1 (C1_2): parameter C1_2 = -2e-10: must be finite and > 0",
            params.display()
        )),
        "{msg}"
    );
}

#[test]
fn a_multisine_drives_the_run() {
    let dir = scratch("multisine");
    let csv = dir.join("run.csv");
    let o = hasel(&[
        "simulate",
        "--multisine",
        "40:3,30:17:0.5",
        "--t-end",
        "0.2",
        "--out",
        s(&csv),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    // U1 at t = 0.1 s: 40 sin(0.3) + 30 sin(1.7 + 0.5)
    let row: Vec<f64> = text
        .lines()
        .nth(101)
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert!((row[0] - 0.1).abs() < 1e-12);
    assert!(
        (row[1] - (40.0 * 0.3f64.sin() + 30.0 * 2.2f64.sin())).abs() < 1e-9,
        "{row:?}"
    );
    let o = hasel(&["simulate", "--multisine", "40:x"]);
    assert!(
        stderr(&o).contains("'40:x' is not A:OMEGA[:PHASE]"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn bad_flags_are_named() {
    let o = hasel(&["simulate", "--sine", "60,fast"]);
    assert!(
        stderr(&o).contains("--sine 60,fast: expected two numbers U0,OMEGA"),
        "{}",
        stderr(&o)
    );
    let o = hasel(&["simulate", "--rtol", "2", "--t-end", "0.1"]);
    assert!(stderr(&o).contains("rtol = 2e0"), "{}", stderr(&o));
    // refused before any case runs
    for bad in [
        "--rtol=0",
        "--rtol=-1e-6",
        "--rtol=NaN",
        "--rtol=1",
        "--rtol=0.5",
    ] {
        let o = hasel(&["bench", "--diagnose", bad]);
        assert!(!o.status.success());
        assert!(stderr(&o).contains("must be in (0, 0.1)"), "{}", stderr(&o));
        assert!(
            o.stdout.is_empty(),
            "{}",
            String::from_utf8_lossy(&o.stdout)
        );
    }
    // a diagnosis refuses it before reading the records or writing anything
    let out = scratch("diagnose_rtol").join("out");
    let o = hasel(&["diagnose", "missing.csv", "--out", s(&out), "--rtol=0"]);
    assert!(
        stderr(&o).contains("--rtol = 0e0: must be in (0, 0.1)"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
}

#[test]
fn params_round_trip_through_the_command() {
    let dir = scratch("params");
    let p = dir.join("p.toml");
    std::fs::write(&p, "b_1 = 0.2\n").unwrap();
    let out = dir.join("all.toml");
    assert!(
        hasel(&["params", "--params", s(&p), "--out", s(&out)])
            .status
            .success()
    );
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("b_1 = 0.2  # [N.m.s/rad]"), "{text}");
    assert!(text.contains("Kb_2 = 0.3  #"), "{text}");
}

#[test]
fn packing_refuses_a_file_that_is_not_a_library() {
    let dir = scratch("pack");
    let fake = dir.join("lib.so");
    std::fs::write(&fake, "not elf").unwrap();
    let out = dir.join("x.fmu");
    let o = hasel(&["fmu", "--lib", s(&fake), "--out", s(&out)]);
    assert!(
        stderr(&o).contains("not a shared library (ELF, PE or Mach-O)"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
}

/// A fake library: the `header` bytes, then the names of the FMI functions it says it exports.
fn fake_library(header: &[(usize, &[u8])]) -> Vec<u8> {
    let mut bytes = vec![0u8; 64];
    for (at, b) in header {
        bytes[*at..*at + b.len()].copy_from_slice(b);
    }
    bytes.extend_from_slice(b"fmi2Instantiate fmi3InstantiateCoSimulation");
    bytes
}

/// One build of the library exports FMI 2.0's and 3.0's functions: `--lib` alone packs both
/// FMUs. A macOS universal library, which FMI 3.0 cannot take, is refused before either is
/// written, with the flag that gives the FMI 3.0 FMU libraries of its own.
#[test]
fn one_library_packs_both_versions_fmus() {
    let dir = scratch("pack_both");
    let elf = fake_library(&[(0, b"\x7fELF"), (4, &[2, 1]), (16, &[3]), (18, &[62])]);
    let lib = dir.join("libhasel_fmu.so");
    std::fs::write(&lib, elf).unwrap();
    let out = dir.join("p.fmu");
    let o = hasel(&["fmu", "--lib", s(&lib), "--out", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    for (fmu, member) in [
        (out, "binaries/linux64/HaselPlatform.so"),
        (
            dir.join("p-fmi3.fmu"),
            "binaries/x86_64-linux/HaselPlatform.so",
        ),
    ] {
        let mut zip = zip::ZipArchive::new(std::fs::File::open(&fmu).unwrap()).unwrap();
        assert!(
            zip.by_name(member).is_ok(),
            "{} lacks {member}",
            fmu.display()
        );
    }

    let universal = fake_library(&[
        (0, &[0xca, 0xfe, 0xba, 0xbe]),
        (4, &2u32.to_be_bytes()),
        (8, &0x0100_0007u32.to_be_bytes()),
        (28, &0x0100_000cu32.to_be_bytes()),
    ]);
    let lib = dir.join("libhasel_fmu.dylib");
    std::fs::write(&lib, universal).unwrap();
    let out = dir.join("mac.fmu");
    let o = hasel(&["fmu", "--lib", s(&lib), "--out", s(&out)]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("FMI 3.0 takes one library per Mac architecture")
            && stderr(&o).contains("--lib-fmi3"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists() && !dir.join("mac-fmi3.fmu").exists());
}

#[test]
fn identify_refuses_bad_data_and_writes_nothing() {
    let dir = scratch("identify");
    let exp = dir.join("e.csv");
    let o = hasel(&["synth", "--t-end", "2", "--noise", "0.01", "--out", s(&exp)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&exp).unwrap();
    assert!(text.starts_with("t,U1,U2,U3,h1,h2,h3\n"));
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, text.replacen("h2", "height2", 1)).unwrap();
    let out = dir.join("out");
    let o = hasel(&["identify", s(&exp), "--validate", s(&bad), "--out", s(&out)]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains(&format!(
            "{}:1, column height2: unknown column",
            bad.display()
        )),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
}

/// The README's example: a poor first guess, fitted, each estimate printed beside that guess
/// (it was shown beside where the fit after the records' conditions were found began).
#[test]
fn identify_shows_each_estimate_beside_the_callers_start() {
    let dir = scratch("identify_start");
    let (est, val) = (dir.join("est.csv"), dir.join("val.csv"));
    for (file, sine, seed) in [(&est, "60,11", "1"), (&val, "60,30", "2")] {
        let args = ["synth", "--sine", sine, "--noise", "0.01", "--seed", seed];
        let o = hasel(&[&args[..], &["--out", s(file)]].concat());
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let start = dir.join("start.toml");
    std::fs::write(&start, "Kb_1 = 0.4\nb_1 = 0.2\ngamma1_2 = 100\n").unwrap();
    let out = dir.join("out");
    let o = hasel(&[
        "identify",
        s(&est),
        "--validate",
        s(&val),
        "--params",
        s(&start),
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let printed = String::from_utf8_lossy(&o.stdout);
    let line = |name: &str| {
        printed
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{name} ")))
            .unwrap_or_else(|| panic!("{name} not printed: {printed}"))
            .to_string()
    };
    assert!(
        line("Kb_1").contains("(start 0.400000)"),
        "{}",
        line("Kb_1")
    );
    assert!(
        line("gamma1_2").contains("(start 100.000000)"),
        "{}",
        line("gamma1_2")
    );
}

/// `--weigh noise` fits each output over its record's noise and says so in the JSON and the
/// report; a weighting it does not know is refused by name.
#[test]
fn identify_weighs_by_the_noise_when_asked() {
    let dir = scratch("identify_weigh");
    let exp = dir.join("e.csv");
    let o = hasel(&["synth", "--t-end", "1", "--noise", "0.01", "--out", s(&exp)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = dir.join("out");
    let args = ["identify", s(&exp), "--free", "gamma1_1", "--out", s(&out)];
    let o = hasel(&[&args[..], &["--weigh", "noise"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let json = std::fs::read_to_string(out.join("identification.json")).unwrap();
    assert!(json.contains("\"weighting\": \"noise\""), "{json}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("in units of the noise its record shows"),
        "{report}"
    );
    let o = hasel(&[&args[..], &["--weigh", "loud"]].concat());
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--weigh"), "{}", stderr(&o));
}

#[test]
fn diagnose_answers_in_json_and_refuses_bad_data() {
    let dir = scratch("diagnose");
    let (a, b) = (dir.join("w3pi.csv"), dir.join("w11.csv"));
    for (file, sine, seed) in [(&a, "60,9.42477796", "1"), (&b, "60,11", "2")] {
        let o = hasel(&[
            "synth",
            "--effect",
            "none",
            "--sine",
            sine,
            "--t-end",
            "3",
            "--seed",
            seed,
            "--out",
            s(file),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(String::from_utf8_lossy(&o.stdout).contains("hidden: no effect"));
    }
    let out = dir.join("out");
    let o = hasel(&["diagnose", s(&a), s(&b), "--out", s(&out), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON on stdout");
    assert_eq!(json["verdict"], "none");
    assert_eq!(json["effects"], serde_json::json!([]));
    for key in ["fit_before", "fit_after", "candidates", "ambiguous_between"] {
        assert!(json.get(key).is_some(), "{key} missing");
    }
    for file in [
        "diagnosis.json",
        "report.md",
        "fitted.toml",
        "diagnosis_0.png",
    ] {
        assert!(out.join(file).exists(), "{file} missing");
    }

    let bad = dir.join("bad.csv");
    let text = std::fs::read_to_string(&b).unwrap();
    // the second data row (file line 3) gets a field that is not a number
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    lines[2] = lines[2].replacen(',', ",x", 1);
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let out = dir.join("out2");
    let o = hasel(&["diagnose", s(&a), s(&bad), "--out", s(&out)]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains(&format!("{}:3", bad.display())),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());

    let o = hasel(&[
        "synth",
        "--effect",
        "gremlins",
        "--out",
        s(&dir.join("g.csv")),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--effect gremlins"), "{}", stderr(&o));
}

/// `hasel inverse` on a 40 µm tip circle around the level platform at 60 µm by `method`: the
/// path's rows t, x, y, z and the written rows t, h1..h3, U1..U3.
fn inverse_circle(dir: &Path, method: &[&str]) -> (Vec<[f64; 4]>, Vec<Vec<f64>>) {
    let kinematics = Platform::new(Params::default()).unwrap().kinematics;
    let z = kinematics.tip([60e-6; 3])[2];
    let mut text = String::from("t,tip_x,tip_y,tip_z\n");
    let path: Vec<[f64; 4]> = (0..25)
        .map(|k| {
            let t = k as f64 / 12.0;
            let phase = std::f64::consts::PI * t;
            [t, 40e-6 * phase.cos(), 40e-6 * phase.sin(), z]
        })
        .collect();
    for p in &path {
        text.push_str(&format!("{:?},{:?},{:?},{:?}\n", p[0], p[1], p[2], p[3]));
    }
    let (tip, out) = (dir.join("tip.csv"), dir.join("inverse.csv"));
    std::fs::write(&tip, text).unwrap();
    let mut args = vec!["inverse", "--tip", s(&tip), "--out", s(&out)];
    args.extend_from_slice(method);
    let o = hasel(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = Table::read(&out).unwrap();
    assert_eq!(table.header, ["t", "h1", "h2", "h3", "U1", "U2", "U3"]);
    (path, table.rows)
}

#[test]
fn inverse_writes_heights_whose_forward_kinematics_is_the_tip_path() {
    let dir = scratch("inverse");
    let kinematics = Platform::new(Params::default()).unwrap().kinematics;
    for (method, xyz) in [
        (&["--method", "exact"][..], 3),
        (&["--method", "xy", "--mean-height", "60e-6"][..], 2),
    ] {
        let (path, rows) = inverse_circle(&dir, method);
        assert_eq!(rows.len(), path.len());
        for (row, p) in rows.iter().zip(&path) {
            assert!((row[0] - p[0]).abs() <= 1e-12, "t {} vs {}", row[0], p[0]);
            let tip = kinematics.tip([row[1], row[2], row[3]]);
            for axis in 0..xyz {
                // the heights as written (13 digits) put the tip on the path to 1e-12 m
                assert!(
                    (tip[axis] - p[axis + 1]).abs() <= 1e-12,
                    "{method:?} t = {}: tip {tip:?} vs {p:?}",
                    p[0]
                );
            }
            if xyz == 2 {
                let mean_height = (row[1] + row[2] + row[3]) / 3.0;
                assert!((mean_height - 60e-6).abs() <= 1e-15, "{mean_height}");
            }
            assert!(row[4..].iter().all(|u| *u > 0.0), "{row:?}");
        }
    }
}

#[test]
fn inverse_lists_the_points_it_cannot_reach_and_writes_nothing() {
    let dir = scratch("unreachable");
    let tip = dir.join("tip.csv");
    std::fs::write(
        &tip,
        "t,tip_x,tip_y,tip_z\n0,0,0,0.05005\n0.5,0,0,0.0503\n1,0,0,0.049\n",
    )
    .unwrap();
    let out = dir.join("inverse.csv");
    let o = hasel(&["inverse", "--tip", s(&tip), "--out", s(&out)]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("2 of 3 tip points cannot be reached (nothing written)")
            && err.contains("line 3, t = 0.5 s: actuator 1: h = 3.000000e-4 m is at or beyond")
            && err.contains(
                "line 4, t = 1 s: actuator 1: h = -1.000000e-3 m is below the rest height"
            ),
        "{err}"
    );
    assert!(!out.exists());
    let o = hasel(&[
        "inverse",
        "--tip",
        s(&tip),
        "--method",
        "xy",
        "--out",
        s(&out),
    ]);
    assert!(
        stderr(&o).contains("--method xy needs --mean-height H"),
        "{}",
        stderr(&o)
    );
}
