//! Packs an FMU archive, FMI 2.0 or 3.0: `modelDescription.xml`, the shared library
//! (`binaries/linux64/<modelIdentifier>.so`, FMI 3.0: `binaries/x86_64-linux/...`),
//! `documentation/index.html` and `resources/parameters.toml`, all generated from one variable
//! table and one parameter set: the platform's ([`platform`]) or the inverse's
//! ([`super::inverse::spec`], FMI 2.0 only).

use std::io::Write;
use std::path::Path;

use super::structure::model_structure;
use super::variables::variables;
use super::{RESOURCE_PARAMS, model_info};
use crate::fmi_common::model_api::ModelStructure;
use crate::fmi_common::variables::{Causality, ModelInfo, Variable};
use crate::fmi2::model_description::{guid_for, model_description_xml};
use crate::fmi3::model_description as fmi3_description;
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

/// `write` (the FMI 3.0 description or its token) of `spec`.
fn fmi3_model(
    spec: &Spec,
    write: fn(&fmi3_description::Model) -> Result<String, String>,
) -> String {
    let vars = fmi3_description::with_time(spec.variables.clone());
    write(&fmi3_description::Model {
        info: &spec.info,
        vars: &vars,
        structure: &spec.structure,
    })
    .expect("the variable table is valid (tested)")
}

/// The FMI version of an FMU archive: which description, library folder and C functions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FmiVersion {
    V2,
    V3,
}

impl FmiVersion {
    /// The version as the standard writes it.
    pub fn name(self) -> &'static str {
        match self {
            FmiVersion::V2 => "FMI 2.0",
            FmiVersion::V3 => "FMI 3.0",
        }
    }

    /// The platform folder under `binaries/` (FMI 2.0 section 2.3, FMI 3.0 section 2.5.1.1).
    fn platform(self) -> &'static str {
        match self {
            FmiVersion::V2 => "linux64",
            FmiVersion::V3 => "x86_64-linux",
        }
    }

    /// A function every library of this version exports, and one none does.
    fn marker_symbols(self) -> (&'static str, &'static str) {
        match self {
            FmiVersion::V2 => ("fmi2Instantiate", "fmi3InstantiateCoSimulation"),
            FmiVersion::V3 => ("fmi3InstantiateCoSimulation", "fmi2Instantiate"),
        }
    }

    /// The `modelDescription.xml` of `spec` in this version.
    pub fn model_description(self, spec: &Spec) -> String {
        match self {
            FmiVersion::V2 => model_description(spec),
            FmiVersion::V3 => fmi3_model(spec, fmi3_description::model_description_xml),
        }
    }

    /// The GUID (FMI 2.0) or instantiationToken (FMI 3.0) of that description.
    pub fn token(self, spec: &Spec) -> String {
        match self {
            FmiVersion::V2 => guid(spec),
            FmiVersion::V3 => fmi3_model(spec, fmi3_description::instantiation_token),
        }
    }
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
pub fn documentation(spec: &Spec, version: FmiVersion) -> String {
    let info = &spec.info;
    let mut html = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{id}</title>\n\
         <style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}}table{{border-collapse:collapse}}\
         td,th{{border:1px solid #ccc;padding:2px 6px;text-align:left}}</style></head><body>\n\
         <h1>{id}</h1>\n<p>{desc}</p>\n\
         <p>{version} {interfaces}, {token_name} <code>{guid}</code>. {about}</p>\n\
         <p>Default experiment: 0 to {stop} s, step {step} s, tolerance {tol}.</p>\n",
        id = info.model_identifier,
        desc = escape(&info.description),
        version = version.name(),
        token_name = match version {
            FmiVersion::V2 => "GUID",
            FmiVersion::V3 => "instantiationToken",
        },
        guid = version.token(spec),
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

/// Whether `bytes` contain `text`.
fn contains(bytes: &[u8], text: &str) -> bool {
    bytes.windows(text.len()).any(|w| w == text.as_bytes())
}

/// Reads the shared library at `library`, which must be the build of `version`
/// (`--features fmi3` for FMI 3.0).
pub fn read_library(library: &Path, version: FmiVersion) -> Result<Vec<u8>, FileError> {
    let so = std::fs::read(library)
        .map_err(|e| FileError::new(library, format!("cannot read the FMU library: {e}")))?;
    if !so.starts_with(b"\x7fELF") {
        return Err(FileError::new(library, "not an ELF shared library"));
    }
    let (needed, foreign) = version.marker_symbols();
    if !contains(&so, needed) || contains(&so, foreign) {
        let build = match version {
            FmiVersion::V2 => "cargo build --release --lib",
            FmiVersion::V3 => "cargo build --release --lib --features fmi3",
        };
        return Err(FileError::new(
            library,
            format!(
                "not the {} build of the library (it must export {needed} and not {foreign}; build it with `{build}`)",
                version.name()
            ),
        ));
    }
    Ok(so)
}

/// Writes the FMU of `spec` in `version` to `out` (atomically) with the library `so` of
/// [`read_library`] and `params` as its resource file.
pub fn pack(
    so: Vec<u8>,
    spec: &Spec,
    params: &Params,
    out: &Path,
    version: FmiVersion,
) -> Result<(), FileError> {
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    let entries: [(String, Vec<u8>); 4] = [
        (
            "modelDescription.xml".into(),
            version.model_description(spec).into_bytes(),
        ),
        (
            format!(
                "binaries/{}/{}.so",
                version.platform(),
                spec.info.model_identifier
            ),
            so,
        ),
        (
            "documentation/index.html".into(),
            documentation(spec, version).into_bytes(),
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
    fn a_library_of_the_other_version_is_refused() {
        let dir = std::env::temp_dir().join(format!("hasel_pack_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let lib = dir.join("lib.so");
        std::fs::write(&lib, b"\x7fELF ... fmi2Instantiate ...").unwrap();
        assert!(read_library(&lib, FmiVersion::V2).is_ok());
        let e = read_library(&lib, FmiVersion::V3).unwrap_err().to_string();
        assert!(
            e.contains("not the FMI 3.0 build") && e.contains("--features fmi3"),
            "{e}"
        );
        std::fs::write(&lib, b"\x7fELF fmi3InstantiateCoSimulation").unwrap();
        assert!(read_library(&lib, FmiVersion::V2).is_err());
        assert!(read_library(&lib, FmiVersion::V3).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_fmi3_description_has_the_variables_of_the_fmi2_one_and_time() {
        let p = Params::default();
        let (v2, v3) = (
            FmiVersion::V2.model_description(&platform(&p)),
            FmiVersion::V3.model_description(&platform(&p)),
        );
        assert!(
            v3.contains("fmiVersion=\"3.0\"") && v3.contains(&FmiVersion::V3.token(&platform(&p)))
        );
        for v in variables(&p, DEFAULT_RTOL) {
            let declared = format!(
                "name=\"{}\" valueReference=\"{}\"",
                v.name, v.value_reference
            );
            assert!(
                v2.contains(&declared) && v3.contains(&declared),
                "{}",
                v.name
            );
        }
        assert!(v3.contains("<Float64 name=\"time\""));
        let mut stiffer = p.clone();
        stiffer.set("Kb_1", 0.31).unwrap();
        assert_ne!(
            FmiVersion::V3.token(&platform(&p)),
            FmiVersion::V3.token(&platform(&stiffer))
        );
    }

    #[test]
    fn both_versions_declare_the_interfaces_and_derivatives_the_model_offers() {
        let p = Params::default();
        for version in [FmiVersion::V2, FmiVersion::V3] {
            let flag = match version {
                FmiVersion::V2 => "providesDirectionalDerivative=",
                FmiVersion::V3 => "providesDirectionalDerivatives=",
            };
            let count = |xml: &str, value: &str| xml.matches(&format!("{flag}\"{value}\"")).count();
            // the platform: Model Exchange and Co-Simulation, each with directional derivatives
            let full = version.model_description(&platform(&p));
            assert!(full.contains("<ModelExchange") && full.contains("<CoSimulation"));
            assert_eq!((count(&full, "true"), count(&full, "false")), (2, 0));
            // the inverse: Co-Simulation only, without them
            let inverse = version.model_description(&inverse::spec(&p));
            assert!(!inverse.contains("<ModelExchange") && inverse.contains("<CoSimulation"));
            assert_eq!((count(&inverse, "true"), count(&inverse, "false")), (0, 1));
        }
    }

    #[test]
    fn documentation_lists_every_variable() {
        for spec in specs() {
            let doc = documentation(&spec, FmiVersion::V2);
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
