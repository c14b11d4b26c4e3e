//! Model Exchange through the C functions: the state machine of section 3.2.3 on every call,
//! argument checks, the state vector, directional derivatives (both interfaces) and FMU
//! states of a Model Exchange instance.

use std::ptr::{null, null_mut};

use super::*;

/// A Model Exchange instance of the toy, in Initialization Mode at t = 0.
fn me_in_init() -> Fmu {
    let fmu = Fmu::of_type(FMI2_MODEL_EXCHANGE, &toy_guid(), None);
    assert_eq!(fmu.setup(0.0, None), Fmi2Status::Ok);
    assert_eq!(
        unsafe { toy::fmi2EnterInitializationMode(fmu.c) },
        Fmi2Status::Ok
    );
    fmu
}

/// A Model Exchange instance in Continuous-Time Mode, y(0) = `y0`.
fn me_continuous(y0: f64) -> Fmu {
    let fmu = me_in_init();
    assert_eq!(fmu.set(Y_START, y0), Fmi2Status::Ok);
    unsafe {
        assert_eq!(toy::fmi2ExitInitializationMode(fmu.c), Fmi2Status::Ok);
        let mut info = event_info();
        assert_eq!(toy::fmi2NewDiscreteStates(fmu.c, &mut info), Fmi2Status::Ok);
        assert_eq!(toy::fmi2EnterContinuousTimeMode(fmu.c), Fmi2Status::Ok);
    }
    fmu
}

/// An event info with every flag set, to see them cleared.
fn event_info() -> fmi2EventInfo {
    fmi2EventInfo {
        new_discrete_states_needed: FMI2_TRUE,
        terminate_simulation: FMI2_TRUE,
        nominals_of_continuous_states_changed: FMI2_TRUE,
        values_of_continuous_states_changed: FMI2_TRUE,
        next_event_time_defined: FMI2_TRUE,
        next_event_time: 1.0,
    }
}

fn derivative(fmu: &Fmu) -> (Fmi2Status, f64) {
    let mut dx = [f64::NAN];
    let status = unsafe { toy::fmi2GetDerivatives(fmu.c, dx.as_mut_ptr(), 1) };
    (status, dx[0])
}

fn directional(
    fmu: &Fmu,
    unknowns: &[u32],
    knowns: &[u32],
    seed: &[f64],
) -> (Fmi2Status, Vec<f64>) {
    let mut out = vec![f64::NAN; unknowns.len()];
    let status = unsafe {
        toy::fmi2GetDirectionalDerivative(
            fmu.c,
            unknowns.as_ptr(),
            unknowns.len(),
            knowns.as_ptr(),
            knowns.len(),
            seed.as_ptr(),
            out.as_mut_ptr(),
        )
    };
    (status, out)
}

#[test]
fn an_integrator_drives_the_model() {
    let fmu = me_in_init();
    let mut x = [f64::NAN];
    unsafe {
        assert_eq!(fmu.set(Y_START, 0.5), Fmi2Status::Ok);
        assert_eq!(
            toy::fmi2GetContinuousStates(fmu.c, x.as_mut_ptr(), 1),
            Fmi2Status::Ok
        );
        assert_eq!(x[0], 0.5, "the initial state in Initialization Mode");
        assert_eq!(toy::fmi2ExitInitializationMode(fmu.c), Fmi2Status::Ok);
        let mut info = event_info();
        assert_eq!(toy::fmi2NewDiscreteStates(fmu.c, &mut info), Fmi2Status::Ok);
        assert_eq!(
            [
                info.new_discrete_states_needed,
                info.terminate_simulation,
                info.nominals_of_continuous_states_changed,
                info.values_of_continuous_states_changed,
                info.next_event_time_defined
            ],
            [FMI2_FALSE; 5]
        );
        assert_eq!(toy::fmi2EnterContinuousTimeMode(fmu.c), Fmi2Status::Ok);
        let mut nominal = [0.0];
        assert_eq!(
            toy::fmi2GetNominalsOfContinuousStates(fmu.c, nominal.as_mut_ptr(), 1),
            Fmi2Status::Ok
        );
        assert_eq!(nominal, [1.0]);
        assert_eq!(
            toy::fmi2GetEventIndicators(fmu.c, null_mut(), 0),
            Fmi2Status::Ok
        );
        // explicit Euler over 1 s in 1000 steps with u = 1: y → 1 - 0.5 e^-1
        assert_eq!(fmu.set(U, 1.0), Fmi2Status::Ok);
        let h = 1e-3;
        for k in 0..1000 {
            assert_eq!(toy::fmi2SetTime(fmu.c, k as f64 * h), Fmi2Status::Ok);
            let (status, dy) = derivative(&fmu);
            assert_eq!(status, Fmi2Status::Ok);
            assert_eq!(dy, fmu.get(DER_Y), "der(y) is a variable");
            x[0] += h * dy;
            assert_eq!(
                toy::fmi2SetContinuousStates(fmu.c, x.as_ptr(), 1),
                Fmi2Status::Ok
            );
            let (mut event, mut terminate) = (FMI2_TRUE, FMI2_TRUE);
            assert_eq!(
                toy::fmi2CompletedIntegratorStep(fmu.c, FMI2_TRUE, &mut event, &mut terminate),
                Fmi2Status::Ok
            );
            assert_eq!((event, terminate), (FMI2_FALSE, FMI2_FALSE));
        }
        assert!((fmu.get(Y) - (1.0 - 0.5 * (-1.0f64).exp())).abs() < 1e-3);
        assert_eq!(toy::fmi2EnterEventMode(fmu.c), Fmi2Status::Ok);
        assert_eq!(
            fmu.set(MAX_STEP, 2.0),
            Fmi2Status::Ok,
            "tunable in Event Mode"
        );
        assert_eq!(toy::fmi2EnterContinuousTimeMode(fmu.c), Fmi2Status::Ok);
        assert_eq!(toy::fmi2Terminate(fmu.c), Fmi2Status::Ok);
        assert_eq!(
            toy::fmi2GetDerivatives(fmu.c, x.as_mut_ptr(), 1),
            Fmi2Status::Ok
        );
    }
    assert!(fmu.log.records().is_empty(), "{:?}", fmu.log.records());
}

#[test]
fn the_state_machine_is_checked_on_every_call() {
    let fmu = Fmu::of_type(FMI2_MODEL_EXCHANGE, &toy_guid(), None);
    let mut x = [0.0];
    let mut info = event_info();
    let (mut event, mut terminate) = (FMI2_FALSE, FMI2_FALSE);
    unsafe {
        // instantiated: only the nominals
        assert_eq!(derivative(&fmu).0, Fmi2Status::Error);
        assert_eq!(
            toy::fmi2GetContinuousStates(fmu.c, x.as_mut_ptr(), 1),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2GetNominalsOfContinuousStates(fmu.c, x.as_mut_ptr(), 1),
            Fmi2Status::Ok
        );
        assert_eq!(toy::fmi2SetTime(fmu.c, 0.0), Fmi2Status::Error);
        assert_eq!(toy::fmi2EnterEventMode(fmu.c), Fmi2Status::Error);
    }
    fmu.log.assert_error(&[
        "fmi2GetDerivatives: not allowed in state instantiated (allowed in: terminated, error, eventMode, continuousTimeMode)",
        "fmi2SetTime: not allowed in state instantiated",
        "fmi2EnterEventMode: not allowed in state instantiated",
    ]);
    let fmu = me_in_init();
    unsafe {
        assert_eq!(derivative(&fmu).0, Fmi2Status::Error);
        assert_eq!(
            toy::fmi2NewDiscreteStates(fmu.c, &mut info),
            Fmi2Status::Error
        );
        assert_eq!(toy::fmi2ExitInitializationMode(fmu.c), Fmi2Status::Ok);
        // Event Mode
        assert_eq!(
            toy::fmi2SetContinuousStates(fmu.c, x.as_ptr(), 1),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2CompletedIntegratorStep(fmu.c, FMI2_TRUE, &mut event, &mut terminate),
            Fmi2Status::Error
        );
        assert_eq!(toy::fmi2SetTime(fmu.c, 0.5), Fmi2Status::Ok);
        assert_eq!(fmu.step(0.0, 0.1), Fmi2Status::Error);
        assert_eq!(toy::fmi2EnterContinuousTimeMode(fmu.c), Fmi2Status::Ok);
        // Continuous-Time Mode
        assert_eq!(
            toy::fmi2NewDiscreteStates(fmu.c, &mut info),
            Fmi2Status::Error
        );
        assert_eq!(toy::fmi2EnterContinuousTimeMode(fmu.c), Fmi2Status::Error);
        assert_eq!(fmu.set(MAX_STEP, 2.0), Fmi2Status::Error);
        assert_eq!(fmu.set(U, 2.0), Fmi2Status::Ok);
        assert_eq!(toy::fmi2Terminate(fmu.c), Fmi2Status::Ok);
        let mut t = 0.0;
        assert_eq!(
            toy::fmi2GetRealStatus(fmu.c, FMI2_LAST_SUCCESSFUL_TIME, &mut t),
            Fmi2Status::Error
        );
        assert_eq!(toy::fmi2SetTime(fmu.c, 1.0), Fmi2Status::Error);
    }
    fmu.log.assert_error(&[
        "fmi2NewDiscreteStates: not allowed in state initializationMode (allowed in: eventMode)",
        "fmi2SetContinuousStates: not allowed in state eventMode (allowed in: continuousTimeMode)",
        "fmi2CompletedIntegratorStep: not allowed in state eventMode",
        "fmi2DoStep: is a Co-Simulation function; this instance was instantiated for Model Exchange",
        "fmi2NewDiscreteStates: not allowed in state continuousTimeMode",
        "max_step (value reference 2, causality parameter, variability tunable, initial exact) cannot be set in state continuousTimeMode",
        "fmi2GetRealStatus: is a Co-Simulation function",
        "fmi2SetTime: not allowed in state terminated",
    ]);
}

#[test]
fn model_exchange_functions_refuse_a_co_simulation_instance() {
    let fmu = Fmu::running(0.0);
    let mut x = [0.0];
    unsafe {
        assert_eq!(toy::fmi2SetTime(fmu.c, 1.0), Fmi2Status::Error);
        assert_eq!(derivative(&fmu).0, Fmi2Status::Error);
        assert_eq!(
            toy::fmi2GetContinuousStates(fmu.c, x.as_mut_ptr(), 1),
            Fmi2Status::Error
        );
        assert_eq!(toy::fmi2EnterEventMode(fmu.c), Fmi2Status::Error);
    }
    fmu.log.assert_error(&[
        "fmi2SetTime: is a Model Exchange function; this instance was instantiated for Co-Simulation",
        "fmi2GetDerivatives: is a Model Exchange function",
        "fmi2GetContinuousStates: is a Model Exchange function",
    ]);
    assert_eq!(fmu.step(0.0, 0.1), Fmi2Status::Ok, "still usable");
}

#[test]
fn arguments_are_checked() {
    let fmu = me_continuous(0.0);
    let mut x = [0.0; 2];
    unsafe {
        assert_eq!(
            toy::fmi2SetContinuousStates(fmu.c, x.as_ptr(), 2),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2GetContinuousStates(fmu.c, x.as_mut_ptr(), 0),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2GetDerivatives(fmu.c, null_mut(), 1),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2GetNominalsOfContinuousStates(fmu.c, null_mut(), 1),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2SetContinuousStates(fmu.c, null(), 1),
            Fmi2Status::Error
        );
        assert_eq!(
            toy::fmi2GetEventIndicators(fmu.c, x.as_mut_ptr(), 1),
            Fmi2Status::Error
        );
        assert_eq!(toy::fmi2SetTime(fmu.c, f64::NAN), Fmi2Status::Error);
        let mut event = FMI2_FALSE;
        assert_eq!(
            toy::fmi2CompletedIntegratorStep(fmu.c, FMI2_TRUE, &mut event, null_mut()),
            Fmi2Status::Error
        );
        x[0] = f64::INFINITY;
        assert_eq!(
            toy::fmi2SetContinuousStates(fmu.c, x.as_ptr(), 1),
            Fmi2Status::Error
        );
        assert_eq!(toy::fmi2EnterEventMode(fmu.c), Fmi2Status::Ok);
        assert_eq!(
            toy::fmi2NewDiscreteStates(fmu.c, null_mut()),
            Fmi2Status::Error
        );
    }
    fmu.log.assert_error(&[
        "fmi2SetContinuousStates: nx = 2, but the FMU has 1 continuous states",
        "fmi2GetContinuousStates: nx = 0",
        "fmi2GetDerivatives: argument derivatives is NULL",
        "fmi2GetNominalsOfContinuousStates: argument x_nominal is NULL",
        "fmi2SetContinuousStates: argument x is NULL",
        "fmi2GetEventIndicators: ni = 1, but the FMU has no event indicators",
        "fmi2SetTime: time = NaN is not finite",
        "fmi2CompletedIntegratorStep: argument terminateSimulation is NULL",
        "fmi2SetContinuousStates: y = inf must be finite",
        "fmi2NewDiscreteStates: argument fmi2eventInfo is NULL",
    ]);
    assert_eq!(fmu.get(Y), 0.0, "rejected states change nothing");
}

#[test]
fn directional_derivatives_in_both_interfaces() {
    let tau = 1.0; // the toy's start value
    let me = me_continuous(0.25);
    let cs = Fmu::running(0.0);
    for fmu in [&me, &cs] {
        let (status, d) = directional(fmu, &[DER_Y, Y], &[Y, U], &[2.0, 3.0]);
        assert_eq!(status, Fmi2Status::Ok, "{:?}", fmu.log.records());
        assert_eq!(d, [(-2.0 + 3.0) / tau, 2.0]);
        let (status, d) = directional(fmu, &[], &[Y], &[1.0]);
        assert_eq!((status, d), (Fmi2Status::Ok, vec![]));
        assert_eq!(directional(fmu, &[TAU], &[Y], &[1.0]).0, Fmi2Status::Error);
        assert_eq!(
            directional(fmu, &[DER_Y], &[TAU], &[1.0]).0,
            Fmi2Status::Error
        );
        assert_eq!(directional(fmu, &[99], &[Y], &[1.0]).0, Fmi2Status::Error);
        assert_eq!(
            directional(fmu, &[DER_Y], &[Y], &[f64::NAN]).0,
            Fmi2Status::Error
        );
        let status = unsafe {
            toy::fmi2GetDirectionalDerivative(
                fmu.c,
                [DER_Y].as_ptr(),
                1,
                [Y].as_ptr(),
                1,
                null(),
                null_mut(),
            )
        };
        assert_eq!(status, Fmi2Status::Error);
        fmu.log.assert_error(&[
            "unknown tau (value reference 0) is neither a state derivative nor an output",
            "known tau (value reference 0) is not a continuous state or an input",
            "unknown value reference 99",
            "dvKnown for y is NaN",
            "argument dvKnown is NULL",
        ]);
    }
    // Initialization Mode: the states are calculated, the inputs are the knowns
    let init = me_in_init();
    assert_eq!(
        directional(&init, &[DER_Y], &[U], &[1.0]),
        (Fmi2Status::Ok, vec![1.0 / tau])
    );
    assert_eq!(
        directional(&init, &[DER_Y], &[Y], &[1.0]).0,
        Fmi2Status::Error
    );
    init.log
        .assert_error(&["is not an input (the states are calculated in Initialization Mode)"]);
    let fresh = Fmu::of_type(FMI2_MODEL_EXCHANGE, &toy_guid(), None);
    assert_eq!(
        directional(&fresh, &[DER_Y], &[U], &[1.0]).0,
        Fmi2Status::Error
    );
    fresh
        .log
        .assert_error(&["fmi2GetDirectionalDerivative: not allowed in state instantiated"]);
}

#[test]
fn fmu_states_of_model_exchange() {
    let fmu = me_continuous(0.25);
    let saved = fmu.get_state();
    let x = [0.75];
    unsafe {
        assert_eq!(
            toy::fmi2SetContinuousStates(fmu.c, x.as_ptr(), 1),
            Fmi2Status::Ok
        );
        assert_eq!(toy::fmi2EnterEventMode(fmu.c), Fmi2Status::Ok);
        assert_eq!(toy::fmi2SetFMUstate(fmu.c, saved), Fmi2Status::Ok);
    }
    assert_eq!(fmu.get(Y), 0.25);
    // back in Continuous-Time Mode: states can be set again
    assert_eq!(
        unsafe { toy::fmi2SetContinuousStates(fmu.c, x.as_ptr(), 1) },
        Fmi2Status::Ok
    );
    // through bytes, into another Model Exchange instance
    let mut size = 0;
    let other = me_in_init();
    unsafe {
        assert_eq!(
            toy::fmi2SerializedFMUstateSize(fmu.c, saved, &mut size),
            Fmi2Status::Ok
        );
        let mut bytes = vec![0u8; size];
        assert_eq!(
            toy::fmi2SerializeFMUstate(fmu.c, saved, bytes.as_mut_ptr().cast(), size),
            Fmi2Status::Ok
        );
        let mut restored = null_mut();
        assert_eq!(
            toy::fmi2DeSerializeFMUstate(other.c, bytes.as_ptr().cast(), size, &mut restored),
            Fmi2Status::Ok
        );
        assert_eq!(toy::fmi2SetFMUstate(other.c, restored), Fmi2Status::Ok);
        assert_eq!(other.get(Y), 0.25);
        assert_eq!(
            toy::fmi2EnterEventMode(other.c),
            Fmi2Status::Ok,
            "in Continuous-Time Mode"
        );
        // a Co-Simulation instance takes neither the state nor its bytes
        let cs = Fmu::running(0.0);
        assert_eq!(toy::fmi2SetFMUstate(cs.c, saved), Fmi2Status::Error);
        let mut into_cs = null_mut();
        assert_eq!(
            toy::fmi2DeSerializeFMUstate(cs.c, bytes.as_ptr().cast(), size, &mut into_cs),
            Fmi2Status::Error
        );
        cs.log.assert_error(&[
            "the state is of a Model Exchange instance, this one is Co-Simulation",
            "ModelExchange",
        ]);
        for mut s in [saved, restored] {
            assert_eq!(toy::fmi2FreeFMUstate(fmu.c, &mut s), Fmi2Status::Ok);
        }
    }
}
