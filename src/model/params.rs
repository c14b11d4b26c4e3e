//! The model's parameters: one struct, one flat name table, validated in one place.
//!
//! Every parameter has a flat name (`Kb_1`, `Lp`, …) shared by the parameter files, the FMU
//! variables and the identification reports. The table `PARAMETERS` is the single source of
//! truth for names, units, descriptions, the validation rule and how to read and write each value.

use super::effects::{Effect, EffectParams};

/// Parameters of one HASEL actuator (the paper's identified table: book/src/model.md,
/// "Parameters").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActuatorParams {
    /// Top-film stiffness K [N/m].
    pub k: f64,
    /// Bending stiffness Kb [N m/rad].
    pub kb: f64,
    /// Rotational damping b [N m s/rad, as identified with I = Lv m / 24].
    pub b: f64,
    /// Source resistance R0 \[Ω\].
    pub r0: f64,
    /// Leak resistance R1 of the retention capacitor \[Ω\].
    pub r1: f64,
    /// Leak resistance R2 of the electrode capacitor \[Ω\].
    pub r2: f64,
    /// Retention capacitance C1 \[F\].
    pub c1: f64,
    /// Input gain γ1 [–] of ga(θ) = γ1 cos(γ2 θ).
    pub gamma1: f64,
    /// Input-gain angle factor γ2 [–].
    pub gamma2: f64,
}

/// All parameters of the platform: the three actuators, the common shell values, the pinned
/// open choices (book/src/model.md, "Open choices and pinned defaults") and the kinematics.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    pub act: [ActuatorParams; 3],
    /// Rest length of the top film Lp \[m\].
    pub lp: f64,
    /// Length of the lateral (shell) film Lv \[m\].
    pub lv: f64,
    /// Electrode length Le \[m\].
    pub le: f64,
    /// Liquid gap height at the unzipped part Xh \[m\].
    pub xh: f64,
    /// Moving mass m \[kg\].
    pub m: f64,
    /// Relative permittivity εr [–].
    pub eps_r: f64,
    /// Vacuum permittivity ε0 [F/m].
    pub eps0: f64,
    /// Actuator width w \[m\].
    pub w: f64,
    /// Film thickness t \[m\].
    pub t_film: f64,
    /// Gravity g [m/s²].
    pub g: f64,
    /// Constant liquid area A_T \[m²\].
    pub a_t: f64,
    /// Radius of the anchor circle \[m\].
    pub anchor_radius: f64,
    /// Anchor angles of actuators 1, 2, 3 \[rad\].
    pub anchor_angle: [f64; 3],
    /// Antenna length L \[m\].
    pub antenna_length: f64,
    /// The effect library's parameters (neutral by default).
    pub effects: EffectParams,
}

impl Default for Params {
    /// The paper's identified table and the pinned defaults (book/src/model.md, "Parameters").
    fn default() -> Self {
        let a = |k, kb, b, r1, r2, c1, gamma1, gamma2| ActuatorParams {
            k,
            kb,
            b,
            r0: 600.0,
            r1,
            r2,
            c1,
            gamma1,
            gamma2,
        };
        let mut p = Params {
            act: [
                a(0.250, 0.305, 0.129, 99.98, 5.385e4, 2.15e-10, 118.4, 58.0),
                a(0.200, 0.300, 0.010, 112.7, 5.60e4, 2.00e-10, 131.9, 30.5),
                a(0.250, 0.300, 0.015, 100.0, 5.5e4, 2.20e-10, 118.4, 25.0),
            ],
            lp: 0.014,
            lv: 0.012,
            le: 0.020,
            xh: 0.002,
            m: 0.001133,
            eps_r: 2.2,
            eps0: 8.854e-12,
            w: 0.025,
            t_film: 18e-6,
            g: 9.8,
            a_t: 0.0,
            anchor_radius: 0.020,
            anchor_angle: [90f64.to_radians(), 210f64.to_radians(), 330f64.to_radians()],
            antenna_length: 0.050,
            effects: EffectParams::default(),
        };
        p.a_t = p.unzipped_liquid_area();
        p
    }
}

/// The rule a parameter's value must satisfy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    Positive,
    /// A limit: finite and > 0, or 0 where 0 switches it off (not +∞: an importer reads an
    /// infinite start value as an error).
    Limit,
    NonNegative,
    /// A weight of a non-negative series (book/src/effects.md, "creep"): ≥ 0, and
    /// fitted in its own units, not its logarithm, so that a fit can set it to 0.
    Weight,
    Finite,
    /// An index 0, 1, …, n − 1 choosing among n forms.
    Index(u8),
}

impl Rule {
    fn holds(self, v: f64) -> bool {
        match self {
            Rule::Positive => v.is_finite() && v > 0.0,
            Rule::NonNegative | Rule::Weight | Rule::Limit => v.is_finite() && v >= 0.0,
            Rule::Finite => v.is_finite(),
            Rule::Index(n) => v >= 0.0 && v < f64::from(n) && v.fract() == 0.0,
        }
    }
    fn text(self) -> String {
        match self {
            Rule::Positive => "must be finite and > 0".into(),
            Rule::Limit => "must be finite and >= 0 (0: no limit)".into(),
            Rule::NonNegative | Rule::Weight => "must be finite and >= 0".into(),
            Rule::Finite => "must be finite".into(),
            Rule::Index(n) => format!("must be one of 0 .. {}", n - 1),
        }
    }

    /// Whether a fit moves a parameter of this rule, starting at `prior`, in ln p (it must stay
    /// positive) rather than in p (book/src/identify.md, "How `hasel identify` estimates").
    pub fn fitted_in_log(self, prior: f64) -> bool {
        !matches!(self, Rule::Finite | Rule::Weight) && prior > 0.0
    }
}

/// One row of the parameter table.
pub struct ParamDef {
    /// Flat name, e.g. `Kb_1` (letters, digits and `_` only).
    pub name: &'static str,
    /// SI unit as written in modelDescription.xml (`1` for dimensionless).
    pub unit: &'static str,
    pub description: &'static str,
    pub rule: Rule,
    /// The actuator (0-based) a per-actuator parameter belongs to; `None` for common ones.
    pub actuator: Option<usize>,
    pub get: fn(&Params) -> f64,
    pub set: fn(&mut Params, f64),
}

/// A parameter value that breaks its rule, or a name that does not exist.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    #[error("parameter {name} = {value:e}: {rule}")]
    Invalid {
        name: String,
        value: f64,
        rule: String,
    },
    #[error("unknown parameter '{name}'")]
    Unknown { name: String },
}

macro_rules! actuator_rows {
    ($($field:ident, $name:literal, $unit:literal, $rule:ident, $desc:literal;)*) => {
        [$(
            actuator_rows!(@one $field, $name, $unit, $rule, $desc, 1),
            actuator_rows!(@one $field, $name, $unit, $rule, $desc, 2),
            actuator_rows!(@one $field, $name, $unit, $rule, $desc, 3),
        )*]
    };
    (@one $field:ident, $name:literal, $unit:literal, $rule:ident, $desc:literal, $i:literal) => {
        ParamDef {
            name: concat!($name, "_", $i),
            unit: $unit,
            description: concat!($desc, " of actuator ", $i),
            rule: Rule::$rule,
            actuator: Some($i - 1),
            get: |p| p.act[$i - 1].$field,
            set: |p, v| p.act[$i - 1].$field = v,
        }
    };
}

/// After the rows, each `grid PREFIX, UNIT, DESCRIPTION, FIELD;` adds the six weights of a Prony
/// series' grid (book/src/effects.md, "Prony series"; `effects::prony::GRID`),
/// `PREFIX_30ms` … `PREFIX_10s`, of rule `Weight`: `effects.FIELD[0]` … `[5]`.
macro_rules! common_rows {
    (@weight $prefix:literal, $gunit:literal, $gdesc:literal, $suffix:literal, $tau:literal, $g:literal, $($gfield:ident).+) => {
        $crate::model::params::ParamDef {
            name: concat!($prefix, $suffix),
            unit: $gunit,
            description: concat!($gdesc, " at tau = ", $tau, " s (0: off)"),
            rule: $crate::model::params::Rule::Weight,
            actuator: None,
            get: |p| p.effects.$($gfield).+[$g],
            set: |p, v| p.effects.$($gfield).+[$g] = v,
        }
    };
    ($($name:literal, $unit:literal, $rule:ident, $desc:literal, $($field:ident).+ $([$idx:literal])?;)*
     $(grid $prefix:literal, $gunit:literal, $gdesc:literal, $($gfield:ident).+;)*) => {
        [$(
            $crate::model::params::ParamDef {
                name: $name,
                unit: $unit,
                description: $desc,
                rule: $crate::model::params::Rule::$rule,
                actuator: None,
                get: |p| p.$($field).+ $([$idx])?,
                set: |p, v| p.$($field).+ $([$idx])? = v,
            },
        )*
        $(
            $crate::model::params::common_rows!(@weight $prefix, $gunit, $gdesc, "_30ms", "0.03", 0, $($gfield).+),
            $crate::model::params::common_rows!(@weight $prefix, $gunit, $gdesc, "_100ms", "0.1", 1, $($gfield).+),
            $crate::model::params::common_rows!(@weight $prefix, $gunit, $gdesc, "_300ms", "0.3", 2, $($gfield).+),
            $crate::model::params::common_rows!(@weight $prefix, $gunit, $gdesc, "_1s", "1", 3, $($gfield).+),
            $crate::model::params::common_rows!(@weight $prefix, $gunit, $gdesc, "_3s", "3", 4, $($gfield).+),
            $crate::model::params::common_rows!(@weight $prefix, $gunit, $gdesc, "_10s", "10", 5, $($gfield).+),
        )*]
    };
}
// the families' modules write their rows with it
pub(crate) use common_rows;

const ACTUATOR_ROWS: [ParamDef; 27] = actuator_rows! {
    k, "K", "N/m", NonNegative, "Top-film stiffness K";
    kb, "Kb", "N.m/rad", Positive, "Bending stiffness Kb";
    b, "b", "N.m.s/rad", NonNegative, "Rotational damping b";
    r0, "R0", "Ohm", Positive, "Source resistance R0";
    r1, "R1", "Ohm", Positive, "Leak resistance R1 of the retention capacitor C1";
    r2, "R2", "Ohm", Positive, "Leak resistance R2 of the electrode capacitor C2";
    c1, "C1", "F", Positive, "Retention capacitance C1";
    gamma1, "gamma1", "1", Positive, "Input gain gamma1 of ga = gamma1 cos(gamma2 theta)";
    gamma2, "gamma2", "1", Positive, "Angle factor gamma2 of ga = gamma1 cos(gamma2 theta)";
};

const COMMON_ROWS: [ParamDef; 16] = common_rows! {
    "Lp", "m", Positive, "Rest length of the top film", lp;
    "Lv", "m", Positive, "Length of the lateral shell film", lv;
    "Le", "m", Positive, "Electrode length", le;
    "Xh", "m", Positive, "Liquid gap height of the unzipped electrode", xh;
    "m", "kg", Positive, "Moving mass per actuator", m;
    "eps_r", "1", Positive, "Relative permittivity of the film", eps_r;
    "eps0", "F/m", Positive, "Vacuum permittivity", eps0;
    "w", "m", Positive, "Actuator width", w;
    "t_film", "m", Positive, "Film thickness", t_film;
    "g", "m/s2", Finite, "Gravitational acceleration", g;
    "A_T", "m2", Positive, "Constant liquid area (default: unzipped at theta = 0)", a_t;
    "anchor_radius", "m", Positive, "Radius of the anchor circle", anchor_radius;
    "anchor_angle_1", "rad", Finite, "Anchor angle of actuator 1", anchor_angle[0];
    "anchor_angle_2", "rad", Finite, "Anchor angle of actuator 2", anchor_angle[1];
    "anchor_angle_3", "rad", Finite, "Anchor angle of actuator 3", anchor_angle[2];
    "L", "m", Positive, "Antenna length from the platform centre to the tip", antenna_length;
};

/// Every parameter, per-actuator ones first (`K_1, K_2, K_3, Kb_1, …`), then the common ones,
/// then each family's (book/src/effects.md, "Parameters"), then the families' choices
/// among forms.
pub fn parameters() -> impl Iterator<Item = &'static ParamDef> {
    ACTUATOR_ROWS
        .iter()
        .chain(COMMON_ROWS.iter())
        .chain(Effect::ALL.into_iter().flat_map(|e| e.family().rows))
        .chain(Effect::ALL.into_iter().flat_map(|e| e.family().choices))
}

/// Looks a parameter up by its flat name.
pub fn parameter(name: &str) -> Option<&'static ParamDef> {
    parameters().find(|d| d.name == name)
}

impl Params {
    /// Value of the parameter `name`.
    pub fn get(&self, name: &str) -> Result<f64, ParamError> {
        parameter(name)
            .map(|d| (d.get)(self))
            .ok_or_else(|| ParamError::Unknown { name: name.into() })
    }

    /// Sets the parameter `name` after checking its own rule (cross-parameter rules are checked
    /// by [`Params::validate`]).
    pub fn set(&mut self, name: &str, value: f64) -> Result<(), ParamError> {
        let d = parameter(name).ok_or_else(|| ParamError::Unknown { name: name.into() })?;
        self.set_param(d, value)
    }

    /// [`Params::set`] for a row of the table already in hand (no lookup by name).
    pub fn set_param(&mut self, d: &ParamDef, value: f64) -> Result<(), ParamError> {
        check(d, value)?;
        (d.set)(self, value);
        Ok(())
    }

    /// Checks every parameter's rule and the rules between parameters.
    pub fn validate(&self) -> Result<(), ParamError> {
        for d in parameters() {
            check(d, (d.get)(self))?;
        }
        // asin domain of δ1 at the rest configuration θ = 0: l_p > Lv cos(θ/2) = Lv.
        if self.lp <= self.lv {
            return Err(ParamError::Invalid {
                name: "Lp".into(),
                value: self.lp,
                rule: format!(
                    "must exceed Lv = {:e} (the shell geometry needs l_p > Lv cos(theta/2))",
                    self.lv
                ),
            });
        }
        Ok(())
    }

    /// A_s(θ = 0, l_p = Lp) + Xh·Le: the liquid area for which the electrode is unzipped
    /// (le = 0) at θ = 0, the pinned default of A_T (book/src/model.md, "Open choices and
    /// pinned defaults").
    fn unzipped_liquid_area(&self) -> f64 {
        let geometry = crate::model::shell::Shell::new(0.0, self.lp, self.lv)
            .expect("Lp > Lv at theta = 0 for the default geometry");
        geometry.a_s + self.xh * self.le
    }
}

fn check(d: &ParamDef, value: f64) -> Result<(), ParamError> {
    if d.rule.holds(value) {
        Ok(())
    } else {
        Err(ParamError::Invalid {
            name: d.name.into(),
            value,
            rule: d.rule.text(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_flat() {
        let names: Vec<_> = parameters().map(|d| d.name).collect();
        let mut sorted = names.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), names.len());
        assert!(
            names
                .iter()
                .all(|n| n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'))
        );
    }

    #[test]
    fn get_and_set_address_the_right_field() {
        let mut p = Params::default();
        p.set("gamma2_2", 31.0).unwrap();
        assert_eq!(p.act[1].gamma2, 31.0);
        assert_eq!(p.get("Kb_1").unwrap(), 0.305);
        assert_eq!(p.get("anchor_angle_2").unwrap(), 210f64.to_radians());
    }

    #[test]
    fn default_liquid_area_matches_the_spec() {
        // book/src/model.md, "Parameters": A_T = 61.63 mm²
        let a_t = Params::default().a_t;
        assert!((a_t * 1e6 - 61.63).abs() < 0.005, "A_T = {} mm²", a_t * 1e6);
    }

    #[test]
    fn bad_values_are_named() {
        let mut p = Params::default();
        let e = p.set("C1_2", -1e-10).unwrap_err();
        assert_eq!(
            e.to_string(),
            "parameter C1_2 = -1e-10: must be finite and > 0"
        );
        assert!(p.set("R0_1", f64::NAN).is_err());
        assert!(matches!(
            p.set("nope", 1.0),
            Err(ParamError::Unknown { .. })
        ));
        p.lp = 0.011;
        assert!(p.validate().unwrap_err().to_string().contains("Lp"));
    }
}
