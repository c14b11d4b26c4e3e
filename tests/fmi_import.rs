//! The packed FMU through an independent Rust importer, the `fmi` crate (fmi-rs): it unzips
//! `fmu/HaselPlatform.fmu`, parses its `modelDescription.xml`, loads
//! `binaries/linux64/HaselPlatform.so` and drives it through the FMI 2.0 Co-Simulation calls, and
//! through the Model Exchange calls with the FMU's own Jacobian (directional derivatives).
//!
//! Build the FMU first: `cargo build --release && ./target/release/hasel fmu` (or set
//! `HASEL_FMU` to another .fmu).

use std::path::PathBuf;
use std::sync::Barrier;

use fmi::EventFlags;
use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS, ModelExchange};
use fmi::traits::FmiImport;

const STEP: f64 = 1e-3;
const OUTPUTS: [&str; 6] = ["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"];
const INPUTS: [&str; 3] = ["U1", "U2", "U3"];

fn fmu_path() -> PathBuf {
    let path = std::env::var_os("HASEL_FMU").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fmu/HaselPlatform.fmu"),
        PathBuf::from,
    );
    assert!(
        path.exists(),
        "{} is missing: pack the FMU first with `cargo build --release && ./target/release/hasel fmu`",
        path.display()
    );
    path
}

/// The 1 ms ZOH reference: rows of t, U1..U3, h1..h3, tip_x..tip_z.
fn reference() -> Vec<[f64; 10]> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/reference/zoh1ms_sine60_w3pi.csv");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("t,U1,U2,U3,h1,h2,h3,tip_x,tip_y,tip_z"),
        "unexpected header in {}",
        path.display()
    );
    let rows: Vec<[f64; 10]> = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .map(|x| x.trim().parse().expect("a number"))
                .collect();
            v.try_into().expect("10 columns")
        })
        .collect();
    assert_eq!(rows.len(), 2001, "2 s at 1 ms");
    rows
}

fn import() -> Fmi2Import {
    let path = fmu_path();
    fmi::import::from_path(&path)
        .unwrap_or_else(|e| panic!("the fmi crate cannot import {}: {e}", path.display()))
}

/// The value references of `names`, looked up in the imported model description.
fn value_refs<const N: usize>(import: &Fmi2Import, names: [&str; N]) -> [u32; N] {
    names.map(|name| {
        import
            .model_description()
            .get_model_variables()
            .find(|v| v.name == name)
            .unwrap_or_else(|| panic!("{name} is not in modelDescription.xml"))
            .value_reference
    })
}

/// A fresh instance, initialized at t = 0 with the default tolerance and no stop time.
fn initialized(import: &Fmi2Import, name: &str) -> InstanceCS {
    let mut inst = import
        .instantiate_cs(name, false, false)
        .unwrap_or_else(|e| panic!("fmi2Instantiate failed: {e}"));
    Common::setup_experiment(&mut inst, None, 0.0, None).expect("fmi2SetupExperiment");
    Common::enter_initialization_mode(&mut inst).expect("fmi2EnterInitializationMode");
    Common::exit_initialization_mode(&mut inst).expect("fmi2ExitInitializationMode");
    inst
}

/// Steps one instance over the reference input (each row's input held over the following
/// 1 ms) and returns the outputs at t_1 .. t_2000.
fn run(import: &Fmi2Import, name: &str, rows: &[[f64; 10]]) -> Vec<[f64; 6]> {
    let u_refs = value_refs(import, INPUTS);
    let y_refs = value_refs(import, OUTPUTS);
    let mut inst = initialized(import, name);
    let mut out = Vec::with_capacity(rows.len() - 1);
    let mut t = 0.0;
    for (k, row) in rows[..rows.len() - 1].iter().enumerate() {
        inst.set_real(&u_refs, &row[1..4])
            .unwrap_or_else(|e| panic!("fmi2SetReal at step {k}: {e}"));
        inst.do_step(t, STEP, true)
            .unwrap_or_else(|e| panic!("fmi2DoStep at step {k} (t = {t}): {e}"));
        t += STEP;
        let mut y = [0.0; 6];
        inst.get_real(&y_refs, &mut y)
            .unwrap_or_else(|e| panic!("fmi2GetReal at step {k}: {e}"));
        out.push(y);
    }
    Common::terminate(&mut inst).expect("fmi2Terminate");
    out
}

/// The fmi crate imports the FMU (model description, GUID, binary), and 2 s of 1 ms steps with
/// the ZOH input reproduce the reference heights to 0.01 um.
#[test]
fn fmi_crate_reproduces_the_zoh_reference() {
    let import = import();
    let md = import.model_description();
    assert_eq!(md.fmi_version, "2.0");
    assert_eq!(
        md.co_simulation
            .as_ref()
            .expect("a Co-Simulation FMU")
            .model_identifier,
        "HaselPlatform"
    );

    let rows = reference();
    let out = run(&import, "reference", &rows);
    let mut max_dh: f64 = 0.0;
    let mut motion = [(f64::INFINITY, f64::NEG_INFINITY); 3];
    for (y, row) in out.iter().zip(&rows[1..]) {
        for i in 0..3 {
            max_dh = max_dh.max((y[i] - row[4 + i]).abs());
            motion[i] = (motion[i].0.min(y[i]), motion[i].1.max(y[i]));
        }
    }
    println!(
        "fmi crate vs zoh1ms reference: max |dh| = {:.3e} um",
        max_dh * 1e6
    );
    // the input really moved every actuator, so the comparison is not between two rest states
    assert!(motion.iter().all(|(lo, hi)| hi - lo > 5e-6), "{motion:?}");
    assert!(max_dh <= 0.01e-6, "max |dh| = {max_dh:e} m exceeds 0.01 um");
}

/// Four instances of the one loaded library, stepped at the same time in four threads over the
/// same input, agree bit for bit with a single-threaded run: the FMU keeps no shared state.
#[test]
fn four_threads_agree_bit_for_bit_with_one() {
    let import = import();
    let rows = reference();
    let single = run(&import, "single", &rows);
    let start = Barrier::new(4);
    let results: Vec<Vec<[f64; 6]>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..4)
            .map(|i| {
                let (import, rows, start) = (&import, &rows, &start);
                s.spawn(move || {
                    start.wait();
                    run(import, &format!("thread{i}"), rows)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a stepping thread panicked"))
            .collect()
    });
    let bits =
        |run: &[[f64; 6]]| -> Vec<[u64; 6]> { run.iter().map(|y| y.map(f64::to_bits)).collect() };
    for (i, r) in results.iter().enumerate() {
        assert_eq!(r.len(), single.len());
        assert!(
            bits(r) == bits(&single),
            "thread {i} differs from the single-threaded run"
        );
    }
}

/// The state variables in the order of `<Derivatives>` and their der() variables' references.
fn states_and_derivatives(import: &Fmi2Import) -> (Vec<u32>, Vec<u32>) {
    let md = import.model_description();
    let vars: Vec<_> = md.get_model_variables().collect();
    md.model_structure
        .derivatives
        .unknowns
        .iter()
        .map(|unknown| {
            let der = vars[unknown.index as usize - 1];
            let state = der
                .name
                .strip_prefix("der(")
                .and_then(|n| n.strip_suffix(')'))
                .unwrap_or_else(|| panic!("{} is not named der(...)", der.name));
            (value_refs(import, [state])[0], der.value_reference)
        })
        .unzip()
}

/// Solves `a x = b` in place (`a` row-major n × n) by Gaussian elimination with partial pivoting.
fn solve(mut a: Vec<f64>, b: &mut [f64]) {
    let n = b.len();
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()))
            .unwrap();
        for c in 0..n {
            a.swap(k * n + c, p * n + c);
        }
        b.swap(k, p);
        for i in k + 1..n {
            let f = a[i * n + k] / a[k * n + k];
            for c in k..n {
                a[i * n + c] -= f * a[k * n + c];
            }
            b[i] -= f * b[k];
        }
    }
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|c| a[k * n + c] * b[c]).sum();
        b[k] = (b[k] - s) / a[k * n + k];
    }
}

/// The fmi crate drives Model Exchange, and the FMU's derivatives with its directional
/// derivatives are all an implicit integrator needs: linearly implicit Euler, (I − hJ) Δx = h f
/// with J from fmi2GetDirectionalDerivative column by column at each change of the input, 1 µs
/// steps over the first 10 ms of the reference input (the nanosecond electrical modes rule out
/// an explicit method), stays within 0.01 µm of the Co-Simulation run.
#[test]
fn fmi_crate_drives_model_exchange_with_the_fmus_jacobian() {
    const H: f64 = 1e-6;
    const STEPS_PER_MS: usize = 1000;
    let import = import();
    let md = import.model_description();
    let me_interface = md.model_exchange.as_ref().expect("a Model Exchange FMU");
    assert_eq!(me_interface.model_identifier, "HaselPlatform");
    assert_eq!(me_interface.provides_directional_derivative, Some(true));
    let (states, derivatives) = states_and_derivatives(&import);
    let n = states.len();
    assert_eq!((n, md.num_states()), (99, 99));
    let (u_refs, y_refs) = (value_refs(&import, INPUTS), value_refs(&import, OUTPUTS));
    let rows = &reference()[..11];
    let cs = run(&import, "cs", rows);

    let mut me = import
        .instantiate_me("me", false, false)
        .unwrap_or_else(|e| panic!("fmi2Instantiate (Model Exchange) failed: {e}"));
    Common::setup_experiment(&mut me, None, 0.0, None).expect("fmi2SetupExperiment");
    Common::enter_initialization_mode(&mut me).expect("fmi2EnterInitializationMode");
    Common::exit_initialization_mode(&mut me).expect("fmi2ExitInitializationMode");
    let mut flags = EventFlags::default();
    me.new_discrete_states(&mut flags)
        .expect("fmi2NewDiscreteStates");
    assert!(!flags.discrete_states_need_update && !flags.terminate_simulation);
    me.enter_continuous_time_mode()
        .expect("fmi2EnterContinuousTimeMode");
    let mut x = vec![0.0; n];
    me.get_continuous_states(&mut x)
        .expect("fmi2GetContinuousStates");
    let (mut f, mut jac) = (vec![0.0; n], vec![0.0; n * n]);
    let (mut column, mut seed) = (vec![0.0; n], vec![0.0; n]);
    let mut t = 0.0;
    let mut max_dh: f64 = 0.0;
    for (k, row) in rows[..rows.len() - 1].iter().enumerate() {
        me.enter_event_mode().expect("fmi2EnterEventMode");
        me.set_real(&u_refs, &row[1..4]).expect("fmi2SetReal");
        me.new_discrete_states(&mut flags)
            .expect("fmi2NewDiscreteStates");
        me.enter_continuous_time_mode()
            .expect("fmi2EnterContinuousTimeMode");
        // I − hJ with J at the start of the interval: column c with all states known, seeded
        // with the unit vector e_c (the fmi crate 0.8 asserts as many knowns as unknowns)
        me.set_continuous_states(&x)
            .expect("fmi2SetContinuousStates");
        for c in 0..n {
            seed.fill(0.0);
            seed[c] = 1.0;
            me.get_directional_derivative(&derivatives, &states, &seed, &mut column)
                .expect("fmi2GetDirectionalDerivative");
            for r in 0..n {
                jac[r * n + c] = f64::from(u8::from(r == c)) - H * column[r];
            }
        }
        for _ in 0..STEPS_PER_MS {
            me.set_time(t).expect("fmi2SetTime");
            me.set_continuous_states(&x)
                .expect("fmi2SetContinuousStates");
            me.get_derivatives(&mut f).expect("fmi2GetDerivatives");
            let mut dx: Vec<f64> = f.iter().map(|v| H * v).collect();
            solve(jac.clone(), &mut dx);
            for (xi, d) in x.iter_mut().zip(&dx) {
                *xi += d;
            }
            t += H;
            let (mut event, mut terminate) = (true, true);
            me.completed_integrator_step(true, &mut event, &mut terminate)
                .expect("fmi2CompletedIntegratorStep");
            assert!(!event && !terminate);
        }
        me.set_continuous_states(&x)
            .expect("fmi2SetContinuousStates");
        let mut y = [0.0; 6];
        me.get_real(&y_refs, &mut y).expect("fmi2GetReal");
        for i in 0..3 {
            max_dh = max_dh.max((y[i] - cs[k][i]).abs());
        }
    }
    println!(
        "fmi crate, Model Exchange with linearly implicit Euler (h = {H:e} s, J by directional \
         derivatives) vs Co-Simulation over 10 ms: max |dh| = {:.3e} um",
        max_dh * 1e6
    );
    assert!(max_dh <= 0.01e-6, "max |dh| = {max_dh:e} m exceeds 0.01 um");
    Common::terminate(&mut me).expect("fmi2Terminate");
}
