//! Where and how the model disagrees with the data: per experiment and output, the residual
//! against the measurement noise, its harmonics of the drive, its drift, the time window where
//! it is worst, and its correlation with the signals a missing effect would follow.

use crate::identify::{Channel, Experiment};
use crate::simulation::Sample;

/// Highest harmonic of the drive examined.
pub const HARMONICS: usize = 6;

/// Number of time windows the record is split into to find where the model is worst.
const WINDOWS: usize = 12;

/// The disagreement on one output of one experiment.
#[derive(Clone, Debug)]
pub struct Disagreement {
    pub experiment: String,
    pub channel: Channel,
    /// Residual (measured − simulated) RMS [m].
    pub rms: f64,
    /// Measurement noise estimated from the data's second differences [m].
    pub noise: f64,
    /// Residual variance beyond the noise, as a fraction of the noise variance (0 at the
    /// noise floor).
    pub excess: f64,
    /// Drive frequency found in U1 [rad/s].
    pub omega: f64,
    /// Residual amplitude at k·ω, k = 0 (mean) … HARMONICS [m].
    pub harmonics: Vec<f64>,
    /// Mean residual over the last quarter minus the first quarter [m].
    pub drift: f64,
    /// The window of the record where the residual RMS is largest: (start, end) [s], RMS [m].
    pub worst_window: ((f64, f64), f64),
    /// Correlation of the residual with: the other outputs' simulated values, the simulated
    /// velocity, its sign, U² of the own actuator (for heights) or of the sum (tip); and of its
    /// size with the output's distance from its mean (amplitude dependence).
    pub correlations: Vec<(String, f64)>,
    /// Share of the residual power at frequencies that are not harmonics of the drive nor slow
    /// (below ω/2): structure no term driven by U can produce.
    pub off_harmonic: f64,
}

/// Measurement noise from second differences: a smooth signal's second difference at 1 ms is
/// negligible, white noise's has variance 6 σ².
pub fn noise_level(y: &[f64]) -> f64 {
    let n = y.len();
    if n < 3 {
        return 0.0;
    }
    let s: f64 = (1..n - 1)
        .map(|k| (y[k + 1] - 2.0 * y[k] + y[k - 1]).powi(2))
        .sum();
    (s / (6.0 * (n - 2) as f64)).sqrt()
}

/// Drive frequency from the zero crossings of U1 − mean [rad/s].
pub fn drive_frequency(exp: &Experiment) -> f64 {
    let u: Vec<f64> = exp.t.iter().map(|&t| exp.input.value(t)[0]).collect();
    let mean = u.iter().sum::<f64>() / u.len() as f64;
    let crossings: Vec<f64> = (1..u.len())
        .filter(|&k| (u[k - 1] - mean) * (u[k] - mean) < 0.0)
        .map(|k| exp.t[k])
        .collect();
    if crossings.len() < 3 {
        return 0.0;
    }
    let span = crossings[crossings.len() - 1] - crossings[0];
    std::f64::consts::PI * (crossings.len() - 1) as f64 / span
}

/// The largest |U_i| commanded in an experiment [V].
pub fn peak_command(exp: &Experiment) -> f64 {
    exp.t
        .iter()
        .flat_map(|&t| exp.input.value(t))
        .fold(0.0, |m: f64, u| m.max(u.abs()))
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma).powi(2);
        sbb += (y - mb).powi(2);
    }
    if saa == 0.0 || sbb == 0.0 {
        0.0
    } else {
        sab / (saa * sbb).sqrt()
    }
}

/// Amplitude of the component of `r` at frequency `w` over times `t` (least squares on
/// sin and cos; the mean for w = 0).
fn amplitude(t: &[f64], r: &[f64], w: f64) -> f64 {
    let n = t.len() as f64;
    if w == 0.0 {
        return (r.iter().sum::<f64>() / n).abs();
    }
    let (mut s, mut c) = (0.0, 0.0);
    for (ti, ri) in t.iter().zip(r) {
        s += ri * (w * ti).sin();
        c += ri * (w * ti).cos();
    }
    2.0 * (s * s + c * c).sqrt() / n
}

/// The disagreement of `sim` with `exp` on every measured output.
pub fn disagreements(exp: &Experiment, sim: &[Sample]) -> Vec<Disagreement> {
    let omega = drive_frequency(exp);
    let t = &exp.t;
    let n = t.len();
    exp.channels
        .iter()
        .map(|(channel, y)| {
            let yhat: Vec<f64> = sim.iter().map(|s| channel.of(s)).collect();
            let r: Vec<f64> = y.iter().zip(&yhat).map(|(a, b)| a - b).collect();
            let rms = (r.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
            let noise = noise_level(y);
            let excess = if noise > 0.0 {
                (rms / noise).powi(2) - 1.0
            } else {
                f64::INFINITY
            };
            let harmonics: Vec<f64> = (0..=HARMONICS)
                .map(|k| amplitude(t, &r, k as f64 * omega))
                .collect();
            let q = n / 4;
            let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len().max(1) as f64;
            let drift = mean(&r[n - q..]) - mean(&r[..q]);
            let w = n / WINDOWS;
            let worst_window = (0..WINDOWS)
                .map(|k| {
                    let s = &r[k * w..((k + 1) * w).min(n)];
                    let rms = (s.iter().map(|v| v * v).sum::<f64>() / s.len() as f64).sqrt();
                    ((t[k * w], t[((k + 1) * w).min(n) - 1]), rms)
                })
                .fold(((0.0, 0.0), -1.0), |a, b| if b.1 > a.1 { b } else { a });
            let velocity: Vec<f64> = (0..n)
                .map(|k| {
                    let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
                    (yhat[b] - yhat[a]) / (t[b] - t[a])
                })
                .collect();
            let sign: Vec<f64> = velocity.iter().map(|v| v.signum()).collect();
            let u2: Vec<f64> = t
                .iter()
                .map(|&tk| {
                    let u = exp.input.value(tk);
                    match channel {
                        Channel::H(i) => u[*i] * u[*i],
                        Channel::Tip(_) => u.iter().map(|v| v * v).sum(),
                    }
                })
                .collect();
            let mut correlations = Vec::new();
            for other in exp
                .channels
                .iter()
                .map(|(c, _)| *c)
                .filter(|c| c != channel)
            {
                let s: Vec<f64> = sim.iter().map(|x| other.of(x)).collect();
                correlations.push((format!("simulated {}", other.name()), correlation(&r, &s)));
            }
            correlations.push(("velocity".into(), correlation(&r, &velocity)));
            correlations.push(("sign of velocity".into(), correlation(&r, &sign)));
            correlations.push(("U^2".into(), correlation(&r, &u2)));
            // amplitude dependence: does the misfit grow where the output swings far?
            let mean_hat = yhat.iter().sum::<f64>() / n as f64;
            let level: Vec<f64> = yhat.iter().map(|v| (v - mean_hat).abs()).collect();
            let size: Vec<f64> = r.iter().map(|v| v.abs()).collect();
            correlations.push((
                "|residual| with |output - mean|".into(),
                correlation(&size, &level),
            ));
            let explained: f64 =
                harmonics[1..].iter().map(|a| 0.5 * a * a).sum::<f64>() + harmonics[0].powi(2);
            let slow = slow_power(t, &r, 0.5 * omega);
            let structured = (rms * rms - noise * noise).max(0.0);
            let off_harmonic = if structured > 0.0 {
                ((structured - explained - slow) / structured).clamp(0.0, 1.0)
            } else {
                0.0
            };
            Disagreement {
                experiment: exp.name.clone(),
                channel: *channel,
                rms,
                noise,
                excess,
                omega,
                harmonics,
                drift,
                worst_window,
                correlations,
                off_harmonic,
            }
        })
        .collect()
}

/// Power of `r` below `w_max` beyond its mean: a moving average over one period of w_max.
fn slow_power(t: &[f64], r: &[f64], w_max: f64) -> f64 {
    if w_max <= 0.0 || t.len() < 2 {
        return 0.0;
    }
    let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    let m = ((2.0 * std::f64::consts::PI / w_max / dt) as usize).clamp(1, t.len());
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    let mut acc: f64 = r[..m].iter().sum();
    let mut p = 0.0;
    let mut count = 0;
    for k in m..=r.len() {
        p += (acc / m as f64 - mean).powi(2);
        count += 1;
        if k < r.len() {
            acc += r[k] - r[k - m];
        }
    }
    p / count as f64
}
