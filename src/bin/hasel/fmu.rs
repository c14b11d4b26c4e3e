//! `hasel fmu` and `hasel describe`.

use std::path::{Path, PathBuf};

use hasel_fmu::fmu::pack::{self, FmiVersion, Spec};
use hasel_fmu::fmu::{MODEL_IDENTIFIER, REDUCED_MODEL_IDENTIFIER, inverse};
use hasel_fmu::io::file::write_text_atomic;
use hasel_fmu::model::Params;

use crate::common::load_params;
use crate::error::Error;

/// Which FMU: the platform, or its inverse for feedforward.
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
enum Model {
    /// HaselPlatform: voltages in, heights and tip out
    Platform,
    /// HaselPlatformReduced: the same with the slow model (one angle per actuator), its
    /// library built with `--features reduced-fmu`
    Reduced,
    /// HaselInverse: tip x, y and mean height in, heights and holding voltages out (FMI 2.0, its
    /// library built with `--features inverse-fmu`)
    Inverse,
}

impl Model {
    fn spec(self, params: &Params) -> Spec {
        match self {
            Model::Platform => pack::platform(params),
            Model::Reduced => pack::reduced(params),
            Model::Inverse => pack::inverse(params),
        }
    }

    /// The cargo feature its library is built with.
    fn feature(self) -> Option<&'static str> {
        match self {
            Model::Platform => None,
            Model::Reduced => Some("reduced-fmu"),
            Model::Inverse => Some("inverse-fmu"),
        }
    }

    fn identifier(self) -> &'static str {
        match self {
            Model::Platform => MODEL_IDENTIFIER,
            Model::Reduced => REDUCED_MODEL_IDENTIFIER,
            Model::Inverse => inverse::MODEL_IDENTIFIER,
        }
    }
}

/// `--fmi 2` or `--fmi 3`.
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub enum Fmi {
    #[value(name = "2")]
    V2,
    #[value(name = "3")]
    V3,
}

impl From<Fmi> for FmiVersion {
    fn from(f: Fmi) -> Self {
        match f {
            Fmi::V2 => FmiVersion::V2,
            Fmi::V3 => FmiVersion::V3,
        }
    }
}

#[derive(clap::Args)]
pub struct Args {
    /// Parameter file whose values become the FMU's start values
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
    /// The FMU to pack
    #[arg(long, value_enum, default_value = "platform")]
    model: Model,
    /// Pack only the FMU of this FMI version (default: both for the platform; the inverse is
    /// FMI 2.0 only)
    #[arg(long, value_name = "2|3")]
    fmi: Option<Fmi>,
    /// Where to write the FMU (default: fmu/HaselPlatform.fmu, fmu/HaselPlatformReduced.fmu,
    /// fmu/HaselInverse.fmu; FMI 3.0:
    /// with `-fmi3` added to the name when both are packed)
    #[arg(long)]
    out: Option<PathBuf>,
    /// The shared library, built for that model; once for each platform (Linux .so, Windows
    /// .dll, macOS universal .dylib of both architectures), each packed into the folder FMI 2.0
    /// names for it, and into FMI 3.0's unless `--lib-fmi3` is given (one build exports both
    /// versions' functions) (default: libhasel_fmu.so beside this executable)
    #[arg(long, value_name = "FILE")]
    lib: Vec<PathBuf>,
    /// The libraries of the FMI 3.0 FMU where they differ from `--lib`'s, e.g. macOS's, which
    /// FMI 3.0 takes one architecture a folder (x86_64 and arm64 each on its own)
    #[arg(long, value_name = "FILE")]
    lib_fmi3: Vec<PathBuf>,
    /// Take the libraries of this FMU (of the same model, any version and platforms, e.g. one
    /// the wheel installed) instead of `--lib`/`--lib-fmi3`: the same FMU with other start values
    #[arg(long, value_name = "FILE.fmu", conflicts_with_all = ["lib", "lib_fmi3"])]
    from: Option<PathBuf>,
}

#[derive(clap::Args)]
pub struct DescribeArgs {
    /// Parameter file whose values become the start values
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
    /// The FMU to describe
    #[arg(long, value_enum, default_value = "platform")]
    model: Model,
    /// The FMI version of the description
    #[arg(long, value_name = "2|3", default_value = "2")]
    fmi: Fmi,
    /// Write here instead of standard output
    #[arg(long, value_name = "FILE.xml")]
    out: Option<PathBuf>,
}

/// `libs`, or if none is given `name` beside this executable.
fn or_beside_exe(libs: Vec<PathBuf>, name: &str) -> Result<Vec<PathBuf>, Error> {
    if !libs.is_empty() {
        return Ok(libs);
    }
    Ok(vec![
        std::env::current_exe()
            .map_err(Error::CurrentExe)?
            .with_file_name(name),
    ])
}

/// `out` with `-fmi3` added to the file name (`x.fmu` → `x-fmi3.fmu`).
fn fmi3_name(out: &Path) -> PathBuf {
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    let ext = out
        .extension()
        .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
    out.with_file_name(format!("{stem}-fmi3{ext}"))
}

/// The inverse FMU exists for FMI 2.0 only.
fn check_version(model: Model, fmi: Option<Fmi>) -> Result<(), Error> {
    if model == Model::Inverse && fmi == Some(Fmi::V3) {
        return Err(Error::flag(
            "fmi",
            3,
            "the inverse FMU is packed for FMI 2.0 only",
        ));
    }
    Ok(())
}

pub fn run(a: Args) -> Result<(), Error> {
    check_version(a.model, a.fmi)?;
    let params = load_params(&a.params)?;
    let spec = a.model.spec(&params);
    if let Some(from) = &a.from {
        return repack(&a, from, &spec, &params);
    }
    let out = a
        .out
        .unwrap_or_else(|| PathBuf::from(format!("fmu/{}.fmu", a.model.identifier())));
    let v2 = or_beside_exe(a.lib, "libhasel_fmu.so")?;
    let v3_from_lib = a.lib_fmi3.is_empty();
    let v3 = if v3_from_lib { v2.clone() } else { a.lib_fmi3 };
    let jobs = match (a.fmi, a.model) {
        (Some(Fmi::V2), _) | (None, Model::Inverse) => vec![(FmiVersion::V2, v2, out)],
        (Some(Fmi::V3), _) => vec![(FmiVersion::V3, v3, out)],
        (None, Model::Platform | Model::Reduced) => {
            let out3 = fmi3_name(&out);
            vec![(FmiVersion::V2, v2, out), (FmiVersion::V3, v3, out3)]
        }
    };
    // every library is checked before anything is written
    let mut libraries = Vec::with_capacity(jobs.len());
    for (version, libs, _) in &jobs {
        let read: Result<Vec<_>, _> = libs
            .iter()
            .map(|lib| pack::read_library(lib, *version, a.model.feature()))
            .collect();
        libraries.push(read.map_err(|mut e| {
            if v3_from_lib && *version == FmiVersion::V3 {
                e.message += " (the FMI 3.0 FMU takes --lib's libraries where --lib-fmi3 names none of its own)";
            }
            e
        })?);
    }
    for ((version, libs, out), read) in jobs.into_iter().zip(libraries) {
        let packed: Vec<String> = read
            .iter()
            .zip(&libs)
            .map(|(l, path)| format!("{} ({}) from {}", l.folder, l.platform, path.display()))
            .collect();
        pack::pack(read, &spec, &params, &out, version)?;
        say!(
            "wrote {} ({}, token {}), binaries {}",
            out.display(),
            version.name(),
            version.token(&spec),
            packed.join(", ")
        );
    }
    Ok(())
}

/// `hasel fmu --from`: the libraries of the FMU `from`, packed with `params`.
fn repack(a: &Args, from: &Path, spec: &Spec, params: &Params) -> Result<(), Error> {
    let (version, libraries) = pack::libraries_in(from, a.model.identifier(), a.model.feature())?;
    if let Some(fmi) = a.fmi
        && FmiVersion::from(fmi) != version
    {
        return Err(Error::flag(
            "fmi",
            version_number(fmi),
            format!("{} is an {} FMU", from.display(), version.name()),
        ));
    }
    let out = a.out.clone().unwrap_or_else(|| {
        let out = PathBuf::from(format!("fmu/{}.fmu", a.model.identifier()));
        match version {
            FmiVersion::V2 => out,
            FmiVersion::V3 => fmi3_name(&out),
        }
    });
    let folders: Vec<&str> = libraries.iter().map(|l| l.folder).collect();
    pack::pack(libraries, spec, params, &out, version)?;
    say!(
        "wrote {} ({}, token {}), binaries {} from {}",
        out.display(),
        version.name(),
        version.token(spec),
        folders.join(", "),
        from.display()
    );
    Ok(())
}

fn version_number(fmi: Fmi) -> u8 {
    match fmi {
        Fmi::V2 => 2,
        Fmi::V3 => 3,
    }
}

pub fn describe(a: DescribeArgs) -> Result<(), Error> {
    check_version(a.model, Some(a.fmi))?;
    let spec = a.model.spec(&load_params(&a.params)?);
    let xml = FmiVersion::from(a.fmi).model_description(&spec);
    match a.out {
        Some(path) => Ok(write_text_atomic(&path, &xml)?),
        None => {
            say_raw!("{xml}");
            Ok(())
        }
    }
}
