//! Control design from the model (book/src/control.md, "Control design: `hasel linearize`"): the
//! model's input and output Jacobians against central differences, the equilibrium, the
//! linearization against the nonlinear simulation, the port-Hamiltonian decomposition and
//! passivity, the reduced model, and `hasel linearize`.

mod common;

use std::path::Path;

use common::{hasel, s, scratch};

use hasel_fmu::control::frequency::{self, Evaluator, log_grid};
use hasel_fmu::control::linearize::Point;
use hasel_fmu::control::port_hamiltonian::{self, PortHamiltonian};
use hasel_fmu::control::{
    ControlError, Linearization, linalg, linearize_at, linearize_equilibrium, reduce,
};
use hasel_fmu::model::effects::Effect;
use hasel_fmu::model::effects::hysteresis::HysteresisLaw;
use hasel_fmu::model::{Params, Platform, actuator};
use hasel_fmu::simulation::{Input, Simulator};
use nalgebra::DMatrix;

fn paper() -> Platform {
    Platform::new(Params::default()).unwrap()
}

/// The state the paper's excitation (60 V sine at 3π rad/s) reaches at 0.3 s, and the
/// voltages there: charged, moving, off the equilibria.
fn simulated_state(model: &Platform) -> (Vec<f64>, [f64; 3]) {
    let mut sim = Simulator::new(model.clone(), 0.0, 1e-9).unwrap();
    let input = Input::sine(60.0, 3.0 * std::f64::consts::PI);
    sim.run(&input, 0.3, 0.3, |_| {}).unwrap();
    (sim.state().to_vec(), input.value(0.3))
}

/// Central differences of `f` (m outputs) in each coordinate of `x` with steps `h`, as an
/// m × n matrix.
fn central(f: impl Fn(&[f64]) -> Vec<f64>, x: &[f64], h: &[f64]) -> DMatrix<f64> {
    let m = f(x).len();
    let mut d = DMatrix::zeros(m, x.len());
    for c in 0..x.len() {
        let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
        xp[c] += h[c];
        xm[c] -= h[c];
        let (fp, fm) = (f(&xp), f(&xm));
        for r in 0..m {
            d[(r, c)] = (fp[r] - fm[r]) / (2.0 * h[c]);
        }
    }
    d
}

/// Per column: max_r |w_r (analytic − fd)| ≤ 1e-6 max_r |w_r fd| (w: row weights, the inverse
/// state scales for ẋ so that charges and angles weigh alike).
fn assert_columns(what: &str, analytic: &DMatrix<f64>, fd: &DMatrix<f64>, w: &[f64]) {
    for c in 0..fd.ncols() {
        let err = (0..fd.nrows())
            .map(|r| (w[r] * (analytic[(r, c)] - fd[(r, c)])).abs())
            .fold(0.0, f64::max);
        let size = (0..fd.nrows())
            .map(|r| (w[r] * fd[(r, c)]).abs())
            .fold(0.0, f64::max);
        assert!(
            err <= 1e-6 * size || (size == 0.0 && err == 0.0),
            "{what}, column {c}: error {err:e} against {size:e}"
        );
    }
}

fn rhs(model: &Platform, x: &[f64], u: [f64; 3]) -> Vec<f64> {
    let mut f = vec![0.0; x.len()];
    model.rhs(x, u, &mut f).unwrap();
    f
}

/// A, B and C of the model at (x, u) against central differences of f and of the outputs.
fn check_jacobians(model: &Platform, x: &[f64], u: [f64; 3]) {
    let n = model.n_states();
    let scales = model.state_scales();
    let weights: Vec<f64> = scales.iter().map(|s| 1.0 / s).collect();
    let h: Vec<f64> = scales.iter().map(|s| 1e-6 * s).collect();

    let mut a = vec![0.0; n * n];
    model.jacobian(x, u, &mut a).unwrap();
    let fd = central(|x| rhs(model, x, u), x, &h);
    assert_columns("A", &DMatrix::from_column_slice(n, n, &a), &fd, &weights);

    let mut b = vec![0.0; n * 3];
    model.input_jacobian(x, u, &mut b).unwrap();
    let hu: Vec<f64> = u.iter().map(|v| 1e-3 * v.abs().max(1.0)).collect();
    let fd = central(|v| rhs(model, x, [v[0], v[1], v[2]]), &u, &hu);
    assert_columns("B", &DMatrix::from_column_slice(n, 3, &b), &fd, &weights);

    let mut c = vec![0.0; 6 * n];
    model.output_jacobian(x, &mut c);
    let fd = central(|x| model.outputs(x).to_vec(), x, &h);
    assert_columns("C", &DMatrix::from_column_slice(6, n, &c), &fd, &[1.0; 6]);
    assert_eq!(model.output_input_jacobian(), [[0.0; 3]; 6]);
}

#[test]
fn input_and_output_jacobians_match_central_differences_away_from_rest() {
    let model = paper();
    let (x, u) = simulated_state(&model);
    assert!(x[actuator::P].abs() > 0.0 && u.iter().all(|v| v.abs() > 1.0));
    check_jacobians(&model, &x, u);
    // at an equilibrium with every voltage on
    let lin = linearize_equilibrium(&model, [60.0, 30.0, 45.0]).unwrap();
    check_jacobians(&model, &lin.x0, lin.u0);
}

#[test]
fn hessian_and_port_output_jacobian_match_central_differences() {
    let model = paper();
    let (x, _) = simulated_state(&model);
    for (i, a) in model.actuators.iter().enumerate() {
        let xi = &x[5 * i..5 * i + 5];
        let scales = &model.state_scales()[5 * i..5 * i + 5];
        let h: Vec<f64> = scales.iter().map(|s| 1e-6 * s).collect();
        let hess = a.hessian(xi).unwrap();
        let analytic = DMatrix::from_fn(5, 5, |r, c| hess[r][c]);
        let fd = central(|x| a.grad_h(x).unwrap().to_vec(), xi, &h);
        let w: Vec<f64> = scales.to_vec();
        // ∂(∇H)_r/∂x_c weighs with the scale of x_r (∇H_r is a force conjugate to x_r)
        assert_columns("Hessian", &analytic, &fd, &w);
        assert_eq!(analytic, analytic.transpose(), "symmetric");
        let cp = a.port_output_jacobian(xi).unwrap();
        let fd = central(|x| vec![a.port_output(x).unwrap()], xi, &h);
        assert_columns(
            "port output",
            &DMatrix::from_row_slice(1, 5, &cp),
            &fd,
            &[1.0],
        );
    }
}

#[test]
fn the_equilibrium_is_exact_to_rounding_and_is_where_the_simulation_settles() {
    let model = paper();
    let u = [60.0, 30.0, 45.0];
    let lin = linearize_equilibrium(&model, u).unwrap();
    let Point::Equilibrium(eq) = &lin.point else {
        panic!("an equilibrium")
    };
    // |f(x0, u0)| relative to the size of its terms: rounding
    assert!(eq.residual < 1e-15, "residual {:e}", eq.residual);
    for i in 0..3 {
        assert_eq!(lin.x0[5 * i + actuator::P], 0.0);
        assert!(eq.stiffness[i][i] > 0.0);
    }
    // 8 s from rest under the constant voltages: 40 time constants of the slowest mode
    let mut sim = Simulator::new(model.clone(), 0.0, 1e-10).unwrap();
    sim.run(&Input::constant(u), 8.0, 8.0, |_| {}).unwrap();
    let y = model.outputs(sim.state());
    for (r, (got, want)) in y.iter().zip(lin.y0).enumerate() {
        assert!(
            (got - want).abs() <= 1e-12,
            "output {r}: simulated {got:e}, equilibrium {want:e}"
        );
    }
}

#[test]
fn eigenvalues_at_rest_are_the_readmes_time_scales() {
    let model = paper();
    let lin = linearize_equilibrium(&model, [0.0; 3]).unwrap();
    let ev = &lin.eigenvalues;
    assert_eq!(ev.len(), 15);
    assert!(ev.iter().all(|e| e.im == 0.0), "all real at rest");
    let mut rates: Vec<f64> = ev.iter().map(|e| -e.re).collect();
    rates.sort_by(f64::total_cmp);
    // one zero per actuator (the Casimir), to rounding
    for r in &rates[..3] {
        assert!(r.abs() < 1e-12, "zero eigenvalue {r:e}");
    }
    // book/src/control.md, "Time scales and accuracy": slow −2.4 to −30, mechanical −1.8e4 to
    // −2.3e5, electrical −4.4e7 and −3.65e8
    let near = |got: f64, want: f64, tol: f64| (got / want - 1.0).abs() <= tol;
    assert!(
        near(rates[3], 2.4, 0.02) && near(rates[5], 30.0, 0.01),
        "{rates:?}"
    );
    assert!(
        near(rates[6], 1.8e4, 0.03) && near(rates[8], 2.3e5, 0.02),
        "{rates:?}"
    );
    for r in &rates[9..12] {
        assert!(near(*r, 4.4e7, 0.04), "{rates:?}");
    }
    for r in &rates[12..] {
        assert!(near(*r, 3.65e8, 0.005), "{rates:?}");
    }
    // the minimal model has exactly the others
    let mut minimal: Vec<f64> = lin.minimal_eigenvalues.iter().map(|e| -e.re).collect();
    minimal.sort_by(f64::total_cmp);
    for (m, r) in minimal.iter().zip(&rates[3..]) {
        assert!(near(*m, *r, 1e-9), "{m} vs {r}");
    }
    // w_iᵀ A = 0 and w_iᵀ B = 0 at the equilibrium
    assert!(lin.casimirs.left_residual < 1e-15 && lin.casimirs.input_residual == 0.0);
}

#[test]
fn a_small_sine_through_the_nonlinear_model_has_the_linear_gain_and_phase() {
    let model = paper();
    let lin = linearize_equilibrium(&model, [60.0, 30.0, 45.0]).unwrap();
    let checks = frequency::sine_check(&model, &lin, 0.5, &[0.2, 2.0, 20.0], 1e-9).unwrap();
    assert_eq!(checks.len(), 18, "every output at three frequencies");
    for c in &checks {
        // gain and phase together: |G_nonlinear / G_linear − 1| ≤ 1 %
        let rel = (c.nonlinear / c.linear - 1.0).norm();
        assert!(
            rel <= 0.01,
            "{} Hz, output {}: gain error {:e}, phase error {:e} rad",
            c.frequency,
            c.output,
            c.gain_error(),
            c.phase_error()
        );
    }
}

fn decompose(model: &Platform, u: [f64; 3]) -> (Linearization, PortHamiltonian) {
    let lin = linearize_equilibrium(model, u).unwrap();
    let ph = port_hamiltonian::decompose(model, &lin).unwrap();
    (lin, ph)
}

#[test]
fn at_rest_the_linearization_is_exactly_port_hamiltonian_and_passive() {
    let model = paper();
    let (_, ph) = decompose(&model, [0.0; 3]);
    let c = &ph.checks;
    assert_eq!(c.j_skew, 0.0);
    assert_eq!(c.r_asymmetry, 0.0);
    assert!(c.r_eigenvalues.0 >= -1e-12 * c.r_eigenvalues.1);
    assert!(c.q_asymmetry < 1e-15);
    assert!(c.q_reachable_eigenvalues.0 > 0.0);
    // the plain Hessian misses the variation of J (∂H/∂l_p ≠ 0 under gravity) ...
    assert!(
        c.residual_hessian_rows > 1e-12,
        "{:e}",
        c.residual_hessian_rows
    );
    // ... which the Casimir leaf's curvature absorbs exactly, at both ports
    assert!(
        c.residual_source_port_rows < 1e-15,
        "{:e}",
        c.residual_source_port_rows
    );
    assert!(c.residual_voltage_port_rows < 1e-15);
    assert!(c.collocation_voltage_port < 1e-15);
    assert!(c.kyp_voltage_port >= -1e-15, "{:e}", c.kyp_voltage_port);
    assert!(ph.passivity.passive && ph.passivity.min_hermitian > 0.0);
}

#[test]
fn under_voltage_the_source_port_is_exactly_port_hamiltonian_the_voltage_port_is_not() {
    let model = paper();
    let (lin, ph) = decompose(&model, [60.0, 30.0, 45.0]);
    let c = &ph.checks;
    // exact: A = (J − R) Q + g_w K_x, B = g_w K_u, Q ≥ 0 on the reachable subspace
    assert!(
        c.residual_source_port_rows < 1e-15,
        "{:e}",
        c.residual_source_port_rows
    );
    assert_eq!(c.residual_input, 0.0);
    assert!(c.q_reachable_eigenvalues.0 > 0.0);
    // what the voltage port misses is the modulated source ga'(θ0) U0, not rounding
    assert!(c.residual_voltage_port_rows > 1e-3);
    assert!(c.collocation_voltage_port > 1e-3);
    assert!(c.kyp_voltage_port < -1e-6);
    // and its passivity: lost for actuator 1 at 60 V, a negative static conductance, which
    // central differences of the port current along the equilibria confirm
    let p = &ph.passivity;
    assert!(p.stable && !p.passive);
    assert_eq!(p.worst_frequency, 0.0);
    assert!(
        p.dc[0] < 0.0 && p.dc[1] > 0.0 && p.dc[2] > 0.0,
        "{:?}",
        p.dc
    );
    let port = |u1: f64| {
        let eq = hasel_fmu::control::equilibrium(&model, [u1, 30.0, 45.0]).unwrap();
        model.actuators[0].port_output(&eq.x[..5]).unwrap()
    };
    let fd = (port(60.01) - port(59.99)) / 0.02;
    assert!((fd / p.dc[0] - 1.0).abs() < 1e-6, "{fd} vs {}", p.dc[0]);
    let _ = lin;
    // at 30 V every port is still passive
    let (_, ph) = decompose(&model, [30.0; 3]);
    assert!(ph.passivity.passive, "{:?}", ph.passivity);
}

#[test]
fn the_reduced_model_keeps_its_error_bound_and_drops_the_zero_modes() {
    let model = paper();
    let lin = linearize_equilibrium(&model, [60.0, 30.0, 45.0]).unwrap();
    let r = reduce::reduce(&lin, 1e-3).unwrap();
    assert!(r.order >= 3 && r.order <= 6, "order {}", r.order);
    assert!(r.bound <= 1e-3 * r.peak_gain);
    assert!(r.hankel.windows(2).all(|w| w[0] >= w[1]));
    assert!(
        r.eigenvalues.iter().all(|e| e.re < -1.0),
        "{:?}",
        r.eigenvalues
    );
    assert!(r.system.states.iter().all(|s| s.starts_with('z')));
    // the a-priori bound holds at every frequency, not only up to 100 Hz
    assert!(r.error.max_abs <= r.bound);
    let full = Evaluator::new(&lin.minimal());
    let reduced = Evaluator::new(&r.system);
    let mut freqs = vec![0.0];
    freqs.extend(log_grid(1e-2, 1e9, 10));
    for f in freqs {
        let w = 2.0 * std::f64::consts::PI * f;
        let e = full.at(w).unwrap() - reduced.at(w).unwrap();
        assert!(linalg::spectral_norm(&e) <= r.bound, "{f} Hz");
    }
    // the full state from the reduced one, at DC: δx = state_map z + input_map δU
    let du = DMatrix::from_column_slice(3, 1, &[1.0, 1.0, 1.0]);
    let m = lin.minimal();
    let x_min = -linalg::solve(&m.a, &(&m.b * &du), "test").unwrap();
    let z = -linalg::solve(&r.system.a, &(&r.system.b * &du), "test").unwrap();
    let x = &r.state_map * z + &r.input_map * &du;
    for i in 0..3 {
        let theta = x_min[(4 * i, 0)];
        assert!(
            (x[(5 * i, 0)] / theta - 1.0).abs() < 1e-6,
            "theta_{}",
            i + 1
        );
    }
    // at rest there is nothing to reduce: the first-order gain is zero (force ∝ U²)
    let rest = linearize_equilibrium(&model, [0.0; 3]).unwrap();
    assert!(matches!(
        reduce::reduce(&rest, 1e-3),
        Err(ControlError::NoGain)
    ));
}

#[test]
fn effects_are_linearized_with_the_model() {
    let mut p = Params::default();
    for (name, value) in [
        ("k_c", 20.0),
        ("R3", 2e4),
        ("tau3", 0.05),
        ("k_v", 0.1),
        ("tau_v", 0.05),
        ("tau_a", 2e-3),
        ("U_max", 100.0),
        ("k3", 50.0),
        ("tau0_2", 1e-4),
    ] {
        p.set(name, value).unwrap();
    }
    let model = Platform::new(p.clone()).unwrap();
    assert_eq!(model.n_states(), 3 * 8);
    let u = [60.0, 30.0, 45.0];
    let lin = linearize_equilibrium(&model, u).unwrap();
    let Point::Equilibrium(eq) = &lin.point else {
        panic!()
    };
    assert!(eq.residual < 1e-14, "residual {:e}", eq.residual);
    assert_eq!(lin.system.n_states(), 24);
    assert!(lin.notes.is_empty(), "{:?}", lin.notes);
    check_jacobians(&model, &lin.x0, u);
    let (x, v) = simulated_state(&model);
    check_jacobians(&model, &x, v);
    // the simulation settles where the equilibrium is
    let mut sim = Simulator::new(model.clone(), 0.0, 1e-10).unwrap();
    sim.run(&Input::constant(u), 8.0, 8.0, |_| {}).unwrap();
    let y = model.outputs(sim.state());
    for (r, (got, want)) in y.iter().zip(lin.y0).enumerate() {
        assert!(
            (got - want).abs() <= 1e-11,
            "output {r}: {got:e} vs {want:e}"
        );
    }
    // the PH decomposition is for the paper's model
    assert!(matches!(
        port_hamiltonian::decompose(&model, &lin),
        Err(ControlError::Unsupported { .. })
    ));
    assert!(reduce::reduce(&lin, 1e-3).is_ok());

    // the clamp exactly at its limit, and hysteresis at rest, are not smooth: said so
    let mut q = Params::default();
    q.set("U_max", 60.0).unwrap();
    q.set("k_h", 0.05).unwrap();
    q.effects.hysteresis.law = HysteresisLaw::BoucWen;
    let model = Platform::new(q).unwrap();
    assert!(
        model
            .params()
            .effects
            .active()
            .contains(&Effect::Hysteresis)
    );
    let lin = linearize_equilibrium(&model, [60.0, 30.0, 0.0]).unwrap();
    let rough: Vec<_> = lin.notes.iter().filter(|n| !n.smooth).collect();
    assert!(
        rough
            .iter()
            .any(|n| n.effect == "saturation" && n.actuator == Some(1)),
        "{:?}",
        lin.notes
    );
    assert!(
        rough
            .iter()
            .any(|n| n.effect == "hysteresis" && n.actuator == Some(1))
    );
}

#[test]
fn a_simulated_state_linearizes_as_a_frozen_jacobian() {
    let model = paper();
    let (x, u) = simulated_state(&model);
    let lin = linearize_at(&model, &x, u, 0.3).unwrap();
    let Point::Trajectory { rate, .. } = lin.point else {
        panic!()
    };
    assert!(rate > 1e-3, "not an equilibrium: {rate:e}");
    let minimal = lin.minimal();
    assert_eq!(minimal.n_states(), 12);
    assert!(!minimal.states.iter().any(|s| s.starts_with("l_p")));
}

#[test]
fn bad_voltages_are_refused() {
    let model = paper();
    let e = linearize_equilibrium(&model, [f64::INFINITY, 0.0, 0.0]).unwrap_err();
    assert_eq!(e.to_string(), "U1 = inf: must be a finite number");
}

// ----- the command line -----

/// A CSV matrix as written for numpy's loadtxt(delimiter=",") and MATLAB's readmatrix: plain
/// numbers, no header, every row the same length.
fn read_csv(path: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
        .collect();
    assert!(rows.iter().all(|r| r.len() == rows[0].len()));
    rows
}

fn json_matrix(v: &serde_json::Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

#[test]
fn cli_linearize_writes_the_model_the_matrices_and_the_figures() {
    let dir = scratch("ok");
    let o = hasel(&["linearize", "--u", "60,30,0", "--out", s(&dir)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("3 zero, one per actuator"), "{out}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("linearization.json")).unwrap())
            .unwrap();
    let n = json["states"].as_array().unwrap().len();
    assert_eq!(n, 15);
    assert_eq!(json["states"][1], "l_p_1");
    assert_eq!(json["inputs"], serde_json::json!(["U1", "U2", "U3"]));
    assert_eq!(json["outputs"][3], "tip_x");
    // the CSVs hold the library's numbers to the last bit (the JSON too, but serde_json's
    // default parser may round the last bit on reading, so it is compared to 1 ulp)
    let lin = linearize_equilibrium(&paper(), [60.0, 30.0, 0.0]).unwrap();
    let sys = &lin.system;
    for (key, m, rows, cols) in [
        ("A", &sys.a, n, n),
        ("B", &sys.b, n, 3),
        ("C", &sys.c, 6, n),
        ("D", &sys.d, 6, 3),
    ] {
        let csv = read_csv(&dir.join(format!("{key}.csv")));
        assert_eq!(linalg::rows(m), csv, "{key}.csv");
        let from_json = json_matrix(&json[key]);
        assert_eq!((from_json.len(), from_json[0].len()), (rows, cols), "{key}");
        for (a, b) in from_json.iter().flatten().zip(csv.iter().flatten()) {
            assert!((a - b).abs() <= 2.3e-16 * b.abs(), "{key}: {a} vs {b}");
        }
    }
    assert_eq!(json["eigenvalues"].as_array().unwrap().len(), n);
    assert_eq!(json["zero_eigenvalues"]["count"], 3);
    assert_eq!(json["u0"], serde_json::json!([60.0, 30.0, 0.0]));
    assert_eq!(json["point"]["kind"], "equilibrium");
    let ph = &json["port_hamiltonian"];
    assert_eq!(json_matrix(&ph["J"]).len(), n);
    assert!(
        ph["checks_scaled"]["residual_source_port"]
            .as_f64()
            .unwrap()
            < 1e-15
    );
    assert_eq!(ph["passivity_voltage_port"]["passive"], false);
    let reduced: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("reduced.json")).unwrap()).unwrap();
    let r = reduced["order"].as_u64().unwrap() as usize;
    assert_eq!(json_matrix(&reduced["A"]).len(), r);
    assert!(
        reduced["frequency_error"]["max_abs"].as_f64().unwrap()
            <= reduced["error_bound"].as_f64().unwrap()
    );
    for png in ["bode.png", "step.png"] {
        assert!(
            std::fs::read(dir.join(png))
                .unwrap()
                .starts_with(b"\x89PNG")
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_linearize_at_a_time_of_a_simulation() {
    let dir = scratch("at");
    let o = hasel(&[
        "linearize",
        "--at-time",
        "0.25",
        "--sine",
        "60,11",
        "--out",
        s(&dir),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("linearization.json")).unwrap())
            .unwrap();
    assert_eq!(json["point"]["kind"], "trajectory");
    assert_eq!(json["point"]["t"], 0.25);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_bad_voltages_are_named_and_nothing_is_written() {
    for (u, message) in [
        ("60,30", "--u 60,30: expected three voltages U1,U2,U3 [V]"),
        ("60,30,0,1", "expected three voltages"),
        ("60,x,0", "expected three voltages"),
        ("60,nan,0", "U2 = NaN: must be a finite number"),
        ("1e400,0,0", "U1 = inf: must be a finite number"),
    ] {
        let dir = scratch("bad").join("out");
        let o = hasel(&["linearize", "--u", u, "--out", s(&dir)]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{u}");
        assert!(err.contains(message), "{u}: {err}");
        assert!(!dir.exists(), "{u}: nothing written");
    }
    // --u and --at-time (or the input flags) exclude each other
    let o = hasel(&["linearize", "--u", "1,2,3", "--sine", "60,11"]);
    assert!(!o.status.success());
    let o = hasel(&["linearize", "--out", "/tmp"]);
    assert!(!o.status.success());
}
