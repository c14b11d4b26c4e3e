//! Fuzzes start files (TOML heights, `--start FILE`): the check of tests/fuzz/checks.rs, which
//! tests/fuzz_replay.rs replays.
#![no_main]

// each target uses one check of the module
#[allow(dead_code)]
#[path = "../checks.rs"]
mod checks;

libfuzzer_sys::fuzz_target!(|data: &[u8]| checks::heights_toml(data));
