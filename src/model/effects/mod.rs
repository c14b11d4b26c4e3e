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

    /// The parameters of the effect (flat names of the parameter table): the ones that
    /// switch it on first.
    pub fn parameters(self) -> &'static [&'static str] {
        match self {
            Effect::Coupling => &["k_c"],
            Effect::ChargeDrift => &["R3", "tau3"],
            Effect::Creep => &["k_v", "tau_v"],
            Effect::Hysteresis => &["k_h", "theta_h"],
            Effect::AmplifierLag => &["tau_a"],
            Effect::Delay => &["tau_d"],
            Effect::Saturation => &["U_max"],
            Effect::Stiffening => &["k3"],
            Effect::Preload => &["tau0_1", "tau0_2", "tau0_3"],
        }
    }

    /// Is the effect switched on by `p`?
    pub fn is_active(self, p: &EffectParams) -> bool {
        match self {
            Effect::Coupling => p.coupling.k_c != 0.0,
            Effect::ChargeDrift => p.charge_drift.r3 > 0.0,
            Effect::Creep => p.creep.k_v > 0.0,
            Effect::Hysteresis => p.hysteresis.k_h > 0.0,
            Effect::AmplifierLag => p.amplifier_lag.tau_a > 0.0,
            Effect::Delay => p.delay.tau_d > 0.0,
            Effect::Saturation => p.saturation.u_max.is_finite(),
            Effect::Stiffening => p.stiffening.k3 != 0.0,
            Effect::Preload => p.preload.tau0.iter().any(|&t| t != 0.0),
        }
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

/// A slow charge-retention stage in series with the circuit, parameterized by R3 and
/// τ3 = R3 C3 so that R3 = 0 is off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChargeDrift {
    /// R3 [Ω]; 0 switches the stage off.
    pub r3: f64,
    /// τ3 = R3 C3 [s].
    pub tau3: f64,
    /// Library form: false. True splits the stage into two traps in series, (R3/2, τ3/3) and
    /// (R3/2, 3 τ3): a spread of trapping times.
    pub two_stages: bool,
}

/// Viscoelastic creep: standard linear solid branches (k, τ) on θ. The library has one branch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Creep {
    /// k_v [N m/rad].
    pub k_v: f64,
    /// τ_v = η / k_v [s].
    pub tau_v: f64,
    /// Library form: false. True splits k_v into two equal branches at τ_v/3 and 3 τ_v.
    pub two_branches: bool,
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
    pub law: HysteresisLaw,
}

/// Bandwidth of the amplifier: first order in the library, or two stages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmplifierLag {
    /// τ_a [s]; 0 is an ideal amplifier.
    pub tau_a: f64,
    /// Library form: 1. With 2, two stages of 0.8 τ_a and 0.2 τ_a (the same low-frequency
    /// phase lag, a steeper roll-off).
    pub order: usize,
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
                two_stages: false,
            },
            creep: Creep {
                k_v: 0.0,
                tau_v: 1.0,
                two_branches: false,
            },
            hysteresis: Hysteresis {
                k_h: 0.0,
                theta_h: 1e-3,
                law: HysteresisLaw::BoucWen,
            },
            amplifier_lag: AmplifierLag {
                tau_a: 0.0,
                order: 1,
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
