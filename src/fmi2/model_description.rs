//! Generation of `modelDescription.xml` (FMI 2.0 standard, section 2.2) and of the GUID
//! that ties the binary to it.

use std::collections::BTreeSet;
use std::io;

use quick_xml::Writer;
use quick_xml::events::{BytesDecl, Event};
use sha2::{Digest, Sha256};

use super::logging::WRAPPER_CATEGORIES;
use crate::fmi_common::model_api::ModelStructure;
use crate::fmi_common::units::{self, BASE_UNIT_NAMES};
use crate::fmi_common::variables::{Causality, Initial, ModelInfo, Variable, check_variable_table};

/// What `modelDescription.xml` is made of: the model-level data, the variable table and the
/// model structure of a core.
#[derive(Clone, Copy)]
struct Description<'a> {
    info: &'a ModelInfo,
    vars: &'a [Variable],
    structure: &'a ModelStructure,
}

/// The complete `modelDescription.xml`, with the GUID of [`guid_for`].
pub fn model_description_xml(
    info: &ModelInfo,
    vars: &[Variable],
    structure: &ModelStructure,
) -> Result<String, String> {
    let d = Description {
        info,
        vars,
        structure,
    };
    write_xml(d, &guid_for(info, vars, structure)?)
}

/// The GUID (section 2.2.1): a UUID in braces made of the SHA-256 of the description
/// generated with an empty GUID, so that any change of the description (a variable, a start
/// value, a unit, a capability) changes it. Formatted as an RFC 9562 version-8 UUID.
pub fn guid_for(
    info: &ModelInfo,
    vars: &[Variable],
    structure: &ModelStructure,
) -> Result<String, String> {
    let d = Description {
        info,
        vars,
        structure,
    };
    let hash = Sha256::digest(write_xml(d, "")?.as_bytes());
    let mut b = [0u8; 16];
    b.copy_from_slice(&hash[..16]);
    b[6] = (b[6] & 0x0f) | 0x80;
    b[8] = (b[8] & 0x3f) | 0x80;
    let hex: String = b.iter().map(|x| format!("{x:02x}")).collect();
    Ok(format!(
        "{{{}-{}-{}-{}-{}}}",
        &hex[..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..]
    ))
}

/// A double in its shortest exactly round-tripping form (valid `xs:double`).
/// An xs:double: Rust's shortest round-trip form, infinities as `INF` / `-INF`.
fn real(x: f64) -> String {
    match x {
        f64::INFINITY => "INF".into(),
        f64::NEG_INFINITY => "-INF".into(),
        _ => format!("{x:?}"),
    }
}

fn check_info(info: &ModelInfo) -> Result<(), String> {
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

/// All log categories: the wrapper's, then the model's that are not among them.
pub fn log_categories(info: &ModelInfo) -> Vec<(String, String)> {
    let mut all: Vec<(String, String)> = WRAPPER_CATEGORIES
        .iter()
        .map(|(n, d)| (n.to_string(), d.to_string()))
        .collect();
    for (name, description) in &info.log_categories {
        if !all.iter().any(|(n, _)| n == name) {
            all.push((name.clone(), description.clone()));
        }
    }
    all
}

/// Checks that every value reference of the structure is a variable of the table, and that
/// each derivative is declared as the derivative of its state.
fn check_structure(d: Description) -> Result<(), String> {
    let var = |vr: u32| {
        d.vars
            .iter()
            .find(|v| v.value_reference == vr)
            .ok_or(format!(
                "the model structure names value reference {vr}, which is not in the variable table"
            ))
    };
    for s in &d.structure.derivatives {
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
    for o in &d.structure.outputs {
        if var(o.output)?.causality != Causality::Output {
            return Err(format!(
                "value reference {} of <Outputs> is not an output",
                o.output
            ));
        }
        for &vr in &o.dependencies {
            var(vr)?;
        }
    }
    Ok(())
}

fn write_xml(d: Description, guid: &str) -> Result<String, String> {
    check_info(d.info)?;
    check_variable_table(d.vars)?;
    check_structure(d)?;
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    write_document(&mut w, d, guid).map_err(|e| format!("writing modelDescription.xml: {e}"))?;
    String::from_utf8(w.into_inner()).map_err(|e| e.to_string())
}

fn write_document(w: &mut Writer<Vec<u8>>, d: Description, guid: &str) -> io::Result<()> {
    let (info, vars) = (d.info, d.vars);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    let mut root = w.create_element("fmiModelDescription").with_attributes([
        ("fmiVersion", "2.0"),
        ("modelName", info.model_name.as_str()),
        ("guid", guid),
    ]);
    for (key, value) in [
        ("description", &info.description),
        ("author", &info.author),
        ("version", &info.version),
        ("generationTool", &info.generation_tool),
    ] {
        if !value.is_empty() {
            root = root.with_attribute((key, value.as_str()));
        }
    }
    root.with_attributes([
        ("variableNamingConvention", "flat"),
        ("numberOfEventIndicators", "0"),
    ])
    .write_inner_content(|w| {
        if info.model_exchange {
            write_model_exchange(w, info)?;
        }
        write_co_simulation(w, info)?;
        write_units(w, vars)?;
        write_log_categories(w, info)?;
        write_default_experiment(w, info)?;
        write_variables(w, vars)?;
        write_model_structure(w, d)
    })?;
    Ok(())
}

fn flag(b: bool) -> &'static str {
    if b { "true" } else { "false" }
}

/// `<ModelExchange>` with the capability flags (section 3.3.1): the same binary and model
/// identifier as Co-Simulation.
fn write_model_exchange(w: &mut Writer<Vec<u8>>, info: &ModelInfo) -> io::Result<()> {
    w.create_element("ModelExchange")
        .with_attributes([
            ("modelIdentifier", info.model_identifier.as_str()),
            ("needsExecutionTool", "false"),
            ("completedIntegratorStepNotNeeded", "true"),
            ("canBeInstantiatedOnlyOncePerProcess", "false"),
            ("canNotUseMemoryManagementFunctions", "true"),
            ("canGetAndSetFMUstate", "true"),
            ("canSerializeFMUstate", "true"),
            (
                "providesDirectionalDerivative",
                flag(info.directional_derivatives),
            ),
        ])
        .write_empty()?;
    Ok(())
}

/// `<CoSimulation>` with the capability flags (section 4.3.1).
fn write_co_simulation(w: &mut Writer<Vec<u8>>, info: &ModelInfo) -> io::Result<()> {
    w.create_element("CoSimulation")
        .with_attributes([
            ("modelIdentifier", info.model_identifier.as_str()),
            ("needsExecutionTool", "false"),
            ("canHandleVariableCommunicationStepSize", "true"),
            ("canInterpolateInputs", "false"),
            ("maxOutputDerivativeOrder", "0"),
            ("canRunAsynchronuously", "false"),
            ("canBeInstantiatedOnlyOncePerProcess", "false"),
            ("canNotUseMemoryManagementFunctions", "true"),
            ("canGetAndSetFMUstate", "true"),
            ("canSerializeFMUstate", "true"),
            (
                "providesDirectionalDerivative",
                flag(info.directional_derivatives),
            ),
        ])
        .write_empty()?;
    Ok(())
}

/// `<UnitDefinitions>`: every unit used, with its SI base units (section 2.2.2).
fn write_units(w: &mut Writer<Vec<u8>>, vars: &[Variable]) -> io::Result<()> {
    let used: BTreeSet<&str> = vars.iter().filter_map(|v| v.unit.as_deref()).collect();
    if used.is_empty() {
        return Ok(());
    }
    w.create_element("UnitDefinitions")
        .write_inner_content(|w| {
            for unit in used {
                // check_variable_table has verified that every unit is in the table
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
                            .write_empty()?;
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
    Ok(())
}

/// `<LogCategories>` (section 2.2.4).
fn write_log_categories(w: &mut Writer<Vec<u8>>, info: &ModelInfo) -> io::Result<()> {
    w.create_element("LogCategories").write_inner_content(|w| {
        for (name, description) in log_categories(info) {
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

/// `<DefaultExperiment>` (section 2.2.5).
fn write_default_experiment(w: &mut Writer<Vec<u8>>, info: &ModelInfo) -> io::Result<()> {
    let e = &info.default_experiment;
    let (start, stop, tol, step) = (
        real(e.start_time),
        real(e.stop_time),
        real(e.tolerance),
        real(e.step_size),
    );
    w.create_element("DefaultExperiment")
        .with_attributes([
            ("startTime", start.as_str()),
            ("stopTime", &stop),
            ("tolerance", &tol),
            ("stepSize", &step),
        ])
        .write_empty()?;
    Ok(())
}

/// The 1-based index of the variable with value reference `vr` in `<ModelVariables>`.
fn index(vars: &[Variable], vr: u32) -> usize {
    // the structure's references are checked against the table before writing
    vars.iter()
        .position(|v| v.value_reference == vr)
        .unwrap_or_default()
        + 1
}

fn index_of(vars: &[Variable], vr: u32) -> String {
    index(vars, vr).to_string()
}

/// `<ModelVariables>` (section 2.2.7). `initial` is written whenever the table allows it,
/// as the declared or default value, so readers need not know the defaults; a state
/// derivative names its state's index in `derivative`.
fn write_variables(w: &mut Writer<Vec<u8>>, vars: &[Variable]) -> io::Result<()> {
    w.create_element("ModelVariables")
        .write_inner_content(|w| {
            for v in vars {
                let vr = v.value_reference.to_string();
                let mut sv = w
                    .create_element("ScalarVariable")
                    .with_attributes([("name", v.name.as_str()), ("valueReference", &vr)]);
                if !v.description.is_empty() {
                    sv = sv.with_attribute(("description", v.description.as_str()));
                }
                sv = sv.with_attributes([
                    ("causality", v.causality.as_str()),
                    ("variability", v.variability.as_str()),
                ]);
                if let Some(initial) = v.effective_initial() {
                    sv = sv.with_attribute(("initial", initial.as_str()));
                }
                let start = v.start.map(real);
                let derivative = v.derivative.map(|state| index_of(vars, state));
                sv.write_inner_content(|w| {
                    let mut real_el = w.create_element("Real");
                    if let Some(unit) = &v.unit {
                        real_el = real_el.with_attribute(("unit", unit.as_str()));
                    }
                    if let Some(state) = &derivative {
                        real_el = real_el.with_attribute(("derivative", state.as_str()));
                    }
                    if let Some(start) = &start {
                        real_el = real_el.with_attribute(("start", start.as_str()));
                    }
                    real_el.write_empty()?;
                    Ok(())
                })?;
            }
            Ok(())
        })?;
    Ok(())
}

/// `<ModelStructure>` (section 2.2.8), with 1-based ScalarVariable indices.
///
/// * `<Outputs>`: every output, in index order, with the states (and inputs) it depends on
///   from the core's [`ModelStructure`].
/// * `<Derivatives>`: every state derivative, in the order of the state vector, with the
///   states and inputs it depends on.
/// * `<InitialUnknowns>`: exactly the list section 2.2.8 prescribes — outputs with initial
///   approx or calculated, calculated parameters, and the continuous states and state
///   derivatives with initial approx or calculated — in index order. Their values in
///   Initialization Mode are computed from the parameters with initial exact (the Knowns),
///   so `dependencies=""` ("depends on no Known") would be false; the attribute is omitted,
///   which the standard defines as "depends on all Knowns" — always correct, without the
///   generic layer having to know the physics.
fn write_model_structure(w: &mut Writer<Vec<u8>>, d: Description) -> io::Result<()> {
    let vars = d.vars;
    let list = |vrs: &[u32]| -> String {
        let mut indices: Vec<usize> = vrs.iter().map(|&vr| index(vars, vr)).collect();
        indices.sort_unstable();
        let text: Vec<String> = indices.iter().map(usize::to_string).collect();
        text.join(" ")
    };
    let outputs: Vec<(String, Option<String>)> = vars
        .iter()
        .filter(|v| v.causality == Causality::Output)
        .map(|v| {
            let deps = d
                .structure
                .outputs
                .iter()
                .find(|o| o.output == v.value_reference);
            (
                index_of(vars, v.value_reference),
                deps.map(|o| list(&o.dependencies)),
            )
        })
        .collect();
    let derivatives: Vec<(String, String)> = d
        .structure
        .derivatives
        .iter()
        .map(|s| (index_of(vars, s.derivative), list(&s.dependencies)))
        .collect();
    let is_state_or_derivative = |vr: u32| {
        d.structure
            .derivatives
            .iter()
            .any(|s| s.state == vr || s.derivative == vr)
    };
    let initial_unknowns: Vec<String> = vars
        .iter()
        .enumerate()
        .filter(|(_, v)| {
            let calculated = matches!(
                v.effective_initial(),
                Some(Initial::Approx | Initial::Calculated)
            );
            match v.causality {
                Causality::Output => calculated,
                Causality::CalculatedParameter => true,
                _ => calculated && is_state_or_derivative(v.value_reference),
            }
        })
        .map(|(i, _)| (i + 1).to_string())
        .collect();
    w.create_element("ModelStructure")
        .write_inner_content(|w| {
            if !outputs.is_empty() {
                w.create_element("Outputs").write_inner_content(|w| {
                    for (index, deps) in &outputs {
                        let mut el = w
                            .create_element("Unknown")
                            .with_attribute(("index", index.as_str()));
                        if let Some(deps) = deps {
                            el = el.with_attribute(("dependencies", deps.as_str()));
                        }
                        el.write_empty()?;
                    }
                    Ok(())
                })?;
            }
            if !derivatives.is_empty() {
                w.create_element("Derivatives").write_inner_content(|w| {
                    for (index, deps) in &derivatives {
                        w.create_element("Unknown")
                            .with_attributes([
                                ("index", index.as_str()),
                                ("dependencies", deps.as_str()),
                            ])
                            .write_empty()?;
                    }
                    Ok(())
                })?;
            }
            if !initial_unknowns.is_empty() {
                w.create_element("InitialUnknowns")
                    .write_inner_content(|w| {
                        for index in &initial_unknowns {
                            w.create_element("Unknown")
                                .with_attribute(("index", index.as_str()))
                                .write_empty()?;
                        }
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
    Ok(())
}
