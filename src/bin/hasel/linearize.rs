//! `hasel linearize`: the equilibrium under constant voltages (or the state a simulation reaches),
//! the linearization, its port-Hamiltonian structure and passivity, the Bode and step figures, and
//! a reduced model for controller design
//! (book/src/control.md, "Control design: `hasel linearize`").

use std::path::PathBuf;

use hasel_fmu::control::frequency::{self, SineCheck};
use hasel_fmu::control::linearize::Point;
use hasel_fmu::control::report::{self, Contents, mode_class};
use hasel_fmu::control::{
    ControlError, Linearization, linearize_at, linearize_equilibrium, port_hamiltonian, reduce,
};
use hasel_fmu::model::{Params, Platform};
use hasel_fmu::simulation::{SimError, Simulator};

use crate::common::{InputArgs, load_params};
use crate::error::Error;

#[derive(clap::Args)]
// the fields' docs are their --help text, which gives units in brackets
#[allow(rustdoc::broken_intra_doc_links)]
pub struct Args {
    /// The constant voltages of the equilibrium to linearize at [V]
    #[arg(
        long,
        value_name = "U1,U2,U3",
        allow_hyphen_values = true,
        required_unless_present = "at_time",
        conflicts_with_all = ["at_time", "sine", "offset_sine", "multisine", "input"]
    )]
    u: Option<String>,
    /// Linearize instead at the state a simulation reaches at time T [s], driven by the input
    /// flags below (those of `hasel simulate`; default the paper's sine)
    #[arg(long, value_name = "T")]
    at_time: Option<f64>,
    #[command(flatten)]
    input: InputArgs,
    /// Parameter file (TOML, any subset of `hasel params`)
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
    /// Output folder: linearization.json, A.csv..D.csv, reduced.json, bode.png, step.png
    #[arg(long, value_name = "DIR", default_value = "linearize")]
    out: PathBuf,
    /// The voltage step of step.png, on every actuator [V]
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    step: f64,
    /// Duration of step.png [s] (default: five time constants of the slowest mode)
    #[arg(long, value_name = "SECONDS")]
    step_time: Option<f64>,
    /// The reduced model's a-priori error bound 2 sum sigma_k, relative to the peak gain
    #[arg(long, default_value_t = 1e-3)]
    reduce_tol: f64,
    /// Relative tolerance of the nonlinear simulations (the --at-time run, the step, the
    /// small-signal check)
    #[arg(long, default_value_t = 1e-9)]
    rtol: f64,
}

/// Frequencies of the small-signal check \[Hz\]: below, between and above the slow modes.
const SINE_FREQUENCIES: [f64; 3] = [0.2, 2.0, 20.0];
/// Amplitude of the small-signal check \[V\].
const SINE_AMPLITUDE: f64 = 0.5;

fn voltages_error(text: &str) -> Error {
    Error::flag("u", text, "expected three voltages U1,U2,U3 [V]")
}

fn parse_voltages(text: &str) -> Result<[f64; 3], Error> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let values: Vec<f64> = parts
        .iter()
        .map(|p| p.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| voltages_error(text))?;
    <[f64; 3]>::try_from(values).map_err(|_| voltages_error(text))
}

/// The same parameters without the delay effect: at an equilibrium the delay only shifts
/// the response, and a simulation started there would see 0 V until the first command arrives.
fn without_delay(params: &Params) -> Result<Platform, Error> {
    let mut p = params.clone();
    p.effects.delay.tau_d = 0.0;
    Platform::new(p).map_err(|e| Error::Control(ControlError::Param(e)))
}

pub fn run(a: Args) -> Result<(), Error> {
    check_tolerance_and_step(&a)?;
    let params = load_params(&a.params)?;
    let model =
        Platform::new(params.clone()).map_err(|e| Error::Control(ControlError::Param(e)))?;
    let (lin, start, u_command, sine_model) = point(&a, &params, &model)?;

    let ph = port_hamiltonian::decompose(&model, &lin);
    let reduced = reduce::reduce(&lin, a.reduce_tol);
    if let Err(ControlError::Setting { .. }) = &reduced {
        return Err(Error::Usage(format!(
            "--reduce-tol {}: must be in (0, 1)",
            a.reduce_tol
        )));
    }
    let (sine, sine_error) = sine_check(sine_model.as_ref(), &lin, a.rtol);
    let step_time = step_time(&a, &lin)?;
    let step = frequency::step_comparison(&start, &lin, u_command, [a.step; 3], step_time, 200)?;
    let bode = report::bode_data(&lin)?;

    summary(&lin, &ph, &reduced, &sine, &step);
    if let Some(e) = &sine_error {
        say!("small-signal check: {e}");
    }
    let contents = Contents {
        lin: &lin,
        ph: ph.as_ref(),
        reduced: reduced.as_ref(),
        sine: &sine,
        sine_error: sine_error.as_deref(),
        step: &step,
    };
    let written = report::write(&a.out, &contents, &bode).map_err(ControlError::from)?;
    let names: Vec<String> = written
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    let listed = a.out.join(format!("{{{}}}", names.join(", ")));
    say!("wrote {}", listed.display());
    Ok(())
}

/// The tolerance in (0, 0.1) and a nonzero step, checked before anything is computed.
fn check_tolerance_and_step(a: &Args) -> Result<(), Error> {
    if !(a.rtol.is_finite() && a.rtol > 0.0 && a.rtol < 0.1) {
        return Err(Error::Usage(format!(
            "--rtol {}: must be in (0, 0.1)",
            a.rtol
        )));
    }
    if !(a.step.is_finite() && a.step != 0.0) {
        return Err(Error::Usage(format!(
            "--step {}: must be a nonzero voltage",
            a.step
        )));
    }
    Ok(())
}

/// The point: an equilibrium, or the state of a simulation at --at-time. Returns the
/// linearization, a simulator standing there, the command there, and the model the small-sine
/// check runs on (at an equilibrium only).
fn point(
    a: &Args,
    params: &Params,
    model: &Platform,
) -> Result<(Linearization, Simulator, [f64; 3], Option<Platform>), Error> {
    Ok(match (&a.u, a.at_time) {
        (Some(text), _) => {
            let u = parse_voltages(text)?;
            let lin = linearize_equilibrium(model, u)?;
            let plain = without_delay(params)?;
            let start = Simulator::from_state(plain.clone(), 0.0, &lin.x0, a.rtol)
                .map_err(ControlError::from)?;
            (lin, start, u, Some(plain))
        }
        (None, Some(t)) => {
            if !(t.is_finite() && t > 0.0) {
                return Err(Error::Usage(format!("--at-time {t}: must be > 0")));
            }
            let (input, _) = a.input.input()?;
            let mut sim = Simulator::new(model.clone(), 0.0, a.rtol).map_err(ControlError::from)?;
            sim.run(&input, t, t, |_| {}).map_err(ControlError::from)?;
            // the voltages the model sees at t: the command, late by the delay effect's τ_d
            // (0 V before the first command arrives)
            let tau_d = params.effects.delay.tau_d;
            let seen = if t >= tau_d {
                input.value(t - tau_d)
            } else {
                [0.0; 3]
            };
            let lin = linearize_at(model, sim.state(), seen, t)?;
            (lin, sim, input.value(t), None)
        }
        (None, None) => return Err(Error::Usage("give --u U1,U2,U3 or --at-time T".into())),
    })
}

/// The small-sine check on `sine_model` (none without one), or why it failed. The checks
/// against the nonlinear model are reported, not required: a simulation that fails there (an
/// unstable linearization, a parameter set the solver cannot follow) leaves the linearization
/// itself standing.
fn sine_check(
    sine_model: Option<&Platform>,
    lin: &Linearization,
    rtol: f64,
) -> (Vec<SineCheck>, Option<String>) {
    match sine_model {
        Some(m) => match frequency::sine_check(m, lin, SINE_AMPLITUDE, &SINE_FREQUENCIES, rtol) {
            Ok(s) => (s, None),
            Err(e) => (Vec::new(), Some(e.to_string())),
        },
        None => (Vec::new(), None),
    }
}

/// The step's length: --step-time, or five times the slowest mode's time constant (1 s
/// without a stable mode), within 1 ms .. 100 s.
fn step_time(a: &Args, lin: &Linearization) -> Result<f64, Error> {
    let slowest = lin
        .minimal_eigenvalues
        .iter()
        .map(|e| -e.re)
        .filter(|r| *r > 0.0)
        .fold(f64::INFINITY, f64::min);
    let step_time = a
        .step_time
        .unwrap_or(if slowest.is_finite() {
            5.0 / slowest
        } else {
            1.0
        })
        .clamp(1e-3, 100.0);
    if let Some(t) = a.step_time
        && !(t.is_finite() && t > 0.0)
    {
        return Err(Error::Usage(format!("--step-time {t}: must be > 0")));
    }
    Ok(step_time)
}

fn um(v: f64) -> String {
    format!("{:.3}", v * 1e6)
}

/// Prints the linearization's summary: the point, the eigenvalues, the port-Hamiltonian checks,
/// the small-signal and step checks, and the reduced model.
fn summary(
    lin: &Linearization,
    ph: &Result<port_hamiltonian::PortHamiltonian, ControlError>,
    reduced: &Result<reduce::Reduced, ControlError>,
    sine: &[SineCheck],
    step: &frequency::StepComparison,
) {
    say_point(lin);
    say_eigenvalues(lin);
    say_effect_notes(lin);
    say_port_hamiltonian(ph);
    say_sine_check(sine);
    say_step_check(step);
    say_reduced(lin, reduced);
}

/// The point linearized at: an equilibrium with its outputs and how it was found, or a state
/// of a trajectory with how fast it moves.
fn say_point(lin: &Linearization) {
    let y = lin.y0;
    let u = lin.u0;
    match &lin.point {
        Point::Equilibrium(eq) => say!(
            "equilibrium at U = ({}, {}, {}) V: h = {} / {} / {} um, tip = ({}, {}, {}) um; residual {:.1e} of the terms ({} continuation steps, {} Newton iterations)",
            u[0],
            u[1],
            u[2],
            um(y[0]),
            um(y[1]),
            um(y[2]),
            um(y[3]),
            um(y[4]),
            um(y[5]),
            eq.residual,
            eq.steps,
            eq.iterations
        ),
        Point::Trajectory { t, rate } => say!(
            "state at t = {t} s (U = {:.4}, {:.4}, {:.4} V): h = {} / {} / {} um; not an equilibrium (the state moves at up to {:.2e} state scales per second): the Jacobian frozen there",
            u[0],
            u[1],
            u[2],
            um(y[0]),
            um(y[1]),
            um(y[2]),
            rate
        ),
    }
}

/// The eigenvalues of the minimal model by class, after the three Casimir zeros it leaves out.
fn say_eigenvalues(lin: &Linearization) {
    let zeros = lin
        .casimirs
        .eigenvalues
        .iter()
        .map(|e| e.norm())
        .fold(0.0, f64::max);
    if lin.at_equilibrium() {
        say!(
            "eigenvalues [1/s]: 3 zero, one per actuator (the Casimir of l_p and theta; computed |lambda| <= {zeros:.1e}), removed from the minimal and the reduced model"
        );
    } else {
        say!(
            "eigenvalues [1/s]: 3 near zero (|lambda| <= {zeros:.1e}; the Casimir directions, exactly zero only at equilibria), removed from the minimal and the reduced model"
        );
    }
    for class in ["slow", "mechanical", "electrical"] {
        let list: Vec<String> = lin
            .minimal_eigenvalues
            .iter()
            .filter(|e| mode_class(**e) == class)
            .map(|e| {
                if e.im == 0.0 {
                    format!("{:.4e}", e.re)
                } else {
                    format!("{:.4e}{:+.3e}i", e.re, e.im)
                }
            })
            .collect();
        say!("  {class:>10}: {}", list.join(", "));
    }
}

/// What each effect contributes at the point, flagged where it is not smooth there.
fn say_effect_notes(lin: &Linearization) {
    for n in &lin.notes {
        say!(
            "  effect {}{}: {}{}",
            n.effect,
            n.actuator
                .map(|i| format!(" (actuator {i})"))
                .unwrap_or_default(),
            if n.smooth { "" } else { "NOT SMOOTH: " },
            n.text
        );
    }
}

/// The port-Hamiltonian decomposition's checks and the voltage port's passivity.
fn say_port_hamiltonian(ph: &Result<port_hamiltonian::PortHamiltonian, ControlError>) {
    match ph {
        Ok(ph) => {
            let c = &ph.checks;
            say!(
                "port-Hamiltonian: A = (J - R) Q + g_w K_x holds to {:.1e} (worst row {:.1e}); J skew, R >= 0 (min eigenvalue {:.1e}); Q on the reachable subspace {} (eigenvalues {:.2e} .. {:.2e}, scaled)",
                c.residual_source_port,
                c.residual_source_port_rows,
                c.r_eigenvalues.0,
                if c.q_reachable_eigenvalues.0 >= 0.0 {
                    ">= 0"
                } else {
                    "NOT >= 0"
                },
                c.q_reachable_eigenvalues.0,
                c.q_reachable_eigenvalues.1
            );
            say!(
                "  from the voltages U: A = (J - R) Q misses the modulated source ga'(theta0) U0 by {:.2e} (worst row {:.2e}); collocated output y = g^T grad H off B^T Q by {:.2e}; KYP with 1/2 dx^T Q dx: min eigenvalue {:.2e}",
                c.residual_voltage_port,
                c.residual_voltage_port_rows,
                c.collocation_voltage_port,
                c.kyp_voltage_port
            );
            let p = &ph.passivity;
            say!(
                "  voltage port on {} frequencies, 0 and {:.0e}..{:.0e} Hz: min eigenvalue of Re G = {:.3e} S at {:.3e} Hz (scale {:.3e} S): {}; DC conductances {}",
                p.points,
                p.f_min,
                p.f_max,
                p.min_hermitian,
                p.worst_frequency,
                p.scale,
                if !p.stable {
                    "not applicable (unstable)"
                } else if p.passive {
                    "passive"
                } else {
                    "NOT passive"
                },
                p.dc.iter()
                    .map(|g| format!("{g:.4}"))
                    .collect::<Vec<_>>()
                    .join(" / ")
            );
        }
        Err(e) => say!("port-Hamiltonian decomposition: {e}"),
    }
}

/// How far the nonlinear model's small-sine responses are from the linear model's.
fn say_sine_check(sine: &[SineCheck]) {
    if !sine.is_empty() {
        let gain = sine
            .iter()
            .map(|s| s.gain_error().abs())
            .fold(0.0, f64::max);
        let phase = sine
            .iter()
            .map(|s| s.phase_error().abs())
            .fold(0.0, f64::max);
        say!(
            "small-signal check, {SINE_AMPLITUDE} V sine at {:?} Hz, {} output responses: nonlinear vs linear gain within {:.2e}, phase within {:.2e} rad",
            SINE_FREQUENCIES,
            sine.len(),
            gain,
            phase
        );
    }
}

/// How far the nonlinear model's step response is from the linear model's.
fn say_step_check(step: &frequency::StepComparison) {
    match (&step.nonlinear, step.relative_errors()) {
        (Ok(_), Some(errs)) => say!(
            "step of {} V: linear vs nonlinear, largest difference per output (relative to its response; 1 where the linear response is zero): {}",
            step.du[0],
            errs.iter()
                .map(|e| format!("{e:.2e}"))
                .collect::<Vec<_>>()
                .join(" / ")
        ),
        (Err(SimError::Setting(why)), _) => say!("step: {why}"),
        (Err(e), _) => say!("step: the nonlinear simulation failed: {e}"),
        _ => {
            if let Err(e) = &step.linear {
                say!("step: the linear model's integration failed: {e}");
            }
        }
    }
}

/// The reduced model's order, error bound and measured error.
fn say_reduced(lin: &Linearization, reduced: &Result<reduce::Reduced, ControlError>) {
    match reduced {
        Ok(r) => say!(
            "reduced model: order {} of {} (bound 2 sum sigma = {:.2e} m/V = {:.2e} of the peak gain {:.3e} m/V); error up to {} Hz: {:.2e} m/V ({:.2e} of the peak gain)",
            r.order,
            lin.minimal_eigenvalues.len(),
            r.bound,
            r.bound / r.peak_gain,
            r.peak_gain,
            r.error.f_max,
            r.error.max_abs,
            r.error.relative
        ),
        Err(e) => say!("reduced model: {e}"),
    }
}
