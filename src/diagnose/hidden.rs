//! Data with a hidden mechanism, to prove the diagnosis (issue: "tests on hidden effects"):
//! the base parameters Kb, b, γ1, γ2 off by up to ±20 %, one mechanism of the library in a
//! form that differs from the library's term, its magnitude random within a range where it
//! visibly changes the response, measurement noise of 0.5–2 % of each output's range, and the
//! paper's two experiments (the 60 V sine at 3π and at 11 rad/s). Each family has a second
//! hidden form beside the first where the library has several (a tilt spring, retention across
//! the film, unequal creep times, rate-dependent Dahl hysteresis, a second-order amplifier of
//! equal stages). Also data with no effect and with two mechanisms outside the library (a floor
//! vibration picked up by the sensor, a ripple of the amplifier's supply), and data with two
//! mechanisms of the library at once ([`PAIRS`]). Any case can be recorded as lab data, with
//! artifacts on top ([`Hidden::with_artifacts`]).

use std::f64::consts::PI;

use super::Error;
use super::artifacts::Artifacts;
use crate::identify::Experiment;
use crate::identify::synth::{self, Columns, DATA_RTOL, Normal, Sensor, Spec};
use crate::model::Params;
use crate::model::effects::{ChargeDrift, Creep, DriftSite, Effect, HysteresisLaw, PreloadLaw};
use crate::simulation::input::PAPER_PHASES;
use crate::simulation::{Input, InputError, Interpolation};

/// What the data hide.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Truth {
    Nothing,
    Effect(Effect),
    /// The effect in its second hidden form (the families with several forms).
    Variant(Effect),
    /// A floor vibration at a frequency unrelated to the drive, added to the measurements: more
    /// than two frequency resolutions of a [`RECORD_S`] record from every harmonic of both
    /// drive frequencies.
    Outside,
    /// The amplifier's supply rippling: its gain modulated at a frequency unrelated to the
    /// drive.
    Ripple,
    /// Two mechanisms at once: the two cases of [`PAIRS`]`[k]`.
    Two(usize),
}

/// The families with a second hidden form, and its name.
const VARIANTS: [(Effect, &str); 5] = [
    (Effect::Coupling, "coupling_tilt"),
    (Effect::ChargeDrift, "charge_drift_film"),
    (Effect::Creep, "creep_two_times"),
    (Effect::Hysteresis, "hysteresis_rate"),
    (Effect::AmplifierLag, "amplifier_lag_second_order"),
];

/// The two-mechanism cases: physically independent causes that leave different marks
/// (src/diagnose/diagnose.md, "Two mechanisms at once"), each in a form that differs from the
/// library's term, each at the magnitude of its own case.
pub const PAIRS: [(&str, [Truth; 2]); 3] = [
    // the platform's tilt spring and the film's creep: one couples the heights elastically,
    // the other relaxes each actuator alone
    (
        "coupling_tilt+creep",
        [
            Truth::Variant(Effect::Coupling),
            Truth::Effect(Effect::Creep),
        ],
    ),
    // charge absorbed across the film (electrical, slow, driven by the voltage) and the
    // zipping's Dahl hysteresis (mechanical, rate-independent, driven by the motion)
    (
        "charge_drift_film+hysteresis",
        [
            Truth::Variant(Effect::ChargeDrift),
            Truth::Effect(Effect::Hysteresis),
        ],
    ),
    // the amplifier's two stages (linear, before the actuator) and the film's fifth-power
    // stiffening (nonlinear, in the actuator)
    (
        "amplifier_lag+stiffening",
        [
            Truth::Effect(Effect::AmplifierLag),
            Truth::Effect(Effect::Stiffening),
        ],
    ),
];

impl Truth {
    pub fn name(self) -> &'static str {
        match self {
            Truth::Nothing => "none",
            Truth::Effect(e) => e.name(),
            Truth::Variant(e) => VARIANTS
                .iter()
                .find(|(v, _)| *v == e)
                .map_or(e.name(), |(_, n)| n),
            Truth::Outside => "vibration",
            Truth::Ripple => "supply_ripple",
            Truth::Two(k) => PAIRS.get(k).map_or("two", |p| p.0),
        }
    }

    pub fn from_name(name: &str) -> Option<Truth> {
        Truth::all().into_iter().find(|t| t.name() == name)
    }

    /// The effect the data hide, if it is one of the library's.
    pub fn effect(self) -> Option<Effect> {
        match self {
            Truth::Effect(e) | Truth::Variant(e) => Some(e),
            _ => None,
        }
    }

    /// The effects the data hide: one, both of a pair, or none.
    pub fn effects(self) -> Vec<Effect> {
        match self {
            Truth::Two(k) => PAIRS.get(k).map_or(Vec::new(), |p| {
                p.1.iter().filter_map(|t| t.effect()).collect()
            }),
            t => t.effect().into_iter().collect(),
        }
    }

    /// Every truth: no effect, the nine effects, the five second forms, the two mechanisms
    /// outside the library, the pairs.
    pub fn all() -> Vec<Truth> {
        std::iter::once(Truth::Nothing)
            .chain(Effect::ALL.into_iter().map(Truth::Effect))
            .chain(VARIANTS.iter().map(|(e, _)| Truth::Variant(*e)))
            .chain([Truth::Outside, Truth::Ripple])
            .chain((0..PAIRS.len()).map(Truth::Two))
            .collect()
    }
}

/// The drive frequencies of the paper [rad/s]: identification, then validation.
pub const OMEGAS: [f64; 2] = [3.0 * PI, 11.0];

/// A generated case: the true parameters and what else the data hide.
#[derive(Clone)]
pub struct Hidden {
    pub truth: Truth,
    pub params: Params,
    /// Measurement noise as a fraction of each output's range.
    pub noise: f64,
    /// A transport delay between command and amplifier that wanders around its mean [s]
    /// (mean, phase of the wander), if any.
    pub wandering_delay: Option<(f64, f64)>,
    /// Floor vibration: amplitude (fraction of range), frequency [Hz], phase [rad].
    pub vibration: Option<(f64, f64, f64)>,
    /// Supply ripple: relative depth of the gain's modulation, frequency [Hz], phase [rad].
    pub ripple: Option<(f64, f64, f64)>,
    /// What lab data add on top (`src/diagnose/artifacts.rs`), if any.
    pub artifacts: Option<Artifacts>,
    /// When the logger starts after the drive [s] (0: the records start at rest).
    pub record_from: f64,
    /// The sensor's first-order lag [s], where it is set apart from the artifacts' (0: theirs).
    pub sensor_lag: f64,
    /// The experiments' protocol (the paper's two sines unless drawn).
    pub protocol: Protocol,
    /// The hidden mechanism and its values, in words.
    pub description: String,
}

/// Angle at which the stiffness terms are compared with Kb θ: within the stroke of actuators 2
/// and 3 [rad].
const THETA_REF: f64 = 0.012;

/// Draws a case hiding `truth`; `seed` fixes everything.
pub fn hide(truth: Truth, seed: u64) -> Result<Hidden, Error> {
    let mut rng = Normal::new(seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0x5EED);
    let mut between = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
    let mut params = Params::default();
    for name in crate::identify::default_free() {
        let v = params.get(&name)?;
        params.set(&name, v * between(0.8, 1.2))?;
    }
    let noise = between(0.005, 0.02);
    let mut case = Hidden {
        truth,
        params,
        noise,
        wandering_delay: None,
        vibration: None,
        ripple: None,
        artifacts: None,
        record_from: 0.0,
        sensor_lag: 0.0,
        protocol: Protocol::PAPER,
        description: String::new(),
    };
    let description = plant(&mut case, truth, &mut between)?;
    case.description = format!("{description}; noise {:.2} % of range", 100.0 * noise);
    Ok(case)
}

/// Plants the mechanisms of `truth` in `case` (both of a pair, the first drawn first), their
/// values drawn by `between`; returns them in words.
fn plant(
    case: &mut Hidden,
    truth: Truth,
    mut between: &mut dyn FnMut(f64, f64) -> f64,
) -> Result<String, Error> {
    let params = &mut case.params;
    let kb = params.act.map(|a| a.kb);
    let mean_kb = kb.iter().sum::<f64>() / 3.0;
    let mut wandering_delay = None;
    let mut vibration = None;
    let mut ripple = None;
    let fx = &mut params.effects;
    let description = match truth {
        Truth::Nothing => "no effect".to_string(),
        Truth::Outside => {
            let a = between(0.03, 0.06);
            // off the drive by construction: a frequency a record cannot tell from a harmonic
            // would be counted as harmonic residual, which a library term might explain
            let f = loop {
                let f = between(5.3, 8.7);
                if clear_of_harmonics(f) {
                    break f;
                }
            };
            vibration = Some((a, f, between(0.0, 2.0 * PI)));
            format!(
                "floor vibration of {:.1} % of each output's range at {f:.2} Hz",
                100.0 * a
            )
        }
        Truth::Ripple => {
            let (depth, f) = (between(0.08, 0.15), between(1.1, 1.7));
            ripple = Some((depth, f, between(0.0, 2.0 * PI)));
            format!(
                "the amplifier's supply rippling: gain modulated by {:.0} % at {f:.2} Hz",
                100.0 * depth
            )
        }
        Truth::Variant(Effect::Coupling) => {
            // a tilt spring H = 1/2 (K_x phi_x^2 + K_y phi_y^2), stiffer about one axis; with
            // the anchors at 90, 210 and 330 degrees, phi_x = (h3 - h2) / (sqrt 3 r) and
            // phi_y = (h1 - (h2 + h3)/2) / (1.5 r), so (in units of K_y / r^2)
            // w_12 = w_13 = 2/9 and w_23 = K_x/(3 K_y) - 1/9 (positive for K_x > K_y / 3)
            let ratio = if between(0.0, 1.0) < 0.5 {
                between(1.6, 2.5)
            } else {
                1.0 / between(1.6, 2.5)
            };
            let w = [2.0 / 9.0, 2.0 / 9.0, ratio / 3.0 - 1.0 / 9.0];
            let mean = w.iter().sum::<f64>() / 3.0;
            fx.coupling.weights = w.map(|x| x / mean);
            fx.coupling.k_c = log_between(&mut between, 800.0, 3000.0);
            format!(
                "a platform tilt spring, K_x / K_y = {ratio:.2}: pair weights {:.2?}, k_c = {:.0} N/m",
                fx.coupling.weights, fx.coupling.k_c
            )
        }
        Truth::Variant(Effect::ChargeDrift) => {
            // the source holds the film's voltage through R0 + R1: the branch takes a visible
            // share of the current when its R3 = tau3 / C3 is 1 to 4 times R0 + R1
            let r01 = params.act[0].r0 + params.act[0].r1;
            let (tau3, f) = (
                log_between(&mut between, 0.3, 3.0),
                log_between(&mut between, 1.0, 4.0),
            );
            fx.charge_drift = ChargeDrift {
                site: DriftSite::Film,
                tau3,
                c3: tau3 / (f * r01),
                ..fx.charge_drift
            };
            format!(
                "an absorption branch across the whole film, R3 = {:.0} Ohm ({f:.2} (R0 + R1)), tau3 = {tau3:.2} s",
                f * r01
            )
        }
        Truth::Variant(Effect::Creep) => {
            let k_v = between(0.15, 0.4) * mean_kb;
            let tau_v = log_between(&mut between, 0.1, 0.5);
            let share = between(0.25, 0.4);
            two_branches(&mut fx.creep, k_v, share, tau_v, 8.0 * tau_v);
            format!(
                "creep in two branches, {:.0} % at tau = {tau_v:.2} s and the rest at 8 tau, k_v = {k_v:.3} N.m/rad",
                100.0 * share
            )
        }
        Truth::Variant(Effect::Hysteresis) => {
            fx.hysteresis.law = HysteresisLaw::Dahl;
            fx.hysteresis.k_h = between(0.25, 0.5) * mean_kb;
            fx.hysteresis.theta_h = log_between(&mut between, 2e-3, 6e-3);
            fx.hysteresis.r_h = log_between(&mut between, 2.0, 8.0);
            format!(
                "rate-dependent Dahl hysteresis, k_h = {:.3} N.m/rad, theta_h = {:.2e} rad, relaxing at {:.1} 1/s",
                fx.hysteresis.k_h, fx.hysteresis.theta_h, fx.hysteresis.r_h
            )
        }
        Truth::Variant(Effect::AmplifierLag) => {
            let tau = log_between(&mut between, 0.01, 0.03);
            fx.amplifier_lag.tau_a = tau;
            fx.amplifier_lag.tau_a2 = tau;
            format!(
                "a second-order amplifier, two equal stages of {:.1} ms",
                1000.0 * tau
            )
        }
        Truth::Variant(e) => return Err(Error::NoVariant(e)),
        Truth::Effect(Effect::Coupling) => {
            fx.coupling.k_c = log_between(&mut between, 800.0, 3000.0);
            let k = (between(0.0, 3.0) as usize).min(2);
            fx.coupling.weights = [[0.5, 1.0, 1.5], [1.5, 0.5, 1.0], [1.0, 1.5, 0.5]][k];
            format!(
                "coupling k_c = {:.0} N/m with unequal pair weights {:?}",
                fx.coupling.k_c, fx.coupling.weights
            )
        }
        Truth::Effect(Effect::ChargeDrift) => {
            fx.charge_drift.two_stages = true;
            fx.charge_drift.tau3 = log_between(&mut between, 0.3, 3.0);
            // the stage takes i R3 / (1 + (ω τ3)²)^½ from the electrode: a tenth to a half of
            // its voltage at the drive frequency
            let r2 = params.act[0].r2;
            fx.charge_drift.r3 =
                between(0.1, 0.5) * r2 * (1.0 + (10.0 * fx.charge_drift.tau3).powi(2)).sqrt();
            format!(
                "two trapping stages in series (R3/2 at tau3/3 and 3 tau3), R3 = {:.3e} Ohm, tau3 = {:.2} s",
                fx.charge_drift.r3, fx.charge_drift.tau3
            )
        }
        Truth::Effect(Effect::Creep) => {
            let k_v = between(0.15, 0.4) * mean_kb;
            let tau_v = log_between(&mut between, 0.2, 2.0);
            two_branches(&mut fx.creep, k_v, 0.5, tau_v / 3.0, 3.0 * tau_v);
            format!(
                "creep in two branches (tau_v/3 and 3 tau_v), k_v = {k_v:.3} N.m/rad, tau_v = {tau_v:.2} s"
            )
        }
        Truth::Effect(Effect::Hysteresis) => {
            fx.hysteresis.law = HysteresisLaw::Dahl;
            fx.hysteresis.k_h = between(0.25, 0.5) * mean_kb;
            fx.hysteresis.theta_h = log_between(&mut between, 2e-3, 6e-3);
            format!(
                "Dahl hysteresis, k_h = {:.3} N.m/rad, theta_h = {:.2e} rad",
                fx.hysteresis.k_h, fx.hysteresis.theta_h
            )
        }
        Truth::Effect(Effect::AmplifierLag) => {
            let tau = log_between(&mut between, 0.02, 0.06);
            fx.amplifier_lag.tau_a = 0.8 * tau;
            fx.amplifier_lag.tau_a2 = 0.2 * tau;
            format!(
                "two-stage amplifier, {:.1} ms and {:.1} ms",
                800.0 * tau,
                200.0 * tau
            )
        }
        Truth::Effect(Effect::Delay) => {
            let tau = log_between(&mut between, 0.008, 0.025);
            wandering_delay = Some((tau, between(0.0, 2.0 * PI)));
            format!(
                "a transport delay wandering by +-{:.0} % around {:.1} ms at {WANDER_HZ} Hz (network jitter)",
                100.0 * WANDER,
                1000.0 * tau
            )
        }
        Truth::Effect(Effect::Saturation) => {
            fx.saturation.soft = true;
            fx.saturation.u_max = between(42.0, 55.0);
            format!(
                "amplifier compressing from 0.85 U_max into U_max = {:.1} V",
                fx.saturation.u_max
            )
        }
        Truth::Effect(Effect::Stiffening) => {
            fx.stiffening.exponent = 5;
            let s = between(0.3, 0.8);
            fx.stiffening.k3 = s * mean_kb / THETA_REF.powi(3);
            format!(
                "fifth-power stiffening H += k |theta|^5 / 5, {:.0} % of Kb theta at theta = {THETA_REF} rad",
                100.0 * s
            )
        }
        Truth::Effect(Effect::Preload) => {
            fx.preload.law = PreloadLaw::Weight;
            // a load that lowers each actuator by 3–10 µm at rest: Δθ = 2 Δh / Lv
            for (tau0, kb) in fx.preload.tau0.iter_mut().zip(kb) {
                *tau0 = kb * 2.0 * between(3e-6, 10e-6) / params.lv;
            }
            format!(
                "a weight on the platform, torques {:.2e} {:.2e} {:.2e} N.m (tau0 cos theta)",
                fx.preload.tau0[0], fx.preload.tau0[1], fx.preload.tau0[2]
            )
        }
        Truth::Two(k) => {
            let [a, b] = PAIRS.get(k).ok_or(Error::NoPair(k))?.1;
            let first = plant(case, a, between)?;
            format!("{first}; and {}", plant(case, b, between)?)
        }
    };
    case.wandering_delay = case.wandering_delay.or(wandering_delay);
    case.vibration = case.vibration.or(vibration);
    case.ripple = case.ripple.or(ripple);
    Ok(description)
}

/// Length of the records the generator's cases are drawn for (the benchmark's and the tests'
/// experiments) [s]: their frequency resolution is 1 / RECORD_S [Hz].
pub const RECORD_S: f64 = 6.0;

/// Clearance of the floor vibration from every harmonic of either drive frequency, in units of
/// the record's frequency resolution. A sine Δf away from k·ω/2π leaves |sinc(π Δf T)| of its
/// amplitude in the fit of that harmonic, at most 1/(2π) beyond 2 resolutions (2.5 % of its power).
const HARMONIC_CLEARANCE: f64 = 2.0;

/// Whether a vibration at `f` [Hz] is more than HARMONIC_CLEARANCE resolutions from every
/// harmonic of both drive frequencies in [`OMEGAS`].
fn clear_of_harmonics(f: f64) -> bool {
    OMEGAS.iter().all(|omega| {
        let f_drive = omega / (2.0 * PI);
        let nearest = (f / f_drive).round().max(1.0) * f_drive;
        (f - nearest).abs() > HARMONIC_CLEARANCE / RECORD_S
    })
}

/// Creep of stiffness `k_v` in two branches: a `share` of it at `tau`, the rest at `tau2`.
fn two_branches(creep: &mut Creep, k_v: f64, share: f64, tau: f64, tau2: f64) {
    creep.k_v = share * k_v;
    creep.tau_v = tau;
    creep.k_v2 = (1.0 - share) * k_v;
    creep.tau_v2 = tau2;
}

fn log_between(between: &mut impl FnMut(f64, f64) -> f64, lo: f64, hi: f64) -> f64 {
    between(lo.ln(), hi.ln()).exp()
}

/// Relative wander of the hidden transport delay, and its frequency [Hz].
const WANDER: f64 = 0.05;
const WANDER_HZ: f64 = 0.37;

/// The command late by τ(t) = τ (1 + WANDER sin(2π WANDER_HZ t + phase)), 0 before it
/// arrives.
fn delayed(input: &Input, tau: f64, phase: f64, t_end: f64) -> Result<Input, InputError> {
    resampled(t_end, |tk| {
        let late = tk - tau * (1.0 + WANDER * (2.0 * PI * WANDER_HZ * tk + phase).sin());
        if late < 0.0 {
            [0.0; 3]
        } else {
            input.value(late)
        }
    })
}

/// The command times 1 + depth sin(2π f t + phase): a gain rippling with the supply.
fn rippled(
    input: &Input,
    (depth, f, phase): (f64, f64, f64),
    t_end: f64,
) -> Result<Input, InputError> {
    resampled(t_end, |tk| {
        let gain = 1.0 + depth * (2.0 * PI * f * tk + phase).sin();
        input.value(tk).map(|u| gain * u)
    })
}

/// A drive `u(t)` tabulated every 0.5 ms up to `t_end` and replayed linearly.
fn resampled(t_end: f64, u: impl Fn(f64) -> [f64; 3]) -> Result<Input, InputError> {
    const STEP: f64 = 5e-4;
    let n = (t_end / STEP).ceil() as usize + 1;
    let t: Vec<f64> = (0..=n).map(|k| k as f64 * STEP).collect();
    let values = t.iter().map(|&tk| u(tk)).collect();
    Input::sampled(t, values, Interpolation::Linear)
}

impl Hidden {
    /// This case recorded as lab data: with artifacts drawn from `seed`.
    pub fn with_artifacts(mut self, seed: u64) -> Hidden {
        let a = Artifacts::draw(self.noise, seed);
        self.description = format!("{}; {}", self.description, a.describe());
        self.artifacts = Some(a);
        self
    }

    /// This case recorded by a logger that starts `after` seconds into the drive: its records
    /// start mid-run (the twin of a record from rest).
    pub fn mid_run(mut self, after: f64) -> Hidden {
        self.description = format!(
            "{}; recorded from {after:.2} s into the drive",
            self.description
        );
        self.record_from = after;
        self
    }

    /// This case seen through a sensor with a first-order lag of `lag` seconds.
    pub fn with_sensor_lag(mut self, lag: f64) -> Hidden {
        self.description = format!("{}; sensor lag {:.2} ms", self.description, lag * 1e3);
        self.sensor_lag = lag;
        self
    }

    /// The experiment of `input` recorded in `columns` every `dt` up to `t_end` (from
    /// `record_from`), with this
    /// case's parameters, hidden mechanism and noise (noise drawn from `seed`).
    pub fn spec(
        &self,
        input: Input,
        t_end: f64,
        dt: f64,
        columns: Columns,
        seed: u64,
    ) -> Result<Spec, Error> {
        let drive = match (self.wandering_delay, self.ripple) {
            (Some((tau, phase)), _) => Some(delayed(&input, tau, phase, t_end)?),
            (None, Some(r)) => Some(rippled(&input, r, t_end)?),
            (None, None) => None,
        };
        let mut sensor = self.artifacts.as_ref().map_or(Sensor::IDEAL, |a| a.sensor);
        if self.sensor_lag > 0.0 {
            sensor.lag = self.sensor_lag;
        }
        Ok(Spec {
            input,
            drive,
            vibration: self.vibration,
            params: self.params.clone(),
            t_end: self.record_from + t_end,
            dt,
            noise: self.noise,
            sensor,
            columns,
            seed,
            rtol: DATA_RTOL,
            record_from: self.record_from,
        })
    }

    /// This case recorded with `protocol`.
    pub fn with_protocol(mut self, protocol: Protocol) -> Hidden {
        self.description = format!("{}; {}", self.description, protocol.describe());
        self.protocol = protocol;
        self
    }

    /// The case's two experiments of `t_end` seconds (from `record_from` into the drive), the
    /// estimation then the held-out one, in its protocol (the paper's: the 60 V sine at 3π and
    /// 11 rad/s at 1 ms, named `w3pi.csv` and `w11.csv`).
    pub fn experiments(
        &self,
        columns: Columns,
        t_end: f64,
        seed: u64,
    ) -> Result<Vec<Experiment>, Error> {
        let total = self.record_from + t_end;
        let p = self.protocol;
        (0..2)
            .map(|k| {
                let spec = self.spec(
                    p.input(k, total)?,
                    total,
                    p.dt,
                    columns,
                    seed.wrapping_mul(31).wrapping_add(k as u64),
                )?;
                let exp = synth::experiment(&spec, &p.file_name(k))?;
                match &self.artifacts {
                    Some(a) => a.apply(&exp, self.noise, k as u64),
                    None => Ok(exp),
                }
            })
            .collect()
    }
}

/// The kind of drive a lab records with (issue: lab protocols).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Drive {
    /// The paper's 60 V sine, at 3π rad/s then 11 rad/s.
    Sines,
    /// Each actuator stepping between levels in 0–60 V every 0.3–0.8 s, held between steps.
    Staircase,
    /// A 60 V sine swept logarithmically in frequency, 2 → 20 rad/s, then 20 → 2 rad/s.
    Chirp,
    /// The sine at two voltage levels: 60 V at 3π rad/s, then 35 V at 11 rad/s.
    Levels,
}

/// A protocol: the drive, the sampling interval, and the draw of its random parts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Protocol {
    pub drive: Drive,
    /// Sample interval [s].
    pub dt: f64,
    seed: u64,
}

impl Protocol {
    /// The paper's: two sines at 1 ms.
    pub const PAPER: Protocol = Protocol {
        drive: Drive::Sines,
        dt: 1e-3,
        seed: 0,
    };

    /// A protocol drawn from `seed`: any drive, sampled every 0.5, 1 or 2 ms.
    pub fn draw(seed: u64) -> Protocol {
        let mut rng = Normal::new(seed.wrapping_mul(0xD1B5_4A32_D192_ED03) ^ 0x0907_0C01);
        let pick = |rng: &mut Normal, n: usize| ((rng.uniform() * n as f64) as usize).min(n - 1);
        let drive =
            [Drive::Sines, Drive::Staircase, Drive::Chirp, Drive::Levels][pick(&mut rng, 4)];
        let dt = [5e-4, 1e-3, 2e-3][pick(&mut rng, 3)];
        Protocol { drive, dt, seed }
    }

    pub fn name(&self) -> &'static str {
        match self.drive {
            Drive::Sines => "sines",
            Drive::Staircase => "staircase",
            Drive::Chirp => "chirp",
            Drive::Levels => "levels",
        }
    }

    /// In words, for the case's description.
    pub fn describe(&self) -> String {
        format!("{} sampled every {} ms", self.name(), self.dt * 1e3)
    }

    fn file_name(&self, k: usize) -> String {
        match (self.drive, k) {
            (Drive::Sines, 0) => "w3pi.csv".into(),
            (Drive::Sines, _) => "w11.csv".into(),
            (_, 0) => format!("{}_estimation.csv", self.name()),
            _ => format!("{}_held_out.csv", self.name()),
        }
    }

    /// The command of experiment `k` (0: estimation, 1: held out), `t_end` seconds long.
    fn input(&self, k: usize, t_end: f64) -> Result<Input, InputError> {
        match self.drive {
            Drive::Sines => Ok(Input::sine(60.0, OMEGAS[k])),
            Drive::Levels => Ok(Input::sine([60.0, 35.0][k], OMEGAS[k])),
            Drive::Chirp => {
                let (w0, w1): (f64, f64) = if k == 0 { (2.0, 20.0) } else { (20.0, 2.0) };
                // phase of a logarithmic sweep: ∫ w0 (w1/w0)^(s/T) ds
                let rate = (w1 / w0).ln() / t_end;
                resampled(t_end, |t| {
                    let phase = w0 * ((rate * t).exp() - 1.0) / rate;
                    PAPER_PHASES.map(|phi| 60.0 * (phase + phi).sin())
                })
            }
            Drive::Staircase => {
                let mut rng = Normal::new(self.seed.wrapping_mul(0x51_7CC1_B727_220A) ^ k as u64);
                let mut t = vec![0.0];
                let mut u = vec![[0.0; 3]];
                while t[t.len() - 1] < t_end {
                    let hold = 0.3 + 0.5 * rng.uniform();
                    // steps on the logger's clock: the command changes at a sample
                    let next = ((t[t.len() - 1] + hold) / self.dt).round() * self.dt;
                    t.push(next);
                    u.push([0; 3].map(|_| 60.0 * rng.uniform()));
                }
                Input::sampled(t, u, Interpolation::ZeroOrderHold)
            }
        }
    }
}
