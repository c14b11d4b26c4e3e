//! What `hasel linearize` writes: `linearization.json` and `reduced.json` (row-major
//! matrices), `A.csv` … `D.csv` (plain numbers in the shortest form that reads back to the same
//! f64, for numpy's `loadtxt(delimiter=",")` and MATLAB's `readmatrix`), `bode.png` and
//! `step.png`.

use std::path::Path;

use nalgebra::{Complex, DMatrix};
use plotters::prelude::*;
use serde_json::{Value, json};

use super::ControlError;
use super::frequency::{Evaluator, SineCheck, StepComparison, log_grid};
use super::linalg::rows;
use super::linearize::{Linearization, Point, StateSpace};
use super::port_hamiltonian::PortHamiltonian;
use super::reduce::Reduced;
use crate::io::file::{FileError, write_text_atomic};
use crate::plot::{self, Panel, Series};

/// |λ| above which a mode counts as electrical, and above which as mechanical [1/s]
/// (between them the slow film modes; the time scales at rest in book/src/control.md,
/// "Time scales and accuracy": 2.4–30,
/// 1.8e4–2.3e5 and 4.4e7–3.65e8 s⁻¹).
const ELECTRICAL: f64 = 1e6;
const MECHANICAL: f64 = 1e3;

/// The class of a mode by its rate.
pub fn mode_class(lambda: Complex<f64>) -> &'static str {
    let rate = lambda.norm();
    if rate > ELECTRICAL {
        "electrical"
    } else if rate > MECHANICAL {
        "mechanical"
    } else {
        "slow"
    }
}

fn pairs(ev: &[Complex<f64>]) -> Value {
    json!(ev.iter().map(|e| [e.re, e.im]).collect::<Vec<_>>())
}

/// A matrix as CSV text: one row per line, no header, every number in Rust's shortest
/// round-trip exponent form (`-1.2345e-9`).
fn csv_text(m: &DMatrix<f64>) -> String {
    let mut s = String::new();
    for r in 0..m.nrows() {
        let line: Vec<String> = (0..m.ncols()).map(|c| format!("{:e}", m[(r, c)])).collect();
        s.push_str(&line.join(","));
        s.push('\n');
    }
    s
}

/// The common part of `linearization.json` and `reduced.json`.
fn system_json(
    sys: &StateSpace,
    u0: [f64; 3],
    x0: &[f64],
    y0: [f64; 6],
    ev: &[Complex<f64>],
) -> serde_json::Map<String, Value> {
    let v = json!({
        "u0": u0,
        "x0": x0,
        "y0": y0,
        "states": sys.states,
        "inputs": sys.inputs,
        "outputs": sys.outputs,
        "A": rows(&sys.a),
        "B": rows(&sys.b),
        "C": rows(&sys.c),
        "D": rows(&sys.d),
        "eigenvalues": pairs(ev),
    });
    match v {
        Value::Object(m) => m,
        _ => serde_json::Map::new(),
    }
}

/// Everything `linearization.json` holds.
pub struct Contents<'a> {
    pub lin: &'a Linearization,
    pub ph: Result<&'a PortHamiltonian, &'a ControlError>,
    pub reduced: Result<&'a Reduced, &'a ControlError>,
    pub sine: &'a [SineCheck],
    /// Why the small-signal check could not run, if it could not.
    pub sine_error: Option<&'a str>,
    pub step: &'a StepComparison,
}

/// `linearization.json`.
fn linearization_json(c: &Contents) -> Value {
    let lin = c.lin;
    let mut m = system_json(&lin.system, lin.u0, &lin.x0, lin.y0, &lin.eigenvalues);
    m.insert(
        "units".into(),
        json!("SI: states as named (rad, m, kg m^2/s, C), inputs V, outputs m, time s"),
    );
    m.insert("point".into(), point_json(&lin.point));
    let cas = &lin.casimirs;
    m.insert(
        "zero_eigenvalues".into(),
        json!({
            "count": 3,
            "exact": lin.at_equilibrium(),
            "computed": pairs(&cas.eigenvalues),
            "why": "one per actuator: l_p and theta are tied by dl_p/dt = d dtheta/dt, so c(theta, l_p) with dc/dtheta + d dc/dl_p = 0 is a Casimir and the equilibria form a curve; at an equilibrium w_i = e(l_p_i) - d_i e(theta_i) satisfies w_i^T A = 0 and w_i^T B = 0 (uncontrollable, moves to a neighbouring invariant curve); away from equilibria (p != 0) these eigenvalues are only near zero",
            "curve_slopes_d": cas.slopes,
            "left_null_residual": cas.left_residual,
            "input_residual": cas.input_residual,
            "removed": "in the minimal model (l_p_i follows d_i theta_i) and in reduced.json",
        }),
    );
    m.insert(
        "minimal_eigenvalues".into(),
        json!({
            "states": lin.minimal().states,
            "eigenvalues": pairs(&lin.minimal_eigenvalues),
            "classes": lin.minimal_eigenvalues.iter().map(|e| mode_class(*e)).collect::<Vec<_>>(),
            "thresholds_per_s": {"electrical_above": ELECTRICAL, "mechanical_above": MECHANICAL},
        }),
    );
    m.insert(
        "effects".into(),
        json!(
            lin.notes
                .iter()
                .map(|n| json!({
                    "effect": n.effect, "actuator": n.actuator, "smooth": n.smooth, "note": n.text,
                }))
                .collect::<Vec<_>>()
        ),
    );
    m.insert("input_delay_s".into(), json!(lin.input_delay));
    m.insert(
        "port_hamiltonian".into(),
        match &c.ph {
            Ok(ph) => ph_json(ph, lin),
            Err(why) => json!({"computed": false, "why": why.to_string()}),
        },
    );
    m.insert(
        "small_signal_check".into(),
        json!(
            c.sine
                .iter()
                .map(|s| json!({
                    "frequency_hz": s.frequency,
                    "output": lin.system.outputs[s.output],
                    "linear": [s.linear.re, s.linear.im],
                    "nonlinear": [s.nonlinear.re, s.nonlinear.im],
                    "gain_error": s.gain_error(),
                    "phase_error_rad": s.phase_error(),
                }))
                .collect::<Vec<_>>()
        ),
    );
    m.insert(
        "step".into(),
        match (&c.step.linear, &c.step.nonlinear) {
            (Err(e), _) => json!({
                "du_V": c.step.du,
                "linear": format!("integration failed: {e}"),
            }),
            (_, Err(e)) => json!({
                "du_V": c.step.du,
                "nonlinear": format!("simulation failed: {e}"),
            }),
            _ => json!({
                "du_V": c.step.du,
                "duration_s": c.step.t.last(),
                "max_error_relative": c.step.relative_errors(),
            }),
        },
    );
    m.insert(
        "small_signal_check_error".into(),
        c.sine_error.map_or(Value::Null, |e| json!(e)),
    );
    m.insert(
        "reduced".into(),
        match &c.reduced {
            Ok(r) => json!({"order": r.order, "bound": r.bound, "file": "reduced.json"}),
            Err(why) => json!({"computed": false, "why": why.to_string()}),
        },
    );
    Value::Object(m)
}

fn point_json(p: &Point) -> Value {
    match p {
        Point::Equilibrium(eq) => json!({
            "kind": "equilibrium",
            "method": "Newton on the reduced equations (theta per actuator; l_p on the invariant curve through the rest state, p = 0, charges from the DC circuit), continued in U from 0 V",
            "residual_relative": eq.residual,
            "newton_iterations": eq.iterations,
            "continuation_steps": eq.steps,
            "stiffness_along_curve_Nm_per_rad": eq.stiffness,
        }),
        Point::Trajectory { t, rate } => json!({
            "kind": "trajectory",
            "t": t,
            "rate_state_scales_per_s": rate,
            "note": "not an equilibrium: the linearization is the Jacobian frozen at x(t)",
        }),
    }
}

fn ph_json(ph: &PortHamiltonian, lin: &Linearization) -> Value {
    let ch = &ph.checks;
    let pa = &ph.passivity;
    let exact = ph.source_feedback.iter().all(|v| *v == 0.0) && lin.at_equilibrium();
    json!({
        "form": "A = (J - R) Q + g_w K_x, B = g_w K_u: the linearization is port-Hamiltonian from the source voltages w_i = ga(theta_i) U_i (dw = K_u dU + K_x dx) with the storage 1/2 dx^T Q dx; from the voltages U only where K_x = 0 (U0 = 0)",
        "J": rows(&ph.j),
        "R": rows(&ph.r),
        "Q": rows(&ph.q),
        "Q_is": "the Hessian of H at x0 plus the curvature of the Casimir leaf, M (nonzero on (theta, l_p) only)",
        "hessian": rows(&ph.hessian),
        "g_w": rows(&ph.source_map),
        "K_u": ph.source_gain,
        "K_x": rows(&ph.source_feedback),
        "voltage_port_exact": exact,
        "port": {
            "inputs": ["U1", "U2", "U3"],
            "outputs": ["y1", "y2", "y3"],
            "output_is": "y_i = g(x)^T grad H = G0 ga(theta) (V1 + V2) [A], the model's port output (y U is the supplied power)",
            "C": rows(&ph.port_c),
            "D": [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
        },
        "checks_scaled": {
            "J_skew": ch.j_skew,
            "R_asymmetry": ch.r_asymmetry,
            "R_eigenvalues_min_max": [ch.r_eigenvalues.0, ch.r_eigenvalues.1],
            "Q_asymmetry": ch.q_asymmetry,
            "Q_eigenvalues_reachable_min_max": [ch.q_reachable_eigenvalues.0, ch.q_reachable_eigenvalues.1],
            "Q_eigenvalues_min_max": [ch.q_eigenvalues.0, ch.q_eigenvalues.1],
            "residual_plain_hessian": ch.residual_hessian,
            "residual_plain_hessian_rows": ch.residual_hessian_rows,
            "residual_voltage_port": ch.residual_voltage_port,
            "residual_voltage_port_rows": ch.residual_voltage_port_rows,
            "residual_source_port": ch.residual_source_port,
            "residual_source_port_rows": ch.residual_source_port_rows,
            "residual_input_map": ch.residual_input,
            "collocation_voltage_port": ch.collocation_voltage_port,
            "kyp_voltage_port_min_eigenvalue_relative": ch.kyp_voltage_port,
            "note": "residuals are ||.||_F / ||A||_F and, _rows, the largest row ratio ||row_r(.)|| / ||row_r(A)||, in the states scaled by the state scales",
        },
        "passivity_voltage_port": {
            "grid_hz": [0.0, pa.f_min, pa.f_max],
            "points": pa.points,
            "min_hermitian_part_S": pa.min_hermitian,
            "at_hz": pa.worst_frequency,
            "scale_S": pa.scale,
            "stable": pa.stable,
            "passive": pa.passive,
            "dc_conductance_S": pa.dc,
        },
    })
}

/// `reduced.json`.
fn reduced_json(r: &Reduced, lin: &Linearization) -> Value {
    let mut m = system_json(
        &r.system,
        lin.u0,
        &vec![0.0; r.order],
        lin.y0,
        &r.eigenvalues,
    );
    m.insert(
        "method".into(),
        json!("balanced singular-perturbation approximation of the minimal model (the Casimir directions l_p_i = d_i theta_i removed); the states z are balanced coordinates of the deviation from x0; order: the smallest r with 2 sum_{k>r} sigma_k <= tolerance ||G||_inf"),
    );
    m.insert(
        "x0_is".into(),
        json!(
            "z = 0 at the linearization's point; u and y are absolute (u = u0 + du, y = y0 + dy)"
        ),
    );
    m.insert("hankel_singular_values".into(), json!(r.hankel));
    m.insert("order".into(), json!(r.order));
    m.insert("tolerance".into(), json!(r.tolerance));
    m.insert("error_bound".into(), json!(r.bound));
    m.insert("peak_gain".into(), json!(r.peak_gain));
    m.insert(
        "frequency_error".into(),
        json!({
            "up_to_hz": r.error.f_max,
            "max_abs": r.error.max_abs,
            "relative_to_peak_gain": r.error.relative,
            "at_hz": r.error.at_frequency,
            "per_output_relative": r.error.per_output,
        }),
    );
    m.insert("full_states".into(), json!(lin.system.states));
    m.insert("state_map".into(), json!(rows(&r.state_map)));
    m.insert("input_map".into(), json!(rows(&r.input_map)));
    m.insert(
        "state_map_is".into(),
        json!("dx (every full state) ~= state_map z + input_map du: the perturbed states at their quasi-steady state"),
    );
    Value::Object(m)
}

/// Writes the JSON files, the CSV matrices and the figures into `dir`.
pub fn write(dir: &Path, c: &Contents, bode: &Bode) -> Result<Vec<std::path::PathBuf>, FileError> {
    let mut written = Vec::new();
    let lin = c.lin;
    let mut put = |name: &str, text: String| -> Result<(), FileError> {
        let path = dir.join(name);
        write_text_atomic(&path, &text)?;
        written.push(path);
        Ok(())
    };
    let pretty = |v: &Value| serde_json::to_string_pretty(v).unwrap_or_default() + "\n";
    put("linearization.json", pretty(&linearization_json(c)))?;
    for (name, m) in [
        ("A.csv", &lin.system.a),
        ("B.csv", &lin.system.b),
        ("C.csv", &lin.system.c),
        ("D.csv", &lin.system.d),
    ] {
        put(name, csv_text(m))?;
    }
    if let Ok(r) = &c.reduced {
        put("reduced.json", pretty(&reduced_json(r, lin)))?;
    }
    let path = dir.join("bode.png");
    draw_bode(&path, bode)?;
    written.push(path);
    let path = dir.join("step.png");
    draw_step(&path, c.step)?;
    written.push(path);
    Ok(written)
}

/// The Bode data: G(j2πf) of the full model on a grid, and the poles to mark.
pub struct Bode {
    pub freqs: Vec<f64>,
    pub g: Vec<DMatrix<Complex<f64>>>,
    poles: Vec<Complex<f64>>,
    pub outputs: Vec<String>,
}

/// G(j2πf) of the minimal model from 0.01 Hz to 1e9 Hz (beyond the electrical poles).
pub fn bode_data(lin: &Linearization) -> Result<Bode, ControlError> {
    let minimal = lin.minimal();
    let ev = Evaluator::new(&minimal);
    let freqs = log_grid(1e-2, 1e9, 40);
    let g = freqs
        .iter()
        .map(|f| ev.at(2.0 * std::f64::consts::PI * f))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Bode {
        freqs,
        g,
        poles: lin.minimal_eigenvalues.clone(),
        outputs: minimal.outputs,
    })
}

/// Channels whose gain stays below this fraction of the largest gain are not drawn (−80 dB).
const CHANNEL_FLOOR: f64 = 1e-4;

const COLORS: [RGBColor; 9] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
    RGBColor(188, 189, 34),
];

/// One curve of a Bode panel: (output, input) and its label.
struct Channel {
    output: usize,
    input: usize,
    label: String,
}

fn unwrap_phase(g: &[Complex<f64>]) -> Vec<f64> {
    let mut out = Vec::with_capacity(g.len());
    let mut offset = 0.0;
    let mut prev: Option<f64> = None;
    for z in g {
        let p = z.arg().to_degrees();
        if let Some(q) = prev {
            while p + offset - q > 180.0 {
                offset -= 360.0;
            }
            while p + offset - q < -180.0 {
                offset += 360.0;
            }
        }
        prev = Some(p + offset);
        out.push(p + offset);
    }
    out
}

/// `bode.png`: magnitude (dB re 1 um/V) and phase from each voltage to the heights and to the
/// tip, on a logarithmic frequency axis, with the poles marked by class.
fn draw_bode(path: &Path, b: &Bode) -> Result<(), FileError> {
    let peak =
        b.g.iter()
            .flat_map(|g| g.iter().map(|z| z.norm()))
            .fold(0.0, f64::max);
    let groups = bode_groups();
    let (f0, f1) = (b.freqs[0], b.freqs[b.freqs.len() - 1]);
    plot::to_png(path, (1600, 1500), |root| {
        let areas = root.split_evenly((3, 2));
        for (row, (title, channels)) in groups.iter().enumerate() {
            // channels without gain are left out: an actuator at U0 = 0 (its force goes with
            // U²), or a tip coordinate an actuator does not move (x from actuator 1 at 90°)
            let live: Vec<&Channel> = channels
                .iter()
                .filter(|c| {
                    b.g.iter()
                        .any(|g| g[(c.output, c.input)].norm() > CHANNEL_FLOOR * peak)
                })
                .collect();
            let (mags, phases) = magnitudes_and_phases(b, &live);
            for (col, (data, y_label)) in [
                (&mags, "magnitude [dB re 1 um/V]"),
                (&phases, "phase [deg]"),
            ]
            .into_iter()
            .enumerate()
            {
                let (lo, hi) = y_range(data, col == 0);
                let area = &areas[row * 2 + col];
                let mut chart = ChartBuilder::on(area)
                    .caption(
                        format!("{title}: {}", if col == 0 { "magnitude" } else { "phase" }),
                        ("sans-serif", 20),
                    )
                    .margin(12)
                    .x_label_area_size(42)
                    .y_label_area_size(70)
                    .build_cartesian_2d((f0..f1).log_scale(), lo..hi)
                    .map_err(|e| e.to_string())?;
                chart
                    .configure_mesh()
                    .x_desc("frequency [Hz]")
                    .y_desc(y_label)
                    .x_label_formatter(&|v| format!("{v:.0e}"))
                    .label_style(("sans-serif", 14))
                    .axis_desc_style(("sans-serif", 16))
                    .light_line_style(RGBColor(235, 235, 235))
                    .draw()
                    .map_err(|e| e.to_string())?;
                // the poles, one dashed line each, one legend entry per class
                for (class, color) in [
                    ("electrical", RGBColor(0, 0, 0)),
                    ("mechanical", RGBColor(120, 120, 120)),
                    ("slow", RGBColor(170, 150, 60)),
                ] {
                    let mut first = true;
                    for p in b.poles.iter().filter(|p| mode_class(**p) == class) {
                        let f = p.norm() / (2.0 * std::f64::consts::PI);
                        if !(f > f0 && f < f1) {
                            continue;
                        }
                        let s = chart
                            .draw_series(DashedLineSeries::new(
                                vec![(f, lo), (f, hi)],
                                6,
                                4,
                                color.stroke_width(1),
                            ))
                            .map_err(|e| e.to_string())?;
                        if first && col == 0 {
                            s.label(format!("{class} poles")).legend(move |(x, y)| {
                                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                            });
                            first = false;
                        }
                    }
                }
                for (k, (c, ys)) in live.iter().zip(data).enumerate() {
                    let color = COLORS[k % COLORS.len()];
                    let pts = b
                        .freqs
                        .iter()
                        .zip(ys)
                        .filter(|(_, y)| y.is_finite() && **y >= lo)
                        .map(|(f, y)| (*f, *y));
                    chart
                        .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                        .map_err(|e| e.to_string())?
                        .label(c.label.as_str())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(3))
                        });
                }
                plot::legend(&mut chart, 13)?;
            }
        }
        Ok(())
    })
}

/// The Bode plot's rows: each voltage to its height, to the tip's x and y, and to its z.
fn bode_groups() -> Vec<(&'static str, Vec<Channel>)> {
    vec![
        (
            "heights h_i / U_i",
            (0..3)
                .map(|i| Channel {
                    output: i,
                    input: i,
                    label: format!("h{0}/U{0}", i + 1),
                })
                .collect(),
        ),
        (
            "tip x, y / U_j",
            (3..5)
                .flat_map(|o| {
                    (0..3).map(move |j| Channel {
                        output: o,
                        input: j,
                        label: format!("{}/U{}", ["x", "y"][o - 3], j + 1),
                    })
                })
                .collect(),
        ),
        (
            "tip z / U_j",
            (0..3)
                .map(|j| Channel {
                    output: 5,
                    input: j,
                    label: format!("z/U{}", j + 1),
                })
                .collect(),
        ),
    ]
}

/// Each channel's magnitude [dB re 1 um/V] and unwrapped phase [deg] over the frequencies.
fn magnitudes_and_phases(b: &Bode, live: &[&Channel]) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let mags: Vec<Vec<f64>> = live
        .iter()
        .map(|c| {
            b.g.iter()
                .map(|g| 20.0 * (g[(c.output, c.input)].norm() / 1e-6).log10())
                .collect()
        })
        .collect();
    let phases: Vec<Vec<f64>> = live
        .iter()
        .map(|c| {
            let z: Vec<Complex<f64>> = b.g.iter().map(|g| g[(c.output, c.input)]).collect();
            unwrap_phase(&z)
        })
        .collect();
    (mags, phases)
}

/// The y range of a panel: its finite values with 5 units to spare, a magnitude panel's
/// (`magnitude`) at most 200 dB deep.
fn y_range(data: &[Vec<f64>], magnitude: bool) -> (f64, f64) {
    let finite = data.iter().flatten().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    if lo.is_finite() {
        let lo = if magnitude { lo.max(hi - 200.0) } else { lo };
        (lo - 5.0, hi + 5.0)
    } else {
        (-1.0, 1.0)
    }
}

/// `step.png`: the outputs' response to the voltage step, linear (lines) and nonlinear (dots).
fn draw_step(path: &Path, s: &StepComparison) -> Result<(), FileError> {
    let um = 1e6;
    let series = |outputs: &[(usize, &str)]| -> Vec<Series> {
        outputs
            .iter()
            .enumerate()
            .flat_map(|(k, (o, name))| {
                [
                    Series {
                        label: format!("{name} linear"),
                        points: s
                            .t
                            .iter()
                            .zip(s.linear.as_deref().unwrap_or_default())
                            .map(|(t, y)| (*t, y[*o] * um))
                            .collect(),
                        color: k,
                        dots: false,
                    },
                    Series {
                        label: format!("{name} nonlinear"),
                        points: s
                            .t
                            .iter()
                            .zip(s.nonlinear.as_deref().unwrap_or_default())
                            .map(|(t, y)| (*t, y[*o] * um))
                            .collect(),
                        color: k,
                        dots: true,
                    },
                ]
            })
            .filter(|series| !series.points.is_empty())
            .collect()
    };
    let du = s.du;
    let panels = vec![
        Panel {
            title: format!(
                "Heights after a step dU = ({}, {}, {}) V",
                du[0], du[1], du[2]
            ),
            x_label: "t [s]".into(),
            y_label: "dh [um]".into(),
            series: series(&[(0, "h1"), (1, "h2"), (2, "h3")]),
            equal_axes: false,
        },
        Panel {
            title: "Antenna tip".into(),
            x_label: "t [s]".into(),
            y_label: "d tip [um]".into(),
            series: series(&[(3, "tip x"), (4, "tip y"), (5, "tip z")]),
            equal_axes: false,
        },
    ];
    plot::draw(path, &panels, 2, (1600, 600))
}
