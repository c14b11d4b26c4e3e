//! `hysteresis` (src/model/effects/effects.md, "hysteresis"): hysteresis of zipping, a
//! hysteretic state z_h on θ with the torque −k_h z_h.

use super::family::mean_kb;
use super::terms::{At, Law, States};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, log_between};
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

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hysteresis {
    /// k_h [N m/rad]: the torque −k_h z.
    pub k_h: f64,
    /// θ_h [rad]: the angle where the hysteretic state saturates.
    pub theta_h: f64,
    /// r_h [1/s]: the hysteretic state relaxes at this rate (0: rate-independent).
    pub r_h: f64,
    /// Only for synthetic data: the library's law is Bouc–Wen.
    pub law: HysteresisLaw,
}

impl Default for Hysteresis {
    fn default() -> Self {
        Hysteresis {
            k_h: 0.0,
            theta_h: 1e-3,
            r_h: 0.0,
            law: HysteresisLaw::BoucWen,
        }
    }
}

const FORMS: [Form; 2] = [
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
        "r_h", "Hz", NonNegative, "hysteresis: relaxation rate r_h [1/s] of the hysteretic state (0: rate-independent)", effects.hysteresis.r_h;
    },
    choices: &[],
    state: Some(StateInfo {
        name: "z_h",
        unit: "rad",
        description: "Bouc-Wen state z_h",
    }),
    table_stages: 1,
    is_active: |p| p.hysteresis.k_h > 0.0,
    on: |f| {
        f.hysteresis.k_h = 0.04;
        f.hysteresis.theta_h = 2e-3;
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
    variants: &[("hysteresis_rate", relaxing_dahl)],
    law: None,
};

/// Two saturation angles, without and with relaxation (src/diagnose/diagnose.md, "Screening").
fn probes(params: &Params, _: f64) -> Vec<Probe> {
    let kb = mean_kb(params);
    let mut out = Vec::new();
    for (form, rates) in FORMS.iter().zip([&[0.0][..], &[3.0, 10.0]]) {
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

/// The hysteretic state's terms (effects.md, "hysteresis").
#[derive(Clone, Debug)]
pub struct Terms {
    /// The state's index, when on.
    state: Option<usize>,
    h: Hysteresis,
}

impl Law for Terms {
    type Params = Hysteresis;

    fn new(h: &Hysteresis, states: &mut States) -> Terms {
        Terms {
            state: (h.k_h > 0.0).then(|| states.push(Effect::Hysteresis, 0)),
            h: *h,
        }
    }

    #[inline]
    fn add_rhs(&self, at: &At, dx: &mut [f64]) -> Result<(), DomainError> {
        if let Some(k) = self.state {
            let xi = at.xi();
            let omega = xi[P] / at.act().inertia;
            dx[P] -= self.h.k_h * xi[k];
            dx[k] = self.rate(omega, xi[k]).0;
            debug_assert!(self.h.theta_h > 0.0);
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
        if let Some(k) = self.state {
            let (xi, inertia, o) = (at.xi(), at.act().inertia, offset[at.i]);
            let (_, d_omega, d_z) = self.rate(xi[P] / inertia, xi[k]);
            add(o + P, o + k, -self.h.k_h);
            add(o + k, o + P, d_omega / inertia);
            add(o + k, o + k, d_z);
        }
        Ok(())
    }

    /// The hysteretic torque's work: no storage function, so all of it counts here.
    fn dissipation(&self, act: &Actuator, xi: &[f64]) -> Result<f64, DomainError> {
        Ok(self
            .state
            .map_or(0.0, |k| self.h.k_h * xi[k] * xi[P] / act.inertia))
    }

    fn rest(&self, _: f64, out: &mut Vec<f64>) {
        out.extend(self.state.map(|_| 0.0));
    }

    fn scales(&self, _: &Actuator, theta_star: f64, out: &mut Vec<f64>) {
        out.extend(self.state.map(|_| theta_star));
    }
}

impl Terms {
    /// ż_h and its partial derivatives (∂/∂ω, ∂/∂z), the relaxation −r_h z_h included.
    fn rate(&self, omega: f64, z: f64) -> (f64, f64, f64) {
        let (rate, d_omega, d_z) = self.law(omega, z);
        (rate - self.h.r_h * z, d_omega, d_z - self.h.r_h)
    }

    /// The hysteresis law's ż_h and its partial derivatives (∂/∂ω, ∂/∂z).
    fn law(&self, omega: f64, z: f64) -> (f64, f64, f64) {
        let theta_h = self.h.theta_h;
        match self.h.law {
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
}
