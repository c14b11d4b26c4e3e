//! fmi2Get/Set*: references, NULL arrays, values, and the set rules per state.

use std::ptr::{null, null_mut};

use super::*;

#[test]
fn unknown_value_references_are_named() {
    let fmu = Fmu::in_init(0.0);
    assert_eq!(fmu.try_get(99), Fmi2Status::Error);
    fmu.log
        .assert_error(&["fmi2GetReal: unknown value reference 99"]);
    assert_eq!(fmu.set(77, 1.0), Fmi2Status::Error);
    fmu.log
        .assert_error(&["fmi2SetReal: unknown value reference 77"]);
    let vrs = [U, 55];
    let values = [5.0, 6.0];
    assert_eq!(
        unsafe { toy::fmi2SetReal(fmu.c, vrs.as_ptr(), 2, values.as_ptr()) },
        Fmi2Status::Error
    );
    assert_eq!(
        fmu.get(U),
        0.0,
        "references are all checked before any value is set"
    );
}

#[test]
fn several_values_at_once() {
    let fmu = Fmu::in_init(0.0);
    let vrs = [TAU, U, Y_START];
    assert_eq!(
        unsafe { toy::fmi2SetReal(fmu.c, vrs.as_ptr(), 3, [2.0, 3.0, 4.0].as_ptr()) },
        Fmi2Status::Ok
    );
    let mut out = [0.0; 4];
    let vrs = [Y, RATE, U, TAU];
    assert_eq!(
        unsafe { toy::fmi2GetReal(fmu.c, vrs.as_ptr(), 4, out.as_mut_ptr()) },
        Fmi2Status::Ok
    );
    assert_eq!(out, [4.0, 0.5, 3.0, 2.0]);
}

#[test]
fn null_arrays() {
    let fmu = Fmu::in_init(0.0);
    let mut x = 0.0;
    let vr = U;
    unsafe {
        assert_eq!(
            toy::fmi2GetReal(fmu.c, null(), 1, &mut x),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2GetReal(fmu.c, &vr, 1, null_mut()),
            Fmi2Status::Error
        );
        assert_eq!(toy::fmi2SetReal(fmu.c, &vr, 1, null()), Fmi2Status::Error);
        assert_eq!(
            toy::fmi2SetReal(fmu.c, null(), 0, null()),
            Fmi2Status::Ok,
            "nvr = 0 with NULL arrays"
        );
        assert_eq!(
            toy::fmi2GetReal(fmu.c, null(), 0, null_mut()),
            Fmi2Status::Ok
        );
        assert_eq!(
            toy::fmi2GetInteger(fmu.c, &vr, 1, null_mut()),
            Fmi2Status::Error
        );
    }
    fmu.log.assert_error(&[
        "fmi2GetReal: argument vr is NULL",
        "fmi2GetReal: argument value is NULL",
        "fmi2SetReal: argument value is NULL",
        "fmi2GetInteger: argument value is NULL",
    ]);
}

#[test]
fn bad_values_name_variable_and_value() {
    let fmu = Fmu::in_init(0.0);
    assert_eq!(fmu.set(U, f64::NAN), Fmi2Status::Error);
    fmu.log
        .assert_error(&["fmi2SetReal: u (value reference 4): value is NaN"]);
    assert_eq!(fmu.set(TAU, -1.0), Fmi2Status::Error);
    fmu.log
        .assert_error(&["tau (value reference 0) = -1.0 rejected: tau must be > 0, got -1"]);
    assert_eq!(fmu.get(TAU), 1.0, "rejected value not applied");
}

#[test]
fn set_rules_follow_the_state_table() {
    let fmu = Fmu::new();
    // instantiated: exact/approx variables and inputs
    assert_eq!(fmu.set(TAU, 2.0), Fmi2Status::Ok);
    assert_eq!(fmu.set(U, 0.5), Fmi2Status::Ok);
    assert_eq!(fmu.set(Y, 1.0), Fmi2Status::Error);
    fmu.log.assert_error(&["y (value reference 5, causality output, variability continuous, initial calculated) cannot be set in state instantiated"]);
    assert_eq!(fmu.set(RATE, 1.0), Fmi2Status::Error);
    assert_eq!(fmu.setup(0.0, None), Fmi2Status::Ok);
    assert_eq!(
        unsafe { toy::fmi2EnterInitializationMode(fmu.c) },
        Fmi2Status::Ok
    );
    // initialization mode: exact variables and inputs
    assert_eq!(fmu.set(Y_START, 1.0), Fmi2Status::Ok);
    assert_eq!(fmu.set(U, 0.25), Fmi2Status::Ok);
    assert_eq!(fmu.set(Y, 1.0), Fmi2Status::Error);
    assert_eq!(
        unsafe { toy::fmi2ExitInitializationMode(fmu.c) },
        Fmi2Status::Ok
    );
    // stepComplete: inputs and tunable parameters only
    assert_eq!(fmu.set(U, 0.75), Fmi2Status::Ok);
    assert_eq!(fmu.set(MAX_STEP, 0.5), Fmi2Status::Ok);
    assert_eq!(fmu.set(TAU, 3.0), Fmi2Status::Error);
    fmu.log.assert_error(&["tau (value reference 0, causality parameter, variability fixed, initial exact) cannot be set in state stepComplete"]);
    assert_eq!(fmu.get(TAU), 2.0);
    assert_eq!(unsafe { toy::fmi2Terminate(fmu.c) }, Fmi2Status::Ok);
    assert_eq!(fmu.set(U, 1.0), Fmi2Status::Error, "no set after terminate");
}

#[test]
fn other_types_have_no_variables() {
    let fmu = Fmu::in_init(0.0);
    let vr = 0;
    let mut i = 0;
    let mut b = 0;
    let mut s = null();
    unsafe {
        assert_eq!(
            toy::fmi2GetInteger(fmu.c, null(), 0, null_mut()),
            Fmi2Status::Ok
        );
        assert_eq!(
            toy::fmi2GetInteger(fmu.c, &vr, 1, &mut i),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2GetBoolean(fmu.c, &vr, 1, &mut b),
            Fmi2Status::Error
        );
        assert_eq!(toy::fmi2GetString(fmu.c, &vr, 1, &mut s), Fmi2Status::Error);
        assert_eq!(toy::fmi2SetInteger(fmu.c, &vr, 1, &i), Fmi2Status::Error);
        assert_eq!(toy::fmi2SetBoolean(fmu.c, &vr, 1, &b), Fmi2Status::Error);
        assert_eq!(toy::fmi2SetString(fmu.c, &vr, 1, &s), Fmi2Status::Error);
    }
    fmu.log.assert_error(&[
        "fmi2GetInteger: unknown value reference 0: this FMU has no Integer variables",
        "no String variables",
        "no Boolean variables",
    ]);
}
