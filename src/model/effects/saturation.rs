//! `saturation` (src/model/effects/effects.md, "saturation"): the amplifier clips its output.

use std::f64::consts::PI;

use super::terms::{Law, Port, States};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe, Scaling};
use crate::model::Params;
use crate::model::params::common_rows;

/// Width of the soft saturation's knee, as a fraction of U_max.
const SOFT_KNEE: f64 = 0.15;

/// Amplifier clipping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Saturation {
    /// U_max [V]; +∞ is no clipping.
    pub u_max: f64,
    /// Library form: false (a hard clamp). True: linear up to 0.85 U_max, then a tanh knee
    /// into U_max (an output stage that compresses before it clips).
    pub soft: bool,
}

impl Default for Saturation {
    fn default() -> Self {
        Saturation {
            u_max: f64::INFINITY,
            soft: false,
        }
    }
}

const FORMS: [Form; 1] = [Form::new(Effect::Saturation, "hard", &["U_max"], &[])];

pub const FAMILY: Family = Family {
    effect: Effect::Saturation,
    name: "saturation",
    mechanism: "amplifier clipping",
    form: "U_eff = clamp(U, -U_max, U_max)",
    forms: &FORMS,
    rows: &common_rows! {
        "U_max", "V", PositiveOrInfinite, "saturation: the amplifier clips its output to +-U_max (inf: off)", effects.saturation.u_max;
    },
    choices: &[],
    state: None,
    table_stages: 0,
    is_active: |p| p.saturation.u_max.is_finite(),
    on: |f| f.saturation.u_max = 50.0,
    structures: &[],
    delays_the_command: false,
    magnitude: Magnitude::Limit,
    // limits just below the peak command, kept as they are
    probes: |_, u_peak| {
        [0.8, 0.9, 0.97]
            .into_iter()
            .map(|f| Probe {
                form: &FORMS[0],
                columns: vec![vec![("U_max", f * u_peak)]],
                scaling: Scaling::Fixed,
            })
            .collect()
    },
    exposing: Exposing {
        text: "the same sine at 30 V and 60 V: clipping acts only above U_max",
        drive: Drive::Levels {
            omega: 3.0 * PI,
            switch: 6.0,
        },
        t_end: 12.0,
    },
    hidden: compressing,
    variants: &[],
    law: None,
};

/// An output stage that compresses before it clips.
fn compressing(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    let s = &mut params.effects.saturation;
    s.soft = true;
    s.u_max = between(42.0, 55.0);
    Planted::text(format!(
        "amplifier compressing from 0.85 U_max into U_max = {:.1} V",
        s.u_max
    ))
}

/// The clipping of the port voltage (effects.md, "saturation").
#[derive(Clone, Debug)]
pub struct Terms(Saturation);

impl Law for Terms {
    type Params = Saturation;

    fn new(s: &Saturation, _: &mut States) -> Terms {
        Terms(*s)
    }

    /// The port receives the clipped voltage, at the clipping's slope.
    #[inline]
    fn port(&self, _: &[f64], port: &mut Port) {
        let s = self.0;
        if !s.u_max.is_finite() {
            return;
        }
        let v = port.u_eff;
        // the soft form: linear up to U_max − w, then a tanh knee of width w into U_max
        let knee = if s.soft { SOFT_KNEE * s.u_max } else { 0.0 };
        let start = s.u_max - knee;
        let (u_eff, slope) = if v.abs() <= start {
            (v, 1.0)
        } else if knee == 0.0 {
            (s.u_max.copysign(v), 0.0)
        } else {
            let t = ((v.abs() - start) / knee).tanh();
            ((start + knee * t).copysign(v), 1.0 - t * t)
        };
        port.u_eff = u_eff;
        port.slope *= slope;
    }
}
