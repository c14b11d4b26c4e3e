//! The experiment that tells two tied effects apart (book/src/diagnose.md, "The decision
//! rule"): for each effect, the experiment that exposes it, as an input, and both refitted models
//! driven by it, to show that it would separate them.

use super::Error;
use super::analysis;
use crate::identify::{self, Channel, Experiment};
use crate::model::effects::Drive;
use crate::model::{Effect, Params, Platform};
use crate::simulation::{Input, Interpolation, Simulator, Tone};

/// Sample interval of a separating experiment's predictions [s].
const DT: f64 = 1e-3;

/// The models are told apart when their predictions differ by more than this many noise σ
/// (RMS over the record): the difference then stands out of the noise on every sample's scale.
const SEPARATES: f64 = 1.0;

/// The experiment that exposes one effect, as a command.
pub struct Exposing {
    /// What to do and why it exposes the effect, in words.
    pub text: &'static str,
    /// The commanded voltages and the record's length \[s\].
    pub input: Input,
    pub t_end: f64,
}

/// A piecewise-linear command through `(t, U)` corners, the same on every actuator.
fn corners(points: impl Iterator<Item = (f64, f64)>) -> Input {
    let (t, u) = points.map(|(t, u)| (t, [u; 3])).unzip();
    Input::sampled(t, u, Interpolation::Linear).expect("increasing corners of finite values")
}

/// The experiment exposing `effect` (its family's), at commands up to `u` \[V\].
pub fn exposing(effect: Effect, u: f64) -> Exposing {
    let sine = |amplitude: f64, omega: f64, phase: f64| Tone {
        amplitude,
        omega,
        phase,
    };
    let e = &effect.family().exposing;
    let input = match e.drive {
        Drive::Corners(points) => corners(points.iter().map(|&(t, share)| (t, share * u))),
        Drive::Alone { omega } => Input::Tones {
            offset: [0.0; 3],
            tones: [vec![sine(u, omega, 0.0)], vec![], vec![]],
        },
        Drive::Multisine(omegas) => Input::Tones {
            offset: [0.0; 3],
            tones: crate::simulation::input::PAPER_PHASES.map(|phase| {
                omegas
                    .iter()
                    .enumerate()
                    .map(|(k, &w)| sine(0.25 * u, w, phase + k as f64))
                    .collect()
            }),
        },
        Drive::Levels { omega, switch } => {
            let n = (e.t_end / DT).round() as usize;
            Input::sampled(
                (0..=n).map(|k| k as f64 * DT).collect(),
                (0..=n)
                    .map(|k| {
                        let t = k as f64 * DT;
                        let a = if t < switch { 0.5 * u } else { u };
                        [a * (omega * t).sin(); 3]
                    })
                    .collect(),
                Interpolation::Linear,
            )
            .expect("increasing times, finite values")
        }
    };
    Exposing {
        text: e.text,
        input,
        t_end: e.t_end,
    }
}

/// What simulating one exposing experiment with both tied models shows.
#[derive(Clone, Debug)]
pub struct Separation {
    /// The effect this experiment exposes.
    pub effect: Effect,
    /// The output where the two models' predictions differ most.
    pub channel: Channel,
    /// RMS of their difference there \[m\].
    pub difference: f64,
    /// The measurement noise of that output in the data \[m\].
    pub noise: f64,
}

impl Separation {
    /// Whether the experiment would tell the two models apart.
    pub fn separates(&self) -> bool {
        self.difference > SEPARATES * self.noise
    }
}

/// Outputs of `params` driven by `e`, on the channels of `data`, every [`DT`].
fn predict(
    params: &Params,
    e: &Exposing,
    data: &Experiment,
    rtol: f64,
) -> Result<Vec<Vec<f64>>, Error> {
    let mut sim =
        Simulator::new(Platform::new(params.clone())?, 0.0, rtol).map_err(identify::Error::from)?;
    let mut out = vec![Vec::new(); data.channels.len()];
    sim.run(&e.input, e.t_end, DT, |s| {
        for (o, (c, _)) in out.iter_mut().zip(&data.channels) {
            o.push(c.of(s));
        }
    })
    .map_err(identify::Error::from)?;
    Ok(out)
}

/// Drives the models fitted with effect `a` (`pa`) and with effect `b` (`pb`) by the experiment
/// exposing each, and measures how far apart their predictions come against the noise of `data`.
pub fn separations(
    (a, pa): (Effect, &Params),
    (b, pb): (Effect, &Params),
    data: &Experiment,
    rtol: f64,
) -> Result<Vec<Separation>, Error> {
    let u = analysis::peak_command(data);
    [a, b]
        .into_iter()
        .map(|effect| {
            let e = exposing(effect, u);
            let (ya, yb) = (predict(pa, &e, data, rtol)?, predict(pb, &e, data, rtol)?);
            let best = data
                .channels
                .iter()
                .zip(ya.iter().zip(&yb))
                .map(|((c, y), (sa, sb))| {
                    let d2 = sa.iter().zip(sb).map(|(p, q)| (p - q).powi(2)).sum::<f64>();
                    Separation {
                        effect,
                        channel: *c,
                        difference: (d2 / sa.len().max(1) as f64).sqrt(),
                        noise: analysis::noise_level(&data.t, y),
                    }
                })
                .max_by(|x, y| (x.difference / x.noise).total_cmp(&(y.difference / y.noise)))
                .expect("an experiment has an output");
            Ok(best)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::hidden::{self, Truth};
    use crate::identify::synth::Columns;

    #[test]
    fn a_multisine_separates_a_lag_from_a_delay_that_the_paper_sine_cannot() {
        let case = hidden::hide(Truth::Nothing, 1)
            .unwrap()
            .with_protocol(hidden::Protocol::PAPER.lasting(2.0));
        let data = &case.experiments(Columns::Heights, 1).unwrap()[0];
        let mut lag = case.params.clone();
        lag.set("tau_a", 0.01).unwrap();
        let mut delay = case.params.clone();
        delay.set("tau_d", 0.01).unwrap();
        let s = separations(
            (Effect::AmplifierLag, &lag),
            (Effect::Delay, &delay),
            data,
            identify::FIT_RTOL,
        )
        .unwrap();
        assert!(s.iter().all(|s| s.separates()), "{s:?}");
        // and it is the fast tones that do it: the same models agree within the noise on a
        // slow sine
        let slow = Exposing {
            text: "",
            input: Input::sine(60.0, 1.0),
            t_end: 6.0,
        };
        let (ya, yb) = (
            predict(&lag, &slow, data, identify::FIT_RTOL).unwrap(),
            predict(&delay, &slow, data, identify::FIT_RTOL).unwrap(),
        );
        let d = ya[0]
            .iter()
            .zip(&yb[0])
            .map(|(p, q)| (p - q).powi(2))
            .sum::<f64>()
            / ya[0].len() as f64;
        let noise = analysis::noise_level(&data.t, &data.channels[0].1);
        assert!(d.sqrt() < SEPARATES * noise, "{} vs {noise}", d.sqrt());
    }
}
