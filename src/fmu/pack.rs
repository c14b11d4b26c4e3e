//! Packs an FMU archive, FMI 2.0 or 3.0: `modelDescription.xml`, the shared library of each
//! platform built (`binaries/linux64/<modelIdentifier>.so`, FMI 3.0:
//! `binaries/x86_64-linux/...`, and the others of [`super::binary`]), `documentation/index.html` and `resources/parameters.toml`, all generated from one variable
//! table and one parameter set: the platform's ([`platform`]) or the inverse's ([`inverse`],
//! FMI 2.0 only). Only the `hasel` command packs (feature `tools`): the FMU libraries have none
//! of this.

use std::io::Write;
use std::path::Path;

use super::binary::{Platform, platform_of};
use super::inverse::{self as inverse_fmu, InverseCore};
use super::structure::model_structure;
use super::variables::variables;
use super::{FmuModel, RESOURCE_PARAMS, SlowModel, model_info};
use crate::fmi_common::model_api::{FmuCore, ModelStructure};
use crate::fmi_common::variables::{Causality, ModelInfo, Variable};
use crate::fmi2::model_description::{guid_for, model_description_xml};
use crate::fmi3::model_description as fmi3_description;
use crate::io::file::{FileError, write_bytes_atomic};
use crate::io::params_file;
use crate::model::{Params, Reduction};
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
        variables: variables(Reduction::Full, params, DEFAULT_RTOL),
        structure: model_structure(Reduction::Full),
        about: "Each actuator is the port-Hamiltonian system of Feregrino et al.: state (theta, \
                l_p, p, Q1, Q2), energy H, dynamics dx/dt = (J - R) grad H + g U; the heights \
                h_i = 1/2 Lv sin(theta_i) drive the 3PS platform, whose forward kinematics gives \
                the antenna tip. In Co-Simulation the inputs are held constant over each \
                communication step; the internal solver is a Radau IIA method of order 5 with \
                error control (relative tolerance from fmi2SetupExperiment, else the parameter \
                <code>rtol</code>). In Model Exchange the importer integrates the states (the \
                paper's five per actuator and every state the effects' parameters can switch on, \
                each with its der() variable; an effect that is off keeps its state at 0); the transport delay tau_d needs \
                Co-Simulation. Directional derivatives (both interfaces) come from the model's \
                analytic Jacobian. The simulation starts from the U = 0 equilibrium under gravity.",
    }
}

/// The HaselPlatformReduced FMU with the start values `params`: what `hasel fmu --model
/// reduced` packs.
pub fn reduced(params: &Params) -> Spec {
    Spec {
        info: SlowModel::model_info(),
        variables: variables(Reduction::Slow, params, DEFAULT_RTOL),
        structure: model_structure(Reduction::Slow),
        about: "The slow model of the HaselPlatform FMU (singular perturbation of the same \
                port-Hamiltonian model, same parameters and effects): the charges on the DC \
                circuit's values and the momentum on the force balance, so each actuator keeps \
                one state, its angle theta, moving as dtheta/dt = -(dH/dtheta + d dH/dl_p)/b with \
                the top film on its invariant curve, plus the states of the effects that are on. \
                Without the nanosecond and microsecond modes of the full model its Model Exchange \
                runs under any importer's integrator, fixed-step ones included; it follows the \
                full model within about 0.2 um (the error table is in the project's book, chapter \
                \"Reduced models\"). H is the reduced storage (without the charges' and the \
                momentum's energy), P_supplied adds the electrode's electromechanical power. \
                Co-Simulation runs the same model with the internal Radau IIA solver; directional \
                derivatives come from the reduced model's analytic Jacobian.",
    }
}

/// The HaselInverse FMU with the start values `params`: what `hasel fmu --model inverse` packs.
pub fn inverse(params: &Params) -> Spec {
    Spec {
        info: inverse_fmu::model_info(),
        variables: inverse_fmu::variables::variables(params),
        structure: InverseCore::model_structure(),
        about: "The inverse of the HaselPlatform FMU, for feedforward: each communication step \
                maps the inputs held over it (the antenna tip's x and y and the platform's mean \
                height, which x and y leave open) to the actuator heights by the inverse \
                kinematics from X and Y (Newton on the forward kinematics), and to the constant \
                voltages that hold those heights at equilibrium (closed form: the height's angle, \
                the film on its invariant curve, the torque balance with the charges of the DC \
                circuit). The outputs at the end of a step are those of the inputs held over it; \
                a tip it cannot reach (below the rest height, beyond the height where the input \
                gain vanishes) makes the step return fmi2Discard with the reason logged. Its \
                parameters are the platform's.",
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

    /// A function every library of this version exports (the platform's and the slow model's
    /// libraries export both versions' functions; the inverse's FMI 2.0's alone).
    fn marker_symbol(self) -> &'static str {
        match self {
            FmiVersion::V2 => "fmi2Instantiate",
            FmiVersion::V3 => "fmi3InstantiateCoSimulation",
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
    for (title, rows) in variable_groups(spec) {
        html.push_str(&format!(
            "<h2>{title}</h2>\n<table><tr><th>name</th><th>value reference</th><th>unit</th><th>start</th><th>description</th></tr>\n"
        ));
        for [name, vr, unit, start, description] in rows {
            html.push_str(&format!(
                "<tr><td><code>{name}</code></td><td>{vr}</td><td>{unit}</td><td>{start}</td><td>{}</td></tr>\n",
                escape(&description)
            ));
        }
        html.push_str("</table>\n");
    }
    html.push_str("</body></html>\n");
    html
}

/// The same tables as [`documentation`] in Markdown, for the book's chapter "Parameters"
/// (tests/docs.rs holds the chapter to it).
pub fn variables_markdown(spec: &Spec) -> String {
    let mut md = String::new();
    for (title, rows) in variable_groups(spec) {
        md.push_str(&format!(
            "\n### {title}\n\n| name | value reference | unit | start | description |\n|---|---|---|---|---|\n"
        ));
        for [name, vr, unit, start, description] in rows {
            md.push_str(&format!(
                "| `{name}` | {vr} | {unit} | {start} | {} |\n",
                description.replace('|', "\\|")
            ));
        }
    }
    md
}

/// The variables in the documentation's groups, each as name, value reference, unit, start value
/// and description.
fn variable_groups(spec: &Spec) -> Vec<(&'static str, Vec<[String; 5]>)> {
    ["Inputs", "Outputs", "Parameters", "Diagnostic variables"]
        .into_iter()
        .map(|title| {
            let rows = spec
                .variables
                .iter()
                .filter(|v| group(v) == title)
                .map(|v| {
                    [
                        v.name.clone(),
                        v.value_reference.to_string(),
                        v.unit.clone().unwrap_or_default(),
                        v.start.map(|s| format!("{s:?}")).unwrap_or_default(),
                        v.description.clone(),
                    ]
                })
                .collect();
            (title, rows)
        })
        .collect()
}

/// Whether `bytes` contain `text`.
fn contains(bytes: &[u8], text: &str) -> bool {
    bytes.windows(text.len()).any(|w| w == text.as_bytes())
}

/// A shared library of the FMU, read and checked by [`read_library`].
#[derive(Debug)]
pub struct Library {
    pub platform: Platform,
    /// Its folder under `binaries/`.
    pub folder: &'static str,
    pub bytes: Vec<u8>,
}

/// Reads the shared library at `library`, which must export the functions of `version` (the
/// build with the model's own cargo `feature` where it has one) for a platform that version has
/// a folder for.
pub fn read_library(
    library: &Path,
    version: FmiVersion,
    feature: Option<&str>,
) -> Result<Library, FileError> {
    let bytes = std::fs::read(library)
        .map_err(|e| FileError::new(library, format!("cannot read the FMU library: {e}")))?;
    library_of(bytes, version, feature).map_err(|e| FileError::new(library, e))
}

/// The largest shared library taken out of an FMU: ten times the release build's largest.
const MAX_LIBRARY_BYTES: u64 = 100 << 20;

/// The shared libraries in the FMU `fmu` (its `binaries/`), each checked as [`read_library`]
/// checks a file and named as `identifier`'s, with the FMI version its description declares:
/// to pack the same model with other start values (`hasel fmu --from`).
pub fn libraries_in(
    fmu: &Path,
    identifier: &str,
    feature: Option<&str>,
) -> Result<(FmiVersion, Vec<Library>), FileError> {
    use std::io::Read;
    let fail = |what: String| FileError::new(fmu, what);
    let file = std::fs::File::open(fmu).map_err(|e| fail(format!("cannot read the FMU: {e}")))?;
    let mut zip =
        zip::ZipArchive::new(file).map_err(|e| fail(format!("not an FMU (a zip archive): {e}")))?;
    let mut description = String::new();
    zip.by_name("modelDescription.xml")
        .map_err(|e| fail(format!("no modelDescription.xml: {e}")))?
        .take(MAX_LIBRARY_BYTES)
        .read_to_string(&mut description)
        .map_err(|e| fail(format!("modelDescription.xml: {e}")))?;
    let version = if description.contains(r#"fmiVersion="3.0""#) {
        FmiVersion::V3
    } else if description.contains(r#"fmiVersion="2.0""#) {
        FmiVersion::V2
    } else {
        return Err(fail(
            "modelDescription.xml declares neither fmiVersion 2.0 nor 3.0".into(),
        ));
    };
    let mut libraries = Vec::new();
    for i in 0..zip.len() {
        let mut entry = zip
            .by_index(i)
            .map_err(|e| fail(format!("entry {i}: {e}")))?;
        let name = entry
            .name()
            .map_err(|e| fail(format!("entry {i}: {e}")))?
            .to_string();
        let Some((_, file)) = name
            .strip_prefix("binaries/")
            .and_then(|r| r.split_once('/'))
        else {
            continue;
        };
        if entry.is_dir() || file.is_empty() {
            continue;
        }
        if file.split('.').next() != Some(identifier) {
            return Err(fail(format!(
                "{name}: not a library of {identifier} (an FMU of another model?)"
            )));
        }
        if entry.size() > MAX_LIBRARY_BYTES {
            return Err(fail(format!(
                "{name}: {} bytes, more than a library of this FMU holds",
                entry.size()
            )));
        }
        let mut bytes = Vec::new();
        entry
            .by_ref()
            .take(MAX_LIBRARY_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| fail(format!("{name}: {e}")))?;
        libraries
            .push(library_of(bytes, version, feature).map_err(|e| fail(format!("{name}: {e}")))?);
    }
    if libraries.is_empty() {
        return Err(fail("no shared library under binaries/".into()));
    }
    Ok((version, libraries))
}

/// The shared library in `bytes`, checked as [`read_library`] says.
fn library_of(
    bytes: Vec<u8>,
    version: FmiVersion,
    feature: Option<&str>,
) -> Result<Library, String> {
    let platform = platform_of(&bytes)?;
    let folder = platform
        .folder(version == FmiVersion::V3)
        .map_err(|e| format!("a {platform} library: {e}"))?;
    let needed = version.marker_symbol();
    if !contains(&bytes, needed) {
        let build = match feature {
            None => "cargo build --release --lib".to_string(),
            Some(f) => format!("cargo build --release --lib --features {f}"),
        };
        return Err(format!(
            "not a library of {} (it must export {needed}; build it with `{build}`)",
            version.name()
        ));
    }
    Ok(Library {
        platform,
        folder,
        bytes,
    })
}

/// Writes the FMU of `spec` in `version` to `out` (atomically) with the `libraries` of
/// [`read_library`], at most one a folder, and `params` as its resource file.
pub fn pack(
    libraries: Vec<Library>,
    spec: &Spec,
    params: &Params,
    out: &Path,
    version: FmiVersion,
) -> Result<(), FileError> {
    for (i, lib) in libraries.iter().enumerate() {
        if libraries[..i].iter().any(|l| l.folder == lib.folder) {
            return Err(FileError::new(
                out,
                format!("two libraries for binaries/{}", lib.folder),
            ));
        }
    }
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    let binaries = libraries.into_iter().map(|lib| {
        (
            format!(
                "binaries/{}/{}.{}",
                lib.folder,
                spec.info.model_identifier,
                lib.platform.suffix()
            ),
            lib.bytes,
        )
    });
    let entries = [(
        "modelDescription.xml".to_string(),
        version.model_description(spec).into_bytes(),
    )]
    .into_iter()
    .chain(binaries)
    .chain([
        (
            "documentation/index.html".into(),
            documentation(spec, version).into_bytes(),
        ),
        (
            format!("resources/{RESOURCE_PARAMS}"),
            params_file::to_toml(params).into_bytes(),
        ),
    ]);
    let zip_err = |e: String| FileError::new(out, format!("cannot build the archive: {e}"));
    for (name, bytes) in entries {
        zip.start_file(name.as_str(), options)
            .map_err(|e| zip_err(e.to_string()))?;
        zip.write_all(&bytes).map_err(|e| zip_err(e.to_string()))?;
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
    use crate::fmu::binary::Arch;
    use crate::fmu::binary::tests::header;

    /// Both FMUs at the default parameters.
    fn specs() -> [Spec; 2] {
        let p = Params::default();
        [platform(&p), inverse(&p)]
    }

    #[test]
    fn the_variable_tables_follow_the_fmi_rules() {
        for spec in specs() {
            check_variable_table(&spec.variables).unwrap();
        }
    }

    /// An importer reads an infinite start value as an error (OMSimulator: "getReal returned
    /// +/-inf"): a limit is switched off by 0, not by +∞ (issue: Model Exchange).
    #[test]
    fn no_start_value_is_infinite() {
        for spec in specs() {
            for v in &spec.variables {
                assert!(
                    v.start.is_none_or(f64::is_finite),
                    "{} starts at {:?}",
                    v.name,
                    v.start
                );
            }
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
        let g0 = [guid(&platform(&p)), guid(&inverse(&p))];
        p.set("Kb_1", 0.31).unwrap();
        for (spec, g0) in [platform(&p), inverse(&p)].iter().zip(g0) {
            assert_ne!(g0, guid(spec));
            assert!(model_description(spec).contains(&guid(spec)));
        }
    }

    #[test]
    fn a_library_without_the_versions_functions_is_refused() {
        let dir = std::env::temp_dir().join(format!("hasel_pack_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let lib = dir.join("lib.so");
        let elf = |symbols: &str| [header(Platform::Linux), symbols.as_bytes().to_vec()].concat();
        std::fs::write(&lib, elf("fmi2Instantiate")).unwrap();
        assert!(read_library(&lib, FmiVersion::V2, None).is_ok());
        let e = read_library(&lib, FmiVersion::V3, Some("reduced-fmu"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("not a library of FMI 3.0")
                && e.contains("fmi3InstantiateCoSimulation")
                && e.contains("--features reduced-fmu`"),
            "{e}"
        );
        std::fs::write(&lib, elf("fmi3InstantiateCoSimulation")).unwrap();
        let e = read_library(&lib, FmiVersion::V2, Some("inverse-fmu")).unwrap_err();
        assert!(e.to_string().contains("--features inverse-fmu`"), "{e}");
        assert!(read_library(&lib, FmiVersion::V3, None).is_ok());
        // the platform's library: both versions' functions, one build for both FMUs
        std::fs::write(&lib, elf("fmi2Instantiate fmi3InstantiateCoSimulation")).unwrap();
        assert!(read_library(&lib, FmiVersion::V2, None).is_ok());
        assert!(read_library(&lib, FmiVersion::V3, None).is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn each_platform_goes_in_the_folder_its_version_names_and_only_once() {
        let dir = std::env::temp_dir().join(format!("hasel_pack_all_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = Params::default();
        let spec = platform(&p);
        for (version, platforms, names) in [
            (
                FmiVersion::V2,
                vec![
                    Platform::Linux,
                    Platform::Windows,
                    Platform::DarwinUniversal,
                ],
                vec![
                    "binaries/linux64/HaselPlatform.so",
                    "binaries/win64/HaselPlatform.dll",
                    "binaries/darwin64/HaselPlatform.dylib",
                ],
            ),
            (
                FmiVersion::V3,
                vec![
                    Platform::Linux,
                    Platform::Windows,
                    Platform::Darwin(Arch::X86_64),
                    Platform::Darwin(Arch::Arm64),
                ],
                vec![
                    "binaries/x86_64-linux/HaselPlatform.so",
                    "binaries/x86_64-windows/HaselPlatform.dll",
                    "binaries/x86_64-darwin/HaselPlatform.dylib",
                    "binaries/aarch64-darwin/HaselPlatform.dylib",
                ],
            ),
        ] {
            let symbol = version.marker_symbol();
            let read = |platforms: &[Platform]| -> Vec<Library> {
                platforms
                    .iter()
                    .enumerate()
                    .map(|(i, &pl)| {
                        let lib = dir.join(format!("lib{i}"));
                        std::fs::write(&lib, [header(pl), symbol.as_bytes().to_vec()].concat())
                            .unwrap();
                        read_library(&lib, version, None).unwrap()
                    })
                    .collect()
            };
            let out = dir.join("x.fmu");
            pack(read(&platforms), &spec, &p, &out, version).unwrap();
            let zip = zip::ZipArchive::new(std::fs::File::open(&out).unwrap()).unwrap();
            let mut binaries: Vec<String> = zip
                .file_names()
                .map(|n| n.unwrap().to_string())
                .filter(|n| n.starts_with("binaries/"))
                .collect();
            binaries.sort();
            let mut names = names;
            names.sort();
            assert_eq!(binaries, names);
            let e = pack(
                read(&[Platform::Windows, Platform::Windows]),
                &spec,
                &p,
                &out,
                version,
            )
            .unwrap_err();
            assert!(e.to_string().contains("two libraries for binaries/"), "{e}");
        }
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
        for v in variables(Reduction::Full, &p, DEFAULT_RTOL) {
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
            let inv = version.model_description(&inverse(&p));
            assert!(!inv.contains("<ModelExchange") && inv.contains("<CoSimulation"));
            assert_eq!((count(&inv, "true"), count(&inv, "false")), (0, 1));
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
