//! State machine, instantiation, stepping, status functions, panics.

use std::ffi::CStr;
use std::ptr::{null, null_mut};

use super::*;

#[test]
fn version_strings() {
    assert_eq!(unsafe { CStr::from_ptr(toy::fmi2GetVersion()) }, c"2.0");
    assert_eq!(
        unsafe { CStr::from_ptr(toy::fmi2GetTypesPlatform()) },
        c"default"
    );
}

#[test]
fn full_run_matches_the_exact_solution() {
    let fmu = Fmu::in_init(0.0);
    assert_eq!(fmu.set(TAU, 0.5), Fmi2Status::Ok);
    assert_eq!(fmu.set(Y_START, 2.0), Fmi2Status::Ok);
    assert_eq!(
        fmu.get(Y),
        2.0,
        "output in Initialization Mode follows the parameters"
    );
    assert_eq!(fmu.get(RATE), 2.0);
    assert_eq!(
        unsafe { toy::fmi2ExitInitializationMode(fmu.c) },
        Fmi2Status::Ok
    );
    assert_eq!(fmu.set(U, 1.0), Fmi2Status::Ok);
    let h = 0.01;
    for i in 0..100 {
        assert_eq!(fmu.step(i as f64 * h, h), Fmi2Status::Ok);
    }
    assert_eq!(fmu.get(Y), lag_exact(2.0, 1.0, 0.5, h, 100));
    assert_eq!(unsafe { toy::fmi2Terminate(fmu.c) }, Fmi2Status::Ok);
    assert_eq!(
        fmu.get(Y),
        lag_exact(2.0, 1.0, 0.5, h, 100),
        "get after terminate is allowed"
    );
    assert_eq!(
        unsafe { toy::fmi2Terminate(fmu.c) },
        Fmi2Status::Error,
        "terminate twice"
    );
    fmu.log
        .assert_error(&["fmi2Terminate", "not allowed in state terminated"]);
    assert_eq!(fmu.step(1.0, h), Fmi2Status::Error);
}

#[test]
fn calls_in_the_wrong_state_are_errors() {
    let fmu = Fmu::new();
    assert_eq!(fmu.step(0.0, 0.1), Fmi2Status::Error);
    fmu.log
        .assert_error(&["fmi2DoStep: not allowed in state instantiated"]);
    assert_eq!(fmu.try_get(Y), Fmi2Status::Error);
    fmu.log
        .assert_error(&["fmi2GetReal: not allowed in state instantiated"]);
    assert_eq!(
        unsafe { toy::fmi2ExitInitializationMode(fmu.c) },
        Fmi2Status::Error
    );
    assert_eq!(unsafe { toy::fmi2Terminate(fmu.c) }, Fmi2Status::Error);
    assert_eq!(
        unsafe { toy::fmi2EnterInitializationMode(fmu.c) },
        Fmi2Status::Error
    );
    fmu.log
        .assert_error(&["fmi2SetupExperiment must be called before"]);
    assert_eq!(unsafe { toy::fmi2CancelStep(fmu.c) }, Fmi2Status::Error);
    fmu.log.assert_error(&["fmi2CancelStep", "synchronous"]);
    // the errors changed nothing: the normal sequence still works
    assert_eq!(fmu.setup(0.0, None), Fmi2Status::Ok);
    assert_eq!(
        unsafe { toy::fmi2EnterInitializationMode(fmu.c) },
        Fmi2Status::Ok
    );
    assert_eq!(fmu.setup(0.0, None), Fmi2Status::Error);
    fmu.log
        .assert_error(&["fmi2SetupExperiment: not allowed in state initializationMode"]);
    assert_eq!(fmu.step(0.0, 0.1), Fmi2Status::Error);
    assert_eq!(
        unsafe { toy::fmi2ExitInitializationMode(fmu.c) },
        Fmi2Status::Ok
    );
    assert_eq!(
        unsafe { toy::fmi2EnterInitializationMode(fmu.c) },
        Fmi2Status::Error
    );
    let mut t = 0.0;
    assert_eq!(
        unsafe { toy::fmi2GetRealStatus(fmu.c, FMI2_LAST_SUCCESSFUL_TIME, &mut t) },
        Fmi2Status::Ok
    );
}

#[test]
fn invalid_experiments_are_rejected() {
    let fmu = Fmu::new();
    assert_eq!(fmu.setup(f64::NAN, None), Fmi2Status::Error);
    assert_eq!(fmu.setup(1.0, Some(0.5)), Fmi2Status::Error);
    fmu.log.assert_error(&["stopTime = 0.5"]);
    assert_eq!(
        unsafe { toy::fmi2SetupExperiment(fmu.c, FMI2_TRUE, -1.0, 0.0, FMI2_FALSE, 0.0) },
        Fmi2Status::Error
    );
    fmu.log.assert_error(&["tolerance = -1.0"]);
}

#[test]
fn null_component_and_free_null() {
    unsafe {
        toy::fmi2FreeInstance(null_mut());
        assert_eq!(
            toy::fmi2DoStep(null_mut(), 0.0, 1.0, FMI2_FALSE),
            Fmi2Status::Error
        );
        assert_eq!(toy::fmi2Terminate(null_mut()), Fmi2Status::Error);
        assert_eq!(
            toy::fmi2GetReal(null_mut(), null(), 0, null_mut()),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2SetDebugLogging(null_mut(), FMI2_TRUE, 0, null()),
            Fmi2Status::Error
        );
    }
}

#[test]
fn instantiate_rejects_model_exchange_and_wrong_guid() {
    let (c, log) = instantiate_raw("me", FMI2_MODEL_EXCHANGE, &toy_guid(), None, false);
    assert!(c.is_null());
    log.assert_error(&["fmi2Instantiate", "Model Exchange"]);
    let (c, log) = instantiate_raw(
        "g",
        FMI2_CO_SIMULATION,
        "{00000000-0000-0000-0000-000000000000}",
        None,
        false,
    );
    assert!(c.is_null());
    log.assert_error(&["{00000000-0000-0000-0000-000000000000}", &toy_guid()]);
    let (c, log) = instantiate_raw("", FMI2_CO_SIMULATION, &toy_guid(), None, false);
    assert!(c.is_null());
    log.assert_error(&["instanceName is empty"]);
    let (c, log) = instantiate_raw(
        "r",
        FMI2_CO_SIMULATION,
        &toy_guid(),
        Some("http://example.org/r"),
        false,
    );
    assert!(c.is_null());
    log.assert_error(&["not a file: URI"]);
}

#[test]
fn instantiate_tolerates_missing_callbacks_and_visible() {
    let guid = CString::new(toy_guid()).unwrap();
    let functions = fmi2CallbackFunctions {
        logger: None,
        allocate_memory: None,
        free_memory: None,
        step_finished: None,
        component_environment: null_mut(),
    };
    unsafe {
        let c = toy::fmi2Instantiate(
            c"quiet".as_ptr(),
            FMI2_CO_SIMULATION,
            guid.as_ptr(),
            null(),
            &functions,
            FMI2_TRUE,
            FMI2_TRUE,
        );
        assert!(!c.is_null());
        assert_eq!(
            toy::fmi2DoStep(c, 0.0, 1.0, FMI2_FALSE),
            Fmi2Status::Error,
            "errors without a logger"
        );
        assert_eq!(
            toy::fmi2SetupExperiment(c, FMI2_FALSE, 0.0, 0.0, FMI2_FALSE, 0.0),
            Fmi2Status::Ok
        );
        toy::fmi2FreeInstance(c);
        assert!(
            toy::fmi2Instantiate(
                c"x".as_ptr(),
                FMI2_CO_SIMULATION,
                guid.as_ptr(),
                null(),
                null(),
                FMI2_FALSE,
                FMI2_FALSE
            )
            .is_null()
        );
        assert!(
            toy::fmi2Instantiate(
                null(),
                FMI2_CO_SIMULATION,
                guid.as_ptr(),
                null(),
                &functions,
                FMI2_FALSE,
                FMI2_FALSE
            )
            .is_null()
        );
    }
}

/// A fresh directory under the system temp dir.
fn temp_dir(tag: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("fmi2-shell-test-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn resources_reach_the_core_and_change_the_guid() {
    let dir = temp_dir("res dir");
    std::fs::write(dir.join("tau.txt"), "0.25").unwrap();
    let uri = format!("file://{}", dir.display()).replace(' ', "%20");
    let (c, log) = instantiate_raw("res", FMI2_CO_SIMULATION, &toy_guid(), Some(&uri), false);
    assert!(
        c.is_null(),
        "the start value of tau changed, so the GUID must differ"
    );
    log.assert_error(&["does not match"]);
    let core = LagCore::instantiate(InstanceKind::CoSimulation, Some(&dir)).unwrap();
    let guid = guid_for(&LagCore::model_info(), &core.variables()).unwrap();
    assert_ne!(guid, toy_guid());
    let fmu = Fmu::with_guid(&guid, Some(&uri));
    assert_eq!(fmu.setup(0.0, None), Fmi2Status::Ok);
    assert_eq!(
        unsafe { toy::fmi2EnterInitializationMode(fmu.c) },
        Fmi2Status::Ok
    );
    assert_eq!(fmu.get(TAU), 0.25);
    // reset recreates the core from the same resources
    assert_eq!(fmu.set(TAU, 3.0), Fmi2Status::Ok);
    assert_eq!(unsafe { toy::fmi2Reset(fmu.c) }, Fmi2Status::Ok);
    assert_eq!(fmu.setup(0.0, None), Fmi2Status::Ok);
    assert_eq!(
        unsafe { toy::fmi2EnterInitializationMode(fmu.c) },
        Fmi2Status::Ok
    );
    assert_eq!(fmu.get(TAU), 0.25);
    std::fs::write(dir.join("tau.txt"), "bad").unwrap();
    let (c, log) = instantiate_raw("res", FMI2_CO_SIMULATION, &guid, Some(&uri), false);
    assert!(c.is_null());
    log.assert_error(&["cannot create the model", "tau.txt"]);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn reset_restores_start_values() {
    let fmu = Fmu::running(0.0);
    assert_eq!(fmu.set(U, 1.0), Fmi2Status::Ok);
    assert_eq!(fmu.step(0.0, 0.5), Fmi2Status::Ok);
    assert_eq!(unsafe { toy::fmi2Reset(fmu.c) }, Fmi2Status::Ok);
    assert_eq!(
        fmu.step(0.5, 0.5),
        Fmi2Status::Error,
        "reset goes back to instantiated"
    );
    assert_eq!(fmu.setup(0.0, None), Fmi2Status::Ok);
    assert_eq!(
        unsafe { toy::fmi2EnterInitializationMode(fmu.c) },
        Fmi2Status::Ok
    );
    assert_eq!((fmu.get(U), fmu.get(Y), fmu.get(TAU)), (0.0, 0.0, 1.0));
}

#[test]
fn do_step_checks_time_and_step_size() {
    let fmu = Fmu::running(1.0);
    assert_eq!(fmu.step(1.0, 0.0), Fmi2Status::Error);
    fmu.log.assert_error(&["communicationStepSize = 0.0"]);
    assert_eq!(fmu.step(1.0, -0.1), Fmi2Status::Error);
    assert_eq!(fmu.step(1.0, f64::NAN), Fmi2Status::Error);
    assert_eq!(fmu.step(1.1, 0.1), Fmi2Status::Error, "a skipped step");
    fmu.log
        .assert_error(&["currentCommunicationPoint = 1.1", "time 1.0"]);
    assert_eq!(fmu.step(f64::NAN, 0.1), Fmi2Status::Error);
    assert_eq!(
        fmu.step(1.0 * (1.0 + 1e-13), 0.1),
        Fmi2Status::Ok,
        "rounding difference"
    );
    let mut t = 0.0;
    for _ in 0..1000 {
        let tc = t + 1.1; // accumulated like a master adding step sizes
        assert_eq!(
            fmu.step(tc, 1e-3),
            Fmi2Status::Ok,
            "{:?}",
            fmu.log.records()
        );
        t += 1e-3;
    }
}

#[test]
fn do_step_respects_the_stop_time() {
    let fmu = Fmu::new();
    assert_eq!(fmu.setup(0.0, Some(1.0)), Fmi2Status::Ok);
    unsafe {
        assert_eq!(toy::fmi2EnterInitializationMode(fmu.c), Fmi2Status::Ok);
        assert_eq!(toy::fmi2ExitInitializationMode(fmu.c), Fmi2Status::Ok);
    }
    assert_eq!(fmu.step(0.0, 0.7), Fmi2Status::Ok);
    assert_eq!(fmu.step(0.7, 0.4), Fmi2Status::Error);
    fmu.log.assert_error(&["past stopTime = 1.0"]);
    assert_eq!(
        fmu.step(0.7, 0.3),
        Fmi2Status::Ok,
        "up to the stop time, with rounding"
    );
}

#[test]
fn discarded_step_and_status_functions() {
    let fmu = Fmu::running(0.0);
    assert_eq!(fmu.set(U, 1.0), Fmi2Status::Ok);
    assert_eq!(fmu.step(0.0, 0.5), Fmi2Status::Ok);
    let saved = fmu.get_state();
    let y = fmu.get(Y);
    assert_eq!(fmu.step(0.5, 2.0), Fmi2Status::Discard);
    let discards = fmu.log.text(Fmi2Status::Discard);
    assert!(
        discards.contains("step 2 exceeds max_step 1") && discards.contains("t = 0.5"),
        "{discards}"
    );
    let mut t = 0.0;
    let mut terminated = FMI2_TRUE;
    unsafe {
        assert_eq!(
            toy::fmi2GetRealStatus(fmu.c, FMI2_LAST_SUCCESSFUL_TIME, &mut t),
            Fmi2Status::Ok
        );
        assert_eq!(
            toy::fmi2GetBooleanStatus(fmu.c, FMI2_TERMINATED, &mut terminated),
            Fmi2Status::Ok
        );
    }
    assert_eq!((t, terminated), (0.5, FMI2_FALSE));
    assert_eq!(
        fmu.get(Y),
        y,
        "the core stays at the start of the failed step"
    );
    assert_eq!(
        fmu.step(0.5, 0.5),
        Fmi2Status::Error,
        "fmi2DoStep is not allowed in stepFailed"
    );
    fmu.log.assert_error(&["not allowed in state stepFailed"]);
    assert_eq!(
        unsafe { toy::fmi2SetFMUstate(fmu.c, saved) },
        Fmi2Status::Ok
    );
    assert_eq!(
        fmu.step(0.5, 0.5),
        Fmi2Status::Ok,
        "retry after restoring the state"
    );
    let mut saved = saved;
    assert_eq!(
        unsafe { toy::fmi2FreeFMUstate(fmu.c, &mut saved) },
        Fmi2Status::Ok
    );
    assert!(saved.is_null());
}

#[test]
fn status_kinds_that_need_a_pending_step_are_errors() {
    let fmu = Fmu::running(0.0);
    let mut status = Fmi2Status::Ok;
    let mut i = 0;
    let mut s = null();
    let mut x = 0.0;
    unsafe {
        assert_eq!(
            toy::fmi2GetStatus(fmu.c, FMI2_DO_STEP_STATUS, &mut status),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2GetStringStatus(fmu.c, FMI2_PENDING_STATUS, &mut s),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2GetIntegerStatus(fmu.c, FMI2_LAST_SUCCESSFUL_TIME, &mut i),
            Fmi2Status::Error
        );
        assert_eq!(toy::fmi2GetRealStatus(fmu.c, 17, &mut x), Fmi2Status::Error);
        assert_eq!(
            toy::fmi2GetRealStatus(fmu.c, FMI2_LAST_SUCCESSFUL_TIME, null_mut()),
            Fmi2Status::Error
        );
    }
    fmu.log.assert_error(&[
        "fmi2Pending",
        "status kind 17 is not a valid fmi2StatusKind",
        "argument value is NULL",
    ]);
}

#[test]
fn model_exchange_and_derivative_functions_are_not_offered() {
    let fmu = Fmu::running(0.0);
    let mut x = [0.0; 1];
    let vr = [Y];
    let order = [1];
    unsafe {
        assert_eq!(toy::fmi2SetTime(fmu.c, 1.0), Fmi2Status::Error);
        assert_eq!(
            toy::fmi2GetDerivatives(fmu.c, x.as_mut_ptr(), 1),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2GetRealOutputDerivatives(
                fmu.c,
                vr.as_ptr(),
                1,
                order.as_ptr(),
                x.as_mut_ptr()
            ),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2GetDirectionalDerivative(
                fmu.c,
                vr.as_ptr(),
                1,
                vr.as_ptr(),
                1,
                x.as_ptr(),
                x.as_mut_ptr()
            ),
            Fmi2Status::Error
        );
    }
    fmu.log.assert_error(&[
        "fmi2SetTime: the Model Exchange interface is not offered",
        "fmi2GetRealOutputDerivatives",
        "fmi2GetDirectionalDerivative",
    ]);
    assert_eq!(
        fmu.step(0.0, 0.1),
        Fmi2Status::Ok,
        "the instance is still usable"
    );
}

#[test]
fn panics_in_the_core_are_caught() {
    let fmu = Fmu::running(0.0);
    let before = fmu.get_state();
    assert_eq!(
        fmu.set(EXPLODE, 1.0),
        Fmi2Status::Ok,
        "tunable parameter during the simulation"
    );
    assert_eq!(fmu.step(0.0, 0.1), Fmi2Status::Error);
    fmu.log.assert_error(&[
        "fmi2DoStep: internal error (panic: explode = 1 set)",
        "error state",
    ]);
    assert_eq!(fmu.step(0.0, 0.1), Fmi2Status::Error);
    fmu.log.assert_error(&["not allowed in state error"]);
    assert_eq!(fmu.get(EXPLODE), 1.0, "getters work in the error state");
    assert_eq!(
        unsafe { toy::fmi2SetFMUstate(fmu.c, before) },
        Fmi2Status::Ok
    );
    assert_eq!(
        fmu.step(0.0, 0.1),
        Fmi2Status::Ok,
        "restored from the error state"
    );
    let mut before = before;
    unsafe { toy::fmi2FreeFMUstate(fmu.c, &mut before) };
}
