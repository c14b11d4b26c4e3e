//! `hysteresis` (book/src/effects.md, "hysteresis"): hysteresis of zipping, hysteretic
//! elements on θ, each a state z saturating at its angle θ_j with the torque −k_j z: one at a free
//! angle (the library form), and a Prandtl–Ishlinskii superposition with non-negative weights on
//! a fixed logarithmic grid of angles (the plays).

use super::family::{FittedLaw, TextbookForm, golden, mean_kb, sampled, scaled_to};
use super::terms::{At, Law, States, torque_state_scale};
use super::{
    Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, Scaling, log_between,
};
use crate::model::Params;
use crate::model::actuator::{Actuator, P, StateInfo};
use crate::model::params::common_rows;
use crate::model::shell::DomainError;

/// Hysteresis law of the zipping torque state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HysteresisLaw {
    /// Library form: Bouc–Wen with n = 1, A = 1, β = γ = 1/(2 θ_h).
    BoucWen,
    /// Dahl's law: ż = θ̇ − |θ̇| z / θ_h.
    Dahl,
}

/// The plays' saturation angles \[rad\]: from what the paper's strokes (tens of mrad) show as a
/// sharp corner to a loop as wide as the stroke, two per factor of four.
pub const GRID: [f64; 5] = [0.5e-3, 1e-3, 2e-3, 4e-3, 8e-3];

/// The plays' weights, rows of the parameter table, one per angle of [`GRID`].
const GRID_NAMES: [&str; 5] = [
    "k_h_0p5mrad",
    "k_h_1mrad",
    "k_h_2mrad",
    "k_h_4mrad",
    "k_h_8mrad",
];

/// Elements at any angle, for synthetic data.
const SPREAD: usize = 8;

/// One hysteretic element: stiffness k [N m/rad] (0: off), saturation angle θ \[rad\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    pub k: f64,
    pub theta: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hysteresis {
    /// k_h [N m/rad]: the torque −k_h z of the element at the free angle.
    pub k_h: f64,
    /// θ_h \[rad\]: the angle where that element's state saturates.
    pub theta_h: f64,
    /// The plays: the weight k [N m/rad] of the element at each angle of [`GRID`].
    pub grid: [f64; 5],
    /// r_h [1/s]: every hysteretic state relaxes at this rate (0: rate-independent).
    pub r_h: f64,
    /// Only for synthetic data: the library's law is Bouc–Wen.
    pub law: HysteresisLaw,
    /// Elements at any angles, for synthetic data only (no row of the table reaches them).
    pub spread: [Element; SPREAD],
}

impl Default for Hysteresis {
    fn default() -> Self {
        Hysteresis {
            k_h: 0.0,
            theta_h: 1e-3,
            grid: [0.0; 5],
            r_h: 0.0,
            law: HysteresisLaw::BoucWen,
            spread: [Element {
                k: 0.0,
                theta: 1e-3,
            }; SPREAD],
        }
    }
}

impl Hysteresis {
    fn is_on(&self) -> bool {
        self.k_h > 0.0 || self.plays_on() || self.spread.iter().any(|e| e.k > 0.0)
    }

    /// Are the plays on?
    fn plays_on(&self) -> bool {
        self.grid.iter().any(|&k| k > 0.0)
    }

    /// The elements switched on, (k, θ): the free one, the plays, the synthetic ones.
    fn elements(&self) -> impl Iterator<Item = Element> + '_ {
        let free = Element {
            k: self.k_h,
            theta: self.theta_h,
        };
        let grid = GRID
            .iter()
            .zip(self.grid)
            .map(|(&theta, k)| Element { k, theta });
        std::iter::once(free)
            .chain(grid)
            .chain(self.spread)
            .filter(|e| e.k > 0.0)
    }
}

const FORMS: [Form; 4] = [
    Form::new(
        Effect::Hysteresis,
        "rate_independent",
        &["k_h", "theta_h"],
        &[],
    ),
    Form::new(
        Effect::Hysteresis,
        "rate_dependent",
        &["k_h", "theta_h", "r_h"],
        &[],
    ),
    Form {
        magnitudes: &GRID_NAMES,
        ..Form::new(Effect::Hysteresis, "plays", &GRID_NAMES, &[])
    },
    Form {
        magnitudes: &GRID_NAMES,
        ..Form::new(
            Effect::Hysteresis,
            "plays_rate",
            &[
                "k_h_0p5mrad",
                "k_h_1mrad",
                "k_h_2mrad",
                "k_h_4mrad",
                "k_h_8mrad",
                "r_h",
            ],
            &[],
        )
    },
];

pub const FAMILY: Family = Family {
    effect: Effect::Hysteresis,
    name: "hysteresis",
    mechanism: "rate-independent hysteresis of zipping",
    form: "Bouc-Wen state z on theta (n = 1, beta = gamma = 1/(2 theta_h)), torque -k_h z",
    forms: &FORMS,
    rows: &common_rows! {
        "k_h", "N.m/rad", NonNegative, "hysteresis: stiffness k_h of the Bouc-Wen torque -k_h z (0: off)", effects.hysteresis.k_h;
        "theta_h", "rad", Positive, "hysteresis: angle theta_h at which the Bouc-Wen state saturates", effects.hysteresis.theta_h;
        "r_h", "Hz", NonNegative, "hysteresis: relaxation rate r_h [1/s] of the hysteretic states (0: rate-independent)", effects.hysteresis.r_h;
        "k_h_0p5mrad", "N.m/rad", Weight, "hysteresis: weight of the play saturating at 0.5 mrad (0: off)", effects.hysteresis.grid[0];
        "k_h_1mrad", "N.m/rad", Weight, "hysteresis: weight of the play saturating at 1 mrad (0: off)", effects.hysteresis.grid[1];
        "k_h_2mrad", "N.m/rad", Weight, "hysteresis: weight of the play saturating at 2 mrad (0: off)", effects.hysteresis.grid[2];
        "k_h_4mrad", "N.m/rad", Weight, "hysteresis: weight of the play saturating at 4 mrad (0: off)", effects.hysteresis.grid[3];
        "k_h_8mrad", "N.m/rad", Weight, "hysteresis: weight of the play saturating at 8 mrad (0: off)", effects.hysteresis.grid[4];
    },
    choices: &[],
    state: Some(StateInfo {
        name: "z_h",
        unit: "rad",
        description: "Bouc-Wen state z_h",
    }),
    table_stages: 1 + GRID.len(),
    is_active: |p| p.hysteresis.is_on(),
    on: |f| {
        f.hysteresis.k_h = 0.04;
        f.hysteresis.theta_h = 2e-3;
        f.hysteresis.grid = [0.01; 5];
        f.hysteresis.r_h = 2.0;
    },
    structures: &[],
    delays_the_command: false,
    magnitude: Magnitude::Positive,
    probes,
    exposing: Exposing {
        text: "a slow triangle at two amplitudes: rate-independent loops keep their width at any speed",
        drive: Drive::Corners(&[
            (0.0, 0.0),
            (2.5, 0.5),
            (7.5, -0.5),
            (10.0, 0.0),
            (12.5, 1.0),
            (17.5, -1.0),
            (20.0, 0.0),
        ]),
        t_end: 20.0,
    },
    hidden: dahl,
    variants: &[
        ("hysteresis_rate", relaxing_dahl),
        ("hysteresis_plays", random_plays),
    ],
    law: |p, u_peak| Some(loading_law(p, u_peak)),
};

/// Two saturation angles, without and with relaxation; the plays, one column per angle of the
/// grid, without and with relaxation (book/src/diagnose.md, "Screening").
fn probes(params: &Params, _: f64) -> Vec<Probe> {
    let kb = mean_kb(params);
    let mut out = Vec::new();
    for (form, rates) in FORMS[..2].iter().zip([&[0.0][..], &[3.0, 10.0]]) {
        for &r_h in rates {
            for theta in [1e-3, 3e-3] {
                let mut col = vec![("k_h", 0.2 * kb), ("theta_h", theta)];
                if r_h > 0.0 {
                    col.push(("r_h", r_h));
                }
                out.push(Probe::one(form, col));
            }
        }
    }
    for (form, r_h) in FORMS[2..].iter().zip([0.0, 3.0]) {
        let columns = GRID_NAMES
            .iter()
            .map(|&n| {
                let mut col = vec![(n, 0.2 * kb)];
                if r_h > 0.0 {
                    col.push(("r_h", r_h));
                }
                col
            })
            .collect();
        out.push(Probe {
            form,
            columns,
            scaling: Scaling::Weights,
        });
    }
    out
}

/// Dahl's hysteresis.
fn dahl(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let kb = mean_kb(params);
    let h = &mut params.effects.hysteresis;
    h.law = HysteresisLaw::Dahl;
    h.k_h = between(0.25, 0.5) * kb;
    h.theta_h = log_between(between, 2e-3, 6e-3);
    Planted::text(format!(
        "Dahl hysteresis, k_h = {:.3} N.m/rad, theta_h = {:.2e} rad",
        h.k_h, h.theta_h
    ))
}

/// Dahl's hysteresis, relaxing.
fn relaxing_dahl(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let kb = mean_kb(params);
    let h = &mut params.effects.hysteresis;
    h.law = HysteresisLaw::Dahl;
    h.k_h = between(0.25, 0.5) * kb;
    h.theta_h = log_between(between, 2e-3, 6e-3);
    h.r_h = log_between(between, 2.0, 8.0);
    Planted::text(format!(
        "rate-dependent Dahl hysteresis, k_h = {:.3} N.m/rad, theta_h = {:.2e} rad, relaxing at {:.1} 1/s",
        h.k_h, h.theta_h, h.r_h
    ))
}

/// A Prandtl–Ishlinskii superposition of elements at angles off the grid, their weights a
/// random log-normal density of saturation angles: centred at θ_c in [1, 5] mrad (log), of
/// log-width σ in [0.3, 1], over θ_c e^(±2σ); the total k_h in [0.25, 0.5] × mean Kb, as Dahl's.
fn random_plays(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let kb = mean_kb(params);
    let total = between(0.25, 0.5) * kb;
    let centre = log_between(between, 1e-3, 5e-3);
    let sigma = between(0.3, 1.0);
    let h = &mut params.effects.hysteresis;
    let u: Vec<f64> = (0..SPREAD)
        .map(|j| -2.0 + 4.0 * j as f64 / (SPREAD - 1) as f64)
        .collect();
    let density: Vec<f64> = u.iter().map(|x| (-0.5 * x * x).exp()).collect();
    let sum: f64 = density.iter().sum();
    for ((e, x), w) in h.spread.iter_mut().zip(&u).zip(&density) {
        *e = Element {
            k: total * w / sum,
            theta: centre * (sigma * x).exp(),
        };
    }
    Planted::text(format!(
        "a Prandtl-Ishlinskii superposition of {SPREAD} plays, their saturation angles log-normal about {:.2} mrad (log-width {sigma:.2}), k_h = {total:.3} N.m/rad in all",
        1000.0 * centre
    ))
}

/// The virgin loading curve Σ_j k_j θ_j (1 − exp(−θ/θ_j)): the hysteretic torque from rest as θ
/// grows (each element's state z_j' = θ' (1 − z_j/θ_j) from 0), over 0 to 20 mrad, beside the
/// textbook forms fitted to it (book/src/diagnose.md, "The fitted law"): one element, and
/// the elastic–perfectly plastic k min(θ, θ_y).
fn loading_law(params: &Params, _: f64) -> FittedLaw {
    let h = params.effects.hysteresis;
    let element = |k: f64, t: f64, th: f64| k * t * (1.0 - (-th / t).exp());
    let curve = sampled(0.0, 0.02, |th| {
        h.elements().map(|e| element(e.k, e.theta, th)).sum()
    });
    let scaled = |g: &dyn Fn(f64) -> f64| scaled_to(&curve, g);
    let one = move |t: f64| move |th: f64| element(1.0, t, th);
    let plastic = move |t: f64| move |th: f64| th.min(t);
    let t1 = golden(1e-4, 0.05, |t| scaled(&one(t)).1);
    let (k1, _) = scaled(&one(t1));
    let ty = golden(1e-4, 0.05, |t| scaled(&plastic(t)).1);
    let (ky, _) = scaled(&plastic(ty));
    let weights: Vec<String> = GRID
        .iter()
        .zip(h.grid)
        .map(|(t, k)| format!("{k:.3} ({:.1} mrad)", 1000.0 * t))
        .collect();
    let text = format!(
        "hysteretic torque from rest: k_h {:.3} N.m/rad at theta_h {:.2} mrad, plays {} N.m/rad, relaxing at {:.2} 1/s",
        h.k_h,
        1000.0 * h.theta_h,
        weights.join(", "),
        h.r_h
    );
    let forms: Vec<TextbookForm> = vec![
        (
            "one element",
            format!("k_h = {k1:.3} N.m/rad, theta_h = {:.2} mrad", 1000.0 * t1),
            Box::new(move |th| k1 * one(t1)(th)),
        ),
        (
            "elastic-perfectly plastic",
            format!("k = {ky:.3} N.m/rad, yield at {:.2} mrad", 1000.0 * ty),
            Box::new(move |th| ky * plastic(ty)(th)),
        ),
    ];
    FittedLaw::of_curve(text, ["theta [rad]", "torque [N.m]"], curve, forms)
}

/// The hysteretic elements' terms (effects.md, "hysteresis").
#[derive(Clone, Debug)]
pub struct Terms {
    /// (index, k, θ) per element.
    elements: Vec<(usize, f64, f64)>,
    law: HysteresisLaw,
    r_h: f64,
}

impl Law for Terms {
    type Params = Hysteresis;

    /// Stage 0 is the element at the free angle, 1 … 5 the plays, the synthetic ones after them.
    fn new(h: &Hysteresis, states: &mut States) -> Terms {
        let grid = GRID.iter().zip(h.grid).map(|(&theta, k)| (k, theta));
        let spread = h.spread.iter().map(|e| (e.k, e.theta));
        let free = (h.k_h, h.theta_h);
        let elements = states.push_grid(Effect::Hysteresis, free, grid, h.plays_on(), spread);
        Terms {
            elements,
            law: h.law,
            r_h: h.r_h,
        }
    }

    #[inline]
    fn add_rhs(&self, at: &At, dx: &mut [f64]) -> Result<(), DomainError> {
        let xi = at.xi();
        let omega = xi[P] / at.act().inertia;
        for &(k, kj, theta) in &self.elements {
            dx[P] -= kj * xi[k];
            dx[k] = self.rate(theta, omega, xi[k]).0;
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
        let (xi, inertia, o) = (at.xi(), at.act().inertia, offset[at.i]);
        for &(k, kj, theta) in &self.elements {
            let (_, d_omega, d_z) = self.rate(theta, xi[P] / inertia, xi[k]);
            add(o + P, o + k, -kj);
            add(o + k, o + P, d_omega / inertia);
            add(o + k, o + k, d_z);
        }
        Ok(())
    }

    /// The hysteretic torques' work: no storage function, so all of it counts here.
    fn dissipation(&self, act: &Actuator, xi: &[f64]) -> Result<f64, DomainError> {
        Ok(self
            .elements
            .iter()
            .map(|&(k, kj, _)| kj * xi[k] * xi[P] / act.inertia)
            .sum())
    }

    fn rest(&self, _: f64, out: &mut Vec<f64>) {
        out.extend(self.elements.iter().map(|_| 0.0));
    }

    fn scales(&self, a: &Actuator, theta_star: f64, out: &mut Vec<f64>) {
        out.extend(
            self.elements
                .iter()
                .map(|&(_, k, _)| torque_state_scale(a, theta_star, k)),
        );
    }
}

impl Terms {
    /// ż of the element saturating at θ_j and its partial derivatives (∂/∂ω, ∂/∂z), the
    /// relaxation −r_h z included.
    fn rate(&self, theta_j: f64, omega: f64, z: f64) -> (f64, f64, f64) {
        let (rate, d_omega, d_z) = law(self.law, theta_j, omega, z);
        (rate - self.r_h * z, d_omega, d_z - self.r_h)
    }
}

/// The hysteresis law's ż of an element saturating at θ_h and its partial derivatives
/// (∂/∂ω, ∂/∂z).
fn law(law: HysteresisLaw, theta_h: f64, omega: f64, z: f64) -> (f64, f64, f64) {
    match law {
        HysteresisLaw::BoucWen => {
            let c = 0.5 / theta_h; // β = γ
            (
                omega - c * omega.abs() * z - c * omega * z.abs(),
                1.0 - c * omega.signum() * z - c * z.abs(),
                -c * omega.abs() - c * omega * z.signum(),
            )
        }
        HysteresisLaw::Dahl => (
            omega - omega.abs() * z / theta_h,
            1.0 - omega.signum() * z / theta_h,
            -omega.abs() / theta_h,
        ),
    }
}
