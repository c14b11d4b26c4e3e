//! Input voltages U1..U3 as functions of time: the paper's sine, the offset sine, multisines and
//! sampled inputs with a documented interpolation. An input is split into smooth pieces at its
//! breakpoints, so the integrator stops exactly there and restarts rather than stepping blindly
//! over a jump or a kink; a C² spline is smooth enough to be stepped across.

use serde::{Deserialize, Serialize};

/// One sinusoid A sin(ω t + φ) [V, rad/s, rad].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tone {
    pub amplitude: f64,
    pub omega: f64,
    pub phase: f64,
}

/// How a sampled input is read between its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Interpolation {
    /// Sample k holds from t_k until t_{k+1} (what a co-simulation master with ZOH inputs does).
    /// The integrator stops and restarts at every sample.
    ZeroOrderHold,
    /// Piecewise linear: continuous, with a kink at every sample (a stop at each).
    Linear,
    /// Monotone piecewise-cubic Hermite (Fritsch–Carlson): continuous slope, no overshoot; its
    /// second derivative jumps at the samples, where the integrator stops.
    Pchip,
    /// Natural cubic spline: continuous second derivative, so the integrator steps across the
    /// samples; the cheapest way to replay a densely sampled smooth signal.
    Spline,
    /// A measured command (book/src/identify.md, "How an experiment is simulated"): the
    /// natural spline through each smooth run of samples, and the command held across a step
    /// (a change from one sample to the next larger than `STEP_MIN`, at a rate `STEP_RATIO`
    /// times both neighbouring intervals' rates: a gap of dropped rows is no step), where the integrator stops exactly, as with zero-order hold.
    /// A staircase replays as steps, a sine or a chirp as one spline.
    Measured,
}

/// A change between two samples of a measured command is a step when it exceeds this \[V\]…
const STEP_MIN: f64 = 0.5;
/// …and this many times the changes before and after it.
const STEP_RATIO: f64 = 4.0;

/// Why samples cannot make a sampled input.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InputError {
    #[error("{times} sample times but {voltages} voltage samples")]
    Lengths { times: usize, voltages: usize },
    #[error("{0} samples: a sampled input needs at least 2")]
    TooFew(usize),
    #[error("sample {sample}: time {t} is not finite")]
    TimeNotFinite { sample: usize, t: f64 },
    #[error("sample {sample}: time {t} does not increase from {previous}")]
    NotIncreasing {
        sample: usize,
        t: f64,
        previous: f64,
    },
    #[error("sample {sample}: voltages {u:?} are not finite")]
    VoltageNotFinite { sample: usize, u: [f64; 3] },
    /// Voltages or time steps so far out of range that the interpolation's slope overflows.
    #[error(
        "sample {sample}: the voltages change faster than a number can hold (slope {slope:?} V/s)"
    )]
    SlopeNotFinite { sample: usize, slope: [f64; 3] },
}

/// Samples `u[k]` at strictly increasing `t[k]`, with the knot slopes of the interpolation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Samples {
    t: Vec<f64>,
    u: Vec<[f64; 3]>,
    interpolation: Interpolation,
    /// du/dt at the samples for the cubic interpolations (empty otherwise).
    slopes: Vec<[f64; 3]>,
    /// For a measured command, the intervals [t_k, t_{k+1}) it steps in, by k, increasing.
    #[serde(default)]
    steps: Vec<usize>,
}

impl Samples {
    /// The number of samples at or before `t`, as `t.partition_point(|tk| tk <= t)`, searched
    /// outward from where even sampling puts `t`: the solver asks at every stage, and bisecting a
    /// long record there took a twentieth of a diagnosis.
    fn count_until(&self, t: f64) -> usize {
        let ts = &self.t;
        let n = ts.len();
        let (Some(&first), Some(&last)) = (ts.first(), ts.last()) else {
            return 0;
        };
        // `as` saturates: a time before the record (or NaN) guesses 0, after it n − 1
        let g = ((t - first) / (last - first) * (n - 1) as f64) as usize;
        let g = g.min(n - 1);
        // widen by doubling steps to an interval that holds the answer, then bisect it
        let (lo, hi) = if ts[g] <= t {
            let (mut lo, mut step) = (g + 1, 1);
            while lo + step <= n && ts[lo + step - 1] <= t {
                lo += step;
                step *= 2;
            }
            (lo, (lo + step).min(n))
        } else {
            let (mut hi, mut step) = (g, 1);
            while hi >= step && ts[hi - step] > t {
                hi -= step;
                step *= 2;
            }
            (hi.saturating_sub(step), hi)
        };
        lo + ts[lo..hi].partition_point(|&tk| tk <= t)
    }
}

/// The three actuator voltages over time \[V\].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Input {
    /// Per actuator: offset + Σ tones (sine, offset sine and multisine are all of this form).
    Tones {
        offset: [f64; 3],
        tones: [Vec<Tone>; 3],
    },
    /// Sampled voltages, held at the first value before the first sample and at the last after.
    Sampled(Samples),
}

/// The phases of the paper's excitation: 0°, 120°, 240°.
pub const PAPER_PHASES: [f64; 3] = [
    0.0,
    2.0 * std::f64::consts::FRAC_PI_3,
    4.0 * std::f64::consts::FRAC_PI_3,
];

impl Input {
    /// The paper's excitation u_i(t) = U0 sin(ω t + φ_i), φ = 0°, 120°, 240°.
    pub fn sine(u0: f64, omega: f64) -> Input {
        Input::Tones {
            offset: [0.0; 3],
            tones: PAPER_PHASES.map(|phase| {
                vec![Tone {
                    amplitude: u0,
                    omega,
                    phase,
                }]
            }),
        }
    }

    /// The unipolar form u_i(t) = U0 (1 + sin(ω t + φ_i)) / 2.
    pub fn offset_sine(u0: f64, omega: f64) -> Input {
        Input::Tones {
            offset: [0.5 * u0; 3],
            tones: PAPER_PHASES.map(|phase| {
                vec![Tone {
                    amplitude: 0.5 * u0,
                    omega,
                    phase,
                }]
            }),
        }
    }

    /// A constant voltage on each actuator.
    pub fn constant(u: [f64; 3]) -> Input {
        Input::Tones {
            offset: u,
            tones: [vec![], vec![], vec![]],
        }
    }

    /// A sampled input; at least two samples, strictly increasing finite times, finite values.
    pub fn sampled(
        t: Vec<f64>,
        u: Vec<[f64; 3]>,
        interpolation: Interpolation,
    ) -> Result<Input, InputError> {
        if t.len() != u.len() {
            return Err(InputError::Lengths {
                times: t.len(),
                voltages: u.len(),
            });
        }
        if t.len() < 2 {
            return Err(InputError::TooFew(t.len()));
        }
        if let Some(k) = (0..t.len()).find(|&k| !t[k].is_finite()) {
            return Err(InputError::TimeNotFinite { sample: k, t: t[k] });
        }
        if let Some(k) = (1..t.len()).find(|&k| t[k] <= t[k - 1]) {
            return Err(InputError::NotIncreasing {
                sample: k,
                t: t[k],
                previous: t[k - 1],
            });
        }
        if let Some(k) = (0..u.len()).find(|&k| !u[k].iter().all(|v| v.is_finite())) {
            return Err(InputError::VoltageNotFinite { sample: k, u: u[k] });
        }
        let steps = if interpolation == Interpolation::Measured {
            steps(&t, &u)
        } else {
            Vec::new()
        };
        let slopes = match interpolation {
            Interpolation::Pchip => (0..t.len()).map(|k| pchip_slope(&t, &u, k)).collect(),
            Interpolation::Spline => spline_slopes(&t, &u),
            Interpolation::Measured => runs(t.len(), &steps)
                .flat_map(|(a, b)| {
                    if a == b {
                        vec![[0.0; 3]]
                    } else {
                        spline_slopes(&t[a..=b], &u[a..=b])
                    }
                })
                .collect(),
            Interpolation::ZeroOrderHold | Interpolation::Linear => Vec::new(),
        };
        // found by fuzzing (tests/fuzz, csv_input): voltages near f64::MAX, or a large change
        // over a tiny time step, gave NaN between and at the samples
        let secants =
            (1..t.len()).map(|k| [0, 1, 2].map(|i| (u[k][i] - u[k - 1][i]) / (t[k] - t[k - 1])));
        if let Some((k, slope)) = secants
            .chain(slopes.iter().copied())
            .enumerate()
            .find(|(_, m)| !m.iter().all(|v| v.is_finite()))
        {
            let sample = if k < t.len() - 1 {
                k + 1
            } else {
                k + 1 - t.len()
            };
            return Err(InputError::SlopeNotFinite { sample, slope });
        }
        Ok(Input::Sampled(Samples {
            t,
            u,
            interpolation,
            slopes,
            steps,
        }))
    }

    /// The last sample time of a sampled input.
    pub fn last_sample(&self) -> Option<f64> {
        match self {
            Input::Sampled(s) => s.t.last().copied(),
            Input::Tones { .. } => None,
        }
    }

    /// The smooth piece that starts at `t` and the time it ends (a breakpoint, or +∞).
    pub fn piece_at(&self, t: f64) -> (Piece<'_>, f64) {
        let s = match self {
            Input::Tones { offset, tones } => {
                return (Piece::Tones { offset, tones }, f64::INFINITY);
            }
            Input::Sampled(s) => s,
        };
        let (ts, u) = (&s.t, &s.u);
        // index of the sample interval [t_k, t_{k+1}) containing t
        let k = s.count_until(t);
        if k == 0 {
            return (Piece::Constant(u[0]), ts[0]);
        }
        if k == ts.len() {
            return (Piece::Constant(u[k - 1]), f64::INFINITY);
        }
        let k = k - 1;
        let segment = |m0: [f64; 3], m1: [f64; 3]| Piece::Hermite {
            t0: ts[k],
            h: ts[k + 1] - ts[k],
            u0: u[k],
            u1: u[k + 1],
            m0,
            m1,
        };
        match s.interpolation {
            Interpolation::ZeroOrderHold => (Piece::Constant(u[k]), ts[k + 1]),
            Interpolation::Linear => {
                let h = ts[k + 1] - ts[k];
                let slope = [0, 1, 2].map(|i| (u[k + 1][i] - u[k][i]) / h);
                (segment(slope, slope), ts[k + 1])
            }
            Interpolation::Pchip => (segment(s.slopes[k], s.slopes[k + 1]), ts[k + 1]),
            Interpolation::Spline => (Piece::Spline(s), ts[ts.len() - 1]),
            Interpolation::Measured => {
                // the step at or after interval k: held through it, else the spline up to it
                let j = s.steps.partition_point(|&step| step < k);
                match s.steps.get(j) {
                    Some(&step) if step == k => (Piece::Constant(u[k]), ts[k + 1]),
                    Some(&step) => (Piece::Spline(s), ts[step]),
                    None => (Piece::Spline(s), ts[ts.len() - 1]),
                }
            }
        }
    }

    /// U(t), reading a sampled input from the right at a sample time.
    pub fn value(&self, t: f64) -> [f64; 3] {
        self.piece_at(t).0.value(t)
    }
}

/// Fritsch–Carlson slope at sample k: the weighted harmonic mean of the neighbouring secants
/// where they agree in sign, zero where they do not, one-sided at the ends.
fn pchip_slope(t: &[f64], u: &[[f64; 3]], k: usize) -> [f64; 3] {
    let secant = |j: usize, i: usize| (u[j + 1][i] - u[j][i]) / (t[j + 1] - t[j]);
    let last = t.len() - 1;
    [0, 1, 2].map(|i| {
        if k == 0 {
            return secant(0, i);
        }
        if k == last {
            return secant(last - 1, i);
        }
        let (d0, d1) = (secant(k - 1, i), secant(k, i));
        if d0 * d1 <= 0.0 {
            return 0.0;
        }
        let (h0, h1) = (t[k] - t[k - 1], t[k + 1] - t[k]);
        let (w0, w1) = (2.0 * h1 + h0, h1 + 2.0 * h0);
        (w0 + w1) / (w0 / d0 + w1 / d1)
    })
}

/// The intervals a measured command steps in (see [`Interpolation::Measured`]), on any of the
/// three channels.
fn steps(t: &[f64], u: &[[f64; 3]]) -> Vec<usize> {
    // rates, not differences: a gap of dropped rows is no step
    let rate = |k: usize, i: usize| -> f64 {
        if k + 1 < u.len() {
            (u[k + 1][i] - u[k][i]).abs() / (t[k + 1] - t[k])
        } else {
            0.0
        }
    };
    (0..u.len() - 1)
        .filter(|&k| {
            (0..3).any(|i| {
                let before = if k > 0 { rate(k - 1, i) } else { 0.0 };
                (u[k + 1][i] - u[k][i]).abs() > STEP_MIN
                    && rate(k, i) > STEP_RATIO * before.max(rate(k + 1, i))
            })
        })
        .collect()
}

/// The smooth runs of samples between `steps` of a command of `n` samples, as first and last
/// sample (a run of one sample is its own spline: slope 0).
fn runs(n: usize, steps: &[usize]) -> impl Iterator<Item = (usize, usize)> + '_ {
    let starts = std::iter::once(0).chain(steps.iter().map(|&k| k + 1));
    let ends = steps.iter().copied().chain(std::iter::once(n - 1));
    starts.zip(ends)
}

/// Knot slopes of the natural cubic spline (zero second derivative at both ends), from its
/// tridiagonal system solved by the Thomas algorithm:
/// h_k m_{k−1} + 2 (h_{k−1} + h_k) m_k + h_{k−1} m_{k+1} = 3 (h_k d_{k−1} + h_{k−1} d_k).
fn spline_slopes(t: &[f64], u: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let n = t.len();
    let h: Vec<f64> = (0..n - 1).map(|k| t[k + 1] - t[k]).collect();
    let d: Vec<[f64; 3]> = (0..n - 1)
        .map(|k| [0, 1, 2].map(|i| (u[k + 1][i] - u[k][i]) / h[k]))
        .collect();
    // rows: sub a, diagonal b, super c, right-hand side r
    let (mut a, mut b, mut c) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut r = vec![[0.0; 3]; n];
    (b[0], c[0], r[0]) = (2.0, 1.0, d[0].map(|x| 3.0 * x));
    for k in 1..n - 1 {
        (a[k], b[k], c[k]) = (h[k], 2.0 * (h[k - 1] + h[k]), h[k - 1]);
        r[k] = [0, 1, 2].map(|i| 3.0 * (h[k] * d[k - 1][i] + h[k - 1] * d[k][i]));
    }
    (a[n - 1], b[n - 1], r[n - 1]) = (1.0, 2.0, d[n - 2].map(|x| 3.0 * x));
    for k in 1..n {
        let w = a[k] / b[k - 1];
        b[k] -= w * c[k - 1];
        r[k] = [0, 1, 2].map(|i| r[k][i] - w * r[k - 1][i]);
    }
    let mut m = vec![[0.0; 3]; n];
    m[n - 1] = r[n - 1].map(|x| x / b[n - 1]);
    for k in (0..n - 1).rev() {
        m[k] = [0, 1, 2].map(|i| (r[k][i] - c[k] * m[k + 1][i]) / b[k]);
    }
    m
}

/// An input restricted to an interval on which it is smooth, evaluated also at the interval's
/// closed end (a held sample applies up to and including the end of its step).
#[derive(Clone, Copy, Debug)]
pub enum Piece<'a> {
    Constant([f64; 3]),
    Tones {
        offset: &'a [f64; 3],
        tones: &'a [Vec<Tone>; 3],
    },
    /// Cubic Hermite on [t0, t0 + h] with end values u0, u1 and end slopes m0, m1.
    Hermite {
        t0: f64,
        h: f64,
        u0: [f64; 3],
        u1: [f64; 3],
        m0: [f64; 3],
        m1: [f64; 3],
    },
    /// The natural cubic spline through all samples, on [t_first, t_last].
    Spline(&'a Samples),
}

/// Cubic Hermite value at s ∈ [0, 1] of an interval of length h.
fn hermite(s: f64, h: f64, u0: [f64; 3], u1: [f64; 3], m0: [f64; 3], m1: [f64; 3]) -> [f64; 3] {
    let (s2, s3) = (s * s, s * s * s);
    let (h00, h10, h01, h11) = (
        2.0 * s3 - 3.0 * s2 + 1.0,
        s3 - 2.0 * s2 + s,
        -2.0 * s3 + 3.0 * s2,
        s3 - s2,
    );
    [0, 1, 2].map(|i| h00 * u0[i] + h10 * h * m0[i] + h01 * u1[i] + h11 * h * m1[i])
}

impl Piece<'_> {
    pub fn value(&self, t: f64) -> [f64; 3] {
        match *self {
            Piece::Constant(u) => u,
            Piece::Tones { offset, tones } => [0, 1, 2].map(|i| {
                offset[i]
                    + tones[i]
                        .iter()
                        .map(|c| c.amplitude * (c.omega * t + c.phase).sin())
                        .sum::<f64>()
            }),
            Piece::Hermite {
                t0,
                h,
                u0,
                u1,
                m0,
                m1,
            } => hermite((t - t0) / h, h, u0, u1, m0, m1),
            Piece::Spline(s) => {
                let k = s.count_until(t).clamp(1, s.t.len() - 1) - 1;
                let h = s.t[k + 1] - s.t[k];
                hermite(
                    (t - s.t[k]) / h,
                    h,
                    s.u[k],
                    s.u[k + 1],
                    s.slopes[k],
                    s.slopes[k + 1],
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The search from the guess finds what bisection finds: on even and uneven sampling
    /// (rows dropped, a jitter), at, between, before and after the samples.
    #[test]
    fn a_sample_is_found_as_bisection_finds_it() {
        let even: Vec<f64> = (0..1000).map(|k| 1.62 + k as f64 * 1e-3).collect();
        let uneven: Vec<f64> = (0..1000)
            .filter(|k| k % 7 != 3 && !(400..460).contains(k))
            .map(|k| k as f64 * 1e-3 + 3e-4 * ((k * k) % 5) as f64 / 5.0)
            .collect();
        for t in [even, uneven] {
            let u = vec![[0.0; 3]; t.len()];
            let Input::Sampled(s) = Input::sampled(t.clone(), u, Interpolation::Linear).unwrap()
            else {
                unreachable!()
            };
            let (a, b) = (t[0] - 0.1, t[t.len() - 1] + 0.1);
            let probes = (0..=20_000).map(|k| a + (b - a) * k as f64 / 20_000.0);
            for x in
                probes
                    .chain(t.iter().copied())
                    .chain([f64::NAN, f64::INFINITY, f64::NEG_INFINITY])
            {
                assert_eq!(
                    s.count_until(x),
                    t.partition_point(|&tk| tk <= x),
                    "t = {x}"
                );
            }
        }
    }

    /// A measured staircase replays as steps: held across each, the integrator stopping at the
    /// sample after it; a sine sampled the same way stays one spline.
    #[test]
    fn a_measured_command_steps_where_it_jumps() {
        let t: Vec<f64> = (0..=40).map(|k| k as f64 * 1e-3).collect();
        let stair = |tk: f64| {
            if tk < 0.0155 {
                10.0
            } else if tk < 0.0305 {
                40.0
            } else {
                25.0
            }
        };
        let u: Vec<[f64; 3]> = t.iter().map(|&tk| [stair(tk), 0.0, 1.0]).collect();
        let input = Input::sampled(t.clone(), u, Interpolation::Measured).unwrap();
        // held across the step in [15, 16) ms, no overshoot anywhere
        let (piece, end) = input.piece_at(0.0152);
        assert!(matches!(piece, Piece::Constant(v) if v[0] == 10.0) && end == 0.016);
        let (_, end) = input.piece_at(0.002);
        assert_eq!(end, 0.015);
        for k in 0..4000 {
            let v = input.value(k as f64 * 1e-5)[0];
            assert!(
                (10.0 - 1e-9..=40.0 + 1e-9).contains(&v),
                "{v} at {} ms",
                k as f64 * 1e-2
            );
        }
        let u: Vec<[f64; 3]> = t.iter().map(|&tk| [60.0 * (30.0 * tk).sin(); 3]).collect();
        let input = Input::sampled(t, u, Interpolation::Measured).unwrap();
        assert!(matches!(input.piece_at(0.0), (Piece::Spline(_), end) if end == 0.04));
    }

    #[test]
    fn paper_sine_has_its_phases() {
        let u = Input::sine(60.0, 3.0 * std::f64::consts::PI).value(0.0);
        assert_eq!(u[0], 0.0);
        assert!((u[1] - 51.96152422707).abs() < 1e-9 && (u[2] + 51.96152422707).abs() < 1e-9);
        let v = Input::offset_sine(60.0, 11.0).value(0.0);
        assert!((v[0] - 30.0).abs() < 1e-12);
    }

    #[test]
    fn sampled_pieces_end_at_the_next_sample() {
        let t = vec![0.0, 1.0, 2.0, 3.0];
        let u = vec![[0.0; 3], [1.0; 3], [3.0; 3], [2.0; 3]];
        for interp in [
            Interpolation::ZeroOrderHold,
            Interpolation::Linear,
            Interpolation::Pchip,
            Interpolation::Spline,
        ] {
            let inp = Input::sampled(t.clone(), u.clone(), interp).unwrap();
            let (piece, end) = inp.piece_at(1.0);
            // the C² spline is one piece over all samples
            assert_eq!(
                end,
                if interp == Interpolation::Spline {
                    3.0
                } else {
                    2.0
                }
            );
            assert_eq!(piece.value(1.0), [1.0; 3]);
            let at_end = piece.value(2.0)[0];
            let want = if interp == Interpolation::ZeroOrderHold {
                1.0
            } else {
                3.0
            };
            assert!((at_end - want).abs() < 1e-14, "{interp:?}: {at_end}");
            assert_eq!(inp.piece_at(7.0).1, f64::INFINITY);
            assert_eq!(inp.value(7.0), [2.0; 3]);
        }
        // the monotone cubic does not overshoot the local maximum at t = 2
        let inp = Input::sampled(t, u, Interpolation::Pchip).unwrap();
        assert!((0..=100).all(|k| inp.value(1.0 + k as f64 / 50.0)[0] <= 3.0));
    }

    #[test]
    fn the_spline_is_twice_continuously_differentiable_and_natural() {
        let t: Vec<f64> = (0..12)
            .map(|k| k as f64 * 0.3 + 0.01 * (k * k) as f64)
            .collect();
        let u: Vec<[f64; 3]> = t
            .iter()
            .map(|&x| [x.sin(), x * x, 1.0 / (1.0 + x)])
            .collect();
        let inp = Input::sampled(t.clone(), u.clone(), Interpolation::Spline).unwrap();
        let d2 = |x: f64, i: usize| {
            let e = 1e-4;
            (inp.value(x + e)[i] - 2.0 * inp.value(x)[i] + inp.value(x - e)[i]) / (e * e)
        };
        for k in 1..t.len() - 1 {
            let e = 1e-3;
            for (i, uki) in u[k].iter().enumerate() {
                assert!((inp.value(t[k])[i] - uki).abs() < 1e-14);
                assert!(
                    (d2(t[k] - e, i) - d2(t[k] + e, i)).abs() < 0.05,
                    "u'' jumps at knot {k}"
                );
            }
        }
        assert!(d2(t[0] + 1e-3, 0).abs() < 0.05 && d2(t[11] - 1e-3, 1).abs() < 0.1);
    }

    #[test]
    fn bad_samples_are_refused() {
        assert!(
            Input::sampled(vec![0.0], vec![[0.0; 3]], Interpolation::Linear)
                .unwrap_err()
                .to_string()
                .contains("at least 2")
        );
        assert!(
            Input::sampled(vec![0.0, 0.0], vec![[0.0; 3]; 2], Interpolation::Linear)
                .unwrap_err()
                .to_string()
                .contains("does not increase")
        );
        assert!(
            Input::sampled(
                vec![0.0, 1.0],
                vec![[0.0; 3], [f64::NAN; 3]],
                Interpolation::Linear
            )
            .unwrap_err()
            .to_string()
            .contains("not finite")
        );
    }

    /// Found by fuzzing (tests/fuzz, csv_input): finite samples whose interpolation overflows.
    #[test]
    fn an_interpolation_that_overflows_is_refused() {
        let t = vec![0.0, 1.0, 2.0, 3.0];
        let huge = vec![
            [1e308, 0.0, 0.0],
            [-1e308, 0.0, 0.0],
            [1e308, 0.0, 0.0],
            [0.0; 3],
        ];
        let steep = vec![[0.0; 3], [0.0, 1e10, 0.0], [0.0; 3], [0.0; 3]];
        let tiny = vec![0.0, 1e-300, 1.0, 2.0];
        for how in [
            Interpolation::ZeroOrderHold,
            Interpolation::Linear,
            Interpolation::Pchip,
            Interpolation::Spline,
            Interpolation::Measured,
        ] {
            let e = Input::sampled(t.clone(), huge.clone(), how).unwrap_err();
            assert!(
                e.to_string()
                    .starts_with("sample 1: the voltages change faster"),
                "{e}"
            );
            let e = Input::sampled(tiny.clone(), steep.clone(), how).unwrap_err();
            assert!(
                e.to_string()
                    .starts_with("sample 1: the voltages change faster"),
                "{e}"
            );
            assert!(Input::sampled(t.clone(), steep.clone(), how).is_ok());
        }
    }
}
