//! The inverse path (src/model/model.md, "Inverse kinematics" and "Statics"): `hasel inverse`
//! writes heights whose forward kinematics is the tip path and voltages that hold those heights
//! in a simulation; its inverse of the equilibrium map agrees with the forward one of
//! `hasel linearize`; the points it cannot reach are named and nothing is written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use hasel_fmu::control::equilibrium;
use hasel_fmu::io::csv::Table;
use hasel_fmu::model::statics::{StaticsError, Unreachable, holding_voltages};
use hasel_fmu::model::{Params, Platform};
use hasel_fmu::simulation::Simulator;

fn hasel(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hasel"))
        .args(args)
        .output()
        .expect("hasel runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hasel-inverse-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn paper() -> Platform {
    Platform::new(Params::default()).unwrap()
}

/// Mean height of the paths [m].
const MEAN: f64 = 60e-6;

/// A tip circle of radius 40 µm around the level platform at MEAN (the z of the level
/// platform: its forward kinematics), 25 points over one period of 2 s.
fn circle(dir: &Path) -> (PathBuf, Vec<[f64; 4]>) {
    let z = paper().kinematics.tip([MEAN; 3])[2];
    let points: Vec<[f64; 4]> = (0..25)
        .map(|k| {
            let t = 2.0 * k as f64 / 24.0;
            let phase = std::f64::consts::PI * t;
            [t, 40e-6 * phase.cos(), 40e-6 * phase.sin(), z]
        })
        .collect();
    let mut text = String::from("t,tip_x,tip_y,tip_z\n");
    for p in &points {
        text.push_str(&format!("{:?},{:?},{:?},{:?}\n", p[0], p[1], p[2], p[3]));
    }
    let path = dir.join("tip.csv");
    std::fs::write(&path, text).unwrap();
    (path, points)
}

/// `hasel inverse` on the circle by `method`: rows t, h1..h3, U1..U3.
fn inverse(dir: &Path, method: &[&str]) -> Vec<Vec<f64>> {
    let (tip, _) = circle(dir);
    let out = dir.join("inverse.csv");
    let mut args = vec!["inverse", "--tip", s(&tip), "--out", s(&out)];
    args.extend_from_slice(method);
    let o = hasel(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = Table::read(&out).unwrap();
    assert_eq!(table.header, ["t", "h1", "h2", "h3", "U1", "U2", "U3"]);
    table.rows
}

#[test]
fn the_heights_forward_kinematics_is_the_tip_path() {
    let dir = scratch("fkm");
    let (_, points) = circle(&dir);
    let kinematics = paper().kinematics;
    let mean = MEAN.to_string();
    for (method, xyz) in [
        (&["--method", "exact"][..], 3),
        (&["--method", "xy", "--mean-height", &mean][..], 2),
    ] {
        let rows = inverse(&dir, method);
        assert_eq!(rows.len(), points.len());
        for (row, p) in rows.iter().zip(&points) {
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
                assert!((mean_height - MEAN).abs() <= 1e-15, "{mean_height}");
            }
        }
    }
}

#[test]
fn the_voltages_hold_the_heights_in_a_simulation() {
    let dir = scratch("hold");
    let rows = inverse(&dir, &["--method", "closed"]);
    let model = paper();
    let rest = model.heights(&model.rest_state().unwrap());
    for row in rows.iter().step_by(6) {
        let (h, u) = ([row[1], row[2], row[3]], [row[4], row[5], row[6]]);
        // from rest under the constant voltages: 4 s are 14 time constants of the slowest
        // mode (actuator 1, -3.6 1/s here)
        let mut sim = Simulator::new(model.clone(), 0.0, 1e-10).unwrap();
        sim.step_held(u, 4.0).unwrap();
        let reached = model.heights(sim.state());
        for i in 0..3 {
            let stroke = h[i] - rest[i];
            assert!(
                (reached[i] - h[i]).abs() <= 1e-3 * stroke,
                "t = {}, actuator {}: {} m reached, {} m asked (stroke {stroke} m) under {u:?} V",
                row[0],
                i + 1,
                reached[i],
                h[i]
            );
        }
    }
}

#[test]
fn the_holding_voltages_invert_the_equilibrium_of_hasel_linearize() {
    let model = paper();
    for u in [[60.0, 30.0, 0.5], [45.0, 36.6, 40.4], [100.0, 100.0, 100.0]] {
        let eq = equilibrium::equilibrium(&model, u).unwrap();
        let back = holding_voltages(&model, model.heights(&eq.x)).unwrap();
        for i in 0..3 {
            assert!(
                (back[i] - u[i]).abs() <= 1e-12 * u[i],
                "{back:?} V vs {u:?} V"
            );
        }
    }
}

#[test]
fn heights_without_a_holding_voltage_are_named() {
    let model = paper();
    let rest = model.heights(&model.rest_state().unwrap());
    let cases = [
        ([rest[0] - 1e-6, 5e-5, 5e-5], 1, "below"),
        ([5e-5, 5e-5, 4e-4], 3, "beyond"),
        ([5e-5, 7e-3, 5e-5], 2, "no angle"),
    ];
    for (h, actuator, what) in cases {
        let e = holding_voltages(&model, h).unwrap_err();
        let StaticsError::Actuator { actuator: a, cause } = &e else {
            panic!("{e}")
        };
        assert_eq!(*a, actuator, "{e}");
        let matches = match what {
            "below" => matches!(cause, Unreachable::BelowRest { .. }),
            "beyond" => matches!(cause, Unreachable::BeyondGain { .. }),
            _ => matches!(cause, Unreachable::NoAngle { .. }),
        };
        assert!(matches, "{what}: {e}");
    }
    let mut p = Params::default();
    p.set("k_v", 0.05).unwrap();
    let e = holding_voltages(&Platform::new(p).unwrap(), [5e-5; 3]).unwrap_err();
    assert!(matches!(e, StaticsError::Effects(_)), "{e}");
}

#[test]
fn unreachable_points_are_listed_and_nothing_is_written() {
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
    let err = String::from_utf8_lossy(&o.stderr);
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
        String::from_utf8_lossy(&o.stderr).contains("--method xy needs --mean-height H"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
