//! The missing-effect library (book/src/effects.md, "The effect library"): mechanisms
//! the paper's model leaves out, each an optional extension with its own parameters and, where it
//! needs them, its own states. Every family is neutral at its default parameters, so the default
//! model is the paper's, state for state.
//!
//! Each family has one module that holds all of it: its parameters (their struct, its neutral
//! default and its rows of the parameter table), its states, its terms (a [`terms::Law`]: energy,
//! right-hand side, Jacobian, dissipation), its "on" values, its screening probes, the
//! experiment that exposes it, and its hidden forms for synthetic data (its [`Family`]). The
//! registry below lists the modules once; everything else reads the families from it.
//!
//! Terms, parameters and energy of each family: [book/src/effects.md](effects.md).

mod family;
pub mod terms;

pub mod amplifier_lag;
pub mod charge_drift;
pub mod convex;
pub mod coupling;
pub mod creep;
pub mod delay;
pub mod hysteresis;
pub mod preload;
pub mod prony;
pub mod saturation;
pub mod stiffening;

use std::fmt;

pub use family::{
    Drive, Exposing, Family, FittedLaw, Form, Magnitude, Plant, Planted, Probe, Scaling, Textbook,
    log_between, nonnegative_least_squares,
};
use terms::{At, Law, Port, States, Torque};

use crate::model::actuator::Actuator;
use crate::model::shell::DomainError;

/// The registry: one line per family, `Variant => module(ParamsStruct)`, in the order of
/// book/src/effects.md. It makes the [`Effect`] names, the [`EffectParams`] (one field
/// per family, named by its module) and the [`Laws`] that evaluate every family's terms in this
/// order, each statically. The module provides `FAMILY` (its [`Family`]), the params struct
/// (its `Default` neutral) and `Terms` (its [`Law`]).
macro_rules! registry {
    ($($variant:ident => $module:ident($params:ident),)*) => {
        /// The families of the library, in the order of book/src/effects.md.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum Effect {
            $($variant,)*
        }

        impl Effect {
            pub const ALL: [Effect; [$(Effect::$variant),*].len()] = [$(Effect::$variant),*];

            /// The family's description, from its module.
            pub fn family(self) -> &'static Family {
                match self {
                    $(Effect::$variant => &$module::FAMILY,)*
                }
            }
        }

        /// The parameters of all families; [`Default`] is neutral (the paper's model) in
        /// library form.
        #[derive(Clone, Copy, Debug, PartialEq, Default)]
        pub struct EffectParams {
            $(pub $module: $module::$params,)*
        }

        impl EffectParams {
            /// `effect` back at its neutral default.
            pub fn switch_off(&mut self, effect: Effect) {
                match effect {
                    $(Effect::$variant => self.$module = Default::default(),)*
                }
            }
        }

        /// Every family's terms, evaluated in registry order.
        #[derive(Clone, Debug)]
        struct Laws {
            $($module: $module::Terms,)*
        }

        impl Law for Laws {
            type Params = EffectParams;

            fn new(p: &EffectParams, states: &mut States) -> Laws {
                Laws { $($module: Law::new(&p.$module, states),)* }
            }

            fn links_actuators(&self) -> bool {
                false $(|| self.$module.links_actuators())*
            }

            #[inline]
            fn port(&self, xi: &[f64], port: &mut Port) {
                $(self.$module.port(xi, port);)*
            }

            #[inline]
            fn port_rows(&self, rows: &mut impl FnMut(usize)) {
                $(self.$module.port_rows(rows);)*
            }

            #[inline]
            fn static_torque(&self, a: &[&Actuator; 3], theta: [f64; 3], i: usize, t: &mut Torque) {
                $(self.$module.static_torque(a, theta, i, t);)*
            }

            #[inline]
            fn add_rhs(&self, at: &At, dx: &mut [f64]) -> Result<(), DomainError> {
                $(self.$module.add_rhs(at, dx)?;)*
                Ok(())
            }

            #[inline]
            fn add_jacobian(
                &self,
                at: &At,
                offset: [usize; 3],
                add: &mut impl FnMut(usize, usize, f64),
            ) -> Result<(), DomainError> {
                $(self.$module.add_jacobian(at, offset, add)?;)*
                Ok(())
            }

            #[inline]
            fn add_input_jacobian(&self, at: &At, add: &mut impl FnMut(usize, f64)) {
                $(self.$module.add_input_jacobian(at, add);)*
            }

            fn energy(&self, a: &[&Actuator; 3], x: [&[f64]; 3]) -> f64 {
                0.0 $(+ self.$module.energy(a, x))*
            }

            fn port_power(&self, at: &At) -> f64 {
                0.0 $(+ self.$module.port_power(at))*
            }

            fn dissipation(&self, act: &Actuator, xi: &[f64]) -> Result<f64, DomainError> {
                Ok(0.0 $(+ self.$module.dissipation(act, xi)?)*)
            }

            fn rest(&self, theta: f64, out: &mut Vec<f64>) {
                $(self.$module.rest(theta, out);)*
            }

            fn scales(&self, a: &Actuator, theta_star: f64, out: &mut Vec<f64>) {
                $(self.$module.scales(a, theta_star, out);)*
            }
        }
    };
}

registry! {
    Coupling => coupling(Coupling),
    ChargeDrift => charge_drift(ChargeDrift),
    Creep => creep(Creep),
    Hysteresis => hysteresis(Hysteresis),
    AmplifierLag => amplifier_lag(AmplifierLag),
    Delay => delay(Delay),
    Saturation => saturation(Saturation),
    Stiffening => stiffening(Stiffening),
    Preload => preload(Preload),
}

impl Effect {
    /// The family's name in book/src/effects.md, the CLI and the reports.
    pub fn name(self) -> &'static str {
        self.family().name
    }

    pub fn from_name(name: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.name() == name)
    }

    /// The physical mechanism, in words.
    pub fn mechanism(self) -> &'static str {
        self.family().mechanism
    }

    /// Whether the effect delays the command on its way to the actuators (a transport delay,
    /// an amplifier's lag): what a lag of the sensor does to the outputs of a nearly linear
    /// device, so the two are not fitted side by side.
    pub fn delays_the_command(self) -> bool {
        self.family().delays_the_command
    }

    /// The library's term, as written in book/src/effects.md ("The effect library").
    pub fn form(self) -> &'static str {
        self.family().form
    }

    /// The parameters of the family's library form (flat names of the parameter table): the
    /// ones that switch it on first.
    pub fn parameters(self) -> &'static [&'static str] {
        Form::library(self).free
    }

    /// The forms of the family (book/src/effects.md, each family's "Forms"), the
    /// library form first; its parameters are [`Effect::parameters`].
    pub fn forms(self) -> &'static [Form] {
        self.family().forms
    }

    /// Is the family switched on by `p`?
    pub fn is_active(self, p: &EffectParams) -> bool {
        (self.family().is_active)(p)
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl EffectParams {
    /// The families switched on, in registry order.
    pub fn active(&self) -> Vec<Effect> {
        Effect::ALL
            .into_iter()
            .filter(|e| e.is_active(self))
            .collect()
    }
}

#[cfg(test)]
mod tests;
