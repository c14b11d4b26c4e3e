//! `hasel fmu` and `hasel describe`.

use std::path::{Path, PathBuf};

use hasel_fmu::fmu::pack::{self, FmiVersion};
use hasel_fmu::io::file::write_text_atomic;

use crate::common::load_params;
use crate::error::Error;

/// `--fmi 2` or `--fmi 3`.
#[derive(Clone, Copy, clap::ValueEnum)]
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
    /// Pack only the FMU of this FMI version (default: both)
    #[arg(long, value_name = "2|3")]
    fmi: Option<Fmi>,
    /// Where to write the FMU (FMI 3.0: with `-fmi3` added to the name when both are packed)
    #[arg(long, default_value = "fmu/HaselPlatform.fmu")]
    out: PathBuf,
    /// The FMI 2.0 shared library (default: libhasel_fmu.so beside this executable)
    #[arg(long, value_name = "FILE.so")]
    lib: Option<PathBuf>,
    /// The FMI 3.0 shared library, built with `--features fmi3` (default:
    /// libhasel_fmu_fmi3.so beside this executable)
    #[arg(long, value_name = "FILE.so")]
    lib_fmi3: Option<PathBuf>,
}

#[derive(clap::Args)]
pub struct DescribeArgs {
    /// Parameter file whose values become the start values
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
    /// The FMI version of the description
    #[arg(long, value_name = "2|3", default_value = "2")]
    fmi: Fmi,
    /// Write here instead of standard output
    #[arg(long, value_name = "FILE.xml")]
    out: Option<PathBuf>,
}

/// `name.so` beside this executable.
fn beside_exe(name: &str) -> Result<PathBuf, Error> {
    Ok(std::env::current_exe()
        .map_err(Error::CurrentExe)?
        .with_file_name(name))
}

/// `out` with `-fmi3` added to the file name (`x.fmu` → `x-fmi3.fmu`).
fn fmi3_name(out: &Path) -> PathBuf {
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    let ext = out
        .extension()
        .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
    out.with_file_name(format!("{stem}-fmi3{ext}"))
}

pub fn run(a: Args) -> Result<(), Error> {
    let params = load_params(&a.params)?;
    let v2 = match a.lib {
        Some(p) => p,
        None => beside_exe("libhasel_fmu.so")?,
    };
    let v3 = match a.lib_fmi3 {
        Some(p) => p,
        None => beside_exe("libhasel_fmu_fmi3.so")?,
    };
    let jobs = match a.fmi {
        Some(Fmi::V2) => vec![(FmiVersion::V2, v2, a.out)],
        Some(Fmi::V3) => vec![(FmiVersion::V3, v3, a.out)],
        None => {
            let out3 = fmi3_name(&a.out);
            vec![(FmiVersion::V2, v2, a.out), (FmiVersion::V3, v3, out3)]
        }
    };
    // every library is checked before anything is written
    let mut libraries = Vec::with_capacity(jobs.len());
    for (version, lib, _) in &jobs {
        libraries.push(pack::read_library(lib, *version)?);
    }
    for ((version, lib, out), so) in jobs.into_iter().zip(libraries) {
        pack::pack(so, &params, &out, version)?;
        let token = version.token(&params);
        say!(
            "wrote {} ({}, token {token}, library {})",
            out.display(),
            version.name(),
            lib.display()
        );
    }
    Ok(())
}

pub fn describe(a: DescribeArgs) -> Result<(), Error> {
    let xml = FmiVersion::from(a.fmi).model_description(&load_params(&a.params)?);
    match a.out {
        Some(path) => Ok(write_text_atomic(&path, &xml)?),
        None => {
            say_raw!("{xml}");
            Ok(())
        }
    }
}
