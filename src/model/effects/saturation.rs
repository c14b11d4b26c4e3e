//! `saturation` (book/src/effects.md, "saturation"): the amplifier's static output
//! map, a monotone map of the command: unequal limits up and down, a knee of any softness (the
//! hard clamp its limit), a dead zone.

use std::f64::consts::PI;

use super::family::{FittedLaw, TextbookForm, golden, sampled};
use super::terms::{Law, Port, States};
use super::{Drive, Effect, Exposing, Family, Form, Magnitude, Planted, Probe};
use crate::model::Params;
use crate::model::params::common_rows;

/// The amplifier's static output map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Saturation {
    /// The limit of the positive side U_max \[V\]; +∞ is no clipping.
    pub u_max: f64,
    /// The limit of the negative side, −U_max_neg \[V\]; +∞: −U_max (symmetric).
    pub u_max_neg: f64,
    /// Softness s of the knee \[1\]: the Rapp curve of exponent 1/s; 0 is the hard clamp.
    pub knee: f64,
    /// Dead zone \[V\]: commands within ±U_dead give 0, beyond it the map starts from 0.
    pub u_dead: f64,
    /// For synthetic data only (no row of the table): when > 0, the knee is instead linear up
    /// to (1 − w) of the limit, then a tanh of width w into it (an output stage that
    /// compresses late, unlike the Rapp curve, which bends everywhere).
    pub tanh_knee: f64,
}

impl Default for Saturation {
    fn default() -> Self {
        Saturation {
            u_max: 0.0,
            u_max_neg: 0.0,
            knee: 0.0,
            u_dead: 0.0,
            tanh_knee: 0.0,
        }
    }
}

/// The Rapp curve x (1 + xⁿ)^(−1/n) of a command x ≥ 0 relative to its limit, and its slope
/// (1 + xⁿ)^(−1/n − 1): monotone, 1 at small x, tending to the hard clamp min(x, 1) as n → ∞
/// (the standard AM/AM curve of a solid-state amplifier). Beyond x = 1 it is written in x⁻ⁿ,
/// which cannot overflow for a sharp knee.
pub fn rapp(x: f64, n: f64) -> (f64, f64) {
    if n.is_infinite() {
        return if x <= 1.0 { (x, 1.0) } else { (1.0, 0.0) };
    }
    if x <= 1.0 {
        let b = 1.0 + x.powf(n);
        (x * b.powf(-1.0 / n), b.powf(-1.0 / n - 1.0))
    } else {
        let y = x.powf(-n);
        let b = 1.0 + y;
        (b.powf(-1.0 / n), y / x * b.powf(-1.0 / n - 1.0))
    }
}

impl Saturation {
    /// Whether the map differs from the identity.
    pub fn is_on(&self) -> bool {
        self.u_max > 0.0 || self.u_max_neg > 0.0 || self.u_dead > 0.0
    }

    /// The limit of the negative side \[V\] (positive).
    pub fn negative_limit(&self) -> f64 {
        if self.u_max_neg > 0.0 {
            self.u_max_neg
        } else {
            self.u_max
        }
    }

    /// The map's output for the command v and its slope du/dv (effects.md, "saturation"). At a
    /// corner of the hard clamp or of the dead zone the slope is the inner side's (1 at
    /// |v| = U_max, 0 at |v| = U_dead).
    pub fn map(&self, v: f64) -> (f64, f64) {
        let limit = if v >= 0.0 {
            self.u_max
        } else {
            self.negative_limit()
        };
        let w = v.abs() - self.u_dead;
        if self.u_dead > 0.0 && w <= 0.0 {
            return (0.0, 0.0);
        }
        if limit == 0.0 {
            return (w.copysign(v), 1.0);
        }
        let x = w / limit;
        let (s, slope) = if self.tanh_knee > 0.0 {
            let start = 1.0 - self.tanh_knee;
            if x <= start {
                (x, 1.0)
            } else {
                let t = ((x - start) / self.tanh_knee).tanh();
                (start + self.tanh_knee * t, 1.0 - t * t)
            }
        } else {
            rapp(x, 1.0 / self.knee)
        };
        ((limit * s).copysign(v), slope)
    }

    /// The limits in words: "+50 V / -45 V", a side without one "none".
    pub fn limits_text(&self) -> String {
        let side = |l: f64| {
            if l > 0.0 {
                format!("{l:.1} V")
            } else {
                "none".to_string()
            }
        };
        format!("+{} / -{}", side(self.u_max), side(self.negative_limit()))
    }

    /// Whether the command v sits on a corner of the map, where it has no derivative.
    pub fn at_corner(&self, v: f64) -> bool {
        let hard = self.knee == 0.0 && self.tanh_knee == 0.0;
        let limit = if v >= 0.0 {
            self.u_max
        } else {
            self.negative_limit()
        };
        (self.u_dead > 0.0 && v.abs() == self.u_dead) || (hard && v.abs() - self.u_dead == limit)
    }
}

const FORMS: [Form; 3] = [
    Form::new(Effect::Saturation, "hard", &["U_max"], &[]),
    Form {
        magnitudes: &["U_max", "U_max_neg"],
        ..Form::new(Effect::Saturation, "unequal", &["U_max", "U_max_neg"], &[])
    },
    Form {
        magnitudes: &["U_max", "U_max_neg"],
        ..Form::new(
            Effect::Saturation,
            "shaped",
            &["U_max", "U_max_neg", "sat_knee"],
            &[],
        )
    },
];

pub const FAMILY: Family = Family {
    effect: Effect::Saturation,
    name: "saturation",
    mechanism: "the amplifier's output stage saturating",
    form: "U_eff = clamp(U, -U_max, U_max)",
    forms: &FORMS,
    rows: &common_rows! {
        "U_max", "V", Limit, "saturation: the amplifier's output is limited to U_max (and to -U_max unless U_max_neg is set; 0: no limit)", effects.saturation.u_max;
        "U_max_neg", "V", Limit, "saturation: the limit -U_max_neg of the negative side (0: -U_max, symmetric)", effects.saturation.u_max_neg;
        "sat_knee", "1", NonNegative, "saturation: softness of the knee, the Rapp curve of exponent 1/sat_knee (0: the hard clamp)", effects.saturation.knee;
        "U_dead", "V", NonNegative, "saturation: dead zone, commands within +-U_dead give 0 (0: none)", effects.saturation.u_dead;
    },
    choices: &[],
    state: None,
    table_stages: 0,
    is_active: |p| p.saturation.is_on(),
    on: |f| {
        f.saturation.u_max = 50.0;
        f.saturation.u_max_neg = 45.0;
        f.saturation.knee = 0.2;
        f.saturation.u_dead = 1.0;
    },
    structures: &[],
    delays_the_command: false,
    magnitude: Magnitude::Limit,
    probes,
    exposing: Exposing {
        text: "the same sine at 30 V and 60 V: clipping acts only above U_max",
        drive: Drive::Levels {
            omega: 3.0 * PI,
            switch: 6.0,
        },
        t_end: 12.0,
    },
    hidden: compressing,
    variants: &[("saturation_unequal", unequal)],
    law: |p, u_peak| Some(law(p, u_peak)),
};

/// Limits just below the peak command, kept as they are: equal (`hard`), unequal with either
/// side below the other or not clipping at all (`unequal`), and a soft knee whose limits lie
/// from a level below the hard ones' to above the peak, as a Rapp curve compresses before its
/// limit (`shaped`; book/src/diagnose.md, "Screening").
fn probes(_: &Params, u_peak: f64) -> Vec<Probe> {
    let fixed = Probe::fixed;
    let mut out: Vec<Probe> = [0.8, 0.9, 0.97]
        .into_iter()
        .map(|f| fixed(&FORMS[0], vec![("U_max", f * u_peak)]))
        .collect();
    let levels = [0.8, 0.9, 1.1];
    for a in levels {
        for b in levels.into_iter().filter(|&b| b != a) {
            let limits = vec![("U_max", a * u_peak), ("U_max_neg", b * u_peak)];
            out.push(fixed(&FORMS[1], limits));
        }
    }
    for (a, b) in [
        (0.7, 0.7),
        (0.8, 0.8),
        (0.9, 0.9),
        (1.0, 1.0),
        (0.9, 1.15),
        (1.15, 0.9),
    ] {
        let shaped = vec![
            ("U_max", a * u_peak),
            ("U_max_neg", b * u_peak),
            ("sat_knee", 0.2),
        ];
        out.push(fixed(&FORMS[2], shaped));
    }
    out
}

/// Limits of an output stage in [42, 55] V, one side and the other apart by `apart` [V] (either
/// side the lower), with a tanh knee of width w in [0.05, 0.3] of the limit: a shape the Rapp
/// knee of the fitted form does not contain.
fn draw(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64, apart: (f64, f64)) {
    let s = &mut params.effects.saturation;
    let upper = between(42.0, 55.0);
    let d = between(apart.0, apart.1);
    let lower = if between(0.0, 1.0) < 0.5 {
        upper - d
    } else {
        upper + d
    };
    s.u_max = upper;
    s.u_max_neg = lower;
    s.tanh_knee = between(0.05, 0.3);
}

fn described(s: &Saturation) -> String {
    format!(
        "an output stage limited to +{:.1} V and -{:.1} V, linear up to {:.0} % of each limit, then a tanh knee",
        s.u_max,
        s.u_max_neg,
        100.0 * (1.0 - s.tanh_knee)
    )
}

/// An output stage that compresses before it clips, nearly symmetric (its sides within 3 V).
fn compressing(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    draw(params, between, (0.0, 3.0));
    Planted::text(described(&params.effects.saturation))
}

/// An output stage that saturates at different levels up and down (its sides 6–14 V apart).
fn unequal(params: &mut Params, between: &mut dyn FnMut(f64, f64) -> f64) -> Planted {
    draw(params, between, (6.0, 14.0));
    Planted::text(described(&params.effects.saturation))
}

/// The fitted map over the commands ±U_peak, beside the textbook forms fitted to it
/// (book/src/diagnose.md, "The fitted law"): the symmetric clamp, the unequal clamp, the
/// symmetric tanh L tanh(U/L).
fn law(params: &Params, u_peak: f64) -> FittedLaw {
    let s = params.effects.saturation;
    let curve = sampled(-u_peak, u_peak, |v| s.map(v).0);
    let sse = |pick: fn(f64) -> bool, g: &dyn Fn(f64) -> f64| -> f64 {
        curve
            .iter()
            .filter(|(v, _)| pick(*v))
            .map(|&(v, u)| (g(v) - u).powi(2))
            .sum()
    };
    // the best limit of the side(s) `pick` over [U_peak/20, 2 U_peak]: beyond, nothing clips
    let fit = |pick: fn(f64) -> bool, g: fn(f64, f64) -> f64| {
        golden(0.05 * u_peak, 2.0 * u_peak, |l| sse(pick, &|v| g(l, v)))
    };
    let clamp = |l: f64, v: f64| v.clamp(-l, l);
    let tanh = |l: f64, v: f64| l * (v / l).tanh();
    let both = fit(|_| true, clamp);
    let up = fit(|v| v >= 0.0, clamp);
    let down = fit(|v| v < 0.0, clamp);
    let soft = fit(|_| true, tanh);
    // a clamp at or above the peak command clips none of it
    let limit = |l: f64| {
        if l < u_peak {
            format!("{l:.1} V")
        } else {
            "none".to_string()
        }
    };
    let text = format!(
        "u_eff from the command: limits {}, knee softness {:.3}{}",
        s.limits_text(),
        s.knee,
        if s.u_dead > 0.0 {
            format!(", dead zone +-{:.2} V", s.u_dead)
        } else {
            String::new()
        }
    );
    let forms: Vec<TextbookForm> = vec![
        (
            "symmetric clamp",
            format!("+-{}", limit(both)),
            Box::new(move |v| clamp(both, v)),
        ),
        (
            "tanh saturation",
            format!("{soft:.1} V"),
            Box::new(move |v| tanh(soft, v)),
        ),
        (
            "unequal clamp",
            format!("+{} / -{}", limit(up), limit(down)),
            Box::new(move |v| v.clamp(-down, up)),
        ),
    ];
    FittedLaw::of_curve(text, ["command U [V]", "u_eff [V]"], curve, forms)
}

/// The map of the port voltage (effects.md, "saturation").
#[derive(Clone, Debug)]
pub struct Terms(Saturation);

impl Law for Terms {
    type Params = Saturation;

    fn new(s: &Saturation, _: &mut States) -> Terms {
        Terms(*s)
    }

    /// The port receives the mapped voltage, at the map's slope.
    #[inline]
    fn port(&self, _: &[f64], port: &mut Port) {
        if !self.0.is_on() {
            return;
        }
        let (u_eff, slope) = self.0.map(port.u_eff);
        port.u_eff = u_eff;
        port.slope *= slope;
    }
}
