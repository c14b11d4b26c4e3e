//! The missing-effect library (src/model/effects/effects.md, "The effect library"): mechanisms
//! the paper's model leaves out, each an optional extension with its own parameters and, where it
//! needs them, its own states. Every effect is neutral at its default parameters, so the default
//! model is the paper's, state for state.
//!
//! Each effect has its library form (the canonical term of src/model/effects/effects.md, the one
//! `hasel diagnose` fits) and, for some, other forms of the same mechanism (another coupling
//! geometry, a drift stage elsewhere in the circuit, another hysteresis law, …). The other forms
//! are not in the parameter table: they exist so that synthetic data can hide a mechanism whose
//! form differs from the library's term, as real data does.
//!
//! The terms themselves (their energy, right-hand side and Jacobian) are in [`terms`]; the
//! platform assembles them around the unchanged actuator equations.
//!
//! Terms, parameters and energy of each effect: [src/model/effects/effects.md](effects.md).

pub mod terms;

use std::fmt;

/// The effects of the library, in the order of src/model/effects/effects.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Effect {
    Coupling,
    ChargeDrift,
    Creep,
    Hysteresis,
    AmplifierLag,
    Delay,
    Saturation,
    Stiffening,
    Preload,
}

impl Effect {
    pub const ALL: [Effect; 9] = [
        Effect::Coupling,
        Effect::ChargeDrift,
        Effect::Creep,
        Effect::Hysteresis,
        Effect::AmplifierLag,
        Effect::Delay,
        Effect::Saturation,
        Effect::Stiffening,
        Effect::Preload,
    ];

    /// The effect's name in src/model/effects/effects.md, the CLI and the reports.
    pub fn name(self) -> &'static str {
        match self {
            Effect::Coupling => "coupling",
            Effect::ChargeDrift => "charge_drift",
            Effect::Creep => "creep",
            Effect::Hysteresis => "hysteresis",
            Effect::AmplifierLag => "amplifier_lag",
            Effect::Delay => "delay",
            Effect::Saturation => "saturation",
            Effect::Stiffening => "stiffening",
            Effect::Preload => "preload",
        }
    }

    pub fn from_name(name: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.name() == name)
    }

    /// The physical mechanism, in words.
    pub fn mechanism(self) -> &'static str {
        match self {
            Effect::Coupling => "elastic coupling of the actuators through the shared platform",
            Effect::ChargeDrift => "a slow charge-retention stage (dielectric charge trapping)",
            Effect::Creep => "viscoelastic creep of the shell film",
            Effect::Hysteresis => "rate-independent hysteresis of zipping",
            Effect::AmplifierLag => "bandwidth of the high-voltage amplifier",
            Effect::Delay => "transport delay between command and actuator",
            Effect::Saturation => "amplifier clipping",
            Effect::Stiffening => "nonlinear stiffness of the film",
            Effect::Preload => "a constant load on each actuator",
        }
    }

    /// Whether the effect delays the command on its way to the actuators (a transport delay,
    /// an amplifier's lag): what a lag of the sensor does to the outputs of a nearly linear
    /// device, so the two are not fitted side by side.
    pub fn delays_the_command(self) -> bool {
        matches!(self, Effect::Delay | Effect::AmplifierLag)
    }

    /// The library's term, as written in src/model/effects/effects.md ("The effect library").
    pub fn form(self) -> &'static str {
        match self {
            Effect::Coupling => "H += 1/2 k_c sum_{i<j} (h_i - h_j)^2",
            Effect::ChargeDrift => {
                "one more (C3 || R3) stage in the series circuit, V3 = R3 Q3 / tau3"
            }
            Effect::Creep => "H += 1/2 k_v (theta - z)^2, dz/dt = (theta - z) / tau_v",
            Effect::Hysteresis => {
                "Bouc-Wen state z on theta (n = 1, beta = gamma = 1/(2 theta_h)), torque -k_h z"
            }
            Effect::AmplifierLag => "tau_a dU_eff/dt = U - U_eff",
            Effect::Delay => "U_eff(t) = U(t - tau_d)",
            Effect::Saturation => "U_eff = clamp(U, -U_max, U_max)",
            Effect::Stiffening => "H += 1/4 k3 theta^4",
            Effect::Preload => "H += tau0_i theta_i (a constant torque against theta)",
        }
    }

    /// The parameters of the effect's library form (flat names of the parameter table): the
    /// ones that switch it on first.
    pub fn parameters(self) -> &'static [&'static str] {
        Form::library(self).free
    }

    /// The forms of the family (src/model/effects/effects.md, each effect's "Forms"), the
    /// library form first; its parameters are [`Effect::parameters`].
    pub fn forms(self) -> &'static [Form] {
        const fn form(
            effect: Effect,
            name: &'static str,
            free: &'static [&'static str],
            settings: &'static [(&'static str, f64)],
        ) -> Form {
            Form {
                effect,
                name,
                free,
                magnitudes: free.split_at(1).0,
                settings,
            }
        }
        use Effect::*;
        const COUPLING: [Form; 2] = [
            form(Coupling, "equal", &["k_c"], &[]),
            form(Coupling, "pairs", &["k_c", "w_c13", "w_c23"], &[]),
        ];
        const DRIFT: [Form; 3] = [
            form(
                ChargeDrift,
                "series",
                &["R3", "tau3"],
                &[("drift_site", 0.0)],
            ),
            form(
                ChargeDrift,
                "electrode",
                &["C3", "tau3"],
                &[("drift_site", 1.0)],
            ),
            form(ChargeDrift, "film", &["C3", "tau3"], &[("drift_site", 2.0)]),
        ];
        const CREEP: [Form; 2] = [
            form(Creep, "one_time", &["k_v", "tau_v"], &[]),
            Form {
                magnitudes: &["k_v", "k_v2"],
                ..form(Creep, "two_times", &["k_v", "tau_v", "k_v2", "tau_v2"], &[])
            },
        ];
        const HYSTERESIS: [Form; 2] = [
            form(Hysteresis, "rate_independent", &["k_h", "theta_h"], &[]),
            form(
                Hysteresis,
                "rate_dependent",
                &["k_h", "theta_h", "r_h"],
                &[],
            ),
        ];
        const AMPLIFIER: [Form; 2] = [
            form(AmplifierLag, "first_order", &["tau_a"], &[]),
            Form {
                magnitudes: &["tau_a", "tau_a2"],
                ..form(AmplifierLag, "second_order", &["tau_a", "tau_a2"], &[])
            },
        ];
        const DELAY: [Form; 1] = [form(Delay, "constant", &["tau_d"], &[])];
        const SATURATION: [Form; 1] = [form(Saturation, "hard", &["U_max"], &[])];
        const STIFFENING: [Form; 1] = [form(Stiffening, "quartic", &["k3"], &[])];
        const PRELOAD: [Form; 1] = [form(
            Preload,
            "constant",
            &["tau0_1", "tau0_2", "tau0_3"],
            &[],
        )];
        match self {
            Coupling => &COUPLING,
            ChargeDrift => &DRIFT,
            Creep => &CREEP,
            Hysteresis => &HYSTERESIS,
            AmplifierLag => &AMPLIFIER,
            Delay => &DELAY,
            Saturation => &SATURATION,
            Stiffening => &STIFFENING,
            Preload => &PRELOAD,
        }
    }

    /// The form of the family called `name`.
    pub fn form_named(self, name: &str) -> Option<&'static Form> {
        self.forms().iter().find(|f| f.name == name)
    }

    /// Is the effect switched on by `p`?
    pub fn is_active(self, p: &EffectParams) -> bool {
        match self {
            Effect::Coupling => p.coupling.k_c != 0.0,
            Effect::ChargeDrift => match p.charge_drift.site {
                DriftSite::Series => p.charge_drift.r3 > 0.0,
                _ => p.charge_drift.c3 > 0.0,
            },
            Effect::Creep => p.creep.k_v > 0.0 || p.creep.k_v2 > 0.0,
            Effect::Hysteresis => p.hysteresis.k_h > 0.0,
            Effect::AmplifierLag => p.amplifier_lag.tau_a > 0.0,
            Effect::Delay => p.delay.tau_d > 0.0,
            Effect::Saturation => p.saturation.u_max.is_finite(),
            Effect::Stiffening => p.stiffening.k3 != 0.0,
            Effect::Preload => p.preload.tau0.iter().any(|&t| t != 0.0),
        }
    }
}

/// One form of an effect's family: the parameters it frees (its magnitude first) and the
/// settings that select it (src/model/effects/effects.md, each effect's "Forms").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Form {
    pub effect: Effect,
    pub name: &'static str,
    pub free: &'static [&'static str],
    /// The parameters that switch the form on, any one of which is enough: its first free
    /// parameter, or each of interchangeable ones (the two stages of a second-order amplifier,
    /// the two creep branches), of which a fit may leave either near 0.
    pub magnitudes: &'static [&'static str],
    /// Parameters set to select the form, never fitted (e.g. `drift_site`).
    pub settings: &'static [(&'static str, f64)],
}

impl Form {
    /// The library form of `effect`.
    pub fn library(effect: Effect) -> &'static Form {
        &effect.forms()[0]
    }

    /// Is this the family's library form?
    pub fn is_library(&self) -> bool {
        self.name == self.effect.forms()[0].name
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Elastic coupling through the platform. Library form: equal weights on the three pairs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coupling {
    /// k_c [N/m]: H += ½ k_c Σ_{i<j} w_ij (h_i − h_j)².
    pub k_c: f64,
    /// Pair weights (w_12, w_13, w_23); all 1 in the library's form.
    pub weights: [f64; 3],
}

/// Where the charge-retention element sits in the circuit (src/model/effects/effects.md,
/// "charge_drift").
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

/// Bandwidth of the amplifier: one first-order stage, or two in cascade.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmplifierLag {
    /// τ_a [s]; 0 is an ideal amplifier.
    pub tau_a: f64,
    /// τ_a2 [s] of a second stage after the first; 0 (the default) is none.
    pub tau_a2: f64,
}

/// Transport delay between the command and the actuator; applied by the simulation, which
/// holds the input history. Before the first command has arrived the actuator sees U = 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Delay {
    /// τ_d [s].
    pub tau_d: f64,
}

/// Amplifier clipping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Saturation {
    /// U_max [V]; +∞ is no clipping.
    pub u_max: f64,
    /// Library form: false (a hard clamp). True: linear up to 0.85 U_max, then a tanh knee
    /// into U_max (an output stage that compresses before it clips).
    pub soft: bool,
}

/// Nonlinear film stiffness: H += k3 |θ|^n / n.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stiffening {
    /// k3 [N m/rad^(n−1)].
    pub k3: f64,
    /// Library form: 4.
    pub exponent: i32,
}

/// How a preload acts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PreloadLaw {
    /// Library form: a constant torque τ0 against θ (H += τ0 θ).
    Constant,
    /// A weight carried on the platform: the torque τ0 cos θ (H += τ0 sin θ).
    Weight,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Preload {
    /// τ0,i [N m] per actuator, positive against θ.
    pub tau0: [f64; 3],
    pub law: PreloadLaw,
}

/// The parameters of all effects; [`Default`] is neutral (the paper's model) in library form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EffectParams {
    pub coupling: Coupling,
    pub charge_drift: ChargeDrift,
    pub creep: Creep,
    pub hysteresis: Hysteresis,
    pub amplifier_lag: AmplifierLag,
    pub delay: Delay,
    pub saturation: Saturation,
    pub stiffening: Stiffening,
    pub preload: Preload,
}

impl Default for EffectParams {
    fn default() -> Self {
        EffectParams {
            coupling: Coupling {
                k_c: 0.0,
                weights: [1.0; 3],
            },
            charge_drift: ChargeDrift {
                r3: 0.0,
                tau3: 1.0,
                c3: 0.0,
                site: DriftSite::Series,
                two_stages: false,
            },
            creep: Creep {
                k_v: 0.0,
                tau_v: 1.0,
                k_v2: 0.0,
                tau_v2: 3.0,
            },
            hysteresis: Hysteresis {
                k_h: 0.0,
                theta_h: 1e-3,
                r_h: 0.0,
                law: HysteresisLaw::BoucWen,
            },
            amplifier_lag: AmplifierLag {
                tau_a: 0.0,
                tau_a2: 0.0,
            },
            delay: Delay { tau_d: 0.0 },
            saturation: Saturation {
                u_max: f64::INFINITY,
                soft: false,
            },
            stiffening: Stiffening {
                k3: 0.0,
                exponent: 4,
            },
            preload: Preload {
                tau0: [0.0; 3],
                law: PreloadLaw::Constant,
            },
        }
    }
}

impl EffectParams {
    /// The effects switched on, in library order.
    pub fn active(&self) -> Vec<Effect> {
        Effect::ALL
            .into_iter()
            .filter(|e| e.is_active(self))
            .collect()
    }
}

#[cfg(test)]
mod tests;
