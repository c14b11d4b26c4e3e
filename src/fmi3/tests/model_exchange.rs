//! Model Exchange through the FMI 3.0 functions: the mode changes, the state vector, the
//! derivatives and the directional derivatives, and the checks of each call.

use super::{Cs, v3, vr};
use crate::fmi_common::model_api::FmuCore;
use crate::fmi3::types::*;
use crate::fmu::HaselCore;

/// An ME instance in Continuous-Time Mode, and its number of states.
fn continuous_time() -> (Cs, usize) {
    let me = Cs::model_exchange();
    me.init_me();
    let mut n = 0;
    unsafe {
        assert_eq!(
            v3::fmi3GetNumberOfContinuousStates(me.c, &mut n),
            Fmi3Status::Ok
        );
        assert_eq!(v3::fmi3EnterContinuousTimeMode(me.c), Fmi3Status::Ok);
    }
    (me, n)
}

impl Cs {
    /// Initialization of an ME instance, on to Event Mode and through one event iteration.
    fn init_me(&self) {
        let mut flags = [9u8; 5];
        let mut next = f64::NAN;
        let [a, b, c, d, e] = &mut flags;
        unsafe {
            assert_eq!(
                v3::fmi3EnterInitializationMode(self.c, 0, 0.0, 0.0, 0, 0.0),
                Fmi3Status::Ok
            );
            assert_eq!(v3::fmi3ExitInitializationMode(self.c), Fmi3Status::Ok);
            let status = v3::fmi3UpdateDiscreteStates(self.c, a, b, c, d, e, &mut next);
            assert_eq!((status, flags), (Fmi3Status::Ok, [0; 5]));
        }
    }

    fn states(&self, n: usize) -> Vec<f64> {
        let mut x = vec![0.0; n];
        let s = unsafe { v3::fmi3GetContinuousStates(self.c, x.as_mut_ptr(), n) };
        assert_eq!(s, Fmi3Status::Ok);
        x
    }

    fn derivatives(&self, n: usize) -> Vec<f64> {
        let mut dx = vec![0.0; n];
        let s = unsafe { v3::fmi3GetContinuousStateDerivatives(self.c, dx.as_mut_ptr(), n) };
        assert_eq!(s, Fmi3Status::Ok);
        dx
    }

    fn set_states(&self, x: &[f64]) -> Fmi3Status {
        unsafe { v3::fmi3SetContinuousStates(self.c, x.as_ptr(), x.len()) }
    }
}

#[test]
fn a_directional_derivative_is_the_slope_of_the_derivatives() {
    let (me, n) = continuous_time();
    assert_eq!(n, 99, "the paper's 15 states and the 84 of the effects");
    // d der(p_2) / d Q2_2 by the shell, against central differences of the derivatives
    let structure = HaselCore::model_structure();
    let (unknown, known) = (vr("der(p_2)"), vr("Q2_2"));
    let i = structure
        .derivatives
        .iter()
        .position(|d| d.derivative == unknown)
        .unwrap();
    let j = structure
        .derivatives
        .iter()
        .position(|d| d.state == known)
        .unwrap();
    // away from rest: a charge on the zipping capacitor, the film moving, 80 V on actuator 2
    let mut x = me.states(n);
    x[j] = 2e-9;
    let p = vr("p_2");
    x[structure
        .derivatives
        .iter()
        .position(|d| d.state == p)
        .unwrap()] = 1e-8;
    assert_eq!(me.set_states(&x), Fmi3Status::Ok);
    assert_eq!(me.set(&[vr("U2")], &[80.0]), Fmi3Status::Ok);
    let mut exact = [0.0];
    let s = unsafe {
        v3::fmi3GetDirectionalDerivative(
            me.c,
            [unknown].as_ptr(),
            1,
            [known].as_ptr(),
            1,
            [1.0].as_ptr(),
            1,
            exact.as_mut_ptr(),
            1,
        )
    };
    assert_eq!(s, Fmi3Status::Ok);
    let h = 1e-6 * x[j].abs();
    let at = |dxj: f64| {
        let mut y = x.clone();
        y[j] += dxj;
        assert_eq!(me.set_states(&y), Fmi3Status::Ok);
        me.derivatives(n)[i]
    };
    let central = (at(h) - at(-h)) / (2.0 * h);
    assert!(exact[0] != 0.0);
    assert!(
        (exact[0] - central).abs() <= 1e-6 * central.abs(),
        "{} against {central}",
        exact[0]
    );
}

#[test]
fn model_exchange_calls_are_checked() {
    let (me, n) = continuous_time();
    let x = me.states(n);
    // Co-Simulation calls on a Model Exchange instance
    let (mut a, mut b, mut c, mut t) = (0, 0, 0, 0.0);
    let s = unsafe { v3::fmi3DoStep(me.c, 0.0, 1e-3, 1, &mut a, &mut b, &mut c, &mut t) };
    assert_eq!(s, Fmi3Status::Error);
    me.log.assert_error(&["fmi3DoStep", "Continuous-Time Mode"]);
    // sizes, NaN, time
    assert_eq!(me.set_states(&x[..n - 1]), Fmi3Status::Error);
    me.log.assert_error(&[
        "fmi3SetContinuousStates",
        &format!("nContinuousStates = {}", n - 1),
    ]);
    let mut bad = x.clone();
    bad[0] = f64::NAN;
    assert_eq!(me.set_states(&bad), Fmi3Status::Error);
    me.log
        .assert_error(&["continuousStates[0] (theta_1) is NaN"]);
    assert_eq!(me.states(n), x, "a refused call changes nothing");
    assert_eq!(
        unsafe { v3::fmi3SetTime(me.c, f64::INFINITY) },
        Fmi3Status::Error
    );
    me.log
        .assert_error(&["fmi3SetTime", "time = inf is not finite"]);
    let mut z = [0.0];
    assert_eq!(
        unsafe { v3::fmi3GetEventIndicators(me.c, z.as_mut_ptr(), 1) },
        Fmi3Status::Error
    );
    me.log.assert_error(&["nEventIndicators = 1", "has none"]);
    assert_eq!(
        unsafe { v3::fmi3GetEventIndicators(me.c, z.as_mut_ptr(), 0) },
        Fmi3Status::Ok
    );
    let mut dx = vec![0.0; n];
    let s = unsafe { v3::fmi3GetContinuousStateDerivatives(me.c, std::ptr::null_mut(), n) };
    assert_eq!(s, Fmi3Status::Error);
    let s = unsafe { v3::fmi3GetContinuousStateDerivatives(me.c, dx.as_mut_ptr(), n + 1) };
    assert_eq!(s, Fmi3Status::Error);
    // parameters are fixed once initialized; inputs can be set in Continuous-Time Mode
    assert_eq!(me.set(&[vr("Kb_1")], &[0.4]), Fmi3Status::Error);
    me.log
        .assert_error(&["Kb_1", "cannot be set in state Continuous-Time Mode"]);
    assert_eq!(me.set(&[vr("U1")], &[10.0]), Fmi3Status::Ok);
    // the integrator's step, events, the state machine
    let (mut enter, mut terminate) = (9, 9);
    let s = unsafe { v3::fmi3CompletedIntegratorStep(me.c, 1, &mut enter, &mut terminate) };
    assert_eq!((s, enter, terminate), (Fmi3Status::Ok, 0, 0));
    assert_eq!(unsafe { v3::fmi3EnterStepMode(me.c) }, Fmi3Status::Error);
    me.log
        .assert_error(&["fmi3EnterStepMode", "created for Model Exchange"]);
    unsafe {
        assert_eq!(v3::fmi3EnterEventMode(me.c), Fmi3Status::Ok);
        assert_eq!(
            v3::fmi3CompletedIntegratorStep(me.c, 1, &mut enter, &mut terminate),
            Fmi3Status::Error
        );
        assert_eq!(v3::fmi3EnterContinuousTimeMode(me.c), Fmi3Status::Ok);
        assert_eq!(v3::fmi3Terminate(me.c), Fmi3Status::Ok);
    }
    assert_eq!(me.set_states(&x), Fmi3Status::Error);
    me.log
        .assert_error(&["fmi3SetContinuousStates", "not allowed in state Terminated"]);
}

#[test]
fn a_model_exchange_state_restores_its_states() {
    let (me, n) = continuous_time();
    let mut x = me.states(n);
    let mut state: fmi3FMUState = std::ptr::null_mut();
    unsafe { assert_eq!(v3::fmi3GetFMUState(me.c, &mut state), Fmi3Status::Ok) };
    let saved = x.clone();
    x[0] += 1e-4;
    assert_eq!(me.set_states(&x), Fmi3Status::Ok);
    unsafe { assert_eq!(v3::fmi3SetFMUState(me.c, state), Fmi3Status::Ok) };
    assert_eq!(me.states(n), saved);
    // a Co-Simulation state is refused
    let cs = Cs::new(false);
    let s = unsafe { v3::fmi3SetFMUState(cs.c, state) };
    assert_eq!(s, Fmi3Status::Error);
    cs.log
        .assert_error(&["the state is of a Model Exchange instance, this one is Co-Simulation"]);
    unsafe { assert_eq!(v3::fmi3FreeFMUState(me.c, &mut state), Fmi3Status::Ok) };
}
