//! Convex added energies of one variable (book/src/effects.md, "Convex series"), shared
//! by `stiffening` (of θ) and `coupling` (of a pair's height difference): a non-negative series
//! of even powers on a fixed grid, and the hardening laws synthetic data hide beyond it.

use super::log_between;

/// The energy, force dE/dx and stiffness d²E/dx² of a non-negative series
/// Σ_n w_n x_ref² |x/x_ref|ⁿ / n at x: each term convex and even, so the force is odd and
/// monotone; w_n is the secant stiffness its power has at x_ref. Weights at 0 cost nothing.
pub fn series(powers: &[i32], weights: &[f64], x_ref: f64, x: f64) -> (f64, f64, f64) {
    let r = x.abs() / x_ref;
    let mut h = (0.0, 0.0, 0.0);
    for (&n, &w) in powers.iter().zip(weights).filter(|(_, w)| **w > 0.0) {
        let nf = f64::from(n);
        h.0 += w * x_ref * x_ref * r.powi(n) / nf;
        h.1 += (w * x_ref * r.powi(n - 1)).copysign(x);
        h.2 += w * (nf - 1.0) * r.powi(n - 2);
    }
    h
}

/// The force of a power law of exponent n, secant stiffness 1 at x_ref: x_ref |x/x_ref|ⁿ⁻¹
/// signed as x, the textbook power law a series' fitted law is compared with
/// (book/src/diagnose.md, "The fitted law").
pub fn power_force(x_ref: f64, n: f64) -> impl Fn(f64) -> f64 {
    move |x: f64| (x_ref * (x.abs() / x_ref).powf(n - 1.0)).copysign(x)
}

/// A series' weights in words, each with its power, to `decimals` places: "w (n = 4), …".
pub fn weights_text(powers: &[i32], weights: &[f64], decimals: usize) -> String {
    let words: Vec<String> = powers
        .iter()
        .zip(weights)
        .map(|(n, w)| format!("{w:.decimals$} (n = {n})"))
        .collect();
    words.join(", ")
}

/// The sum of energies, forces and stiffnesses.
pub fn sum<const N: usize>(parts: [(f64, f64, f64); N]) -> (f64, f64, f64) {
    parts
        .iter()
        .fold((0.0, 0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2))
}

/// A hardening law for synthetic data only (no row of the table reaches it): convex, even, of
/// higher than second order at 0, none of a series' powers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Hardening {
    None,
    /// E = k x_ref² |x/x_ref|ⁿ / n, n any real > 2: secant stiffness k at x_ref.
    Power {
        k: f64,
        n: f64,
    },
    /// E = k x_s² (cosh(x/x_s) − 1 − (x/x_s)²/2): exponential hardening.
    Exponential {
        k: f64,
        x_s: f64,
    },
}

impl Hardening {
    /// The energy, force dE/dx and stiffness d²E/dx² at x.
    pub fn at(&self, x_ref: f64, x: f64) -> (f64, f64, f64) {
        match *self {
            Hardening::None => (0.0, 0.0, 0.0),
            Hardening::Power { k, n } => {
                let r = x.abs() / x_ref;
                (
                    k * x_ref * x_ref * r.powf(n) / n,
                    (k * x_ref * r.powf(n - 1.0)).copysign(x),
                    k * (n - 1.0) * r.powf(n - 2.0),
                )
            }
            Hardening::Exponential { k, x_s } => {
                let y = x / x_s;
                (
                    k * x_s * x_s * (y.cosh() - 1.0 - 0.5 * y * y),
                    k * x_s * (y.sinh() - y),
                    k * (y.cosh() - 1.0),
                )
            }
        }
    }

    /// A law drawn at random, with equal odds, from outside a series: a power of any real
    /// exponent in [3, 10], or exponential hardening of scale x_s log-uniform in `scales`; its
    /// added stiffness at x_ref `k`. Also the law in words, of the variable called `x`, its
    /// scale written in `unit` (a name, and the unit's value in x's).
    pub fn random(
        between: &mut dyn FnMut(f64, f64) -> f64,
        k: f64,
        x_ref: f64,
        scales: (f64, f64),
        x: &str,
        unit: (&str, f64),
    ) -> (Hardening, String) {
        if between(0.0, 1.0) < 0.5 {
            let n = between(3.0, 10.0);
            (Hardening::Power { k, n }, format!("a power {n:.2} of {x}"))
        } else {
            let x_s = log_between(between, scales.0, scales.1);
            // its stiffness k (cosh(x_ref/x_s) − 1) at x_ref is k
            let law = Hardening::Exponential {
                k: k / ((x_ref / x_s).cosh() - 1.0),
                x_s,
            };
            let text = format!(
                "exponential hardening, cosh({x} / {x}_s) with {x}_s = {:.1} {}",
                x_s / unit.1,
                unit.0
            );
            (law, text)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Energy, force and stiffness of the series and of the hardening laws agree with each
    /// other by finite differences, and the energy is convex: the force monotone.
    #[test]
    fn forces_are_the_energies_slopes_and_monotone() {
        let laws: [&dyn Fn(f64) -> (f64, f64, f64); 3] = [
            &|x| series(&[2, 4, 8], &[1.0, 0.0, 3.0], 0.5, x),
            &|x| Hardening::Power { k: 2.0, n: 4.7 }.at(0.5, x),
            &|x| Hardening::Exponential { k: 2.0, x_s: 0.3 }.at(0.5, x),
        ];
        for law in laws {
            let mut last = f64::NEG_INFINITY;
            for k in -20..=20 {
                let x = 0.06 * f64::from(k) + 0.001;
                let (e, f, s) = law(x);
                let dx = 1e-6;
                let fd = (law(x + dx).0 - law(x - dx).0) / (2.0 * dx);
                let sd = (law(x + dx).1 - law(x - dx).1) / (2.0 * dx);
                assert!((fd - f).abs() <= 1e-6 * (1.0 + f.abs()), "x {x}: {fd} {f}");
                assert!((sd - s).abs() <= 1e-5 * (1.0 + s.abs()), "x {x}: {sd} {s}");
                assert!(e >= 0.0 && s >= 0.0 && f > last, "x {x}: {e} {f} {s}");
                last = f;
            }
        }
    }
}
