//! The accuracy contract (book/src/model.md, "Accuracy contract"): at the default rtol 1e-6
//! every documented kind of input up to 100 V and 100 rad/s stays within 0.01 µm (h) and 0.02 µm
//! (tip) of a converged solution.

use hasel_fmu::model::{Params, Platform};
use hasel_fmu::simulation::{DEFAULT_RTOL, Input, Interpolation, Sample, Simulator, Tone};

fn run(input: &Input, rtol: f64, t_end: f64) -> Vec<Sample> {
    let mut sim = Simulator::new(Platform::new(Params::default()).unwrap(), 0.0, rtol).unwrap();
    let mut out = Vec::new();
    sim.run(input, t_end, 1e-3, |s| out.push(*s)).unwrap();
    out
}

fn check(name: &str, input: Input, t_end: f64) {
    let fast = run(&input, DEFAULT_RTOL, t_end);
    let converged = run(&input, 1e-11, t_end);
    let (mut dh, mut dtip): (f64, f64) = (0.0, 0.0);
    for (a, b) in fast.iter().zip(&converged) {
        for i in 0..3 {
            dh = dh.max((a.h[i] - b.h[i]).abs());
            dtip = dtip.max((a.tip[i] - b.tip[i]).abs());
        }
    }
    println!(
        "{name}: max |dh| = {:.2e} um, max |dtip| = {:.2e} um",
        dh * 1e6,
        dtip * 1e6
    );
    assert!(dh <= 0.01e-6 && dtip <= 0.02e-6, "{name}");
}

#[test]
fn sine_at_100_volts_and_100_rad_per_s() {
    check("sine 100 V, 100 rad/s", Input::sine(100.0, 100.0), 1.0);
}

#[test]
fn offset_sine() {
    check(
        "offset sine 100 V, 11 rad/s",
        Input::offset_sine(100.0, 11.0),
        2.0,
    );
}

#[test]
fn multisine() {
    let tones = |phase: f64| {
        vec![
            Tone {
                amplitude: 40.0,
                omega: 3.0,
                phase,
            },
            Tone {
                amplitude: 30.0,
                omega: 17.0,
                phase: 2.0 * phase,
            },
            Tone {
                amplitude: 25.0,
                omega: 60.0,
                phase: 0.5,
            },
        ]
    };
    check(
        "multisine",
        Input::Tones {
            offset: [5.0, 0.0, -5.0],
            tones: [tones(0.0), tones(2.1), tones(4.2)],
        },
        2.0,
    );
}

#[test]
fn sampled_inputs_with_each_interpolation() {
    let t: Vec<f64> = (0..=400).map(|k| k as f64 * 2.5e-3).collect();
    let u: Vec<[f64; 3]> = t
        .iter()
        .map(|&tk| Input::sine(100.0, 100.0).value(tk))
        .collect();
    for interpolation in [
        Interpolation::ZeroOrderHold,
        Interpolation::Linear,
        Interpolation::Pchip,
        Interpolation::Spline,
    ] {
        let input = Input::sampled(t.clone(), u.clone(), interpolation).unwrap();
        check(
            &format!("sampled every 2.5 ms, {interpolation:?}"),
            input,
            1.0,
        );
    }
}
