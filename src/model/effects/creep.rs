//! `creep` (src/model/effects/effects.md, "creep"): viscoelastic creep of the shell film,
//! standard linear solid branches on θ.

use super::family::mean_kb;
use super::log_between;
use super::terms::{At, Law, States};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, Scaling};
use crate::model::Params;
use crate::model::actuator::{Actuator, P, StateInfo, THETA};
use crate::model::params::common_rows;
use crate::model::shell::DomainError;

/// Viscoelastic creep: standard linear solid branches (k, τ) on θ, one or two.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Creep {
    /// k_v [N m/rad] of the first branch; 0 switches it off.
    pub k_v: f64,
    /// τ_v = η / k_v [s].
    pub tau_v: f64,
    /// k_v2 [N m/rad] of the second branch; 0 (the default) switches it off.
    pub k_v2: f64,
    /// τ_v2 [s] of the second branch.
    pub tau_v2: f64,
}

impl Default for Creep {
    fn default() -> Self {
        Creep {
            k_v: 0.0,
            tau_v: 1.0,
            k_v2: 0.0,
            tau_v2: 3.0,
        }
    }
}

const FORMS: [Form; 2] = [
    Form::new(Effect::Creep, "one_time", &["k_v", "tau_v"], &[]),
    Form {
        magnitudes: &["k_v", "k_v2"],
        ..Form::new(
            Effect::Creep,
            "two_times",
            &["k_v", "tau_v", "k_v2", "tau_v2"],
            &[],
        )
    },
];

pub const FAMILY: Family = Family {
    effect: Effect::Creep,
    name: "creep",
    mechanism: "viscoelastic creep of the shell film",
    form: "H += 1/2 k_v (theta - z)^2, dz/dt = (theta - z) / tau_v",
    forms: &FORMS,
    rows: &common_rows! {
        "k_v", "N.m/rad", NonNegative, "creep: stiffness k_v of the standard linear solid on theta (0: off)", effects.creep.k_v;
        "tau_v", "s", Positive, "creep: relaxation time tau_v = eta / k_v", effects.creep.tau_v;
        "k_v2", "N.m/rad", NonNegative, "creep: stiffness k_v2 of a second branch (0: off)", effects.creep.k_v2;
        "tau_v2", "s", Positive, "creep: relaxation time tau_v2 of the second branch", effects.creep.tau_v2;
    },
    choices: &[],
    state: Some(StateInfo {
        name: "z_v",
        unit: "rad",
        description: "internal angle z of the standard linear solid",
    }),
    table_stages: 2,
    is_active: |p| p.creep.k_v > 0.0 || p.creep.k_v2 > 0.0,
    on: |f| {
        f.creep.k_v = 0.05;
        f.creep.tau_v = 0.3;
        f.creep.k_v2 = 0.02;
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
    hidden: spread_times,
    variants: &[("creep_two_times", unequal_times)],
    law: None,
};

/// One branch at three times, two branches at a short and a long time (src/diagnose/
/// diagnose.md, "Screening").
fn probes(params: &Params, _: f64) -> Vec<Probe> {
    let kb = mean_kb(params);
    let mut out: Vec<Probe> = [0.2, 0.6, 2.0]
        .into_iter()
        .map(|tau| Probe::one(&FORMS[0], vec![("k_v", 0.2 * kb), ("tau_v", tau)]))
        .collect();
    out.push(Probe {
        form: &FORMS[1],
        columns: vec![
            vec![("k_v", 0.2 * kb), ("tau_v", 0.2)],
            vec![("k_v2", 0.2 * kb), ("tau_v2", 2.0)],
        ],
        scaling: Scaling::Magnitude,
    });
    out
}

/// Creep in two equal branches at τ_v/3 and 3 τ_v.
fn spread_times(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let k_v = between(0.15, 0.4) * mean_kb(params);
    let tau_v = log_between(between, 0.2, 2.0);
    two_branches(
        &mut params.effects.creep,
        k_v,
        0.5,
        tau_v / 3.0,
        3.0 * tau_v,
    );
    Planted::text(format!(
        "creep in two branches (tau_v/3 and 3 tau_v), k_v = {k_v:.3} N.m/rad, tau_v = {tau_v:.2} s"
    ))
}

/// Creep in two unequal branches at τ and 8 τ.
fn unequal_times(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let k_v = between(0.15, 0.4) * mean_kb(params);
    let tau_v = log_between(between, 0.1, 0.5);
    let share = between(0.25, 0.4);
    two_branches(&mut params.effects.creep, k_v, share, tau_v, 8.0 * tau_v);
    Planted::text(format!(
        "creep in two branches, {:.0} % at tau = {tau_v:.2} s and the rest at 8 tau, k_v = {k_v:.3} N.m/rad",
        100.0 * share
    ))
}

/// Creep of stiffness `k_v` in two branches: a `share` of it at `tau`, the rest at `tau2`.
fn two_branches(creep: &mut Creep, k_v: f64, share: f64, tau: f64, tau2: f64) {
    creep.k_v = share * k_v;
    creep.tau_v = tau;
    creep.k_v2 = (1.0 - share) * k_v;
    creep.tau_v2 = tau2;
}

/// The branches' terms: H += ½ k_b (θ − z_b)², ż_b = (θ − z_b) / τ_b (effects.md, "creep").
#[derive(Clone, Debug)]
pub struct Terms {
    /// (index, k, τ) per branch.
    branches: Vec<(usize, f64, f64)>,
}

impl Law for Terms {
    type Params = Creep;

    fn new(cr: &Creep, states: &mut States) -> Terms {
        let mut branches = Vec::new();
        for (b, (kb, tb)) in [(cr.k_v, cr.tau_v), (cr.k_v2, cr.tau_v2)]
            .into_iter()
            .enumerate()
        {
            if kb > 0.0 {
                branches.push((states.push(Effect::Creep, b), kb, tb));
            }
        }
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
