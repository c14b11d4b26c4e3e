//! `amplifier_lag` (src/model/effects/effects.md, "amplifier_lag"): the finite bandwidth of
//! the high-voltage amplifier, first-order stages in cascade between the command and the port.

use super::terms::{At, Law, Port, States};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, log_between};
use crate::model::Params;
use crate::model::actuator::{Actuator, StateInfo};
use crate::model::params::common_rows;
use crate::model::shell::DomainError;

/// Bandwidth of the amplifier: one first-order stage, or two in cascade.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct AmplifierLag {
    /// τ_a [s]; 0 is an ideal amplifier.
    pub tau_a: f64,
    /// τ_a2 [s] of a second stage after the first; 0 (the default) is none.
    pub tau_a2: f64,
}

const FORMS: [Form; 2] = [
    Form::new(Effect::AmplifierLag, "first_order", &["tau_a"], &[]),
    Form {
        magnitudes: &["tau_a", "tau_a2"],
        ..Form::new(
            Effect::AmplifierLag,
            "second_order",
            &["tau_a", "tau_a2"],
            &[],
        )
    },
];

pub const FAMILY: Family = Family {
    effect: Effect::AmplifierLag,
    name: "amplifier_lag",
    mechanism: "bandwidth of the high-voltage amplifier",
    form: "tau_a dU_eff/dt = U - U_eff",
    forms: &FORMS,
    rows: &common_rows! {
        "tau_a", "s", NonNegative, "amplifier_lag: time constant tau_a of the amplifier (0: off)", effects.amplifier_lag.tau_a;
        "tau_a2", "s", NonNegative, "amplifier_lag: time constant tau_a2 of a second stage (0: none)", effects.amplifier_lag.tau_a2;
    },
    choices: &[],
    state: Some(StateInfo {
        name: "U_amp",
        unit: "V",
        description: "amplifier output voltage",
    }),
    table_stages: 2,
    is_active: |p| p.amplifier_lag.tau_a > 0.0,
    on: |f| {
        f.amplifier_lag.tau_a = 0.02;
        f.amplifier_lag.tau_a2 = 0.005;
    },
    structures: &[],
    delays_the_command: true,
    magnitude: Magnitude::Positive,
    probes,
    exposing: Exposing {
        text: "a multisine up to 100 rad/s: a lag attenuates the fast tones",
        drive: Drive::Multisine(&[5.0, 15.0, 40.0, 100.0]),
        t_end: 6.0,
    },
    hidden: unequal_stages,
    variants: &[("amplifier_lag_second_order", equal_stages)],
    law: None,
};

/// One stage, and two of half the time, at a fast and a slow time (src/diagnose/diagnose.md,
/// "Screening").
fn probes(_: &Params, _: f64) -> Vec<Probe> {
    let mut out = Vec::new();
    for form in &FORMS {
        for tau in [0.01, 0.04] {
            out.push(Probe::one(
                form,
                if form.name == "first_order" {
                    vec![("tau_a", tau)]
                } else {
                    vec![("tau_a", 0.5 * tau), ("tau_a2", 0.5 * tau)]
                },
            ));
        }
    }
    out
}

/// Two stages of 80 % and 20 % of the lag.
fn unequal_stages(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let tau = log_between(between, 0.02, 0.06);
    let a = &mut params.effects.amplifier_lag;
    a.tau_a = 0.8 * tau;
    a.tau_a2 = 0.2 * tau;
    Planted::text(format!(
        "two-stage amplifier, {:.1} ms and {:.1} ms",
        800.0 * tau,
        200.0 * tau
    ))
}

/// Two equal stages.
fn equal_stages(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let tau = log_between(between, 0.01, 0.03);
    let a = &mut params.effects.amplifier_lag;
    a.tau_a = tau;
    a.tau_a2 = tau;
    Planted::text(format!(
        "a second-order amplifier, two equal stages of {:.1} ms",
        1000.0 * tau
    ))
}

/// The stages' terms: each follows the one before it, the first the command (effects.md,
/// "amplifier_lag").
#[derive(Clone, Debug)]
pub struct Terms {
    /// (index, time constant) per stage.
    stages: Vec<(usize, f64)>,
}

impl Law for Terms {
    type Params = AmplifierLag;

    fn new(al: &AmplifierLag, states: &mut States) -> Terms {
        let mut stages = Vec::new();
        if al.tau_a > 0.0 {
            stages.push((states.push(Effect::AmplifierLag, 0), al.tau_a));
            if al.tau_a2 > 0.0 {
                stages.push((states.push(Effect::AmplifierLag, 1), al.tau_a2));
            }
        }
        Terms { stages }
    }

    /// The port reads the last stage.
    #[inline]
    fn port(&self, xi: &[f64], port: &mut Port) {
        if let Some(&(k, _)) = self.stages.last() {
            port.u_eff = xi[k];
            port.column = Some(k);
        }
    }

    #[inline]
    fn add_rhs(&self, at: &At, dx: &mut [f64]) -> Result<(), DomainError> {
        let xi = at.xi();
        let mut prev = at.u;
        for &(k, t) in &self.stages {
            dx[k] = (prev - xi[k]) / t;
            prev = xi[k];
        }
        Ok(())
    }

    #[inline]
    fn add_jacobian(
        &self,
        at: &At,
        offset: [usize; 3],
        add: &mut impl FnMut(usize, usize, f64),
    ) -> Result<(), DomainError> {
        let o = offset[at.i];
        let mut prev = None;
        for &(k, t) in &self.stages {
            add(o + k, o + k, -1.0 / t);
            if let Some(j) = prev {
                add(o + k, o + j, 1.0 / t);
            }
            prev = Some(k);
        }
        Ok(())
    }

    /// The command drives the first stage: τ U̇_amp = U − U_amp.
    #[inline]
    fn add_input_jacobian(&self, _: &At, add: &mut impl FnMut(usize, f64)) {
        if let Some(&(k, t)) = self.stages.first() {
            add(k, 1.0 / t);
        }
    }

    fn rest(&self, _: f64, out: &mut Vec<f64>) {
        out.extend(self.stages.iter().map(|_| 0.0));
    }

    fn scales(&self, _: &Actuator, _: f64, out: &mut Vec<f64>) {
        out.extend(self.stages.iter().map(|_| 100.0));
    }
}
