//! The variable table and model information a core declares, and the rules on causality,
//! variability, initial and start (FMI 2.0 standard, section 2.2.7). Every variable of this
//! FMU is of type Real.

use super::units;

/// `causality` of a ScalarVariable (section 2.2.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    Parameter,
    CalculatedParameter,
    Input,
    Output,
    Local,
    Independent,
}

/// `variability` of a ScalarVariable (section 2.2.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variability {
    Constant,
    Fixed,
    Tunable,
    Discrete,
    Continuous,
}

/// `initial` of a ScalarVariable (section 2.2.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Initial {
    Exact,
    Approx,
    Calculated,
}

/// One Real ScalarVariable.
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Flat name (`variableNamingConvention="flat"`), `[A-Za-z_][A-Za-z0-9_]*` in this FMU.
    pub name: String,
    pub value_reference: u32,
    pub causality: Causality,
    pub variability: Variability,
    /// `None` means the default of section 2.2.7 for the causality/variability pair.
    pub initial: Option<Initial>,
    /// A unit of the table in [`units`], or none.
    pub unit: Option<String>,
    pub description: String,
    /// Required for inputs and for `initial` exact/approx, forbidden otherwise.
    pub start: Option<f64>,
    /// For a state derivative: the value reference of its state (`derivative` attribute).
    pub derivative: Option<u32>,
}

/// `<DefaultExperiment>` (section 2.2.5).
#[derive(Debug, Clone, PartialEq)]
pub struct DefaultExperiment {
    pub start_time: f64,
    pub stop_time: f64,
    pub step_size: f64,
    pub tolerance: f64,
}

/// The model-level attributes of `modelDescription.xml` (sections 2.2.1, 4.3.1).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelInfo {
    pub model_name: String,
    /// Also the shared library's file name without extension (section 4.3.1).
    pub model_identifier: String,
    pub description: String,
    pub author: String,
    pub version: String,
    pub generation_tool: String,
    pub default_experiment: DefaultExperiment,
    /// Log categories of the model, `(name, description)`; the wrapper's own categories
    /// ([`crate::fmi2::logging::WRAPPER_CATEGORIES`]) are listed in addition.
    pub log_categories: Vec<(String, String)>,
    /// Whether the model offers Model Exchange beside Co-Simulation (a model without
    /// continuous dynamics of its own may not) and directional derivatives; the shells
    /// declare exactly these capabilities.
    pub model_exchange: bool,
    pub directional_derivatives: bool,
}

impl Causality {
    /// The attribute value in `modelDescription.xml`.
    pub fn as_str(self) -> &'static str {
        match self {
            Causality::Parameter => "parameter",
            Causality::CalculatedParameter => "calculatedParameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        }
    }
}

impl Variability {
    /// The attribute value in `modelDescription.xml`.
    pub fn as_str(self) -> &'static str {
        match self {
            Variability::Constant => "constant",
            Variability::Fixed => "fixed",
            Variability::Tunable => "tunable",
            Variability::Discrete => "discrete",
            Variability::Continuous => "continuous",
        }
    }
}

impl Initial {
    /// The attribute value in `modelDescription.xml`.
    pub fn as_str(self) -> &'static str {
        match self {
            Initial::Exact => "exact",
            Initial::Approx => "approx",
            Initial::Calculated => "calculated",
        }
    }
}

/// Whether the causality/variability pair is allowed (table in section 2.2.7).
fn combination_allowed(c: Causality, v: Variability) -> bool {
    use Causality as C;
    use Variability as V;
    match v {
        V::Constant => matches!(c, C::Output | C::Local),
        V::Fixed | V::Tunable => matches!(c, C::Parameter | C::CalculatedParameter | C::Local),
        V::Discrete => matches!(c, C::Input | C::Output | C::Local),
        V::Continuous => matches!(c, C::Input | C::Output | C::Local | C::Independent),
    }
}

/// The `initial` values allowed for the pair, default first; empty when the attribute must
/// not be given (inputs and the independent variable). Section 2.2.7, second table.
fn allowed_initials(c: Causality, v: Variability) -> &'static [Initial] {
    use Causality as C;
    use Initial::*;
    use Variability as V;
    match (c, v) {
        (C::Input | C::Independent, _) => &[],
        (_, V::Constant) | (C::Parameter, _) => &[Exact],
        (C::CalculatedParameter, _) | (C::Local, V::Fixed | V::Tunable) => &[Calculated, Approx],
        (C::Output | C::Local, _) => &[Calculated, Exact, Approx],
    }
}

impl Variable {
    /// The `initial` in force: the declared one or the default of section 2.2.7;
    /// `None` for inputs and the independent variable, which have no `initial`.
    pub fn effective_initial(&self) -> Option<Initial> {
        self.initial.or_else(|| {
            allowed_initials(self.causality, self.variability)
                .first()
                .copied()
        })
    }

    /// Whether the variable needs a start value: initial exact or approx, or an input
    /// (section 2.2.7, attribute `start`).
    fn requires_start(&self) -> bool {
        self.causality == Causality::Input
            || matches!(
                self.effective_initial(),
                Some(Initial::Exact | Initial::Approx)
            )
    }
}

/// `[A-Za-z_][A-Za-z0-9_]*`, or `der(name)` of such a name for a state derivative.
fn valid_name(name: &str) -> bool {
    let name = name
        .strip_prefix("der(")
        .and_then(|n| n.strip_suffix(')'))
        .unwrap_or(name);
    let mut chars = name.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Checks one variable against the rules of section 2.2.7 and the unit table.
fn check_variable(v: &Variable) -> Result<(), String> {
    let name = &v.name;
    if !valid_name(name) {
        return Err(format!(
            "variable name {name:?} does not match [A-Za-z_][A-Za-z0-9_]* or der(...) of it"
        ));
    }
    if !combination_allowed(v.causality, v.variability) {
        return Err(format!(
            "variable {name}: causality {} with variability {} is not allowed (FMI 2.0 section 2.2.7)",
            v.causality.as_str(),
            v.variability.as_str()
        ));
    }
    let allowed = allowed_initials(v.causality, v.variability);
    if let Some(initial) = v.initial
        && !allowed.contains(&initial)
    {
        return Err(format!(
            "variable {name}: initial {} is not allowed for causality {} and variability {}",
            initial.as_str(),
            v.causality.as_str(),
            v.variability.as_str()
        ));
    }
    match (v.requires_start(), v.start) {
        (true, None) => return Err(format!("variable {name} needs a start value")),
        (false, Some(s)) => {
            return Err(format!(
                "variable {name} must not have a start value (has {s:?})"
            ));
        }
        (_, Some(s)) if s.is_nan() => {
            // ±∞ is a valid xs:double (INF); NaN is not a value
            return Err(format!("variable {name} has a NaN start value"));
        }
        _ => {}
    }
    if let Some(unit) = &v.unit
        && units::base_unit(unit).is_none()
    {
        return Err(format!(
            "variable {name}: unit {unit:?} is not in the unit table"
        ));
    }
    Ok(())
}

/// Checks a variable table: unique names and value references, valid names, allowed
/// causality/variability/initial combinations, start values where required and only there,
/// finite starts, known units, at most one independent variable, derivatives of continuous
/// variables of the table.
pub fn check_variable_table(vars: &[Variable]) -> Result<(), String> {
    let mut names = std::collections::HashSet::new();
    let mut refs = std::collections::HashSet::new();
    for v in vars {
        check_variable(v)?;
        if !names.insert(v.name.as_str()) {
            return Err(format!("variable name {} is used twice", v.name));
        }
        if !refs.insert(v.value_reference) {
            return Err(format!(
                "value reference {} is used twice (again by {})",
                v.value_reference, v.name
            ));
        }
    }
    if vars
        .iter()
        .filter(|v| v.causality == Causality::Independent)
        .count()
        > 1
    {
        return Err("more than one independent variable".into());
    }
    for v in vars {
        let Some(state) = v.derivative else { continue };
        let of = vars.iter().find(|s| s.value_reference == state);
        if !of.is_some_and(|s| s.variability == Variability::Continuous)
            || v.variability != Variability::Continuous
        {
            return Err(format!(
                "variable {} is the derivative of value reference {state}, which is not a \
                 continuous variable of the table, or is not continuous itself",
                v.name
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn var(name: &str, vr: u32, c: Causality, v: Variability, start: Option<f64>) -> Variable {
        Variable {
            name: name.into(),
            value_reference: vr,
            causality: c,
            variability: v,
            initial: None,
            unit: Some("m".into()),
            description: String::new(),
            start,
            derivative: None,
        }
    }

    fn table() -> Vec<Variable> {
        vec![
            var("k", 0, Causality::Parameter, Variability::Fixed, Some(1.0)),
            var("u", 1, Causality::Input, Variability::Continuous, Some(0.0)),
            var("y", 2, Causality::Output, Variability::Continuous, None),
        ]
    }

    #[test]
    fn accepts_a_valid_table() {
        check_variable_table(&table()).unwrap();
    }

    #[test]
    fn rejects_duplicates() {
        let mut t = table();
        t[2].name = "u".into();
        assert!(
            check_variable_table(&t)
                .unwrap_err()
                .contains("name u is used twice")
        );
        let mut t = table();
        t[2].value_reference = 1;
        assert!(
            check_variable_table(&t)
                .unwrap_err()
                .contains("value reference 1")
        );
    }

    #[test]
    fn rejects_bad_names() {
        for bad in [
            "", "1x", "a.b", "a b", "x[1]", "ä", "der(1x)", "der(u", "der()",
        ] {
            let mut t = table();
            t[0].name = bad.into();
            assert!(check_variable_table(&t).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn derivatives_name_a_continuous_variable() {
        let mut t = table();
        let mut der = var("der(y)", 3, Causality::Local, Variability::Continuous, None);
        der.derivative = Some(2);
        t.push(der);
        check_variable_table(&t).unwrap();
        t[3].derivative = Some(0);
        assert!(check_variable_table(&t).unwrap_err().contains("der(y)"));
        t[3].derivative = Some(7);
        assert!(
            check_variable_table(&t)
                .unwrap_err()
                .contains("reference 7")
        );
    }

    #[test]
    fn start_rules() {
        let mut t = table();
        t[0].start = None;
        assert!(
            check_variable_table(&t)
                .unwrap_err()
                .contains("k needs a start")
        );
        let mut t = table();
        t[1].start = None;
        assert!(
            check_variable_table(&t)
                .unwrap_err()
                .contains("u needs a start")
        );
        let mut t = table();
        t[2].start = Some(0.0);
        assert!(
            check_variable_table(&t)
                .unwrap_err()
                .contains("y must not have")
        );
        let mut t = table();
        t[2].initial = Some(Initial::Exact);
        assert!(
            check_variable_table(&t)
                .unwrap_err()
                .contains("y needs a start")
        );
        let mut t = table();
        t[0].start = Some(f64::NAN);
        assert!(check_variable_table(&t).is_err());
    }

    #[test]
    fn combination_and_initial_rules() {
        let mut t = table();
        t[1].variability = Variability::Fixed;
        assert!(check_variable_table(&t).is_err());
        let mut t = table();
        t[1].initial = Some(Initial::Exact);
        assert!(check_variable_table(&t).is_err());
        let mut t = table();
        t[0].initial = Some(Initial::Calculated);
        assert!(check_variable_table(&t).is_err());
        let mut t = table();
        t[0].unit = Some("furlong".into());
        assert!(check_variable_table(&t).unwrap_err().contains("furlong"));
    }
}
