//! Fuzzes the experiment files of `identify` and `diagnose` (CSV): the check of
//! tests/fuzz/checks.rs, which tests/fuzz_replay.rs replays.
#![no_main]

// each target uses one check of the module
#[allow(dead_code)]
#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::csv_experiment(data));
