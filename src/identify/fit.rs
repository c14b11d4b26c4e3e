//! NRMSE fit in percent, as MATLAB's `compare` reports it (book/src/identify.md, "Fit metric"),
//! and the measurement noise a record shows, which bounds it.

/// fit = 100 (1 − ‖y − ŷ‖ / ‖y − mean(y)‖).
pub fn nrmse_fit(measured: &[f64], simulated: &[f64]) -> f64 {
    let mean = measured.iter().sum::<f64>() / measured.len() as f64;
    let err: f64 = measured
        .iter()
        .zip(simulated)
        .map(|(y, s)| (y - s).powi(2))
        .sum();
    let spread: f64 = measured.iter().map(|y| (y - mean).powi(2)).sum();
    100.0 * (1.0 - (err / spread).sqrt())
}

/// The paper's 2-D tip fit: the same over both coordinates, with the norms over X and Y
/// together: 100 (1 − ‖(x, y) − (x̂, ŷ)‖ / ‖(x, y) − (x̄, ȳ)‖).
pub fn nrmse_fit_2d(x: &[f64], y: &[f64], x_sim: &[f64], y_sim: &[f64]) -> f64 {
    let mx = x.iter().sum::<f64>() / x.len() as f64;
    let my = y.iter().sum::<f64>() / y.len() as f64;
    let err: f64 = x
        .iter()
        .zip(x_sim)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        + y.iter()
            .zip(y_sim)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>();
    let spread: f64 = x.iter().map(|a| (a - mx).powi(2)).sum::<f64>()
        + y.iter().map(|a| (a - my).powi(2)).sum::<f64>();
    100.0 * (1.0 - (err / spread).sqrt())
}

/// Each sample's departure from the straight line through its two neighbours, divided by the
/// standard deviation that white noise of unit σ gives it: y_k − (w₀ y_{k−1} + w₁ y_{k+1}) with
/// w₀ = h₁/(h₀+h₁), w₁ = h₀/(h₀+h₁) has variance σ² (1 + w₀² + w₁²). A smooth signal's departure
/// at 1 ms is negligible, and uneven sampling (dropped rows) changes only the weights.
pub fn departures(t: &[f64], y: &[f64]) -> Vec<f64> {
    (1..y.len().saturating_sub(1))
        .map(|k| {
            let (h0, h1) = (t[k] - t[k - 1], t[k + 1] - t[k]);
            let (w0, w1) = (h1 / (h0 + h1), h0 / (h0 + h1));
            (y[k] - w0 * y[k - 1] - w1 * y[k + 1]) / (1.0 + w0 * w0 + w1 * w1).sqrt()
        })
        .collect()
}

/// Measurement noise σ from the departures of the samples from their neighbours' line (on an
/// even grid, the second differences: their variance is 6 σ²).
pub fn noise_level(t: &[f64], y: &[f64]) -> f64 {
    let d = departures(t, y);
    if d.is_empty() {
        return 0.0;
    }
    (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt()
}

/// The smallest and the largest of `values` (∞ and −∞ where there are none).
pub fn span(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    values
        .into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}

/// A normal σ from absolute deviations: 1.4826 × their median (reorders `abs`).
pub fn robust_sigma(abs: &mut [f64]) -> f64 {
    1.4826 * median(abs)
}

/// The median of `v` (the upper one of an even count; `v` reordered).
pub fn median(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perfect_mean_and_worse() {
        let y = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(nrmse_fit(&y, &y), 100.0);
        assert_eq!(nrmse_fit(&y, &[2.5; 4]), 0.0);
        assert!(nrmse_fit(&y, &[4.0, 3.0, 2.0, 1.0]) < 0.0);
        assert_eq!(nrmse_fit_2d(&y, &y, &y, &y), 100.0);
        assert_eq!(nrmse_fit_2d(&y, &[0.0; 4], &[2.5; 4], &[0.0; 4]), 0.0);
    }
}
