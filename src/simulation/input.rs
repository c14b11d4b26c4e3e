//! Input voltages U1..U3 as functions of time: the paper's sine, the offset sine, multisines and
//! sampled inputs with a documented interpolation. An input is split into smooth pieces at its
//! breakpoints (the samples of a sampled input), so the integrator stops exactly there and
//! restarts, rather than stepping blindly over a jump or a kink.

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
    ZeroOrderHold,
    /// Piecewise linear: continuous, with a kink at every sample.
    Linear,
    /// Monotone piecewise-cubic Hermite (Fritsch–Carlson): continuous slope, no overshoot.
    Pchip,
}

/// The three actuator voltages over time [V].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Input {
    /// Per actuator: offset + Σ tones (sine, offset sine and multisine are all of this form).
    Tones {
        offset: [f64; 3],
        tones: [Vec<Tone>; 3],
    },
    /// Samples `u[k]` at strictly increasing `t[k]`; held at the last value after the end.
    Sampled {
        t: Vec<f64>,
        u: Vec<[f64; 3]>,
        interpolation: Interpolation,
    },
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

    /// The smooth piece that starts at `t` and the time it ends (a breakpoint, or +∞).
    pub fn piece_at(&self, t: f64) -> (Piece<'_>, f64) {
        match self {
            Input::Tones { offset, tones } => (Piece::Tones { offset, tones }, f64::INFINITY),
            Input::Sampled {
                t: ts,
                u,
                interpolation,
            } => {
                // index of the sample interval [t_k, t_{k+1}) containing t
                let k = ts.partition_point(|&tk| tk <= t);
                if k == 0 {
                    return (Piece::Constant(u[0]), ts[0]);
                }
                if k == ts.len() {
                    return (Piece::Constant(u[k - 1]), f64::INFINITY);
                }
                let k = k - 1;
                let piece = match interpolation {
                    Interpolation::ZeroOrderHold => Piece::Constant(u[k]),
                    Interpolation::Linear => {
                        let h = ts[k + 1] - ts[k];
                        let slope = [0, 1, 2].map(|i| (u[k + 1][i] - u[k][i]) / h);
                        Piece::Hermite {
                            t0: ts[k],
                            h,
                            u0: u[k],
                            u1: u[k + 1],
                            m0: slope,
                            m1: slope,
                        }
                    }
                    Interpolation::Pchip => {
                        let (m0, m1) = (pchip_slope(ts, u, k), pchip_slope(ts, u, k + 1));
                        Piece::Hermite {
                            t0: ts[k],
                            h: ts[k + 1] - ts[k],
                            u0: u[k],
                            u1: u[k + 1],
                            m0,
                            m1,
                        }
                    }
                };
                (piece, ts[k + 1])
            }
        }
    }

    /// U(t), reading a sampled input from the right at a sample time.
    pub fn value(&self, t: f64) -> [f64; 3] {
        self.piece_at(t).0.value(t)
    }
}

/// Fritsch–Carlson slope at sample k: the harmonic mean of the neighbouring secants where they
/// agree in sign, zero where they do not, one-sided at the ends.
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
            } => {
                let s = (t - t0) / h;
                let (s2, s3) = (s * s, s * s * s);
                let (h00, h10, h01, h11) = (
                    2.0 * s3 - 3.0 * s2 + 1.0,
                    s3 - 2.0 * s2 + s,
                    -2.0 * s3 + 3.0 * s2,
                    s3 - s2,
                );
                [0, 1, 2].map(|i| h00 * u0[i] + h10 * h * m0[i] + h01 * u1[i] + h11 * h * m1[i])
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        ] {
            let inp = Input::Sampled {
                t: t.clone(),
                u: u.clone(),
                interpolation: interp,
            };
            let (piece, end) = inp.piece_at(1.0);
            assert_eq!(end, 2.0);
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
        let inp = Input::Sampled {
            t,
            u,
            interpolation: Interpolation::Pchip,
        };
        assert!((0..=100).all(|k| inp.value(1.0 + k as f64 / 50.0)[0] <= 3.0));
    }
}
