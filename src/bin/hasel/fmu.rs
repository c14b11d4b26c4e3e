//! `hasel fmu` and `hasel describe`.

use std::path::PathBuf;

use hasel_fmu::fmu::pack;
use hasel_fmu::io::file::write_text_atomic;

use crate::common::load_params;
use crate::error::Error;

#[derive(clap::Args)]
pub struct Args {
    /// Parameter file whose values become the FMU's start values
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
    /// Where to write the FMU
    #[arg(long, default_value = "fmu/HaselPlatform.fmu")]
    out: PathBuf,
    /// The FMU's shared library (default: libhasel_fmu.so beside this executable)
    #[arg(long, value_name = "FILE.so")]
    lib: Option<PathBuf>,
}

#[derive(clap::Args)]
pub struct DescribeArgs {
    /// Parameter file whose values become the start values
    #[arg(long, value_name = "FILE.toml")]
    params: Option<PathBuf>,
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
    pack::pack(&lib, &params, &a.out)?;
    say!(
        "wrote {} (GUID {}, library {})",
        a.out.display(),
        pack::guid(&params),
        lib.display()
    );
    Ok(())
}

pub fn describe(a: DescribeArgs) -> Result<(), Error> {
    let xml = pack::model_description(&load_params(&a.params)?);
    match a.out {
        Some(path) => Ok(write_text_atomic(&path, &xml)?),
        None => {
            say_raw!("{xml}");
            Ok(())
        }
    }
}
