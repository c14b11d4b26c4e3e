//! Generation of the FMI 3.0 `modelDescription.xml` (standard section 2.4) from the same
//! variable table and model information as the FMI 2.0 one, and of the
//! `instantiationToken` that ties the binary to it.

use std::io;

use quick_xml::Writer;
use quick_xml::events::{BytesDecl, Event};
use sha2::{Digest, Sha256};

use super::logging::SHELL_CATEGORIES;
use crate::fmi_common::model_api::ModelStructure;
use crate::fmi_common::variables::{
    Causality, ModelInfo, Variability, Variable, check_variable_table,
};
use crate::fmi_common::xml::{
    XmlWriter, check_info, check_structure, flag, initial_unknowns, model_attributes,
    write_default_experiment, write_log_categories, write_unit_definitions, xs_double,
};

/// The variables of the FMI 3.0 description: the core's table and, unless the table has one,
/// the independent variable `time` [s] that FMI 3.0 requires (section 2.4.7.4), with the
/// value reference after the table's last.
pub fn with_time(mut vars: Vec<Variable>) -> Vec<Variable> {
    if vars.iter().all(|v| v.causality != Causality::Independent) {
        let next = vars
            .iter()
            .map(|v| v.value_reference + 1)
            .max()
            .unwrap_or(0);
        vars.insert(
            0,
            Variable {
                name: "time".into(),
                value_reference: next,
                causality: Causality::Independent,
                variability: Variability::Continuous,
                initial: None,
                unit: Some("s".into()),
                description: "Simulation time".into(),
                start: None,
                derivative: None,
            },
        );
    }
    vars
}

/// What a description is written from: the model information, the variables (already with
/// [`with_time`]) and the model structure.
pub struct Model<'a> {
    pub info: &'a ModelInfo,
    pub vars: &'a [Variable],
    pub structure: &'a ModelStructure,
}

/// The complete `modelDescription.xml`, with the token of [`instantiation_token`].
pub fn model_description_xml(model: &Model) -> Result<String, String> {
    write_xml(model, &instantiation_token(model)?)
}

/// The `instantiationToken` (section 2.4.1): the SHA-256 of the description written with an
/// empty token, in braces, so that any change of the description (a variable, a start value,
/// a unit, a capability) changes it.
pub fn instantiation_token(model: &Model) -> Result<String, String> {
    let hash = Sha256::digest(write_xml(model, "")?.as_bytes());
    let hex: String = hash.iter().map(|b| format!("{b:02x}")).collect();
    Ok(format!("{{{hex}}}"))
}

/// All log categories: the shell's, then the model's that are not among them.
pub fn log_categories(info: &ModelInfo) -> Vec<(String, String)> {
    crate::fmi_common::xml::log_categories(&SHELL_CATEGORIES, info)
}

fn write_xml(model: &Model, token: &str) -> Result<String, String> {
    let vars = model.vars;
    check_variable_table(vars)?;
    if vars
        .iter()
        .filter(|v| v.causality == Causality::Independent)
        .count()
        != 1
    {
        return Err("FMI 3.0 needs exactly one independent variable (section 2.4.7.4)".into());
    }
    check_info(model.info)?;
    check_structure(vars, model.structure)?;
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    write_document(&mut w, model, token)
        .map_err(|e| format!("writing modelDescription.xml: {e}"))?;
    String::from_utf8(w.into_inner()).map_err(|e| e.to_string())
}

fn write_document(w: &mut XmlWriter, model: &Model, token: &str) -> io::Result<()> {
    let (info, vars) = (model.info, model.vars);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    w.create_element("fmiModelDescription")
        .with_attributes([
            ("fmiVersion", "3.0"),
            ("modelName", info.model_name.as_str()),
            ("instantiationToken", token),
        ])
        .with_attributes(model_attributes(info))
        .with_attribute(("variableNamingConvention", "flat"))
        .write_inner_content(|w| {
            if info.model_exchange {
                write_model_exchange(w, info)?;
            }
            write_co_simulation(w, info)?;
            write_unit_definitions(w, vars)?;
            write_log_categories(w, &log_categories(info))?;
            write_default_experiment(w, info)?;
            write_variables(w, vars)?;
            write_model_structure(w, model)
        })?;
    Ok(())
}

/// The capability flags both interfaces share (sections 3.4 and 4.4); directional derivatives
/// as the model offers them.
fn common_capabilities(info: &ModelInfo) -> [(&'static str, &'static str); 6] {
    [
        ("needsExecutionTool", "false"),
        ("canBeInstantiatedOnlyOncePerProcess", "false"),
        ("canGetAndSetFMUState", "true"),
        ("canSerializeFMUState", "true"),
        (
            "providesDirectionalDerivatives",
            flag(info.directional_derivatives),
        ),
        ("providesAdjointDerivatives", "false"),
    ]
}

/// `<ModelExchange>` (section 3.4), if the model offers it: no need for
/// `fmi3CompletedIntegratorStep`, no `fmi3EvaluateDiscreteStates` (no discrete states).
fn write_model_exchange(w: &mut XmlWriter, info: &ModelInfo) -> io::Result<()> {
    w.create_element("ModelExchange")
        .with_attribute(("modelIdentifier", info.model_identifier.as_str()))
        .with_attributes(common_capabilities(info))
        .with_attributes([
            ("needsCompletedIntegratorStep", "false"),
            ("providesEvaluateDiscreteStates", "false"),
        ])
        .write_empty()?;
    Ok(())
}

/// `<CoSimulation>` (section 4.4): variable steps, no event mode of its own, no early return,
/// no intermediate update, no output derivatives.
fn write_co_simulation(w: &mut XmlWriter, info: &ModelInfo) -> io::Result<()> {
    w.create_element("CoSimulation")
        .with_attribute(("modelIdentifier", info.model_identifier.as_str()))
        .with_attributes(common_capabilities(info))
        .with_attributes([
            ("canHandleVariableCommunicationStepSize", "true"),
            ("maxOutputDerivativeOrder", "0"),
            ("hasEventMode", "false"),
            ("providesIntermediateUpdate", "false"),
            ("mightReturnEarlyFromDoStep", "false"),
            ("canReturnEarlyAfterIntermediateUpdate", "false"),
        ])
        .write_empty()?;
    Ok(())
}

/// `<ModelVariables>` (section 2.4.7): one `<Float64>` per variable. `initial` is written
/// whenever the rules allow it, as the declared or default value.
fn write_variables(w: &mut XmlWriter, vars: &[Variable]) -> io::Result<()> {
    w.create_element("ModelVariables")
        .write_inner_content(|w| {
            for v in vars {
                let vr = v.value_reference.to_string();
                let mut el = w
                    .create_element("Float64")
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
                if let Some(unit) = &v.unit {
                    el = el.with_attribute(("unit", unit.as_str()));
                }
                let start = v.start.map(xs_double);
                if let Some(start) = &start {
                    el = el.with_attribute(("start", start.as_str()));
                }
                let state = v.derivative.map(|vr| vr.to_string());
                if let Some(state) = &state {
                    el = el.with_attribute(("derivative", state.as_str()));
                }
                el.write_empty()?;
            }
            Ok(())
        })?;
    Ok(())
}

/// A list of value references as an attribute value.
fn refs(vrs: &[u32]) -> String {
    let text: Vec<String> = vrs.iter().map(u32::to_string).collect();
    text.join(" ")
}

/// `<ModelStructure>` (section 2.4.8), by value reference, from the core's structure.
///
/// * `<Output>`: every output with the states and inputs it depends on.
/// * `<ContinuousStateDerivative>`: the state vector's order, with the dependencies of each
///   derivative.
/// * `<InitialUnknown>`: exactly the list the standard prescribes: outputs with initial
///   approx or calculated, calculated parameters, and states and derivatives with initial
///   approx or calculated, without `dependencies` ("depends on all knowns": always correct
///   without the shell knowing the physics).
fn write_model_structure(w: &mut XmlWriter, model: &Model) -> io::Result<()> {
    let structure = model.structure;
    let initial_unknowns: Vec<String> = initial_unknowns(model.vars, structure)
        .into_iter()
        .map(|(_, v)| v.value_reference.to_string())
        .collect();
    w.create_element("ModelStructure")
        .write_inner_content(|w| {
            for o in &structure.outputs {
                let (vr, deps) = (o.output.to_string(), refs(&o.dependencies));
                w.create_element("Output")
                    .with_attributes([("valueReference", vr.as_str()), ("dependencies", &deps)])
                    .write_empty()?;
            }
            for d in &structure.derivatives {
                let (vr, deps) = (d.derivative.to_string(), refs(&d.dependencies));
                w.create_element("ContinuousStateDerivative")
                    .with_attributes([("valueReference", vr.as_str()), ("dependencies", &deps)])
                    .write_empty()?;
            }
            for vr in &initial_unknowns {
                w.create_element("InitialUnknown")
                    .with_attribute(("valueReference", vr.as_str()))
                    .write_empty()?;
            }
            Ok(())
        })?;
    Ok(())
}
