//! `creep` (book/src/effects.md, "creep"): viscoelastic creep of the shell film, a
//! Prony series of spring–dashpot branches on θ: one branch at a free relaxation time (the
//! library form) and non-negative weights on a fixed logarithmic grid of times (the spectrum).

use super::family::mean_kb;
use super::log_between;
use super::prony::{self, Branch, GRID, SPREAD};
use super::terms::{At, Law, States, torque_state_scale};
use super::{Drive, Effect, Exposing, Family, FittedLaw, Form, Magnitude, Planted, Probe, Scaling};
use crate::model::Params;
use crate::model::actuator::{Actuator, P, StateInfo, THETA};
use crate::model::params::common_rows;
use crate::model::shell::DomainError;

/// The spectrum's weights, rows of the parameter table, one per time of [`GRID`].
pub const GRID_NAMES: [&str; 6] = [
    "k_v_30ms",
    "k_v_100ms",
    "k_v_300ms",
    "k_v_1s",
    "k_v_3s",
    "k_v_10s",
];

/// Viscoelastic creep: spring–dashpot branches (k, τ) on θ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Creep {
    /// k_v [N m/rad] of the branch at the free time; 0 switches it off.
    pub k_v: f64,
    /// τ_v = η / k_v \[s\].
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
            spread: [Branch::OFF; SPREAD],
        }
    }
}

impl Creep {
    /// The branches switched on, (k, τ): the free one, the spectrum's, the synthetic ones.
    pub fn branches(&self) -> Vec<Branch> {
        let free = Branch {
            weight: self.k_v,
            tau: self.tau_v,
        };
        let grid = GRID
            .iter()
            .zip(self.grid)
            .map(|(&tau, weight)| Branch { weight, tau });
        std::iter::once(free)
            .chain(grid)
            .chain(self.spread)
            .filter(|b| b.weight > 0.0)
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
        grid "k_v", "N.m/rad", "creep: weight of the spectrum", creep.grid;
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
    law: |p, _| Some(spectrum_law(&p.effects.creep)),
};

/// One branch at three times; the spectrum, one column per weight (book/src/diagnose.md,
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

/// Creep of a kernel the grid does not contain, at a random strength (effects.md, "Hidden
/// forms for synthetic data"; the kernel [`prony::random_kernel`]).
fn random_kernel(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let k = between(0.15, 0.4) * mean_kb(params);
    let (branches, kernel) = prony::random_kernel(between);
    params.effects.creep.spread = branches.map(|b| Branch {
        weight: k * b.weight,
        ..b
    });
    Planted::text(format!("creep of {kernel}, k = {k:.3} N.m/rad"))
}

/// Creep in two unequal branches at τ and 8 τ.
fn unequal_times(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let k_v = between(0.15, 0.4) * mean_kb(params);
    let tau_v = log_between(between, 0.1, 0.5);
    let share = between(0.25, 0.4);
    let creep = &mut params.effects.creep;
    creep.spread[0] = Branch {
        weight: share * k_v,
        tau: tau_v,
    };
    creep.spread[1] = Branch {
        weight: (1.0 - share) * k_v,
        tau: 8.0 * tau_v,
    };
    Planted::text(format!(
        "creep in two branches, {:.0} % at tau = {tau_v:.2} s and the rest at 8 tau, k_v = {k_v:.3} N.m/rad",
        100.0 * share
    ))
}

/// The creep's weights: stiffnesses.
const WEIGHT: prony::Weight = prony::Weight {
    symbol: "k",
    unit: "N.m/rad",
    axis: "k [N.m/rad]",
};

/// The creep's relaxation spectrum with the textbook kernel it is nearest (effects.md,
/// "creep", "The fitted law"; [`prony::law`]): the branches (τ_b, k_b), the free one and the
/// spectrum's ([`prony::points`]).
fn spectrum_law(creep: &Creep) -> FittedLaw {
    let free = (creep.k_v > 0.0).then_some((creep.tau_v, creep.k_v));
    prony::law(
        free.into_iter()
            .chain(prony::points(&creep.grid, &creep.spread))
            .collect(),
        "relaxation spectrum: the stiffness of each spring-dashpot branch against its relaxation time".into(),
        &WEIGHT,
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

    /// Stage 0 is the free branch, 1 … 6 the grid's, the synthetic ones after them.
    fn new(cr: &Creep, states: &mut States) -> Terms {
        let grid = GRID.iter().zip(cr.grid).map(|(&tau, k)| (k, tau));
        let spread = cr.spread.iter().map(|b| (b.weight, b.tau));
        let free = (cr.k_v, cr.tau_v);
        let branches = states.push_grid(Effect::Creep, free, grid, cr.spectrum_on(), spread);
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

    fn scales(&self, a: &Actuator, theta_star: f64, out: &mut Vec<f64>) {
        out.extend(
            self.branches
                .iter()
                .map(|&(_, k, _)| torque_state_scale(a, theta_star, k)),
        );
    }
}
