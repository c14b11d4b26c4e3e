//! Fuzzes serialized FMI 2.0 FMU states of both FMUs, fed to the deserializer directly: the check
//! of tests/fuzz/checks.rs, which tests/fuzz_replay.rs replays.
#![no_main]

// each target uses one check of the module
#[allow(dead_code)]
#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::fmi2_state(data));
