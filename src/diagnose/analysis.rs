//! Where and how the model disagrees with the data: per experiment and output, the residual
//! against the measurement noise, its harmonics of the drive, its drift, the time window where
//! it is worst, and its correlation with the signals a missing effect would follow.

pub use crate::identify::fit::noise_level;
use crate::identify::fit::{departures, robust_sigma};
use crate::identify::{Channel, Experiment};
use crate::simulation::Sample;

/// Highest harmonic of the drive examined.
const HARMONICS: usize = 6;

/// Number of time windows the record is split into to find where the model is worst.
const WINDOWS: usize = 12;

/// The disagreement on one output of one experiment.
#[derive(Clone, Debug)]
pub struct Disagreement {
    pub experiment: String,
    pub channel: Channel,
    /// Residual (measured − simulated) RMS \[m\].
    pub rms: f64,
    /// Measurement noise estimated from the samples' departures from their neighbours \[m\].
    pub noise: f64,
    /// Residual variance beyond the noise, as a fraction of the noise variance (0 at the
    /// noise floor).
    pub excess: f64,
    /// Drive frequency found in U1 [rad/s].
    pub omega: f64,
    /// Residual amplitude at k·ω, k = 0 (mean) … HARMONICS \[m\].
    pub harmonics: Vec<f64>,
    /// Mean residual over the last quarter minus the first quarter \[m\].
    pub drift: f64,
    /// The window of the record where the residual RMS is largest: (start, end) \[s\], RMS \[m\].
    pub worst_window: ((f64, f64), f64),
    /// Correlation of the residual with: the other outputs' simulated values, the simulated
    /// velocity, its sign, U² of the own actuator (for heights) or of the sum (tip); and of its
    /// size with the output's distance from its mean (amplitude dependence).
    pub correlations: Vec<(String, f64)>,
    /// Share of the residual power at frequencies that are not harmonics of the drive nor slow
    /// (below ω/2): structure no term driven by U can produce.
    pub off_harmonic: f64,
}

/// A sample is an outlier when its departure from its neighbours' line exceeds this many
/// robust σ: white noise goes past 6 σ once in 5·10⁸ samples.
pub const OUTLIER_SIGMAS: f64 = 6.0;

/// The samples of `y` that are outliers: a departure beyond [`OUTLIER_SIGMAS`] times the robust
/// σ (1.4826 × the median absolute departure), larger than both neighbours' (a spike also
/// moves its neighbours' departures, by half its own).
pub fn outliers(t: &[f64], y: &[f64]) -> Vec<usize> {
    let d = departures(t, y);
    if d.len() < 3 {
        return Vec::new();
    }
    let mut abs: Vec<f64> = d.iter().map(|v| v.abs()).collect();
    // quantization can make most departures equal; the RMS keeps the scale honest then
    let rms = (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt();
    let sigma = robust_sigma(&mut abs).max(0.5 * rms);
    let a = |k: usize| d.get(k).map_or(0.0, |v: &f64| v.abs());
    (0..d.len())
        .filter(|&k| {
            let before = if k > 0 { a(k - 1) } else { 0.0 };
            a(k) > OUTLIER_SIGMAS * sigma && a(k) >= before && a(k) >= a(k + 1)
        })
        .map(|k| k + 1)
        .collect()
}

/// The outliers found on one output of one experiment.
#[derive(Clone, Debug)]
pub struct Outliers {
    pub experiment: String,
    pub channel: Channel,
    /// When they occurred \[s\].
    pub times: Vec<f64>,
}

/// The experiments without the rows where any output has an outlier (a trimmed fit: a spike
/// would otherwise pull the least squares, and inflate the noise the verdict is judged
/// against), and the outliers found.
pub fn trim_outliers(
    experiments: Vec<Experiment>,
) -> Result<(Vec<Experiment>, Vec<Outliers>), crate::io::file::FileError> {
    let mut found = Vec::new();
    let mut out = Vec::with_capacity(experiments.len());
    for exp in experiments {
        let mut keep = vec![true; exp.t.len()];
        for (channel, y) in &exp.channels {
            let rows = outliers(&exp.t, y);
            if !rows.is_empty() {
                for &k in &rows {
                    keep[k] = false;
                }
                found.push(Outliers {
                    experiment: exp.name.clone(),
                    channel: *channel,
                    times: rows.iter().map(|&k| exp.t[k]).collect(),
                });
            }
        }
        out.push(if keep.iter().all(|&k| k) {
            exp
        } else {
            exp.rows(&keep)?
        });
    }
    Ok((out, found))
}

/// Drive frequency from the zero crossings of U1 − mean [rad/s].
fn drive_frequency(exp: &Experiment) -> f64 {
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

/// The largest |U_i| commanded in an experiment \[V\].
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
            let noise = noise_level(t, y);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::synth::Normal;

    /// A 50 µm sine at 11 rad/s with 1 µm white noise, sampled every 1 ms but with every
    /// seventh row and a 60 ms stretch missing.
    fn uneven() -> (Vec<f64>, Vec<f64>) {
        let mut rng = Normal::new(7);
        let t: Vec<f64> = (0..6000)
            .filter(|k| k % 7 != 3 && !(2000..2060).contains(k))
            .map(|k| k as f64 * 1e-3)
            .collect();
        let y = t
            .iter()
            .map(|t| 50e-6 * (11.0 * t).sin() + 1e-6 * rng.sample())
            .collect();
        (t, y)
    }

    #[test]
    fn the_noise_is_measured_on_uneven_sampling() {
        let (t, y) = uneven();
        let sigma = noise_level(&t, &y);
        assert!((sigma / 1e-6 - 1.0).abs() < 0.05, "{sigma:e}");
    }

    #[test]
    fn spikes_are_found_and_nothing_else() {
        let (t, mut y) = uneven();
        assert!(outliers(&t, &y).is_empty());
        for (k, a) in [(100, 12e-6), (2500, -20e-6), (4000, 40e-6)] {
            y[k] += a;
        }
        assert_eq!(outliers(&t, &y), vec![100, 2500, 4000]);
    }
}
