//! The FMI 3.0 call sequences of fmi3_sequence.rs against HaselPlatform's FMI 3.0 functions.
#![no_main]

// the seeds' writer is the replay's (tests/fuzz_replay.rs)
#[allow(dead_code)]
mod common;
// each target runs one FMU of the module
#[allow(dead_code)]
mod fmi3_sequence;

use fmi3_sequence::{Call, Fmu, run};

// made once: its instantiation token hashes the model description
static FMU: std::sync::OnceLock<Fmu> = std::sync::OnceLock::new();

libfuzzer_sys::fuzz_target!(|calls: Vec<Call>| {
    run(FMU.get_or_init(Fmu::platform), &calls);
});
