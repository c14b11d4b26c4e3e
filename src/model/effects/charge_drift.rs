//! `charge_drift` (book/src/effects.md, "charge_drift"): a slow charge-retention
//! element, in series with the circuit or as an absorption branch across part of the film; and
//! the same two sites as Prony series on a fixed logarithmic grid of times: dielectric absorption
//! as R–C branches across the film (Debye relaxations) of non-negative capacitances (the
//! spectrum), and trapping as (C ∥ R) stages in series of non-negative resistances (the series
//! spectrum).

use super::prony::{self, Branch, GRID, SPREAD};
use super::terms::{At, Law, States};
use super::{
    Drive, Effect, Exposing, Family, FittedLaw, Form, Magnitude, Planted, Probe, Scaling,
    log_between,
};
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
    fn from_index(v: f64) -> DriftSite {
        DriftSite::ALL[(v.round() as usize).min(2)]
    }
}

/// The spectrum's capacitances, rows of the parameter table, one per time of [`GRID`].
pub const GRID_NAMES: [&str; 6] = [
    "C3_30ms", "C3_100ms", "C3_300ms", "C3_1s", "C3_3s", "C3_10s",
];

/// The series spectrum's resistances, rows of the parameter table, one per time of [`GRID`].
pub const SERIES_NAMES: [&str; 6] = [
    "R3_30ms", "R3_100ms", "R3_300ms", "R3_1s", "R3_3s", "R3_10s",
];

/// The stage of the first of the spectrum's states (`Q32` … `Q37`), after the element's.
const GRID_STAGE: usize = 1;
/// The stage of the first of the series spectrum's states (`Q38` … `Q313`), after the
/// spectrum's.
const SERIES_STAGE: usize = GRID_STAGE + GRID.len();
/// The stage of the synthetic second trap's state, after the series spectrum's.
const SECOND_TRAP_STAGE: usize = SERIES_STAGE + GRID.len();
/// The stage of the first synthetic branch's state.
const SPREAD_STAGE: usize = SECOND_TRAP_STAGE + 1;

/// A slow charge-retention element: in series (R3, τ3 = R3 C3, off at R3 = 0) or as an
/// absorption branch across part of the film (C3, τ3 = R3 C3, off at C3 = 0); absorption
/// branches across the film, (C_b, τ_b) with R_b = τ_b / C_b, on the grid (the spectrum) and,
/// for synthetic data, at any times; and stages in series, (R_k, τ_k) with C_k = τ_k / R_k, on
/// the grid (the series spectrum).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChargeDrift {
    /// R3 \[Ω\] of the series stage; 0 switches it off.
    pub r3: f64,
    /// τ3 = R3 C3 \[s\].
    pub tau3: f64,
    /// C3 \[F\] of an absorption branch (sites other than `Series`); 0 switches it off.
    pub c3: f64,
    pub site: DriftSite,
    /// Only for synthetic data (series site): true splits the stage into two traps in series,
    /// (R3/2, τ3/3) and (R3/2, 3 τ3): a spread of trapping times.
    pub two_stages: bool,
    /// The spectrum: the capacitance C_b \[F\] of the absorption branch across the film at each
    /// time of [`GRID`].
    pub grid: [f64; 6],
    /// Absorption branches across the film at any times (weight C_b \[F\]), for synthetic data
    /// only (no row of the table reaches them): a kernel the grid does not contain.
    pub spread: [Branch; SPREAD],
    /// The series spectrum: the resistance R_k \[Ω\] of the (C ∥ R) stage in series at each
    /// time of [`GRID`].
    pub series: [f64; 6],
}

impl Default for ChargeDrift {
    fn default() -> Self {
        ChargeDrift {
            r3: 0.0,
            tau3: 1.0,
            c3: 0.0,
            site: DriftSite::Series,
            two_stages: false,
            grid: [0.0; 6],
            spread: [Branch::OFF; SPREAD],
            series: [0.0; 6],
        }
    }
}

impl ChargeDrift {
    /// Is the element (the series stage or the one branch) on at its magnitude?
    fn element_on(&self) -> bool {
        match self.site {
            DriftSite::Series => self.r3 > 0.0,
            _ => self.c3 > 0.0,
        }
    }

    /// Is the spectrum on?
    fn spectrum_on(&self) -> bool {
        self.grid.iter().any(|&c| c > 0.0)
    }

    /// Is the series spectrum on?
    fn series_spectrum_on(&self) -> bool {
        self.series.iter().any(|&r| r > 0.0)
    }
}

const FORMS: [Form; 5] = [
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
    // across the film whatever `drift_site`: no setting
    Form {
        magnitudes: &GRID_NAMES,
        ..Form::new(Effect::ChargeDrift, "spectrum", &GRID_NAMES, &[])
    },
    // in series whatever `drift_site`: no setting
    Form {
        magnitudes: &SERIES_NAMES,
        ..Form::new(Effect::ChargeDrift, "series_spectrum", &SERIES_NAMES, &[])
    },
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
        grid "C3", "F", "charge_drift: capacitance of the spectrum's absorption branch across the film", charge_drift.grid;
        grid "R3", "Ohm", "charge_drift: resistance of the series spectrum's (C || R) stage", charge_drift.series;
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
        description: "charge Q3 of a drift stage's or an absorption branch's capacitor",
    }),
    // the element, the grid's branches and the grid's series stages
    table_stages: 1 + 2 * GRID.len(),
    is_active: |p| is_on(&p.charge_drift),
    on: |f| {
        f.charge_drift.r3 = 2e4;
        f.charge_drift.tau3 = 0.5;
        f.charge_drift.grid = [1e-9, 0.0, 2e-9, 0.0, 1e-9, 3e-9];
        f.charge_drift.series = [0.0, 1e4, 0.0, 2e4, 0.0, 1e4];
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
    variants: &[
        ("charge_drift_film", across_the_film),
        ("charge_drift_kernel", random_kernel),
    ],
    law: |p, _| {
        let cd = &p.effects.charge_drift;
        absorption_law(cd).or_else(|| series_law(cd))
    },
};

/// The element is on at its magnitude (R3 in series, C3 across the film), or an absorption
/// branch of the spectrum or a synthetic one, or a stage of the series spectrum.
fn is_on(cd: &ChargeDrift) -> bool {
    cd.element_on()
        || cd.spectrum_on()
        || cd.series_spectrum_on()
        || cd.spread.iter().any(|b| b.weight > 0.0)
}

/// The series stage's resistance in the probes: a stage of it takes a visible share of the
/// film's voltage at the paper's drive.
const PROBE_R3: f64 = 3e4;

/// Each site at three time constants; the spectra, one column per weight (book/src/diagnose.md,
/// "Screening").
fn probes(params: &Params, _: f64) -> Vec<Probe> {
    // the film's voltage is held by the source through R0 + R1: a branch across it shows
    // when its R3 = tau3 / C3 is a few times R0 + R1
    let r01 = params.act[0].r0 + params.act[0].r1;
    let mut out = Vec::new();
    for form in &FORMS[..3] {
        for tau in [0.3, 1.0, 3.0] {
            let magnitude = if form.name == "series" {
                ("R3", PROBE_R3)
            } else {
                ("C3", tau / (3.0 * r01))
            };
            out.push(Probe::one(form, vec![magnitude, ("tau3", tau)]));
        }
    }
    // each branch of the grid as the film's branches are probed: R_b = 3 (R0 + R1)
    out.push(Probe {
        form: &FORMS[3],
        columns: GRID
            .iter()
            .zip(GRID_NAMES)
            .map(|(&tau, n)| vec![(n, tau / (3.0 * r01))])
            .collect(),
        scaling: Scaling::Weights,
    });
    // each stage of the series grid as the series stage is probed
    out.push(Probe {
        form: &FORMS[4],
        columns: SERIES_NAMES.iter().map(|&n| vec![(n, PROBE_R3)]).collect(),
        scaling: Scaling::Weights,
    });
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

/// Dielectric absorption across the film of a kernel the grid does not contain
/// ([`prony::random_kernel`]: two times off the grid, a stretched exponential, a power law),
/// at a random strength (effects.md, "Hidden forms for synthetic data").
fn random_kernel(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let (branches, kernel) = prony::random_kernel(between);
    // as `across_the_film`: the source holds the film's voltage through R0 + R1, and the
    // branches take a visible share of the current when their impedance at the paper's drive,
    // 3π rad/s, is 1 to 4 times R0 + R1 (one branch of ω τ3 ≫ 1: its R3)
    let r01 = params.act[0].r0 + params.act[0].r1;
    let f = log_between(between, 1.0, 4.0);
    let c = 1.0 / (f * r01 * admittance(&branches, 3.0 * std::f64::consts::PI));
    params.effects.charge_drift.spread = branches.map(|b| Branch {
        weight: c * b.weight,
        ..b
    });
    Planted::text(format!(
        "dielectric absorption across the film of {kernel}, C = {c:.3e} F (impedance {f:.2} (R0 + R1) at 3 pi rad/s)"
    ))
}

/// |Σ_b w_b jω / (1 + jω τ_b)|: the admittance at ω [rad/s] of R–C branches of capacitances
/// w_b, per farad.
fn admittance(branches: &[Branch], omega: f64) -> f64 {
    let (re, im) = branches.iter().fold((0.0, 0.0), |(re, im), b| {
        let wt = omega * b.tau;
        let d = 1.0 + wt * wt;
        (re + b.weight * omega * wt / d, im + b.weight * omega / d)
    });
    re.hypot(im)
}

/// The absorption's weights: capacitances.
const WEIGHT: prony::Weight = prony::Weight {
    symbol: "C",
    unit: "F",
    axis: "C [F]",
};

/// The series spectrum's weights: resistances.
const SERIES_WEIGHT: prony::Weight = prony::Weight {
    symbol: "R",
    unit: "Ohm",
    axis: "R [Ohm]",
};

/// The absorption across the film and the electrode as a spectrum, with the textbook kernel
/// it is nearest (effects.md, "charge_drift", "The fitted law"; [`prony::law`]): the branches
/// (τ_b, C_b), the one branch if it is on and the spectrum's ([`prony::points`]); `None` for
/// the series stage alone, which absorbs nothing across the film.
fn absorption_law(cd: &ChargeDrift) -> Option<FittedLaw> {
    let branch = (cd.site != DriftSite::Series && cd.c3 > 0.0).then_some((cd.tau3, cd.c3));
    let points: Vec<(f64, f64)> = branch
        .into_iter()
        .chain(prony::points(&cd.grid, &cd.spread))
        .collect();
    (!points.is_empty()).then(|| {
        prony::law(
            points,
            "absorption spectrum: the capacitance of each R-C absorption branch against its time R C".into(),
            &WEIGHT,
        )
    })
}

/// The series spectrum with the textbook kernel it is nearest (effects.md, "charge_drift", "The
/// fitted law"; [`prony::law`]): the stages (τ_k, R_k), the voltage they hold after a unit step
/// of current settling as Σ R_k (1 − exp(−t/τ_k)); `None` where it is off.
fn series_law(cd: &ChargeDrift) -> Option<FittedLaw> {
    let points: Vec<(f64, f64)> = prony::points(&cd.series, &[]).collect();
    (!points.is_empty()).then(|| {
        prony::law(
            points,
            "retention spectrum: the resistance of each (C || R) stage in series against its time R C".into(),
            &SERIES_WEIGHT,
        )
    })
}

/// How a state's charge is scaled: a series stage's at the current i R through its time τ, a
/// branch's at its capacitance's charge at 100 V.
#[derive(Clone, Copy, Debug)]
enum ChargeScale {
    /// τ \[s\] of a series stage.
    Series(f64),
    /// C \[F\] of a branch.
    Branch(f64),
}

/// The drift element's and the absorption branches' terms (effects.md, "charge_drift").
#[derive(Clone, Debug)]
pub struct Terms {
    /// (index, R, τ) per series stage.
    stages: Vec<(usize, f64, f64)>,
    /// The absorption branches across part of the film: (index, C, τ, site), R = τ / C; a
    /// branch of the spectrum may have C = 0.
    branches: Vec<(usize, f64, f64, DriftSite)>,
    /// Per state in block order, how its charge is scaled.
    scales: Vec<ChargeScale>,
}

impl Law for Terms {
    type Params = ChargeDrift;

    /// Stage 0 is the element (a series stage or one branch), 1 … 6 the grid's branches, 7 … 12
    /// the grid's series stages, 13 the synthetic second trap, the synthetic branches after it.
    /// The grid's branches (stages) come all together, a capacitance (resistance) of 0 among
    /// them included: a fit moves weights to and from 0, and a state that came and went with
    /// its weight would have no sensitivity.
    fn new(cd: &ChargeDrift, states: &mut States) -> Terms {
        let mut t = Terms {
            stages: Vec::new(),
            branches: Vec::new(),
            scales: Vec::new(),
        };
        let series = cd.element_on() && cd.site == DriftSite::Series;
        if series {
            let (r, tau) = if cd.two_stages {
                (0.5 * cd.r3, cd.tau3 / 3.0)
            } else {
                (cd.r3, cd.tau3)
            };
            t.stage(states, 0, r, tau);
        } else if cd.element_on() {
            t.branch(states, 0, (cd.c3, cd.tau3, cd.site), cd.c3);
        }
        if cd.spectrum_on() {
            let total = cd.grid.iter().sum();
            for (b, (&tau, c)) in GRID.iter().zip(cd.grid).enumerate() {
                t.branch(states, GRID_STAGE + b, (c, tau, DriftSite::Film), total);
            }
        }
        if cd.series_spectrum_on() {
            for (k, (&tau, r)) in GRID.iter().zip(cd.series).enumerate() {
                t.stage(states, SERIES_STAGE + k, r, tau);
            }
        }
        if series && cd.two_stages {
            t.stage(states, SECOND_TRAP_STAGE, 0.5 * cd.r3, 3.0 * cd.tau3);
        }
        for (j, b) in cd.spread.iter().enumerate().filter(|(_, b)| b.weight > 0.0) {
            let branch = (b.weight, b.tau, DriftSite::Film);
            t.branch(states, SPREAD_STAGE + j, branch, b.weight);
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
        if !self.branches.is_empty() {
            let v = act.voltages(xi)?;
            for &branch in &self.branches {
                // each branch takes i_b from the part of the film it spans
                let (k, _, _, site) = branch;
                let i = branch_current(branch, &v, xi);
                dx[Q2] -= i;
                if site == DriftSite::Film {
                    dx[Q1] -= i;
                }
                dx[k] = i;
            }
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
        if !self.branches.is_empty() {
            let v = act.voltages(xi)?;
            for &(k, c, tau, site) in &self.branches {
                // ∂i_b/∂x = (C_b ∂V_across/∂x − ∂Q3_b/∂x) / τ_b, entered in the branch's row
                // and (negated) in the rows it takes from
                let film = site == DriftSite::Film;
                let d = [
                    (THETA, c * v.v2_t / tau),
                    (actuator::L_P, c * v.v2_l / tau),
                    (Q2, c / (v.c2 * tau)),
                    (Q1, if film { c / (act.par.c1 * tau) } else { 0.0 }),
                    (k, -1.0 / tau),
                ];
                for (col, value) in d {
                    add(o + k, o + col, value);
                    add(o + Q2, o + col, -value);
                    if film {
                        add(o + Q1, o + col, -value);
                    }
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
            // Σ Q3_b² / (2 C_b); a branch of C_b = 0 holds no charge (its Q3_b' = −Q3_b / τ_b
            // from 0 at rest) and stores nothing
            for &(k, c, _, _) in self.branches.iter().filter(|b| b.1 > 0.0) {
                e += 0.5 * xi[k] * xi[k] / c;
            }
        }
        e
    }

    /// The series stage adds V3 to the port output.
    fn port_power(&self, at: &At) -> f64 {
        let (act, xi) = (at.act(), at.xi());
        act.g0 * act.ga(xi[THETA]) * at.port.u_eff * self.drift_voltage(xi)
    }

    /// The stage's resistor, with the source resistor's share of V3; each branch's resistor
    /// R_b = τ_b / C_b (none where C_b = 0: no current flows there).
    fn dissipation(&self, act: &Actuator, xi: &[f64]) -> Result<f64, DomainError> {
        let mut p = 0.0;
        if !self.stages.is_empty() {
            let v = act.voltages(xi)?;
            let (vs, v3) = (v.v1 + v.v2, self.drift_voltage(xi));
            p += act.g0 * ((vs + v3).powi(2) - vs * vs);
            // a stage of R = 0 holds no voltage and dissipates nothing
            for &(k, r, t) in self.stages.iter().filter(|s| s.1 > 0.0) {
                let vk = r * xi[k] / t;
                p += vk * vk / r;
            }
        }
        if !self.branches.is_empty() {
            let v = act.voltages(xi)?;
            for &branch in self.branches.iter().filter(|b| b.1 > 0.0) {
                let (_, c, tau, _) = branch;
                p += branch_current(branch, &v, xi).powi(2) * tau / c;
            }
        }
        Ok(p)
    }

    fn rest(&self, _: f64, out: &mut Vec<f64>) {
        out.extend(self.scales.iter().map(|_| 0.0));
    }

    /// At a 100 V command, whose source is γ1 · 100 V (the actuator's own scales): a stage's
    /// charge at the current i its voltage i R takes through C = τ / R, i τ; a branch's C at
    /// that source's voltage, which the film and the electrode hold at rest (R0 ≪ R2), a
    /// branch of the spectrum the spectrum's whole capacitance. (At 100 V across instead, a
    /// branch's charge at a start mid-run was held below a seventh of what a 60 V drive gives
    /// it, γ1 ≈ 118: `conditions`' range is 10 scales.)
    fn scales(&self, a: &Actuator, _: f64, out: &mut Vec<f64>) {
        let v_source = a.par.gamma1 * 100.0;
        let i_dc = v_source / (a.par.r0 + a.par.r1 + a.par.r2);
        out.extend(self.scales.iter().map(|s| match *s {
            ChargeScale::Series(tau) => i_dc * tau,
            ChargeScale::Branch(c) => v_source * c,
        }));
    }
}

impl Terms {
    /// Adds a series stage (R, τ) with its state, stage `stage`.
    fn stage(&mut self, states: &mut States, stage: usize, r: f64, tau: f64) {
        self.stages
            .push((states.push(Effect::ChargeDrift, stage), r, tau));
        self.scales.push(ChargeScale::Series(tau));
    }

    /// Adds an absorption branch (C, τ, site) with its state, stage `stage`, whose charge is
    /// scaled at that of capacitance `scale` at 100 V.
    fn branch(&mut self, states: &mut States, stage: usize, b: (f64, f64, DriftSite), scale: f64) {
        let k = states.push(Effect::ChargeDrift, stage);
        self.branches.push((k, b.0, b.1, b.2));
        self.scales.push(ChargeScale::Branch(scale));
    }

    /// Voltage over the drift stages, Σ R_k Q_k / τ_k [V].
    fn drift_voltage(&self, xi: &[f64]) -> f64 {
        self.stages.iter().map(|&(k, r, t)| r * xi[k] / t).sum()
    }
}

/// Current into an absorption branch, i_b = (C_b V_across − Q3_b) / τ_b (effects.md,
/// "charge_drift"), V_across = V2 across the electrode, V1 + V2 across the film.
fn branch_current(
    (k, c, tau, site): (usize, f64, f64, DriftSite),
    v: &actuator::Voltages,
    xi: &[f64],
) -> f64 {
    let across = if site == DriftSite::Film {
        v.v1 + v.v2
    } else {
        v.v2
    };
    (c * across - xi[k]) / tau
}
