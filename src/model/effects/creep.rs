//! `creep` (src/model/effects/effects.md, "creep"): viscoelastic creep of the shell film, a
//! Prony series of spring–dashpot branches on θ: one branch at a free relaxation time (the
//! library form) and non-negative weights on a fixed logarithmic grid of times (the spectrum).

use nalgebra::{DMatrix, DVector};

use super::family::{self, mean_kb, nonnegative_least_squares};
use super::log_between;
use super::terms::{At, Law, States};
use super::{
    Drive, Effect, Exposing, Family, FittedLaw, Form, Magnitude, Planted, Probe, Scaling, Textbook,
};
use crate::model::Params;
use crate::model::actuator::{Actuator, P, StateInfo, THETA};
use crate::model::params::common_rows;
use crate::model::shell::DomainError;

/// The spectrum's relaxation times [s]: from what 1 ms samples of a 1–2 Hz drive resolve to
/// what a 3–20 s record still sees relax, about two per decade.
pub const GRID: [f64; 6] = [0.03, 0.1, 0.3, 1.0, 3.0, 10.0];

/// The spectrum's weights, rows of the parameter table, one per time of [`GRID`].
pub const GRID_NAMES: [&str; 6] = [
    "k_v_30ms",
    "k_v_100ms",
    "k_v_300ms",
    "k_v_1s",
    "k_v_3s",
    "k_v_10s",
];

/// Branches at any time, for synthetic data.
const SPREAD: usize = 16;

/// One spring–dashpot branch: stiffness k [N m/rad] (0: off), relaxation time τ [s].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Branch {
    pub k: f64,
    pub tau: f64,
}

/// Viscoelastic creep: spring–dashpot branches (k, τ) on θ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Creep {
    /// k_v [N m/rad] of the branch at the free time; 0 switches it off.
    pub k_v: f64,
    /// τ_v = η / k_v [s].
    pub tau_v: f64,
    /// The spectrum: the weight k [N m/rad] of the branch at each time of [`GRID`].
    pub grid: [f64; 6],
    /// Branches at any times, for synthetic data only (no row of the table reaches them): a
    /// kernel the grid does not contain.
    pub spread: [Branch; SPREAD],
}

impl Default for Creep {
    fn default() -> Self {
        Creep {
            k_v: 0.0,
            tau_v: 1.0,
            grid: [0.0; 6],
            spread: [Branch { k: 0.0, tau: 1.0 }; SPREAD],
        }
    }
}

impl Creep {
    /// The branches switched on, (k, τ): the free one, the spectrum's, the synthetic ones.
    pub fn branches(&self) -> Vec<Branch> {
        let free = Branch {
            k: self.k_v,
            tau: self.tau_v,
        };
        let grid = GRID
            .iter()
            .zip(self.grid)
            .map(|(&tau, k)| Branch { k, tau });
        std::iter::once(free)
            .chain(grid)
            .chain(self.spread)
            .filter(|b| b.k > 0.0)
            .collect()
    }

    /// Is the spectrum on?
    fn spectrum_on(&self) -> bool {
        self.grid.iter().any(|&k| k > 0.0)
    }
}

const FORMS: [Form; 2] = [
    Form::new(Effect::Creep, "one_time", &["k_v", "tau_v"], &[]),
    Form {
        magnitudes: &GRID_NAMES,
        ..Form::new(Effect::Creep, "spectrum", &GRID_NAMES, &[])
    },
];

pub const FAMILY: Family = Family {
    effect: Effect::Creep,
    name: "creep",
    mechanism: "viscoelastic creep of the shell film",
    form: "H += 1/2 k_v (theta - z)^2, dz/dt = (theta - z) / tau_v",
    forms: &FORMS,
    rows: &common_rows! {
        "k_v", "N.m/rad", NonNegative, "creep: stiffness k_v of the branch at the free time tau_v (0: off)", effects.creep.k_v;
        "tau_v", "s", Positive, "creep: relaxation time tau_v = eta / k_v", effects.creep.tau_v;
        "k_v_30ms", "N.m/rad", Weight, "creep: weight of the spectrum at tau = 0.03 s (0: off)", effects.creep.grid[0];
        "k_v_100ms", "N.m/rad", Weight, "creep: weight of the spectrum at tau = 0.1 s (0: off)", effects.creep.grid[1];
        "k_v_300ms", "N.m/rad", Weight, "creep: weight of the spectrum at tau = 0.3 s (0: off)", effects.creep.grid[2];
        "k_v_1s", "N.m/rad", Weight, "creep: weight of the spectrum at tau = 1 s (0: off)", effects.creep.grid[3];
        "k_v_3s", "N.m/rad", Weight, "creep: weight of the spectrum at tau = 3 s (0: off)", effects.creep.grid[4];
        "k_v_10s", "N.m/rad", Weight, "creep: weight of the spectrum at tau = 10 s (0: off)", effects.creep.grid[5];
    },
    choices: &[],
    state: Some(StateInfo {
        name: "z_v",
        unit: "rad",
        description: "internal angle z of a creep branch",
    }),
    // the free branch and the grid's
    table_stages: 1 + GRID.len(),
    is_active: |p| !p.creep.branches().is_empty(),
    on: |f| {
        f.creep.k_v = 0.05;
        f.creep.tau_v = 0.3;
        f.creep.grid = [0.02, 0.0, 0.01, 0.0, 0.03, 0.01];
    },
    structures: &[],
    delays_the_command: false,
    magnitude: Magnitude::Positive,
    probes,
    exposing: Exposing {
        text: "a step held for tens of seconds and then released: creep relaxes and recovers mechanically",
        drive: Drive::Corners(&[
            (0.0, 0.0),
            (0.05, 1.0),
            (10.0, 1.0),
            (10.05, 0.0),
            (20.0, 0.0),
        ]),
        t_end: 20.0,
    },
    hidden: random_kernel,
    variants: &[("creep_two_times", unequal_times)],
    law: Some(|p, _| spectrum_law(&p.effects.creep)),
};

/// One branch at three times; the spectrum, one column per weight (src/diagnose/diagnose.md,
/// "Screening").
fn probes(params: &Params, _: f64) -> Vec<Probe> {
    let kb = mean_kb(params);
    let mut out: Vec<Probe> = [0.2, 0.6, 2.0]
        .into_iter()
        .map(|tau| Probe::one(&FORMS[0], vec![("k_v", 0.2 * kb), ("tau_v", tau)]))
        .collect();
    out.push(Probe {
        form: &FORMS[1],
        columns: GRID_NAMES.iter().map(|&n| vec![(n, 0.2 * kb)]).collect(),
        scaling: Scaling::Weights,
    });
    out
}

/// Creep of a kernel the grid does not contain, at a random strength: two relaxation times
/// off the grid, a stretched exponential (Kohlrausch–Williams–Watts) or a power law (a
/// fractional kernel), drawn at random (effects.md, "Hidden forms for synthetic data").
fn random_kernel(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let k = between(0.15, 0.4) * mean_kb(params);
    let kind = between(0.0, 3.0);
    let creep = &mut params.effects.creep;
    let text = if kind < 1.0 {
        let tau = log_between(between, 0.05, 1.0);
        let ratio = log_between(between, 4.0, 20.0);
        let share = between(0.3, 0.7);
        creep.spread[0] = Branch { k: share * k, tau };
        creep.spread[1] = Branch {
            k: (1.0 - share) * k,
            tau: ratio * tau,
        };
        format!(
            "creep of two times off the grid, {:.0} % at tau = {tau:.3} s and the rest at {:.2} s, k = {k:.3} N.m/rad",
            100.0 * share,
            ratio * tau
        )
    } else if kind < 2.0 {
        let tau = log_between(between, 0.2, 2.0);
        let beta = between(0.3, 0.7);
        let offset = between(0.0, 1.0);
        spread_over(creep, k, offset, |t| (-(t / tau).powf(beta)).exp());
        format!(
            "creep of a stretched-exponential relaxation k exp(-(t/tau)^beta), tau = {tau:.2} s, beta = {beta:.2}, k = {k:.3} N.m/rad"
        )
    } else {
        let alpha = between(0.2, 0.6);
        let offset = between(0.0, 1.0);
        spread_over(creep, k, offset, |t| (1.0 + t / POWER_CUTOFF).powf(-alpha));
        format!(
            "creep of a power-law (fractional) relaxation k (1 + t/{POWER_CUTOFF} s)^-alpha, alpha = {alpha:.2}, k = {k:.3} N.m/rad"
        )
    };
    Planted::text(text)
}

/// Below this time [s] the synthetic power-law kernel levels off (a pure power law is
/// infinitely stiff at t = 0).
const POWER_CUTOFF: f64 = 0.01;

/// The synthetic branches set to relaxation `g` (g(0) = 1) times `k`: [`SPREAD`] branches three
/// per decade from 1 ms, shifted by `offset` of a step off any fixed grid, their weights fitted
/// to g (non-negative least squares) from 0.1 ms to 100 s.
fn spread_over(creep: &mut Creep, k: f64, offset: f64, g: impl Fn(f64) -> f64) {
    let taus: Vec<f64> = (0..SPREAD)
        .map(|i| 10f64.powf(-3.0 + (i as f64 + offset) / 3.0))
        .collect();
    let times = log_times(1e-4, 100.0, 120);
    let a = DMatrix::from_fn(times.len(), SPREAD, |r, c| (-times[r] / taus[c]).exp());
    let b = DVector::from_iterator(times.len(), times.iter().map(|&t| g(t)));
    let w = nonnegative_least_squares(&a, &b);
    for ((branch, &tau), w) in creep.spread.iter_mut().zip(&taus).zip(w.iter()) {
        *branch = Branch { k: k * w, tau };
    }
}

/// Creep in two unequal branches at τ and 8 τ.
fn unequal_times(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let k_v = between(0.15, 0.4) * mean_kb(params);
    let tau_v = log_between(between, 0.1, 0.5);
    let share = between(0.25, 0.4);
    let creep = &mut params.effects.creep;
    creep.spread[0] = Branch {
        k: share * k_v,
        tau: tau_v,
    };
    creep.spread[1] = Branch {
        k: (1.0 - share) * k_v,
        tau: 8.0 * tau_v,
    };
    Planted::text(format!(
        "creep in two branches, {:.0} % at tau = {tau_v:.2} s and the rest at 8 tau, k_v = {k_v:.3} N.m/rad",
        100.0 * share
    ))
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

/// The creep's relaxation spectrum with the textbook kernel it is nearest (effects.md,
/// "creep", "The fitted law"): each kernel G(t) fitted to the spectrum's relaxation
/// G(t) = Σ k_b exp(−t/τ_b) over [`WINDOW`], the distance the RMS difference relative to G at
/// the window's start; the nearest as [`family::nearest`] names it.
fn spectrum_law(creep: &Creep) -> FittedLaw {
    // the spectrum's weights of 0 too: the fit set them there
    let free = (creep.k_v > 0.0).then_some((creep.tau_v, creep.k_v));
    let grid = GRID
        .iter()
        .copied()
        .zip(creep.grid)
        .filter(|_| creep.spectrum_on());
    let spread = creep
        .spread
        .iter()
        .filter(|b| b.k > 0.0)
        .map(|b| (b.tau, b.k));
    let mut points: Vec<(f64, f64)> = free.into_iter().chain(grid).chain(spread).collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let t = log_times(WINDOW.0, WINDOW.1, 60);
    let g: Vec<f64> = t
        .iter()
        .map(|&t| points.iter().map(|(tau, k)| k * (-t / tau).exp()).sum())
        .collect();
    let scale = g[0].max(f64::MIN_POSITIVE);
    let taus = log_times(1e-3, 1e3, 121);
    let textbook = vec![
        one_time(&t, &g, &taus),
        power_law(&t, &g),
        stretched(&t, &g, &taus),
        two_times(&t, &g, &taus),
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
        what: "relaxation spectrum: the stiffness of each spring-dashpot branch against its relaxation time".into(),
        axes: ["tau [s]", "k [N.m/rad]"],
        points,
        distance: "RMS difference of the relaxation G(t) from 0.01 s to 20 s, relative to G(0.01 s)",
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

/// k exp(−t/τ), τ on `taus`.
fn one_time(t: &[f64], g: &[f64], taus: &[f64]) -> Fitted {
    let (tau, k, d) = closest(t, g, taus.iter().copied(), |tau, t| (-t / tau).exp());
    (
        "one time",
        format!("k = {k:.3e} N.m/rad, tau = {tau:.3} s"),
        d,
    )
}

/// c t^(−α), α from 0 to 1.5 (a fractional, Scott-Blair, kernel).
fn power_law(t: &[f64], g: &[f64]) -> Fitted {
    let alphas = (0..=150).map(|i| i as f64 / 100.0);
    let (alpha, c, d) = closest(t, g, alphas, |alpha, t| t.powf(-alpha));
    (
        "power law",
        format!("G = {c:.3e} N.m/rad (t / 1 s)^-{alpha:.2}"),
        d,
    )
}

/// k exp(−(t/τ)^β), τ on `taus`, β from 0.05 to 1.
fn stretched(t: &[f64], g: &[f64], taus: &[f64]) -> Fitted {
    let shapes = taus
        .iter()
        .flat_map(|&tau| (1..=20).map(move |i| (tau, i as f64 / 20.0)));
    let ((tau, beta), k, d) = closest(t, g, shapes, |(tau, beta), t| (-(t / tau).powf(beta)).exp());
    (
        "stretched exponential",
        format!("k = {k:.3e} N.m/rad, tau = {tau:.3} s, beta = {beta:.2}"),
        d,
    )
}

/// k1 exp(−t/τ1) + k2 exp(−t/τ2), τ1 < τ2 on every other time of `taus`, k ≥ 0.
fn two_times(t: &[f64], g: &[f64], taus: &[f64]) -> Fitted {
    let taus: Vec<f64> = taus.iter().copied().step_by(2).collect();
    let b = DVector::from_column_slice(g);
    let mut best = (0.0, 0.0, 0.0, 0.0, f64::INFINITY);
    for (i, &t1) in taus.iter().enumerate() {
        for &t2 in &taus[i + 1..] {
            let a = DMatrix::from_fn(t.len(), 2, |r, c| (-t[r] / [t1, t2][c]).exp());
            let k = nonnegative_least_squares(&a, &b);
            let d = rms(g, (&a * &k).iter().copied());
            if d < best.4 {
                best = (k[0], t1, k[1], t2, d);
            }
        }
    }
    let (k1, t1, k2, t2, d) = best;
    (
        "two times",
        format!(
            "k1 = {k1:.3e} N.m/rad at tau1 = {t1:.3} s, k2 = {k2:.3e} N.m/rad at tau2 = {t2:.3} s"
        ),
        d,
    )
}

/// The branches' terms: H += ½ k_b (θ − z_b)², ż_b = (θ − z_b) / τ_b (effects.md, "creep").
#[derive(Clone, Debug)]
pub struct Terms {
    /// (index, k, τ) per branch.
    branches: Vec<(usize, f64, f64)>,
}

impl Law for Terms {
    type Params = Creep;

    /// Stage 0 is the free branch, 1 … 6 the grid's, the synthetic ones after them. The grid's
    /// branches come all together, a weight of 0 among them included: a fit moves weights to
    /// and from 0, and a state that came and went with its weight would have no sensitivity.
    fn new(cr: &Creep, states: &mut States) -> Terms {
        let spectrum = cr.spectrum_on();
        let free = (cr.k_v, cr.tau_v, cr.k_v > 0.0);
        let grid = GRID.iter().zip(cr.grid).map(|(&tau, k)| (k, tau, spectrum));
        let spread = cr.spread.iter().map(|b| (b.k, b.tau, b.k > 0.0));
        let branches = std::iter::once(free)
            .chain(grid)
            .chain(spread)
            .enumerate()
            .filter(|(_, (_, _, on))| *on)
            .map(|(stage, (k, tau, _))| (states.push(Effect::Creep, stage), k, tau))
            .collect();
        Terms { branches }
    }

    #[inline]
    fn add_rhs(&self, at: &At, dx: &mut [f64]) -> Result<(), DomainError> {
        let xi = at.xi();
        for &(k, kb, tb) in &self.branches {
            dx[P] -= kb * (xi[THETA] - xi[k]);
            dx[k] = (xi[THETA] - xi[k]) / tb;
        }
        Ok(())
    }

    #[inline]
    fn add_jacobian(
        &self,
        at: &At,
        offset: [usize; 3],
        add: &mut impl FnMut(usize, usize, f64),
    ) -> Result<(), DomainError> {
        let o = offset[at.i];
        for &(k, kb, tb) in &self.branches {
            add(o + P, o + THETA, -kb);
            add(o + P, o + k, kb);
            add(o + k, o + THETA, 1.0 / tb);
            add(o + k, o + k, -1.0 / tb);
        }
        Ok(())
    }

    fn energy(&self, _: &[&Actuator; 3], x: [&[f64]; 3]) -> f64 {
        let mut e = 0.0;
        for xi in x {
            for &(k, kb, _) in &self.branches {
                e += 0.5 * kb * (xi[THETA] - xi[k]).powi(2);
            }
        }
        e
    }

    /// The dashpots.
    fn dissipation(&self, _: &Actuator, xi: &[f64]) -> Result<f64, DomainError> {
        let mut p = 0.0;
        for &(k, kb, tb) in &self.branches {
            p += kb * (xi[THETA] - xi[k]).powi(2) / tb;
        }
        Ok(p)
    }

    /// Each branch relaxed: z_b = θ.
    fn rest(&self, theta: f64, out: &mut Vec<f64>) {
        out.extend(self.branches.iter().map(|_| theta));
    }

    fn scales(&self, _: &Actuator, theta_star: f64, out: &mut Vec<f64>) {
        out.extend(self.branches.iter().map(|_| theta_star));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The law names the textbook kernel a spectrum was made of, nearly exactly.
    #[test]
    fn the_law_names_the_kernel_it_was_made_of() {
        let nearest = |c: &Creep| {
            let law = spectrum_law(c);
            let k = &law.textbook[law.nearest];
            (k.name, k.distance)
        };
        let one = Creep {
            k_v: 0.05,
            tau_v: 0.4,
            ..Creep::default()
        };
        let (name, d) = nearest(&one);
        assert!(name == "one time" && d < 1e-3, "{name} {d}");
        let two = Creep {
            grid: [0.0, 0.03, 0.0, 0.0, 0.03, 0.0],
            ..Creep::default()
        };
        assert_eq!(nearest(&two).0, "two times");
        let mut kww = Creep::default();
        spread_over(&mut kww, 0.05, 0.4, |t| (-(t / 0.5f64).powf(0.4)).exp());
        assert_eq!(nearest(&kww).0, "stretched exponential");
        let mut power = Creep::default();
        spread_over(&mut power, 0.05, 0.4, |t| (1.0 + t / 0.01).powf(-0.4));
        assert_eq!(nearest(&power).0, "power law");
    }
}
