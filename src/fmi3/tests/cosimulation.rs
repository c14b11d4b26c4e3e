//! Co-Simulation through the FMI 3.0 functions: the same trajectory as FMI 2.0 bit for bit,
//! the state machine, and the argument checks.

use std::ptr::null_mut;

use super::{Cs, v2, v3, vr};
use crate::fmi2::types::{Fmi2Status, fmi2CallbackFunctions};
use crate::fmi3::types::*;
use crate::fmu::pack::FmiVersion;
use crate::model::Params;

const OUTPUTS: [&str; 6] = ["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"];

/// The paper's sine inputs at `t`.
fn inputs(t: f64) -> [f64; 3] {
    let w = 3.0 * std::f64::consts::PI;
    [0.0, 1.0, 2.0].map(|k| 60.0 * (w * t + k * 2.0 * std::f64::consts::PI / 3.0).sin())
}

#[test]
fn fmi3_co_simulation_matches_fmi2_bit_for_bit() {
    let u: Vec<u32> = ["U1", "U2", "U3"].map(vr).to_vec();
    let y: Vec<u32> = OUTPUTS.map(vr).to_vec();
    let mut cs = Cs::new(false);
    assert!(!cs.c.is_null());
    cs.init();
    let guid = std::ffi::CString::new(
        FmiVersion::V2.token(&crate::fmu::pack::platform(&Params::default())),
    )
    .unwrap();
    let callbacks = fmi2CallbackFunctions {
        logger: None,
        allocate_memory: None,
        free_memory: None,
        step_finished: None,
        component_environment: null_mut(),
    };
    unsafe {
        let c2 = v2::fmi2Instantiate(
            c"v2".as_ptr(),
            1,
            guid.as_ptr(),
            std::ptr::null(),
            &callbacks,
            0,
            0,
        );
        assert!(!c2.is_null());
        assert_eq!(
            v2::fmi2SetupExperiment(c2, 0, 0.0, 0.0, 0, 0.0),
            Fmi2Status::Ok
        );
        assert_eq!(v2::fmi2EnterInitializationMode(c2), Fmi2Status::Ok);
        assert_eq!(v2::fmi2ExitInitializationMode(c2), Fmi2Status::Ok);
        let h = 1e-3;
        for k in 0..300 {
            let t = k as f64 * h;
            let values = inputs(t);
            assert_eq!(cs.set(&u, &values), Fmi3Status::Ok);
            assert_eq!(
                v2::fmi2SetReal(c2, u.as_ptr(), 3, values.as_ptr()),
                Fmi2Status::Ok
            );
            let (status, last) = cs.step(h);
            assert_eq!(status, Fmi3Status::Ok);
            assert_eq!(v2::fmi2DoStep(c2, t, h, 1), Fmi2Status::Ok);
            let (status, out3) = cs.get(&y);
            assert_eq!(status, Fmi3Status::Ok);
            let mut out2 = [0.0; 6];
            assert_eq!(
                v2::fmi2GetReal(c2, y.as_ptr(), 6, out2.as_mut_ptr()),
                Fmi2Status::Ok
            );
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&out3), bits(&out2), "step {k}");
            assert_eq!(last, cs.t);
        }
        v2::fmi2FreeInstance(c2);
    }
    // the independent variable `time` reads the FMU's time
    let time_vr = crate::fmu::variables::rows().len() as u32;
    assert_eq!(cs.get(&[time_vr]), (Fmi3Status::Ok, vec![cs.t]));
    assert!(cs.get(&[vr("h2")]).1[0] > 1e-6, "the actuator moved");
}

#[test]
fn calls_out_of_state_are_errors_that_change_nothing() {
    let mut cs = Cs::new(false);
    assert_eq!(cs.step(1e-3).0, Fmi3Status::Error);
    cs.log
        .assert_error(&["fmi3DoStep", "not allowed in state Instantiated"]);
    assert_eq!(
        unsafe { v3::fmi3ExitInitializationMode(cs.c) },
        Fmi3Status::Error
    );
    assert_eq!(cs.get(&[vr("h1")]).0, Fmi3Status::Error);
    cs.init();
    // without eventModeUsed there is no Event Mode
    assert_eq!(unsafe { v3::fmi3EnterEventMode(cs.c) }, Fmi3Status::Error);
    cs.log
        .assert_error(&["fmi3EnterEventMode", "eventModeUsed = false"]);
    assert_eq!(unsafe { v3::fmi3EnterStepMode(cs.c) }, Fmi3Status::Error);
    cs.log
        .assert_error(&["fmi3EnterStepMode", "not allowed in state Step Mode"]);
    // Model Exchange functions on a Co-Simulation instance
    assert_eq!(
        unsafe { v3::fmi3EnterContinuousTimeMode(cs.c) },
        Fmi3Status::Error
    );
    cs.log
        .assert_error(&["fmi3EnterContinuousTimeMode", "Model Exchange"]);
    // a fixed parameter after initialization
    assert_eq!(cs.set(&[vr("Kb_1")], &[0.4]), Fmi3Status::Error);
    cs.log
        .assert_error(&["Kb_1", "cannot be set in state Step Mode"]);
    assert_eq!(cs.step(1e-3).0, Fmi3Status::Ok);
    assert_eq!(unsafe { v3::fmi3Terminate(cs.c) }, Fmi3Status::Ok);
    assert_eq!(unsafe { v3::fmi3Terminate(cs.c) }, Fmi3Status::Error);
    cs.log
        .assert_error(&["fmi3Terminate", "not allowed in state Terminated"]);
    assert_eq!(unsafe { v3::fmi3Reset(cs.c) }, Fmi3Status::Ok);
    cs.t = 0.0;
    cs.init();
    assert_eq!(cs.step(1e-3).0, Fmi3Status::Ok);
}

#[test]
fn event_mode_when_the_importer_asks_for_it() {
    let mut cs = Cs::new(true);
    cs.init();
    assert_eq!(cs.step(1e-3).0, Fmi3Status::Error);
    cs.log
        .assert_error(&["fmi3DoStep", "not allowed in state Event Mode"]);
    let mut flags = [9u8; 5];
    let mut next = f64::NAN;
    let [a, b, c, d, e] = &mut flags;
    let status = unsafe { v3::fmi3UpdateDiscreteStates(cs.c, a, b, c, d, e, &mut next) };
    assert_eq!((status, flags), (Fmi3Status::Ok, [0; 5]));
    assert_eq!(unsafe { v3::fmi3EnterStepMode(cs.c) }, Fmi3Status::Ok);
    assert_eq!(cs.step(1e-3).0, Fmi3Status::Ok);
    assert_eq!(unsafe { v3::fmi3EnterEventMode(cs.c) }, Fmi3Status::Ok);
    assert_eq!(unsafe { v3::fmi3EnterStepMode(cs.c) }, Fmi3Status::Ok);
}

#[test]
fn bad_arguments_are_named() {
    let mut cs = Cs::new(false);
    cs.init();
    let h1 = vr("h1");
    // nValues that does not match the references
    let mut out = [0.0; 2];
    let s = unsafe { v3::fmi3GetFloat64(cs.c, [h1].as_ptr(), 1, out.as_mut_ptr(), 2) };
    assert_eq!(s, Fmi3Status::Error);
    cs.log
        .assert_error(&["fmi3GetFloat64", "nValues = 2", "need 1 values"]);
    // unknown reference, NULL arrays, NaN
    assert_eq!(cs.get(&[100_000]).0, Fmi3Status::Error);
    cs.log
        .assert_error(&["fmi3GetFloat64", "unknown value reference 100000"]);
    let s = unsafe { v3::fmi3GetFloat64(cs.c, std::ptr::null(), 1, out.as_mut_ptr(), 1) };
    assert_eq!(s, Fmi3Status::Error);
    cs.log
        .assert_error(&["fmi3GetFloat64", "valueReferences is NULL"]);
    assert_eq!(cs.set(&[vr("U1")], &[f64::NAN]), Fmi3Status::Error);
    cs.log.assert_error(&["U1", "NaN"]);
    // other types: the reference named with its variable and the type
    let mut i = [0i32; 1];
    let s = unsafe { v3::fmi3GetInt32(cs.c, [vr("U1")].as_ptr(), 1, i.as_mut_ptr(), 1) };
    assert_eq!(s, Fmi3Status::Error);
    cs.log.assert_error(&[
        "fmi3GetInt32",
        "value reference 0 is U1, a Float64",
        "no Int32 variables",
    ]);
    let mut b = [0u8; 1];
    let s = unsafe { v3::fmi3GetBoolean(cs.c, [77_777].as_ptr(), 1, b.as_mut_ptr(), 1) };
    assert_eq!(s, Fmi3Status::Error);
    cs.log.assert_error(&[
        "fmi3GetBoolean",
        "unknown value reference 77777",
        "no Boolean",
    ]);
    // DoStep: NaN, negative and mismatched times, NULL out-arguments
    for (tc, h, what) in [
        (0.0, f64::NAN, "communicationStepSize = NaN"),
        (0.0, -1e-3, "communicationStepSize = -0.001"),
        (0.5, 1e-3, "currentCommunicationPoint = 0.5"),
    ] {
        cs.t = tc;
        assert_eq!(cs.step(h).0, Fmi3Status::Error);
        cs.log.assert_error(&["fmi3DoStep", what]);
    }
    cs.t = 0.0;
    let (mut e, mut t, mut r) = (0, 0, 0);
    let s = unsafe { v3::fmi3DoStep(cs.c, 0.0, 1e-3, 1, &mut e, &mut t, &mut r, null_mut()) };
    assert_eq!(s, Fmi3Status::Error);
    cs.log
        .assert_error(&["fmi3DoStep", "lastSuccessfulTime is NULL"]);
    // directional derivatives: unknowns and knowns of the right kinds, sizes that agree
    let seed = [1.0];
    let dd = |unknown: u32, known: u32, n_seed: usize, dy: &mut [f64; 1]| unsafe {
        v3::fmi3GetDirectionalDerivative(
            cs.c,
            [unknown].as_ptr(),
            1,
            [known].as_ptr(),
            1,
            seed.as_ptr(),
            n_seed,
            dy.as_mut_ptr(),
            1,
        )
    };
    let mut dy = [0.0];
    assert_eq!(dd(vr("U1"), vr("theta_1"), 1, &mut dy), Fmi3Status::Error);
    cs.log.assert_error(&[
        "fmi3GetDirectionalDerivative",
        "U1",
        "neither a state derivative nor an output",
    ]);
    assert_eq!(dd(vr("h1"), vr("Kb_1"), 1, &mut dy), Fmi3Status::Error);
    cs.log
        .assert_error(&["Kb_1", "neither a continuous state nor an input"]);
    assert_eq!(dd(vr("h1"), vr("theta_1"), 2, &mut dy), Fmi3Status::Error);
    cs.log.assert_error(&["nSeed = 2 must equal nKnowns = 1"]);
    assert_eq!(dd(vr("h1"), vr("theta_1"), 1, &mut dy), Fmi3Status::Ok);
    assert!(dy[0] > 0.0, "h1 rises with theta_1");
    assert_eq!(
        unsafe { v3::fmi3SetDebugLogging(cs.c, 1, 1, [c"nope".as_ptr()].as_ptr()) },
        Fmi3Status::Error
    );
    cs.log.assert_error(&["unknown log category \"nope\""]);
    assert_eq!(
        unsafe { v3::fmi3SetDebugLogging(null_mut(), 1, 0, std::ptr::null()) },
        Fmi3Status::Error
    );
    // after all that the instance still steps
    cs.log.clear();
    assert_eq!(cs.step(1e-3).0, Fmi3Status::Ok);
}
