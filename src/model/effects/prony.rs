//! Prony series (book/src/effects.md, "Prony series"): a law that is a sum of
//! relaxations w_b exp(−t/τ_b) with non-negative weights, on a fixed logarithmic grid of times
//! (a family's flexible form) or at any times (synthetic data). What the families whose law is
//! one share: the grid, the random kernels of their hidden forms, and the fitted law with its
//! textbook kernels. `creep` (branches on θ) and `charge_drift` (absorption branches across the
//! film) use it.

use nalgebra::{DMatrix, DVector};

use super::family::{self, nonnegative_least_squares};
use super::{FittedLaw, Textbook, log_between};

/// The spectrum's relaxation times \[s\]: from what 1 ms samples of a 1–2 Hz drive resolve to
/// what a 3–20 s record still sees relax, about two per decade.
pub const GRID: [f64; 6] = [0.03, 0.1, 0.3, 1.0, 3.0, 10.0];

/// Branches at any time, for synthetic data.
pub const SPREAD: usize = 16;

/// One branch of a series: weight w ≥ 0 (0: off), relaxation time τ \[s\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Branch {
    pub weight: f64,
    pub tau: f64,
}

impl Branch {
    /// A branch switched off.
    pub const OFF: Branch = Branch {
        weight: 0.0,
        tau: 1.0,
    };
}

/// What a family's weights are: their symbol and unit in words, and the law's weight axis.
pub struct Weight {
    pub symbol: &'static str,
    pub unit: &'static str,
    pub axis: &'static str,
}

/// A kernel the grid does not contain, drawn at random (effects.md, "Hidden forms for
/// synthetic data"): two relaxation times off the grid, a stretched exponential
/// (Kohlrausch–Williams–Watts) or a power law (a fractional kernel). Its branches sum to 1 at
/// t = 0; the text names it.
pub fn random_kernel(between: &mut dyn FnMut(f64, f64) -> f64) -> ([Branch; SPREAD], String) {
    let kind = between(0.0, 3.0);
    let mut branches = [Branch::OFF; SPREAD];
    let text = if kind < 1.0 {
        let tau = log_between(between, 0.05, 1.0);
        let ratio = log_between(between, 4.0, 20.0);
        let share = between(0.3, 0.7);
        branches[0] = Branch { weight: share, tau };
        branches[1] = Branch {
            weight: 1.0 - share,
            tau: ratio * tau,
        };
        format!(
            "two times off the grid, {:.0} % at tau = {tau:.3} s and the rest at {:.2} s",
            100.0 * share,
            ratio * tau
        )
    } else if kind < 2.0 {
        let tau = log_between(between, 0.2, 2.0);
        let beta = between(0.3, 0.7);
        let offset = between(0.0, 1.0);
        branches = spread(offset, |t| (-(t / tau).powf(beta)).exp());
        format!(
            "a stretched-exponential relaxation exp(-(t/tau)^beta), tau = {tau:.2} s, beta = {beta:.2}"
        )
    } else {
        let alpha = between(0.2, 0.6);
        let offset = between(0.0, 1.0);
        branches = spread(offset, |t| (1.0 + t / POWER_CUTOFF).powf(-alpha));
        format!(
            "a power-law (fractional) relaxation (1 + t/{POWER_CUTOFF} s)^-alpha, alpha = {alpha:.2}"
        )
    };
    (branches, text)
}

/// Below this time [s] the synthetic power-law kernel levels off (a pure power law is
/// infinitely stiff at t = 0).
const POWER_CUTOFF: f64 = 0.01;

/// [`SPREAD`] branches whose relaxation is `g` (g(0) = 1): three per decade from 1 ms, shifted
/// by `offset` of a step off any fixed grid, their weights fitted to g (non-negative least
/// squares) from 0.1 ms to 100 s.
pub fn spread(offset: f64, g: impl Fn(f64) -> f64) -> [Branch; SPREAD] {
    let taus: Vec<f64> = (0..SPREAD)
        .map(|i| 10f64.powf(-3.0 + (i as f64 + offset) / 3.0))
        .collect();
    let times = log_times(1e-4, 100.0, 120);
    let a = DMatrix::from_fn(times.len(), SPREAD, |r, c| (-times[r] / taus[c]).exp());
    let b = DVector::from_iterator(times.len(), times.iter().map(|&t| g(t)));
    let w = nonnegative_least_squares(&a, &b);
    let mut out = [Branch::OFF; SPREAD];
    for ((branch, &tau), &weight) in out.iter_mut().zip(&taus).zip(w.iter()) {
        *branch = Branch { weight, tau };
    }
    out
}

/// A spectrum's points (τ_b, w_b): the grid's, weights of 0 included (a fit set them there),
/// if any weight is > 0, and the synthetic branches switched on.
pub fn points<'a>(
    grid: &'a [f64; 6],
    spread: &'a [Branch],
) -> impl Iterator<Item = (f64, f64)> + 'a {
    let on = grid.iter().any(|&w| w > 0.0);
    let grid = GRID.iter().copied().zip(grid.iter().copied());
    let spread = spread.iter().filter(|b| b.weight > 0.0);
    grid.filter(move |_| on)
        .chain(spread.map(|b| (b.tau, b.weight)))
}

/// `n` times spaced evenly in log from `lo` to `hi` [s].
fn log_times(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
        .collect()
}

/// The window over which a spectrum is compared with textbook kernels [s]: from a few samples
/// to about a long record.
const WINDOW: (f64, f64) = (0.01, 20.0);

/// A spectrum `points` (τ_b, w_b) with the textbook kernel it is nearest (effects.md, "Prony
/// series", "The fitted law"): each kernel fitted to the spectrum's relaxation
/// G(t) = Σ w_b exp(−t/τ_b) over `WINDOW`, the distance the RMS difference relative to G at
/// the window's start; the nearest as `family::nearest` names it.
pub fn law(mut points: Vec<(f64, f64)>, what: String, weight: &Weight) -> FittedLaw {
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let t = log_times(WINDOW.0, WINDOW.1, 60);
    let g: Vec<f64> = t
        .iter()
        .map(|&t| points.iter().map(|(tau, w)| w * (-t / tau).exp()).sum())
        .collect();
    let scale = g[0].max(f64::MIN_POSITIVE);
    let taus = log_times(1e-3, 1e3, 121);
    let textbook = vec![
        one_time(&t, &g, &taus, weight),
        power_law(&t, &g, weight),
        stretched(&t, &g, &taus, weight),
        two_times(&t, &g, &taus, weight),
    ];
    let textbook: Vec<Textbook> = textbook
        .into_iter()
        .map(|(name, values, rms)| Textbook {
            name,
            values,
            // a kernel's spectrum is not a curve on the law's axes
            points: Vec::new(),
            distance: rms / scale,
        })
        .collect();
    FittedLaw {
        what,
        axes: ["tau [s]", weight.axis],
        points,
        distance: "RMS difference of the relaxation G(t) = sum of w exp(-t/tau) from 0.01 s to 20 s, relative to G(0.01 s)",
        nearest: family::nearest(&textbook),
        textbook,
    }
}

/// The best non-negative multiple c of `basis` for `g`, and the RMS residual.
fn scaled(g: &[f64], basis: &[f64]) -> (f64, f64) {
    let bb: f64 = basis.iter().map(|b| b * b).sum();
    let c =
        (basis.iter().zip(g).map(|(b, g)| b * g).sum::<f64>() / bb.max(f64::MIN_POSITIVE)).max(0.0);
    (c, rms(g, basis.iter().map(|b| c * b)))
}

fn rms(g: &[f64], fit: impl Iterator<Item = f64>) -> f64 {
    (g.iter().zip(fit).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / g.len() as f64).sqrt()
}

type Fitted = (&'static str, String, f64);

/// The kernel of `shapes` whose best non-negative multiple c fits `g` at `t` closest:
/// (its shape, c, the RMS residual).
fn closest<S: Copy>(
    t: &[f64],
    g: &[f64],
    shapes: impl Iterator<Item = S>,
    kernel: impl Fn(S, f64) -> f64,
) -> (S, f64, f64) {
    shapes
        .map(|shape| {
            let e: Vec<f64> = t.iter().map(|&t| kernel(shape, t)).collect();
            let (c, d) = scaled(g, &e);
            (shape, c, d)
        })
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .expect("kernels to try")
}

/// w exp(−t/τ), τ on `taus`.
fn one_time(t: &[f64], g: &[f64], taus: &[f64], weight: &Weight) -> Fitted {
    let (tau, w, d) = closest(t, g, taus.iter().copied(), |tau, t| (-t / tau).exp());
    let Weight { symbol, unit, .. } = weight;
    (
        "one time",
        format!("{symbol} = {w:.3e} {unit}, tau = {tau:.3} s"),
        d,
    )
}

/// c t^(−α), α from 0 to 1.5 (a fractional, Scott-Blair, kernel).
fn power_law(t: &[f64], g: &[f64], weight: &Weight) -> Fitted {
    let alphas = (0..=150).map(|i| i as f64 / 100.0);
    let (alpha, c, d) = closest(t, g, alphas, |alpha, t| t.powf(-alpha));
    (
        "power law",
        format!("G = {c:.3e} {} (t / 1 s)^-{alpha:.2}", weight.unit),
        d,
    )
}

/// w exp(−(t/τ)^β), τ on `taus`, β from 0.05 to 1.
fn stretched(t: &[f64], g: &[f64], taus: &[f64], weight: &Weight) -> Fitted {
    let shapes = taus
        .iter()
        .flat_map(|&tau| (1..=20).map(move |i| (tau, i as f64 / 20.0)));
    let ((tau, beta), w, d) = closest(t, g, shapes, |(tau, beta), t| (-(t / tau).powf(beta)).exp());
    let Weight { symbol, unit, .. } = weight;
    (
        "stretched exponential",
        format!("{symbol} = {w:.3e} {unit}, tau = {tau:.3} s, beta = {beta:.2}"),
        d,
    )
}

/// w1 exp(−t/τ1) + w2 exp(−t/τ2), τ1 < τ2 on every other time of `taus`, w ≥ 0.
fn two_times(t: &[f64], g: &[f64], taus: &[f64], weight: &Weight) -> Fitted {
    let taus: Vec<f64> = taus.iter().copied().step_by(2).collect();
    let b = DVector::from_column_slice(g);
    let mut best = (0.0, 0.0, 0.0, 0.0, f64::INFINITY);
    for (i, &t1) in taus.iter().enumerate() {
        for &t2 in &taus[i + 1..] {
            let a = DMatrix::from_fn(t.len(), 2, |r, c| (-t[r] / [t1, t2][c]).exp());
            let w = nonnegative_least_squares(&a, &b);
            let d = rms(g, (&a * &w).iter().copied());
            if d < best.4 {
                best = (w[0], t1, w[1], t2, d);
            }
        }
    }
    let (w1, t1, w2, t2, d) = best;
    let Weight { symbol, unit, .. } = weight;
    (
        "two times",
        format!(
            "{symbol}1 = {w1:.3e} {unit} at tau1 = {t1:.3} s, {symbol}2 = {w2:.3e} {unit} at tau2 = {t2:.3} s"
        ),
        d,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const K: Weight = Weight {
        symbol: "k",
        unit: "N.m/rad",
        axis: "k [N.m/rad]",
    };

    /// The law names the textbook kernel a spectrum was made of, nearly exactly.
    #[test]
    fn the_law_names_the_kernel_it_was_made_of() {
        let nearest = |points: Vec<(f64, f64)>| {
            let law = law(points, String::new(), &K);
            let k = &law.textbook[law.nearest];
            (k.name, k.distance)
        };
        let (name, d) = nearest(vec![(0.4, 0.05)]);
        assert!(name == "one time" && d < 1e-3, "{name} {d}");
        assert_eq!(nearest(vec![(0.1, 0.03), (3.0, 0.03)]).0, "two times");
        let points = |branches: [Branch; SPREAD]| {
            branches
                .iter()
                .filter(|b| b.weight > 0.0)
                .map(|b| (b.tau, 0.05 * b.weight))
                .collect()
        };
        let kww = spread(0.4, |t| (-(t / 0.5f64).powf(0.4)).exp());
        assert_eq!(nearest(points(kww)).0, "stretched exponential");
        let power = spread(0.4, |t| (1.0 + t / 0.01).powf(-0.4));
        assert_eq!(nearest(points(power)).0, "power law");
    }
}
