//! Data with a hidden mechanism, to prove the diagnosis (issue: "tests on hidden effects"):
//! the base parameters Kb, b, γ1, γ2 off by up to ±20 %, one mechanism of the library in a
//! form that differs from the library's term, its magnitude random within a range where it
//! visibly changes the response, measurement noise of 0.5–2 % of each output's range, and the
//! paper's two experiments (the 60 V sine at 3π and at 11 rad/s). Families have further hidden
//! forms beside the first (a tilt spring, one hardening about its stiffer axis, retention across the film, unequal creep times,
//! rate-dependent Dahl hysteresis, a second-order amplifier of equal stages, a slewing amplifier,
//! an output stage with unequal limits), drawn at random where the family's law is flexible. Also data with no effect and with two mechanisms outside the library (a floor
//! vibration picked up by the sensor, a ripple of the amplifier's supply), and data with two
//! mechanisms of the library at once ([`PAIRS`]). Any case can be recorded as lab data, with
//! artifacts on top ([`Hidden::with_artifacts`]).

use std::f64::consts::PI;

use super::Error;
use super::artifacts::Artifacts;
use crate::identify::Experiment;
use crate::identify::synth::{self, Columns, DATA_RTOL, Normal, Sensor, Spec};
use crate::model::Params;
use crate::model::effects::delay::{WANDER, WANDER_HZ};
use crate::model::effects::{Effect, Plant};
use crate::simulation::input::PAPER_PHASES;
use crate::simulation::{Input, InputError, Interpolation};

/// What the data hide.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Truth {
    Nothing,
    Effect(Effect),
    /// The effect in its further hidden form k (`Family::variants[k]`).
    Variant(Effect, usize),
    /// A floor vibration at a frequency unrelated to the drive, added to the measurements: more
    /// than two frequency resolutions of a `RECORD_S` record from every harmonic of both
    /// drive frequencies.
    Outside,
    /// The amplifier's supply rippling: its gain modulated at a frequency unrelated to the
    /// drive.
    Ripple,
    /// Two mechanisms at once: the two cases of [`PAIRS`]`[k]`.
    Two(usize),
}

/// The two-mechanism cases: physically independent causes that leave different marks
/// (book/src/diagnose.md, "Two mechanisms at once"), each in a form that differs from the
/// library's term, each at the magnitude of its own case.
pub const PAIRS: [(&str, [Truth; 2]); 3] = [
    // the platform's tilt spring and the film's creep: one couples the heights elastically,
    // the other relaxes each actuator alone
    (
        "coupling_tilt+creep",
        [
            Truth::Variant(Effect::Coupling, 0),
            Truth::Effect(Effect::Creep),
        ],
    ),
    // charge absorbed across the film (electrical, slow, driven by the voltage) and the
    // zipping's Dahl hysteresis (mechanical, rate-independent, driven by the motion)
    (
        "charge_drift_film+hysteresis",
        [
            Truth::Variant(Effect::ChargeDrift, 0),
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
            Truth::Variant(e, k) => e.family().variants.get(k).map_or(e.name(), |v| v.0),
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
            Truth::Effect(e) | Truth::Variant(e, _) => Some(e),
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

    /// Every truth: no effect, each family, each family's further forms, the two mechanisms
    /// outside the library, the pairs.
    pub fn all() -> Vec<Truth> {
        std::iter::once(Truth::Nothing)
            .chain(Effect::ALL.into_iter().map(Truth::Effect))
            .chain(
                Effect::ALL.into_iter().flat_map(|e| {
                    (0..e.family().variants.len()).map(move |k| Truth::Variant(e, k))
                }),
            )
            .chain([Truth::Outside, Truth::Ripple])
            .chain((0..PAIRS.len()).map(Truth::Two))
            .collect()
    }
}

/// The drive frequencies of the paper [rad/s]: identification, then validation (records after
/// the second repeat them, as a lab repeats a run).
const OMEGAS: [f64; 2] = [3.0 * PI, 11.0];

/// The amplitudes of the `levels` protocol's sines [V], record after record (repeated likewise).
const LEVELS: [f64; 2] = [60.0, 35.0];

/// A generated case: the true parameters and what else the data hide.
#[derive(Clone)]
pub struct Hidden {
    pub truth: Truth,
    pub params: Params,
    /// Measurement noise as a fraction of each output's range.
    pub noise: f64,
    /// A transport delay between command and amplifier that wanders around its mean \[s\]
    /// (mean, phase of the wander), if any.
    pub wandering_delay: Option<(f64, f64)>,
    /// Floor vibration: amplitude (fraction of range), frequency \[Hz\], phase \[rad\].
    pub vibration: Option<(f64, f64, f64)>,
    /// Supply ripple: relative depth of the gain's modulation, frequency \[Hz\], phase \[rad\].
    pub ripple: Option<(f64, f64, f64)>,
    /// What lab data add on top (`src/diagnose/artifacts.rs`), if any.
    pub artifacts: Option<Artifacts>,
    /// When the logger starts after the drive \[s\] (0: the records start at rest).
    pub record_from: f64,
    /// The sensor's first-order lag \[s\], where it is set apart from the artifacts' (0: theirs).
    pub sensor_lag: f64,
    /// The experiments' protocol (the paper's two sines unless drawn).
    pub protocol: Protocol,
    /// The hidden mechanism and its values, in words.
    pub description: String,
}

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
    between: &mut dyn FnMut(f64, f64) -> f64,
) -> Result<String, Error> {
    let params = &mut case.params;
    let mut wandering_delay = None;
    let mut vibration = None;
    let mut ripple = None;
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
        Truth::Effect(e) => planted(e.family().hidden, params, &mut wandering_delay, between),
        Truth::Variant(e, k) => match e.family().variants.get(k) {
            Some(&(_, plant)) => planted(plant, params, &mut wandering_delay, between),
            None => return Err(Error::NoVariant(e, k)),
        },
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

/// The mechanism `plant` plants in `params`, in words; a wandering delay it asks for is kept.
fn planted(
    plant: Plant,
    params: &mut Params,
    wandering_delay: &mut Option<(f64, f64)>,
    between: &mut dyn FnMut(f64, f64) -> f64,
) -> String {
    let p = plant(params, between);
    *wandering_delay = p.wandering_delay;
    p.text
}

/// Length of the records the generator's cases are drawn for (the benchmark's and the tests'
/// experiments) \[s\]: their frequency resolution is 1 / RECORD_S \[Hz\].
const RECORD_S: f64 = 6.0;

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

    /// This case recorded as the protocols' benchmark records it (`hasel bench --diagnose
    /// --protocols`): in a lab protocol drawn from the case's place in [`Truth::all`] and
    /// `seed`, so that one case drawn alone is drawn as in the full run, and from 1.3 s into
    /// the drive where the draw's top bit after a multiplicative hash is set (about half).
    pub fn in_drawn_protocol(self, seed: u64) -> Hidden {
        let index = Truth::all()
            .iter()
            .position(|t| *t == self.truth)
            .unwrap_or(0);
        let draw = (index as u64).wrapping_mul(7919).wrapping_add(seed);
        let case = self.with_protocol(Protocol::draw(draw));
        if draw.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 63 == 1 {
            case.mid_run(1.3)
        } else {
            case
        }
    }

    /// The protocol a case is recorded in, in a few words: "staircase 1 ms tip mid-run".
    pub fn protocol_label(&self) -> String {
        let p = &self.protocol;
        format!(
            "{} {} ms{}{}",
            p.name(),
            p.dt * 1e3,
            if p.tip { " tip" } else { "" },
            if self.record_from > 0.0 {
                " mid-run"
            } else {
                ""
            }
        )
    }

    /// This case seen through a sensor with a first-order lag of `lag` seconds.
    pub fn with_sensor_lag(mut self, lag: f64) -> Hidden {
        self.description = format!("{}; sensor lag {:.2} ms", self.description, lag * 1e3);
        self.sensor_lag = lag;
        self
    }

    /// The experiment of `input` recorded in `columns` every `dt` for `t_end` seconds from
    /// `record_from` into the drive, with this case's parameters, hidden mechanism and noise
    /// (noise drawn from `seed`).
    pub fn spec(
        &self,
        input: Input,
        t_end: f64,
        dt: f64,
        columns: Columns,
        seed: u64,
    ) -> Result<Spec, Error> {
        let end = self.record_from + t_end;
        let drive = match (self.wandering_delay, self.ripple) {
            (Some((tau, phase)), _) => Some(delayed(&input, tau, phase, end)?),
            (None, Some(r)) => Some(rippled(&input, r, end)?),
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
            t_end: end,
            dt,
            noise: self.noise,
            sensor,
            columns,
            seed,
            rtol: DATA_RTOL,
            record_from: self.record_from,
        })
    }

    /// The device's true model, what a diagnosis is checked against
    /// ([`crate::diagnose::truth_gaps`]): a delay that wanders about its mean held at its mean,
    /// the time-invariant law nearest it; none where the drive is distorted outside the model (a
    /// rippling supply) or the floor vibrates.
    pub fn true_model(&self) -> Option<Params> {
        if self.ripple.is_some() || self.vibration.is_some() {
            return None;
        }
        let mut model = self.params.clone();
        if let Some((mean, _)) = self.wandering_delay {
            model.effects.delay.tau_d = mean;
        }
        Some(model)
    }

    /// This case recorded with `protocol`.
    pub fn with_protocol(mut self, protocol: Protocol) -> Hidden {
        self.description = format!("{}; {}", self.description, protocol.describe());
        self.protocol = protocol;
        self
    }

    /// The case's experiments in its protocol (from `record_from` into the drive), the
    /// estimation first, then the held-out ones (the paper's: the 60 V sine at 3π and 11 rad/s,
    /// 6 s at 1 ms, named `w3pi.csv` and `w11.csv`), recorded in `columns` unless the protocol
    /// records the tip.
    pub fn experiments(&self, columns: Columns, seed: u64) -> Result<Vec<Experiment>, Error> {
        let p = self.protocol;
        let total = self.record_from + p.length;
        let columns = if p.tip { Columns::TipXy } else { columns };
        (0..p.records)
            .map(|k| {
                let spec = self.spec(
                    p.input(k, total)?,
                    p.length,
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
    /// A 60 V sine swept logarithmically in frequency, 2 → 20 rad/s, then 20 → 2 rad/s (and
    /// so on, record after record).
    Chirp,
    /// The sine at two voltage levels: 60 V at 3π rad/s, then 35 V at 11 rad/s.
    Levels,
}

/// A protocol: the drive, the sampling, the records, and the draw of its random parts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Protocol {
    pub drive: Drive,
    /// Sample interval \[s\].
    pub dt: f64,
    /// Length of each record \[s\].
    pub length: f64,
    /// Number of records: the estimation one, then the held-out ones.
    pub records: usize,
    /// Whether the records hold the tip's X/Y rather than the heights.
    pub tip: bool,
    seed: u64,
}

impl Protocol {
    /// The paper's: two 6 s sines at 1 ms.
    pub const PAPER: Protocol = Protocol {
        drive: Drive::Sines,
        dt: 1e-3,
        length: RECORD_S,
        records: 2,
        tip: false,
        seed: 0,
    };

    /// A protocol drawn from `seed` (issue: lab protocols): any drive, sampled every 0.5, 1
    /// or 2 ms, one to four records of 3–20 s, a quarter of them of the tip.
    pub fn draw(seed: u64) -> Protocol {
        let mut rng = Normal::new(seed.wrapping_mul(0xD1B5_4A32_D192_ED03) ^ 0x0907_0C01);
        let pick = |rng: &mut Normal, n: usize| ((rng.uniform() * n as f64) as usize).min(n - 1);
        let drive =
            [Drive::Sines, Drive::Staircase, Drive::Chirp, Drive::Levels][pick(&mut rng, 4)];
        let dt = [5e-4, 1e-3, 2e-3][pick(&mut rng, 3)];
        // whole seconds: the sines' periods and the staircase's holds need not fit
        let length = 3.0 + pick(&mut rng, 18) as f64;
        let records = 1 + pick(&mut rng, 4);
        let tip = pick(&mut rng, 4) == 0;
        Protocol {
            drive,
            dt,
            length,
            records,
            tip,
            seed,
        }
    }

    /// This protocol with records of `length` seconds.
    pub fn lasting(self, length: f64) -> Protocol {
        Protocol { length, ..self }
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
        format!(
            "{} {} x {} s of the {} sampled every {} ms",
            self.name(),
            self.records,
            self.length,
            if self.tip { "tip" } else { "heights" },
            self.dt * 1e3
        )
    }

    fn file_name(&self, k: usize) -> String {
        match (self.drive, k) {
            (Drive::Sines, 0) => "w3pi.csv".into(),
            (Drive::Sines, 1) => "w11.csv".into(),
            (Drive::Sines, _) => format!("{}_{}.csv", ["w3pi", "w11"][k % 2], k / 2 + 1),
            (_, 0) => format!("{}_estimation.csv", self.name()),
            (_, 1) => format!("{}_held_out.csv", self.name()),
            _ => format!("{}_held_out{k}.csv", self.name()),
        }
    }

    /// The command of experiment `k` (0: estimation, 1: held out), `t_end` seconds long.
    fn input(&self, k: usize, t_end: f64) -> Result<Input, InputError> {
        match self.drive {
            Drive::Sines => Ok(Input::sine(60.0, OMEGAS[k % OMEGAS.len()])),
            Drive::Levels => Ok(Input::sine(
                LEVELS[k % LEVELS.len()],
                OMEGAS[k % OMEGAS.len()],
            )),
            Drive::Chirp => {
                let (w0, w1): (f64, f64) = if k.is_multiple_of(2) {
                    (2.0, 20.0)
                } else {
                    (20.0, 2.0)
                };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::Channel;

    /// The truth a diagnosis is checked against holds a wandering delay at its mean, and keeps
    /// the drawn parameters; a rippling supply or a vibrating floor has none.
    #[test]
    fn a_wandering_delay_is_held_at_its_mean_in_the_true_model() {
        let case = hide(Truth::Effect(Effect::Delay), 17).unwrap();
        let (mean, _) = case.wandering_delay.unwrap();
        let model = case.true_model().unwrap();
        assert_eq!(model.effects.delay.tau_d, mean);
        let mut rest = model.clone();
        rest.effects.delay.tau_d = 0.0;
        assert_eq!(rest, case.params);
        for outside in [Truth::Ripple, Truth::Outside] {
            assert!(hide(outside, 17).unwrap().true_model().is_none());
        }
    }

    #[test]
    fn drawn_protocols_span_the_lab_protocols() {
        let draws: Vec<Protocol> = (0..400).map(Protocol::draw).collect();
        for drive in [Drive::Sines, Drive::Staircase, Drive::Chirp, Drive::Levels] {
            assert!(draws.iter().any(|p| p.drive == drive), "{drive:?}");
        }
        for dt in [5e-4, 1e-3, 2e-3] {
            assert!(draws.iter().any(|p| p.dt == dt), "{dt}");
        }
        for records in 1..=4 {
            assert!(draws.iter().any(|p| p.records == records), "{records}");
        }
        let lengths = draws.iter().map(|p| p.length);
        assert_eq!(lengths.clone().fold(f64::INFINITY, f64::min), 3.0);
        assert_eq!(lengths.fold(0.0, f64::max), 20.0);
        let tips = draws.iter().filter(|p| p.tip).count();
        assert!((60..140).contains(&tips), "{tips} of 400 of the tip");
    }

    /// A record mid-run lasts its protocol's length, not the lead-in too, and the drive a
    /// hidden delay makes reaches its end (it once ran 1.3 s past the drive's table).
    #[test]
    fn a_record_mid_run_lasts_its_protocols_length() {
        let p = (0..)
            .map(Protocol::draw)
            .find(|p| p.drive == Drive::Chirp)
            .unwrap()
            .lasting(2.0);
        let case = hide(Truth::Effect(Effect::Delay), 1)
            .unwrap()
            .with_protocol(p)
            .mid_run(1.3);
        let exp = &case.experiments(Columns::Heights, 1).unwrap()[0];
        let (first, last) = (exp.t[0], exp.t[exp.t.len() - 1]);
        assert!((first - 1.3).abs() <= p.dt, "starts at {first} s");
        assert!((last - 3.3).abs() <= p.dt, "ends at {last} s");
        let spec = case.spec(p.input(0, 3.3).unwrap(), 2.0, p.dt, Columns::Heights, 1);
        let drive = spec.unwrap().drive.unwrap();
        assert!(
            drive.last_sample().unwrap() >= 3.3,
            "{:?}",
            drive.last_sample()
        );
    }

    #[test]
    fn a_case_is_recorded_as_its_protocol_says() {
        let p = (0..)
            .map(Protocol::draw)
            .find(|p| p.tip && p.records == 3)
            .unwrap()
            .lasting(1.0);
        let case = hide(Truth::Nothing, 1).unwrap().with_protocol(p);
        let exps = case.experiments(Columns::Heights, 1).unwrap();
        assert_eq!(exps.len(), 3);
        let names: Vec<&str> = exps.iter().map(|e| e.name.as_str()).collect();
        let unique: std::collections::BTreeSet<&str> = names.iter().copied().collect();
        assert_eq!(unique.len(), 3, "{names:?}");
        for e in &exps {
            let channels: Vec<Channel> = e.channels.iter().map(|(c, _)| *c).collect();
            assert_eq!(channels, Columns::TipXy.channels(), "{}", e.name);
            let span = e.t[e.t.len() - 1] - e.t[0];
            assert!((span - 1.0).abs() <= p.dt, "{}: {span} s", e.name);
        }
    }
}
