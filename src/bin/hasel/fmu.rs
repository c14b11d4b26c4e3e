//! `hasel fmu` and `hasel describe`.

use std::path::PathBuf;

use hasel_fmu::fmu::pack::{self, Spec};
use hasel_fmu::fmu::{MODEL_IDENTIFIER, inverse};
use hasel_fmu::io::file::write_text_atomic;
use hasel_fmu::model::Params;

use crate::common::load_params;
use crate::error::Error;

/// Which FMU: the platform, or its inverse for feedforward.
#[derive(Clone, Copy, clap::ValueEnum)]
enum Model {
    /// HaselPlatform: voltages in, heights and tip out
    Platform,
    /// HaselInverse: tip x, y and mean height in, heights and holding voltages out (its library
    /// built with `--features inverse-fmu`)
    Inverse,
}

impl Model {
    fn spec(self, params: &Params) -> Spec {
        match self {
            Model::Platform => pack::platform(params),
            Model::Inverse => inverse::spec(params),
        }
    }

    fn identifier(self) -> &'static str {
        match self {
            Model::Platform => MODEL_IDENTIFIER,
            Model::Inverse => inverse::MODEL_IDENTIFIER,
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
    /// Where to write the FMU (default: fmu/HaselPlatform.fmu, fmu/HaselInverse.fmu)
    #[arg(long)]
    out: Option<PathBuf>,
    /// The FMU's shared library, built for that model (default: libhasel_fmu.so beside this
    /// executable)
    #[arg(long, value_name = "FILE.so")]
    lib: Option<PathBuf>,
}

#[derive(clap::Args)]
pub struct DescribeArgs {
    /// Parameter file whose values become the start values
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
    /// The FMU to describe
    #[arg(long, value_enum, default_value = "platform")]
    model: Model,
    /// Write here instead of standard output
    #[arg(long, value_name = "FILE.xml")]
    out: Option<PathBuf>,
}

pub fn run(a: Args) -> Result<(), Error> {
    let params = load_params(&a.params)?;
    let lib = match a.lib {
        Some(p) => p,
        None => std::env::current_exe()
            .map_err(Error::CurrentExe)?
            .with_file_name("libhasel_fmu.so"),
    };
    let out = a
        .out
        .unwrap_or_else(|| PathBuf::from(format!("fmu/{}.fmu", a.model.identifier())));
    let spec = a.model.spec(&params);
    pack::pack(&lib, &spec, &params, &out)?;
    say!(
        "wrote {} (GUID {}, library {})",
        out.display(),
        pack::guid(&spec),
        lib.display()
    );
    Ok(())
}

pub fn describe(a: DescribeArgs) -> Result<(), Error> {
    let xml = pack::model_description(&a.model.spec(&load_params(&a.params)?));
    match a.out {
        Some(path) => Ok(write_text_atomic(&path, &xml)?),
        None => {
            say_raw!("{xml}");
            Ok(())
        }
    }
}
