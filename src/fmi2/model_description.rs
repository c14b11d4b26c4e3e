//! Generation of `modelDescription.xml` (FMI 2.0 standard, section 2.2) and of the GUID
//! that ties the binary to it.

use std::io;

use sha2::{Digest, Sha256};

use super::Fmi2;
use super::logging::WRAPPER_CATEGORIES;
use crate::fmi_common::model_api::{InstanceKind, ModelStructure};
use crate::fmi_common::variables::{Causality, ModelInfo, Variable, check_variable_table};
use crate::fmi_common::xml::{
    Description, Dialect, XmlWriter, check_info, check_structure, flag, initial_unknowns,
    variable_element, write_description, xs_double,
};

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
    write_description::<Fmi2>(d, &guid_for(info, vars, structure)?)
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
    let hash = Sha256::digest(write_description::<Fmi2>(d, "")?.as_bytes());
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

impl Dialect for Fmi2 {
    const FMI_VERSION: &'static str = "2.0";
    const TOKEN: &'static str = "guid";
    const ROOT_ATTRIBUTES: &'static [(&'static str, &'static str)] = &[
        ("variableNamingConvention", "flat"),
        ("numberOfEventIndicators", "0"),
    ];
    const CATEGORIES: [(&'static str, &'static str); 5] = WRAPPER_CATEGORIES;

    fn check(d: Description) -> Result<(), String> {
        check_info(d.info)?;
        check_variable_table(d.vars)?;
        check_structure(d.vars, d.structure)
    }

    /// `<ModelExchange>` (section 3.3.1: the same binary and model identifier as
    /// Co-Simulation) and `<CoSimulation>` (section 4.3.1) with their capability flags.
    fn interface_attributes(kind: InstanceKind, info: &ModelInfo) -> Vec<(&'static str, &str)> {
        let mut attributes = vec![
            ("modelIdentifier", info.model_identifier.as_str()),
            ("needsExecutionTool", "false"),
        ];
        attributes.extend_from_slice(match kind {
            InstanceKind::ModelExchange => &[("completedIntegratorStepNotNeeded", "true")][..],
            InstanceKind::CoSimulation => &[
                ("canHandleVariableCommunicationStepSize", "true"),
                ("canInterpolateInputs", "false"),
                ("maxOutputDerivativeOrder", "0"),
                ("canRunAsynchronuously", "false"),
            ],
        });
        attributes.extend([
            ("canBeInstantiatedOnlyOncePerProcess", "false"),
            ("canNotUseMemoryManagementFunctions", "true"),
            ("canGetAndSetFMUstate", "true"),
            ("canSerializeFMUstate", "true"),
            (
                "providesDirectionalDerivative",
                flag(info.directional_derivatives),
            ),
        ]);
        attributes
    }

    /// A `<ScalarVariable>` (section 2.2.7) with its `<Real>`; a state derivative names its
    /// state's index in `derivative`.
    fn write_variable(w: &mut XmlWriter, vars: &[Variable], v: &Variable) -> io::Result<()> {
        let start = v.start.map(xs_double);
        let derivative = v.derivative.map(|state| index_of(vars, state));
        variable_element(w, "ScalarVariable", v).write_inner_content(|w| {
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
    fn write_model_structure(w: &mut XmlWriter, d: Description) -> io::Result<()> {
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
        let initial_unknowns: Vec<String> = initial_unknowns(vars, d.structure)
            .into_iter()
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
