//! What FMI 2.0 and 3.0 write alike in `modelDescription.xml`, and the checks before: numbers
//! as `xs:double`, the model's optional attributes, `<UnitDefinitions>` (FMI 2.0 section 2.2.2,
//! FMI 3.0 section 2.4.3: the same `<Unit><BaseUnit/></Unit>` elements), `<LogCategories>`,
//! `<DefaultExperiment>` and which variables are initial unknowns, the attributes a variable's
//! element starts with, and the document order ([`write_description`]). Each version writes
//! its own dialect around them ([`Dialect`]: capability elements, element names, references
//! by index or by value reference).

use std::collections::BTreeSet;
use std::io;

use quick_xml::Writer;
use quick_xml::events::{BytesDecl, Event};
use quick_xml::writer::ElementWriter;

use super::model_api::{InstanceKind, ModelStructure};
use super::units::{self, BASE_UNIT_NAMES};
use super::variables::{Causality, Initial, ModelInfo, Variable};

/// An XML writer of a description.
pub type XmlWriter = Writer<Vec<u8>>;

/// A double as `xs:double`: the shortest form that reads back to the same bits, infinities
/// as `INF` / `-INF`.
pub fn xs_double(x: f64) -> String {
    if x.is_infinite() {
        return if x > 0.0 { "INF" } else { "-INF" }.into();
    }
    format!("{x:?}")
}

/// A boolean attribute value.
pub fn flag(b: bool) -> &'static str {
    if b { "true" } else { "false" }
}

/// Checks the model information: a consistent, finite default experiment and a model
/// identifier that is a C identifier (it prefixes the library's file name and, in FMI 2.0,
/// may prefix the function names).
pub fn check_info(info: &ModelInfo) -> Result<(), String> {
    let e = &info.default_experiment;
    let times = [
        ("startTime", e.start_time),
        ("stopTime", e.stop_time),
        ("stepSize", e.step_size),
        ("tolerance", e.tolerance),
    ];
    if let Some((name, x)) = times.iter().find(|(_, x)| !x.is_finite()) {
        return Err(format!("DefaultExperiment {name} is not finite: {x:?}"));
    }
    if !(e.stop_time > e.start_time && e.step_size > 0.0 && e.tolerance > 0.0) {
        return Err(format!("DefaultExperiment is inconsistent: {e:?}"));
    }
    let ident = &info.model_identifier;
    if ident.is_empty() || !ident.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(format!(
            "modelIdentifier {ident:?} is not a valid C identifier"
        ));
    }
    Ok(())
}

/// Checks that every value reference of the structure is a variable of the table, that each
/// derivative is declared as the derivative of its state and each output is an output.
pub fn check_structure(vars: &[Variable], structure: &ModelStructure) -> Result<(), String> {
    let var = |vr: u32| {
        vars.iter().find(|v| v.value_reference == vr).ok_or(format!(
            "the model structure names value reference {vr}, which is not in the variable table"
        ))
    };
    for s in &structure.derivatives {
        let der = var(s.derivative)?;
        if der.derivative != Some(s.state) {
            return Err(format!(
                "{} is listed as the derivative of value reference {}, but its derivative attribute says {:?}",
                der.name, s.state, der.derivative
            ));
        }
        for &vr in &s.dependencies {
            var(vr)?;
        }
    }
    for o in &structure.outputs {
        if var(o.output)?.causality != Causality::Output {
            return Err(format!(
                "value reference {} of the outputs is not an output",
                o.output
            ));
        }
        for &vr in &o.dependencies {
            var(vr)?;
        }
    }
    Ok(())
}

/// The optional attributes of `<fmiModelDescription>` the model gives (description, author,
/// version, generationTool), in that order.
fn model_attributes(info: &ModelInfo) -> Vec<(&'static str, &str)> {
    [
        ("description", &info.description),
        ("author", &info.author),
        ("version", &info.version),
        ("generationTool", &info.generation_tool),
    ]
    .into_iter()
    .filter(|(_, value)| !value.is_empty())
    .map(|(key, value)| (key, value.as_str()))
    .collect()
}

/// All log categories: the shell's, then the model's that are not among them.
pub fn log_categories(shell: &[(&str, &str)], info: &ModelInfo) -> Vec<(String, String)> {
    let mut all: Vec<(String, String)> = shell
        .iter()
        .map(|(n, d)| (n.to_string(), d.to_string()))
        .collect();
    for (name, description) in &info.log_categories {
        if all.iter().all(|(n, _)| n != name) {
            all.push((name.clone(), description.clone()));
        }
    }
    all
}

/// `<LogCategories>` (FMI 2.0 section 2.2.4, FMI 3.0 section 2.4.5).
fn write_log_categories(w: &mut XmlWriter, categories: &[(String, String)]) -> io::Result<()> {
    w.create_element("LogCategories").write_inner_content(|w| {
        for (name, description) in categories {
            w.create_element("Category")
                .with_attributes([
                    ("name", name.as_str()),
                    ("description", description.as_str()),
                ])
                .write_empty()?;
        }
        Ok(())
    })?;
    Ok(())
}

/// `<DefaultExperiment>` (FMI 2.0 section 2.2.5, FMI 3.0 section 2.4.6).
fn write_default_experiment(w: &mut XmlWriter, info: &ModelInfo) -> io::Result<()> {
    let e = &info.default_experiment;
    let values = [
        ("startTime", e.start_time),
        ("stopTime", e.stop_time),
        ("tolerance", e.tolerance),
        ("stepSize", e.step_size),
    ]
    .map(|(name, x)| (name, xs_double(x)));
    w.create_element("DefaultExperiment")
        .with_attributes(values.iter().map(|(n, x)| (*n, x.as_str())))
        .write_empty()?;
    Ok(())
}

/// The initial unknowns, as `(position in vars, variable)` in table order: exactly the list the
/// standard prescribes (FMI 2.0 section 2.2.8, FMI 3.0 section 2.4.8): outputs with initial
/// approx or calculated, calculated parameters, and the continuous states and state
/// derivatives with initial approx or calculated. Written without `dependencies` ("depends on
/// all knowns"): always correct without the shell knowing the physics.
pub fn initial_unknowns<'a>(
    vars: &'a [Variable],
    structure: &ModelStructure,
) -> Vec<(usize, &'a Variable)> {
    let in_structure = |vr: u32| {
        structure
            .derivatives
            .iter()
            .any(|d| d.state == vr || d.derivative == vr)
    };
    vars.iter()
        .enumerate()
        .filter(|(_, v)| {
            let calculated = matches!(
                v.effective_initial(),
                Some(Initial::Approx | Initial::Calculated)
            );
            match v.causality {
                Causality::Output => calculated,
                Causality::CalculatedParameter => true,
                _ => calculated && in_structure(v.value_reference),
            }
        })
        .collect()
}

/// `<UnitDefinitions>`: every unit of `vars`, with its SI base-unit exponents; nothing when no
/// variable has a unit. The table must have passed `check_variable_table` (known units only).
fn write_unit_definitions(w: &mut XmlWriter, vars: &[Variable]) -> io::Result<()> {
    let used: BTreeSet<&str> = vars.iter().filter_map(|v| v.unit.as_deref()).collect();
    if used.is_empty() {
        return Ok(());
    }
    w.create_element("UnitDefinitions")
        .write_inner_content(|w| {
            for unit in used {
                let exponents = units::base_unit(unit).unwrap_or_default();
                let base: Vec<(&str, String)> = BASE_UNIT_NAMES
                    .iter()
                    .zip(exponents)
                    .filter(|(_, e)| *e != 0)
                    .map(|(name, e)| (*name, e.to_string()))
                    .collect();
                w.create_element("Unit")
                    .with_attribute(("name", unit))
                    .write_inner_content(|w| {
                        w.create_element("BaseUnit")
                            .with_attributes(base.iter().map(|(n, e)| (*n, e.as_str())))
                            .write_empty()
                            .map(drop)
                    })?;
            }
            Ok(())
        })
        .map(drop)
}

/// What a description is written from: the model-level data, the variable table (FMI 3.0:
/// with `time`) and the model structure of a core.
#[derive(Clone, Copy)]
pub struct Description<'a> {
    pub info: &'a ModelInfo,
    pub vars: &'a [Variable],
    pub structure: &'a ModelStructure,
}

/// What a version writes its own way in `modelDescription.xml`; [`write_description`] puts
/// it in the document order both versions share.
pub trait Dialect {
    /// `fmiVersion`.
    const FMI_VERSION: &'static str;
    /// The attribute of the token (`guid`, `instantiationToken`).
    const TOKEN: &'static str;
    /// The root's attributes after the model's own.
    const ROOT_ATTRIBUTES: &'static [(&'static str, &'static str)];
    /// The shell's log categories, `(name, description)`, listed before the model's own.
    const CATEGORIES: [(&'static str, &'static str); 5];

    /// Checks the description against the version's rules before it is written.
    fn check(d: Description) -> Result<(), String>;
    /// The attributes of `<ModelExchange>` (written if the model offers it) or
    /// `<CoSimulation>`, in order: the model identifier and the capability flags.
    fn interface_attributes(kind: InstanceKind, info: &ModelInfo) -> Vec<(&'static str, &str)>;
    /// The element of `v` in `<ModelVariables>` (of `vars`).
    fn write_variable(w: &mut XmlWriter, vars: &[Variable], v: &Variable) -> io::Result<()>;
    fn write_model_structure(w: &mut XmlWriter, d: Description) -> io::Result<()>;
}

/// The description `d` with `token`, after the version's checks.
pub fn write_description<D: Dialect>(d: Description, token: &str) -> Result<String, String> {
    D::check(d)?;
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    write_document::<D>(&mut w, d, token)
        .map_err(|e| format!("writing modelDescription.xml: {e}"))?;
    String::from_utf8(w.into_inner()).map_err(|e| e.to_string())
}

/// The document order of both versions (FMI 2.0 section 2.2, FMI 3.0 section 2.4).
fn write_document<D: Dialect>(w: &mut XmlWriter, d: Description, token: &str) -> io::Result<()> {
    let info = d.info;
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    w.create_element("fmiModelDescription")
        .with_attributes([
            ("fmiVersion", D::FMI_VERSION),
            ("modelName", info.model_name.as_str()),
            (D::TOKEN, token),
        ])
        .with_attributes(model_attributes(info))
        .with_attributes(D::ROOT_ATTRIBUTES.iter().copied())
        .write_inner_content(|w| {
            let mut interfaces = vec![("CoSimulation", InstanceKind::CoSimulation)];
            if info.model_exchange {
                interfaces.insert(0, ("ModelExchange", InstanceKind::ModelExchange));
            }
            for (tag, kind) in interfaces {
                w.create_element(tag)
                    .with_attributes(D::interface_attributes(kind, info))
                    .write_empty()?;
            }
            write_unit_definitions(w, d.vars)?;
            write_log_categories(w, &log_categories(&D::CATEGORIES, info))?;
            write_default_experiment(w, info)?;
            w.create_element("ModelVariables")
                .write_inner_content(|w| {
                    for v in d.vars {
                        D::write_variable(w, d.vars, v)?;
                    }
                    Ok(())
                })?;
            D::write_model_structure(w, d)
        })?;
    Ok(())
}

/// The start of a variable's element `tag` (`ScalarVariable`, `Float64`): the attributes
/// both versions write alike, from the name to `initial` (whenever the rules allow it, as the
/// declared or default value, so readers need not know the defaults).
pub fn variable_element<'a>(
    w: &'a mut XmlWriter,
    tag: &'a str,
    v: &Variable,
) -> ElementWriter<'a, Vec<u8>> {
    let vr = v.value_reference.to_string();
    let mut el = w
        .create_element(tag)
        .with_attributes([("name", v.name.as_str()), ("valueReference", &vr)]);
    if !v.description.is_empty() {
        el = el.with_attribute(("description", v.description.as_str()));
    }
    el = el.with_attributes([
        ("causality", v.causality.as_str()),
        ("variability", v.variability.as_str()),
    ]);
    if let Some(initial) = v.effective_initial() {
        el = el.with_attribute(("initial", initial.as_str()));
    }
    el
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doubles_read_back_to_the_same_bits() {
        for x in [
            0.0,
            -0.0,
            1e-3,
            0.1 + 0.2,
            8.854187817e-12,
            f64::MAX,
            f64::MIN_POSITIVE,
        ] {
            assert_eq!(xs_double(x).parse::<f64>().unwrap().to_bits(), x.to_bits());
        }
        assert_eq!(xs_double(f64::INFINITY), "INF");
        assert_eq!(xs_double(f64::NEG_INFINITY), "-INF");
    }
}
