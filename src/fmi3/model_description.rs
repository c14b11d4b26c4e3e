//! Generation of the FMI 3.0 `modelDescription.xml` (standard section 2.4) from the same
//! variable table and model information as the FMI 2.0 one, and of the
//! `instantiationToken` that ties the binary to it.

use std::io;

use sha2::{Digest, Sha256};

use super::Fmi3;
use super::logging::SHELL_CATEGORIES;
use crate::fmi_common::model_api::InstanceKind;
use crate::fmi_common::variables::{
    Causality, ModelInfo, Variability, Variable, check_variable_table,
};
use crate::fmi_common::xml::{
    Description, Dialect, XmlWriter, check_info, check_structure, flag, initial_unknowns,
    variable_element, write_description, xs_double,
};

/// The variables of the FMI 3.0 description: the core's table and, unless the table has one,
/// the independent variable `time` \[s\] that FMI 3.0 requires (section 2.4.7.4), with the
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
pub type Model<'a> = Description<'a>;

/// The complete `modelDescription.xml`, with the token of [`instantiation_token`].
pub fn model_description_xml(model: &Model) -> Result<String, String> {
    write_description::<Fmi3>(*model, &instantiation_token(model)?)
}

/// The `instantiationToken` (section 2.4.1): the SHA-256 of the description written with an
/// empty token, in braces, so that any change of the description (a variable, a start value,
/// a unit, a capability) changes it.
pub fn instantiation_token(model: &Model) -> Result<String, String> {
    let hash = Sha256::digest(write_description::<Fmi3>(*model, "")?.as_bytes());
    let hex: String = hash.iter().map(|b| format!("{b:02x}")).collect();
    Ok(format!("{{{hex}}}"))
}

impl Dialect for Fmi3 {
    const FMI_VERSION: &'static str = "3.0";
    const TOKEN: &'static str = "instantiationToken";
    const ROOT_ATTRIBUTES: &'static [(&'static str, &'static str)] =
        &[("variableNamingConvention", "flat")];
    const CATEGORIES: [(&'static str, &'static str); 5] = SHELL_CATEGORIES;

    fn check(d: Description) -> Result<(), String> {
        let vars = d.vars;
        check_variable_table(vars)?;
        if vars
            .iter()
            .filter(|v| v.causality == Causality::Independent)
            .count()
            != 1
        {
            return Err("FMI 3.0 needs exactly one independent variable (section 2.4.7.4)".into());
        }
        check_info(d.info)?;
        check_structure(vars, d.structure)
    }

    /// `<ModelExchange>` (section 3.4: no need for `fmi3CompletedIntegratorStep`, no
    /// `fmi3EvaluateDiscreteStates`, no discrete states) and `<CoSimulation>` (section 4.4:
    /// variable steps, no event mode of its own, no early return, no intermediate update, no
    /// output derivatives), after the capability flags both share.
    fn interface_attributes(kind: InstanceKind, info: &ModelInfo) -> Vec<(&'static str, &str)> {
        let mut attributes = vec![("modelIdentifier", info.model_identifier.as_str())];
        attributes.extend(common_capabilities(info));
        attributes.extend_from_slice(match kind {
            InstanceKind::ModelExchange => &[
                ("needsCompletedIntegratorStep", "false"),
                ("providesEvaluateDiscreteStates", "false"),
            ][..],
            InstanceKind::CoSimulation => &[
                ("canHandleVariableCommunicationStepSize", "true"),
                ("maxOutputDerivativeOrder", "0"),
                ("hasEventMode", "false"),
                ("providesIntermediateUpdate", "false"),
                ("mightReturnEarlyFromDoStep", "false"),
                ("canReturnEarlyAfterIntermediateUpdate", "false"),
            ],
        });
        attributes
    }

    /// A `<Float64>` (section 2.4.7) with its unit, start and the state it is the derivative
    /// of.
    fn write_variable(w: &mut XmlWriter, _vars: &[Variable], v: &Variable) -> io::Result<()> {
        let mut el = variable_element(w, "Float64", v);
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
        Ok(())
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
    fn write_model_structure(w: &mut XmlWriter, model: Description) -> io::Result<()> {
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

/// A list of value references as an attribute value.
fn refs(vrs: &[u32]) -> String {
    let text: Vec<String> = vrs.iter().map(u32::to_string).collect();
    text.join(" ")
}
