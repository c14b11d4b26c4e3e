//! Packs an FMU archive: `modelDescription.xml`, `binaries/linux64/<modelIdentifier>.so`,
//! `documentation/index.html` and `resources/parameters.toml`, all generated from one variable
//! table and one parameter set: the platform's ([`platform`]) or the inverse's
//! ([`super::inverse::spec`]).

use std::io::Write;
use std::path::Path;

use super::structure::model_structure;
use super::variables::variables;
use super::{RESOURCE_PARAMS, model_info};
use crate::fmi_common::model_api::ModelStructure;
use crate::fmi_common::variables::{Causality, ModelInfo, Variable};
use crate::fmi2::model_description::{guid_for, model_description_xml};
use crate::io::file::{FileError, write_bytes_atomic};
use crate::io::params_file;
use crate::model::Params;
use crate::simulation::DEFAULT_RTOL;

/// One FMU of this crate: its model data, its variables with their start values, its structure
/// and what its documentation says of the model.
pub struct Spec {
    pub info: ModelInfo,
    pub variables: Vec<Variable>,
    pub structure: ModelStructure,
    pub about: &'static str,
}

/// The HaselPlatform FMU with the start values `params`.
pub fn platform(params: &Params) -> Spec {
    Spec {
        info: model_info(),
        variables: variables(params, DEFAULT_RTOL),
        structure: model_structure(),
        about: "Each actuator is the port-Hamiltonian system of Feregrino et al.: state (theta, \
                l_p, p, Q1, Q2), energy H, dynamics dx/dt = (J - R) grad H + g U; the heights \
                h_i = 1/2 Lv sin(theta_i) drive the 3PS platform, whose forward kinematics gives \
                the antenna tip. In Co-Simulation the inputs are held constant over each \
                communication step; the internal solver is a Radau IIA method of order 5 with \
                error control (relative tolerance from fmi2SetupExperiment, else the parameter \
                <code>rtol</code>). In Model Exchange the importer integrates the 27 states (the \
                paper's five and four effect states per actuator, each with its der() variable; \
                an effect that is off keeps its state at 0); the transport delay tau_d needs \
                Co-Simulation. Directional derivatives (both interfaces) come from the model's \
                analytic Jacobian. The simulation starts from the U = 0 equilibrium under gravity.",
    }
}

/// The `modelDescription.xml` of `spec`.
pub fn model_description(spec: &Spec) -> String {
    model_description_xml(&spec.info, &spec.variables, &spec.structure)
        .expect("the variable table is valid (tested)")
}

/// The GUID of that description.
pub fn guid(spec: &Spec) -> String {
    guid_for(&spec.info, &spec.variables, &spec.structure)
        .expect("the variable table is valid (tested)")
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn group(v: &Variable) -> &'static str {
    match v.causality {
        Causality::Input => "Inputs",
        Causality::Output => "Outputs",
        Causality::Parameter | Causality::CalculatedParameter => "Parameters",
        _ => "Diagnostic variables",
    }
}

/// `documentation/index.html`: the model, its interface and every variable with its unit,
/// start value and description.
pub fn documentation(spec: &Spec) -> String {
    let info = &spec.info;
    let mut html = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{id}</title>\n\
         <style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}}table{{border-collapse:collapse}}\
         td,th{{border:1px solid #ccc;padding:2px 6px;text-align:left}}</style></head><body>\n\
         <h1>{id}</h1>\n<p>{desc}</p>\n\
         <p>FMI 2.0 {interfaces}, GUID <code>{guid}</code>. {about}</p>\n\
         <p>Default experiment: 0 to {stop} s, step {step} s, tolerance {tol}.</p>\n",
        id = info.model_identifier,
        desc = escape(&info.description),
        guid = guid(spec),
        about = spec.about,
        interfaces = if info.model_exchange {
            "Co-Simulation and Model Exchange (one binary)"
        } else {
            "Co-Simulation"
        },
        stop = info.default_experiment.stop_time,
        step = info.default_experiment.step_size,
        tol = info.default_experiment.tolerance,
    );
    for title in ["Inputs", "Outputs", "Parameters", "Diagnostic variables"] {
        html.push_str(&format!(
            "<h2>{title}</h2>\n<table><tr><th>name</th><th>value reference</th><th>unit</th><th>start</th><th>description</th></tr>\n"
        ));
        for v in spec.variables.iter().filter(|v| group(v) == title) {
            html.push_str(&format!(
                "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                v.name,
                v.value_reference,
                v.unit.as_deref().unwrap_or(""),
                v.start.map(|s| format!("{s:?}")).unwrap_or_default(),
                escape(&v.description)
            ));
        }
        html.push_str("</table>\n");
    }
    html.push_str("</body></html>\n");
    html
}

/// Writes the FMU of `spec` to `out` (atomically) from the shared library at `library`, with
/// `params` as its resource file.
pub fn pack(library: &Path, spec: &Spec, params: &Params, out: &Path) -> Result<(), FileError> {
    let so = std::fs::read(library)
        .map_err(|e| FileError::new(library, format!("cannot read the FMU library: {e}")))?;
    if !so.starts_with(b"\x7fELF") {
        return Err(FileError::new(library, "not an ELF shared library"));
    }
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    let entries: [(String, Vec<u8>); 4] = [
        (
            "modelDescription.xml".into(),
            model_description(spec).into_bytes(),
        ),
        (
            format!("binaries/linux64/{}.so", spec.info.model_identifier),
            so,
        ),
        (
            "documentation/index.html".into(),
            documentation(spec).into_bytes(),
        ),
        (
            format!("resources/{RESOURCE_PARAMS}"),
            params_file::to_toml(params).into_bytes(),
        ),
    ];
    let zip_err = |e: String| FileError::new(out, format!("cannot build the archive: {e}"));
    for (name, bytes) in &entries {
        zip.start_file(name.as_str(), options)
            .map_err(|e| zip_err(e.to_string()))?;
        zip.write_all(bytes).map_err(|e| zip_err(e.to_string()))?;
    }
    let bytes = zip
        .finish()
        .map_err(|e| zip_err(e.to_string()))?
        .into_inner();
    write_bytes_atomic(out, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmi_common::variables::check_variable_table;
    use crate::fmu::inverse;

    /// Both FMUs at the default parameters.
    fn specs() -> [Spec; 2] {
        let p = Params::default();
        [platform(&p), inverse::spec(&p)]
    }

    #[test]
    fn the_variable_tables_follow_the_fmi_rules() {
        for spec in specs() {
            check_variable_table(&spec.variables).unwrap();
        }
    }

    #[test]
    fn committed_model_description_is_the_generated_one() {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("modelDescription/modelDescription.xml");
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            committed == model_description(&platform(&Params::default())),
            "{} differs from the generated description: run `cargo run -- describe --out modelDescription/modelDescription.xml`",
            path.display()
        );
    }

    #[test]
    fn the_guid_follows_the_start_values() {
        let mut p = Params::default();
        let g0 = [guid(&platform(&p)), guid(&inverse::spec(&p))];
        p.set("Kb_1", 0.31).unwrap();
        for (spec, g0) in [platform(&p), inverse::spec(&p)].iter().zip(g0) {
            assert_ne!(g0, guid(spec));
            assert!(model_description(spec).contains(&guid(spec)));
        }
    }

    #[test]
    fn documentation_lists_every_variable() {
        for spec in specs() {
            let doc = documentation(&spec);
            for v in &spec.variables {
                assert!(
                    doc.contains(&format!("<code>{}</code>", v.name)),
                    "{}",
                    v.name
                );
            }
        }
    }
}
