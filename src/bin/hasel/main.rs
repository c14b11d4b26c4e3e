//! The command line `hasel`: simulate, pack the FMUs, identify, diagnose, linearize, benchmark.

/// `println!` that ends quietly when standard output is closed (`hasel simulate | head`)
/// instead of panicking.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// `print!` likewise.
macro_rules! say_raw {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stdout(), $($arg)*);
    }};
}

mod bench;
mod common;
mod diagnose;
mod error;
mod fmu;
mod identify;
mod inverse;
mod linearize;
mod simulate;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "hasel",
    version,
    about = "HASEL-actuated 3PS micro parallel platform: simulation, FMU export, benchmarks"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate the platform and write h_i(t) and the tip (CSV) and a figure (PNG)
    Simulate(simulate::Args),
    /// Print the parameters (defaults, or a file's values over them) as a parameter file
    Params(simulate::ParamsArgs),
    /// Pack the FMUs (FMI 2.0 and 3.0, Co-Simulation and Model Exchange) with a parameter set
    Fmu(fmu::Args),
    /// Print the FMU's modelDescription.xml
    Describe(fmu::DescribeArgs),
    /// Estimate parameters from measured experiments (Levenberg-Marquardt on the simulation error)
    Identify(identify::Args),
    /// Write a synthetic experiment from the model, with measurement noise (and a hidden effect)
    Synth(identify::SynthArgs),
    /// Find where the model and measured data disagree, name the missing effect, add it and
    /// re-identify
    Diagnose(diagnose::Args),
    /// Measure the solver: wall time, work counters and error against the reference data
    Bench(bench::Args),
    /// Linearize at an equilibrium (or a simulated state): A, B, C, D, the port-Hamiltonian
    /// structure, Bode and step figures, a reduced model
    Linearize(linearize::Args),
    /// The heights for a tip path and the constant voltages that hold each at equilibrium
    /// (feedforward)
    Inverse(inverse::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Simulate(a) => simulate::run(a),
        Command::Params(a) => simulate::params(a),
        Command::Bench(a) => bench::run(a),
        Command::Fmu(a) => fmu::run(a),
        Command::Identify(a) => identify::run(a),
        Command::Synth(a) => identify::synth(a),
        Command::Diagnose(a) => diagnose::run(a),
        Command::Describe(a) => fmu::describe(a),
        Command::Linearize(a) => linearize::run(a),
        Command::Inverse(a) => inverse::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("hasel: error: {e}");
            ExitCode::FAILURE
        }
    }
}
