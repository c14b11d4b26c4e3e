//! `amplifier_lag` (book/src/effects.md, "amplifier_lag"): the high-voltage
//! amplifier's dynamics between the command and the port, a rate law dU_amp/dt = r(U − U_amp)
//! with r monotone (linear: a first-order lag; saturating: a slew-rate limit), and a second
//! linear stage in cascade.

use super::family::{FittedLaw, TextbookForm, golden, sampled};
use super::saturation::rapp;
use super::terms::{At, Law, Port, States};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, log_between};
use crate::model::Params;
use crate::model::actuator::{Actuator, StateInfo};
use crate::model::params::common_rows;
use crate::model::shell::DomainError;

/// The amplifier's dynamics: a first stage of rate law r, and a second linear stage after it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmplifierLag {
    /// τ_a \[s\]: the first stage's time constant for small errors; 0 is an ideal amplifier.
    pub tau_a: f64,
    /// τ_a2 \[s\] of a second stage after the first; 0 (the default) is none.
    pub tau_a2: f64,
    /// The first stage's slew rate S [V/s]: r(e) = S φ_p(e / (S τ_a)); 0 is no limit, linear.
    pub slew: f64,
    /// Sharpness p > 0 of the slew's transition φ_p(x) = tanh(|x|^p)^(1/p) sgn x: 1 is the
    /// tanh, p → ∞ the hard rate limit, p < 1 softer than the tanh.
    pub sharpness: f64,
    /// For synthetic data only (no row of the table): when > 0, the slew's transition is the
    /// Rapp curve of this exponent q, r(e) = S x (1 + |x|^q)^(−1/q) with x = e / (S τ_a),
    /// instead of φ_p.
    pub rapp_rate: f64,
}

impl Default for AmplifierLag {
    fn default() -> Self {
        AmplifierLag {
            tau_a: 0.0,
            tau_a2: 0.0,
            slew: 0.0,
            sharpness: 1.0,
            rapp_rate: 0.0,
        }
    }
}

/// The narrowest transition from linear to slewing, S τ_a [V]: below it the stage is a relay
/// whose switching no step size resolves (a fit moving τ_a toward 0 at a finite S met one at
/// S τ_a ~ 1e-8 V, where the integration stalled); 1 mV is far below any error the outputs
/// resolve.
const MIN_TRANSITION: f64 = 1e-3;

impl AmplifierLag {
    /// The first stage's rate dU_amp/dt for the error e = U − U_amp, and its slope dr/de
    /// (effects.md, "amplifier_lag"): monotone, 1/τ_a at small errors, tending to ±S.
    pub fn rate(&self, e: f64) -> (f64, f64) {
        let tau = self.tau_a;
        if self.slew == 0.0 {
            return (e / tau, 1.0 / tau);
        }
        let width = (self.slew * tau).max(MIN_TRANSITION);
        let x = e / width;
        let (phi, slope) = if self.rapp_rate > 0.0 {
            rapp(x.abs(), self.rapp_rate)
        } else {
            transition(x.abs(), self.sharpness)
        };
        (self.slew * phi.copysign(x), self.slew * slope / width)
    }
}

/// The slew's transition φ_p(x) = tanh(x^p)^(1/p) of an error x ≥ 0 relative to S τ_a, and its
/// slope (effects.md, "amplifier_lag"): increasing, x − x^(2p+1)/(3p) + … at small x (slope 1),
/// 1 − (2/p) e^(−2 x^p) + … at large x. Below y = x^p = 1 it is written x (tanh y / y)^(1/p),
/// which keeps the small errors' digits for any p; sech² y in e^(−2y), which cannot overflow.
fn transition(x: f64, p: f64) -> (f64, f64) {
    let y = x.powf(p);
    if y.is_infinite() {
        return (1.0, 0.0);
    }
    let q = (-2.0 * y).exp();
    let sech2 = 4.0 * q / ((1.0 + q) * (1.0 + q));
    if y <= 1.0 {
        let ratio = if y == 0.0 { 1.0 } else { y.tanh() / y };
        (
            x * ratio.powf(p.recip()),
            ratio.powf(p.recip() - 1.0) * sech2,
        )
    } else {
        let t = y.tanh();
        (t.powf(p.recip()), t.powf(p.recip() - 1.0) * sech2 * y / x)
    }
}

const FORMS: [Form; 3] = [
    Form::new(Effect::AmplifierLag, "first_order", &["tau_a"], &[]),
    Form {
        magnitudes: &["tau_a", "tau_a2"],
        exchangeable: Some(("tau_a", "tau_a2")),
        refines: Some("first_order"),
        ..Form::new(
            Effect::AmplifierLag,
            "second_order",
            &["tau_a", "tau_a2"],
            &[],
        )
    },
    // a slewing amplifier may hold its small-signal time τ_a undetermined: S is a magnitude too
    Form {
        magnitudes: &["tau_a", "slew"],
        ..Form::new(
            Effect::AmplifierLag,
            "slew",
            &["tau_a", "slew", "slew_sharpness"],
            &[],
        )
    },
];

pub const FAMILY: Family = Family {
    effect: Effect::AmplifierLag,
    name: "amplifier_lag",
    mechanism: "the high-voltage amplifier's bandwidth and slew rate",
    form: "tau_a dU_eff/dt = U - U_eff",
    forms: &FORMS,
    rows: &common_rows! {
        "tau_a", "s", NonNegative, "amplifier_lag: time constant tau_a of the amplifier (0: off)", effects.amplifier_lag.tau_a;
        "tau_a2", "s", NonNegative, "amplifier_lag: time constant tau_a2 of a second stage (0: none)", effects.amplifier_lag.tau_a2;
        "slew", "V/s", Limit, "amplifier_lag: slew rate S of the first stage, dU_amp/dt = S phi((U - U_amp) / (S tau_a)) (0: no limit, linear)", effects.amplifier_lag.slew;
        "slew_sharpness", "1", Positive, "amplifier_lag: sharpness p of the slew's transition, phi(x) = tanh(|x|^p)^(1/p) sgn(x) (1: tanh; large: the hard rate limit)", effects.amplifier_lag.sharpness;
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
        f.amplifier_lag.slew = 1000.0;
        f.amplifier_lag.sharpness = 2.0;
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
    variants: &[
        ("amplifier_lag_second_order", equal_stages),
        ("amplifier_lag_slew", slewing),
    ],
    law: |p, u_peak| Some(law(p, u_peak)),
};

/// One stage, and two of half the time, at a fast and a slow time; a slewing stage at a fast
/// and a slow time, slewing at 4, 6 or 8 times the peak command per second (the paper's 60 V
/// sines change by up to 11 times it), kept as they are: a slew's change does not scale
/// (book/src/diagnose.md, "Screening"). A lag and a slew both delay the response: the
/// screening's linear projection ranks them alike, and the refits of every form it cannot tell
/// apart decide.
fn probes(_: &Params, u_peak: f64) -> Vec<Probe> {
    let mut out = Vec::new();
    for tau in [0.01, 0.04] {
        out.push(Probe::one(&FORMS[0], vec![("tau_a", tau)]));
        let half = 0.5 * tau;
        out.push(Probe::one(
            &FORMS[1],
            vec![("tau_a", half), ("tau_a2", half)],
        ));
    }
    for tau in [0.005, 0.02] {
        for s in [4.0, 6.0, 8.0] {
            out.push(Probe::fixed(
                &FORMS[2],
                vec![("tau_a", tau), ("slew", s * u_peak)],
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

/// A single stage slewing at S in [250, 450] V/s (the paper's 60 V sines need up to 660 V/s),
/// with a small-signal time in [3, 10] ms (log), its transition from linear to slewing a Rapp
/// curve of exponent q in [1.5, 6] (log): a shape no sharpness of the fitted form's transition
/// contains (it approaches the slew as a power of the error, φ_p exponentially).
fn slewing(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let a = &mut params.effects.amplifier_lag;
    a.tau_a = log_between(between, 0.003, 0.01);
    a.slew = between(250.0, 450.0);
    a.rapp_rate = log_between(between, 1.5, 6.0);
    Planted::text(format!(
        "an amplifier slewing at {:.0} V/s, {:.1} ms for small errors, its transition a Rapp curve of exponent {:.2}",
        a.slew,
        1000.0 * a.tau_a,
        a.rapp_rate
    ))
}

/// The first stage's fitted rate law over errors up to the peak command, beside the textbook
/// forms fitted to it (book/src/diagnose.md, "The fitted law"): the linear lag e/τ, and at the
/// law's small-signal time τ_a the tanh slew S tanh(e/(S τ_a)) and the hard rate limit
/// clamp(e/τ_a, ±S).
fn law(params: &Params, u_peak: f64) -> FittedLaw {
    let a = params.effects.amplifier_lag;
    let curve = sampled(-u_peak, u_peak, |e| a.rate(e).0);
    let sse =
        |g: &dyn Fn(f64) -> f64| -> f64 { curve.iter().map(|&(e, r)| (g(e) - r).powi(2)).sum() };
    let tau = golden(1e-5, 10.0, |t| sse(&|e| e / t));
    let tau_a = a.tau_a;
    let limit = move |s: f64, e: f64| (e / tau_a).clamp(-s, s);
    let tanh = move |s: f64, e: f64| s * (e / (s * tau_a)).tanh();
    let s_limit = golden(1.0, 1e7, |s| sse(&|e| limit(s, e)));
    let s_tanh = golden(1.0, 1e7, |s| sse(&|e| tanh(s, e)));
    let text = format!(
        "dU_amp/dt from the error U - U_amp: tau_a {:.2} ms, slew rate {}{}",
        1000.0 * a.tau_a,
        if a.slew > 0.0 {
            format!("{:.0} V/s, sharpness {:.2}", a.slew, a.sharpness)
        } else {
            "unlimited".into()
        },
        if a.tau_a2 > 0.0 {
            format!(", then a second stage of {:.2} ms", 1000.0 * a.tau_a2)
        } else {
            String::new()
        }
    );
    let linear: TextbookForm = (
        "linear lag",
        format!("tau {:.2} ms", 1000.0 * tau),
        Box::new(move |e| e / tau),
    );
    let small_signal = format!("tau {:.2} ms for small errors", 1000.0 * tau_a);
    // a limit above the fastest rate the law reaches is the linear lag itself
    let slewing = (s_limit * tau_a < u_peak).then(|| -> [TextbookForm; 2] {
        [
            (
                "tanh slew",
                format!("{s_tanh:.0} V/s, {small_signal}"),
                Box::new(move |e| tanh(s_tanh, e)),
            ),
            (
                "hard slew limit",
                format!("{s_limit:.0} V/s, {small_signal}"),
                Box::new(move |e| limit(s_limit, e)),
            ),
        ]
    });
    FittedLaw::of_curve(
        text,
        ["error U - U_amp [V]", "dU_amp/dt [V/s]"],
        curve,
        std::iter::once(linear)
            .chain(slewing.into_iter().flatten())
            .collect(),
    )
}

/// The stages' terms: each follows the one before it, the first the command through its rate
/// law, the others linearly (effects.md, "amplifier_lag").
#[derive(Clone, Debug)]
pub struct Terms {
    /// (index, time constant) per stage.
    stages: Vec<(usize, f64)>,
    law: AmplifierLag,
}

impl Terms {
    /// r'(U − U_amp) of the first stage at `at`.
    fn first_slope(&self, at: &At) -> f64 {
        let k = self.stages[0].0;
        self.law.rate(at.u - at.xi()[k]).1
    }
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
        Terms { stages, law: *al }
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
        for (n, &(k, t)) in self.stages.iter().enumerate() {
            dx[k] = if n == 0 {
                self.law.rate(prev - xi[k]).0
            } else {
                (prev - xi[k]) / t
            };
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
            match prev {
                // the first stage: r(U − U_amp)
                None => add(o + k, o + k, -self.first_slope(at)),
                Some(j) => {
                    add(o + k, o + k, -1.0 / t);
                    add(o + k, o + j, 1.0 / t);
                }
            }
            prev = Some(k);
        }
        Ok(())
    }

    /// The command drives the first stage: U̇_amp = r(U − U_amp).
    #[inline]
    fn add_input_jacobian(&self, at: &At, add: &mut impl FnMut(usize, f64)) {
        if let Some(&(k, _)) = self.stages.first() {
            add(k, self.first_slope(at));
        }
    }

    fn rest(&self, _: f64, out: &mut Vec<f64>) {
        out.extend(self.stages.iter().map(|_| 0.0));
    }

    fn scales(&self, _: &Actuator, _: f64, out: &mut Vec<f64>) {
        out.extend(self.stages.iter().map(|_| 100.0));
    }
}
