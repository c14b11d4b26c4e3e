//! The reduced models (src/model/reduced.rs) against the full one within their documented
//! bounds (book/src/reduced.md, "Error against the full model"): on a step from rest, where the
//! slow model's error is that of its missing inertia right after the jump. Their energy balance
//! is in tests/energy.rs.

use hasel_fmu::model::{Params, Platform, Reduction};
use hasel_fmu::simulation::{Input, Sample, Simulator, largest_difference};

/// Tight enough that the differences are the models', not the integrator's.
const RTOL: f64 = 1e-9;

/// 1 s from rest of a step to 60 / 40 / 20 V, sampled every 1 ms.
fn step_response(reduction: Reduction) -> Vec<Sample> {
    let model = Platform::reduced(Params::default(), reduction).unwrap();
    let mut sim = Simulator::new(model, 0.0, RTOL).unwrap();
    let mut samples = Vec::new();
    sim.run(&Input::constant([60.0, 40.0, 20.0]), 1.0, 1e-3, |s| {
        samples.push(*s)
    })
    .unwrap();
    samples
}

#[test]
fn reduced_models_follow_the_full_one_within_their_bounds() {
    let full = step_response(Reduction::Full);
    // the bounds [µm] on |Δh| and |Δtip| book/src/reduced.md documents
    for (reduction, bound_h, bound_tip) in [
        (Reduction::QuasiStatic, 0.01, 0.02),
        (Reduction::Slow, 0.2, 0.2),
    ] {
        let (dh, dtip) = largest_difference(&full, &step_response(reduction), 0.0);
        let (dh, dtip) = (dh * 1e6, dtip * 1e6);
        println!("{}: |dh| {dh:.4} um, |dtip| {dtip:.4} um", reduction.name());
        assert!(dh <= bound_h, "{}: |dh| {dh} um", reduction.name());
        assert!(dtip <= bound_tip, "{}: |dtip| {dtip} um", reduction.name());
    }
    // the run moves: a model that stood still would not pass for one that follows
    let stroke = full.last().unwrap().h[0] - full[0].h[0];
    assert!(stroke > 10e-6, "stroke {stroke:e} m");
}
