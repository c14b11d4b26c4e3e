//! `charge_drift` (src/model/effects/effects.md, "charge_drift"): a slow charge-retention
//! element, in series with the circuit or as an absorption branch across part of the film.

use super::terms::{At, Law, States};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, log_between};
use crate::model::Params;
use crate::model::actuator::{self, Actuator, Q1, Q2, StateInfo, THETA};
use crate::model::params::{ParamDef, Rule, common_rows};
use crate::model::shell::DomainError;

/// Where the charge-retention element sits in the circuit (effects.md, "charge_drift").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriftSite {
    /// Library form: a (C3 ∥ R3) stage in series with the circuit; R3 is its magnitude.
    Series,
    /// A series R3–C3 absorption branch across the zipping capacitor C2; C3 is its magnitude.
    Electrode,
    /// The same branch across the whole film (C1 ∥ R1 and C2 ∥ R2 in series).
    Film,
}

impl DriftSite {
    pub const ALL: [DriftSite; 3] = [DriftSite::Series, DriftSite::Electrode, DriftSite::Film];

    /// The value of the table's `drift_site`.
    pub fn index(self) -> f64 {
        match self {
            DriftSite::Series => 0.0,
            DriftSite::Electrode => 1.0,
            DriftSite::Film => 2.0,
        }
    }

    /// The site of a `drift_site` value (already checked to be 0, 1 or 2).
    pub fn from_index(v: f64) -> DriftSite {
        DriftSite::ALL[(v.round() as usize).min(2)]
    }
}

/// A slow charge-retention element: in series (R3, τ3 = R3 C3, off at R3 = 0) or as an
/// absorption branch across part of the film (C3, τ3 = R3 C3, off at C3 = 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChargeDrift {
    /// R3 [Ω] of the series stage; 0 switches it off.
    pub r3: f64,
    /// τ3 = R3 C3 [s].
    pub tau3: f64,
    /// C3 [F] of an absorption branch (sites other than `Series`); 0 switches it off.
    pub c3: f64,
    pub site: DriftSite,
    /// Only for synthetic data (series site): true splits the stage into two traps in series,
    /// (R3/2, τ3/3) and (R3/2, 3 τ3): a spread of trapping times.
    pub two_stages: bool,
}

impl Default for ChargeDrift {
    fn default() -> Self {
        ChargeDrift {
            r3: 0.0,
            tau3: 1.0,
            c3: 0.0,
            site: DriftSite::Series,
            two_stages: false,
        }
    }
}

const FORMS: [Form; 3] = [
    Form::new(
        Effect::ChargeDrift,
        "series",
        &["R3", "tau3"],
        &[("drift_site", 0.0)],
    ),
    Form::new(
        Effect::ChargeDrift,
        "electrode",
        &["C3", "tau3"],
        &[("drift_site", 1.0)],
    ),
    Form::new(
        Effect::ChargeDrift,
        "film",
        &["C3", "tau3"],
        &[("drift_site", 2.0)],
    ),
];

pub const FAMILY: Family = Family {
    effect: Effect::ChargeDrift,
    name: "charge_drift",
    mechanism: "a slow charge-retention stage (dielectric charge trapping)",
    form: "one more (C3 || R3) stage in the series circuit, V3 = R3 Q3 / tau3",
    forms: &FORMS,
    rows: &common_rows! {
        "R3", "Ohm", NonNegative, "charge_drift: resistance R3 of a (C3 || R3) stage in series (0: off; drift_site 0)", effects.charge_drift.r3;
        "tau3", "s", Positive, "charge_drift: time constant tau3 = R3 C3 of the drift element", effects.charge_drift.tau3;
        "C3", "F", NonNegative, "charge_drift: capacitance C3 of an R3-C3 absorption branch (0: off; drift_site 1 or 2)", effects.charge_drift.c3;
    },
    choices: &[ParamDef {
        name: "drift_site",
        unit: "1",
        description: "charge_drift: where the element sits: 0 in series (R3), 1 across the zipping capacitor C2 (C3), 2 across the whole film (C3)",
        rule: Rule::Index(3),
        actuator: None,
        get: |p| p.effects.charge_drift.site.index(),
        set: |p, v| p.effects.charge_drift.site = DriftSite::from_index(v),
    }],
    state: Some(StateInfo {
        name: "Q3",
        unit: "C",
        description: "charge Q3 of the drift stage's capacitor C3",
    }),
    table_stages: 1,
    is_active: |p| is_on(&p.charge_drift),
    on: |f| {
        f.charge_drift.r3 = 2e4;
        f.charge_drift.tau3 = 0.5;
    },
    structures: &[
        |f| {
            f.charge_drift.site = DriftSite::Electrode;
            f.charge_drift.c3 = 1e-9;
        },
        |f| {
            f.charge_drift.site = DriftSite::Film;
            f.charge_drift.c3 = 1e-9;
        },
    ],
    delays_the_command: false,
    magnitude: Magnitude::Positive,
    probes,
    exposing: Exposing {
        text: "a unipolar voltage step held for tens of seconds: trapped charge keeps drifting the stroke",
        drive: Drive::Corners(&[(0.0, 0.0), (0.05, 1.0), (20.0, 1.0)]),
        t_end: 20.0,
    },
    hidden: two_traps,
    variants: &[("charge_drift_film", across_the_film)],
    law: None,
};

/// The element is on at its magnitude: R3 in series, C3 across the film.
fn is_on(cd: &ChargeDrift) -> bool {
    match cd.site {
        DriftSite::Series => cd.r3 > 0.0,
        _ => cd.c3 > 0.0,
    }
}

/// Each site at three time constants (src/diagnose/diagnose.md, "Screening").
fn probes(params: &Params, _: f64) -> Vec<Probe> {
    // the film's voltage is held by the source through R0 + R1: a branch across it shows
    // when its R3 = tau3 / C3 is a few times R0 + R1
    let r01 = params.act[0].r0 + params.act[0].r1;
    let mut out = Vec::new();
    for form in &FORMS {
        for tau in [0.3, 1.0, 3.0] {
            let magnitude = if form.name == "series" {
                ("R3", 3e4)
            } else {
                ("C3", tau / (3.0 * r01))
            };
            out.push(Probe::one(form, vec![magnitude, ("tau3", tau)]));
        }
    }
    out
}

/// Two trapping stages in series.
fn two_traps(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let r2 = params.act[0].r2;
    let cd = &mut params.effects.charge_drift;
    cd.two_stages = true;
    cd.tau3 = log_between(between, 0.3, 3.0);
    // the stage takes i R3 / (1 + (ω τ3)²)^½ from the electrode: a tenth to a half of
    // its voltage at the drive frequency
    cd.r3 = between(0.1, 0.5) * r2 * (1.0 + (10.0 * cd.tau3).powi(2)).sqrt();
    Planted::text(format!(
        "two trapping stages in series (R3/2 at tau3/3 and 3 tau3), R3 = {:.3e} Ohm, tau3 = {:.2} s",
        cd.r3, cd.tau3
    ))
}

/// An absorption branch across the whole film.
fn across_the_film(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    // the source holds the film's voltage through R0 + R1: the branch takes a visible
    // share of the current when its R3 = tau3 / C3 is 1 to 4 times R0 + R1
    let r01 = params.act[0].r0 + params.act[0].r1;
    let (tau3, f) = (
        log_between(between, 0.3, 3.0),
        log_between(between, 1.0, 4.0),
    );
    let cd = &mut params.effects.charge_drift;
    *cd = ChargeDrift {
        site: DriftSite::Film,
        tau3,
        c3: tau3 / (f * r01),
        ..*cd
    };
    Planted::text(format!(
        "an absorption branch across the whole film, R3 = {:.0} Ohm ({f:.2} (R0 + R1)), tau3 = {tau3:.2} s",
        f * r01
    ))
}

/// The drift element's terms (effects.md, "charge_drift").
#[derive(Clone, Debug)]
pub struct Terms {
    /// (index, R, τ) per series stage.
    stages: Vec<(usize, f64, f64)>,
    /// The absorption branch across part of the film: (index, C3, τ3, site).
    branch: Option<(usize, f64, f64, DriftSite)>,
    tau3: f64,
}

impl Law for Terms {
    type Params = ChargeDrift;

    fn new(cd: &ChargeDrift, states: &mut States) -> Terms {
        let mut t = Terms {
            stages: Vec::new(),
            branch: None,
            tau3: cd.tau3,
        };
        if !is_on(cd) {
            return t;
        }
        if cd.site == DriftSite::Series {
            let stages = if cd.two_stages {
                vec![(0.5 * cd.r3, cd.tau3 / 3.0), (0.5 * cd.r3, 3.0 * cd.tau3)]
            } else {
                vec![(cd.r3, cd.tau3)]
            };
            for (k, (rk, tk)) in stages.into_iter().enumerate() {
                t.stages.push((states.push(Effect::ChargeDrift, k), rk, tk));
            }
        } else {
            let k = states.push(Effect::ChargeDrift, 0);
            t.branch = Some((k, cd.c3, cd.tau3, cd.site));
        }
        t
    }

    #[inline]
    fn port_rows(&self, rows: &mut impl FnMut(usize)) {
        // the stages carry the series current, driven by G0 ga u_eff
        for &(k, _, _) in &self.stages {
            rows(k);
        }
    }

    #[inline]
    fn add_rhs(&self, at: &At, dx: &mut [f64]) -> Result<(), DomainError> {
        let (act, xi) = (at.act(), at.xi());
        if !self.stages.is_empty() {
            let v = act.voltages(xi)?;
            let v3 = self.drift_voltage(xi);
            dx[Q1] -= act.g0 * v3;
            dx[Q2] -= act.g0 * v3;
            let i0 = act.g0 * (act.ga(xi[THETA]) * at.port.u_eff - v.v1 - v.v2 - v3);
            for &(k, _, tk) in &self.stages {
                dx[k] = i0 - xi[k] / tk;
            }
        }
        if let Some((k, _, _, site)) = self.branch {
            // the branch takes i3 from the part of the film it spans
            let i3 = self.branch_current(&act.voltages(xi)?, xi);
            dx[Q2] -= i3;
            if site == DriftSite::Film {
                dx[Q1] -= i3;
            }
            dx[k] = i3;
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
        let (act, xi, o) = (at.act(), at.xi(), offset[at.i]);
        if !self.stages.is_empty() {
            let v = act.voltages(xi)?;
            let g0 = act.g0;
            let u_eff = at.port.u_eff;
            for &(j, rj, tj) in &self.stages {
                add(o + Q1, o + j, -g0 * rj / tj);
                add(o + Q2, o + j, -g0 * rj / tj);
            }
            for &(k, _, tk) in &self.stages {
                add(
                    o + k,
                    o + THETA,
                    g0 * (act.ga_prime(xi[THETA]) * u_eff - v.v2_t),
                );
                add(o + k, o + actuator::L_P, -g0 * v.v2_l);
                add(o + k, o + Q1, -g0 / act.par.c1);
                add(o + k, o + Q2, -g0 / v.c2);
                for &(j, rj, tj) in &self.stages {
                    add(o + k, o + j, -g0 * rj / tj);
                }
                add(o + k, o + k, -1.0 / tk);
            }
        }
        if let Some((k, c3, t3, site)) = self.branch {
            let v = act.voltages(xi)?;
            // ∂i3/∂x, entered in the branch's row and (negated) in the rows it takes from
            let mut d = vec![
                (THETA, c3 * v.v2_t / t3),
                (actuator::L_P, c3 * v.v2_l / t3),
                (Q2, c3 / (v.c2 * t3)),
                (k, -1.0 / t3),
            ];
            let mut rows = vec![Q2];
            if site == DriftSite::Film {
                d.push((Q1, c3 / (act.par.c1 * t3)));
                rows.push(Q1);
            }
            for (col, value) in d {
                add(o + k, o + col, value);
                for &r in &rows {
                    add(o + r, o + col, -value);
                }
            }
        }
        Ok(())
    }

    fn energy(&self, _: &[&Actuator; 3], x: [&[f64]; 3]) -> f64 {
        let mut e = 0.0;
        for xi in x {
            for &(k, r, t) in &self.stages {
                e += 0.5 * r * xi[k] * xi[k] / t;
            }
            if let Some((k, c3, _, _)) = self.branch {
                e += 0.5 * xi[k] * xi[k] / c3;
            }
        }
        e
    }

    /// The series stage adds V3 to the port output.
    fn port_power(&self, at: &At) -> f64 {
        let (act, xi) = (at.act(), at.xi());
        act.g0 * act.ga(xi[THETA]) * at.port.u_eff * self.drift_voltage(xi)
    }

    /// The stage's resistor, with the source resistor's share of V3; the branch's resistor.
    fn dissipation(&self, act: &Actuator, xi: &[f64]) -> Result<f64, DomainError> {
        let mut p = 0.0;
        if !self.stages.is_empty() {
            let v = act.voltages(xi)?;
            let (vs, v3) = (v.v1 + v.v2, self.drift_voltage(xi));
            p += act.g0 * ((vs + v3).powi(2) - vs * vs);
            for &(k, r, t) in &self.stages {
                let vk = r * xi[k] / t;
                p += vk * vk / r;
            }
        }
        if let Some((_, c3, t3, _)) = self.branch {
            // the branch's resistor R3 = τ3 / C3
            let i3 = self.branch_current(&act.voltages(xi)?, xi);
            p += i3 * i3 * t3 / c3;
        }
        Ok(p)
    }

    fn rest(&self, _: f64, out: &mut Vec<f64>) {
        out.extend(self.stages.iter().map(|_| 0.0));
        out.extend(self.branch.iter().map(|_| 0.0));
    }

    /// The charge at the stage's voltage i R3, with C3 = τ3 / R3; a branch's C3 at the
    /// film's 100 V.
    fn scales(&self, a: &Actuator, _: f64, out: &mut Vec<f64>) {
        let i_dc = a.par.gamma1 * 100.0 / (a.par.r0 + a.par.r1 + a.par.r2);
        out.extend(self.stages.iter().map(|_| i_dc * self.tau3));
        out.extend(self.branch.iter().map(|&(_, c3, _, _)| 100.0 * c3));
    }
}

impl Terms {
    /// Voltage over the drift stages, Σ R_k Q_k / τ_k [V].
    fn drift_voltage(&self, xi: &[f64]) -> f64 {
        self.stages.iter().map(|&(k, r, t)| r * xi[k] / t).sum()
    }

    /// Current into the absorption branch, i3 = (C3 V_across − Q3) / τ3 (effects.md,
    /// "charge_drift"), V_across = V2 across the electrode, V1 + V2 across the film.
    fn branch_current(&self, v: &actuator::Voltages, xi: &[f64]) -> f64 {
        match self.branch {
            Some((k, c3, t3, site)) => {
                let across = if site == DriftSite::Film {
                    v.v1 + v.v2
                } else {
                    v.v2
                };
                (c3 * across - xi[k]) / t3
            }
            None => 0.0,
        }
    }
}
