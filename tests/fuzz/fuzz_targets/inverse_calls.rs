//! The FMI 2.0 call sequences of fmi2_sequence.rs against HaselInverse's functions.
#![no_main]
#![feature(c_variadic)]

// the seeds' writer is the replay's (tests/fuzz_replay.rs)
#[allow(dead_code)]
mod common;
mod fmi2_logger;
// each target runs one FMU of the module
#[allow(dead_code)]
mod fmi2_sequence;

use fmi2_sequence::{Call, Fmu, run};

// made once: its GUID hashes the model description
static FMU: std::sync::OnceLock<Fmu> = std::sync::OnceLock::new();

libfuzzer_sys::fuzz_target!(|calls: Vec<Call>| {
    run(FMU.get_or_init(Fmu::inverse), fmi2_logger::LOGGER, &calls);
});
