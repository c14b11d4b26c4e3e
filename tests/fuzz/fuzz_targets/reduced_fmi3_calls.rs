//! The FMI 3.0 call sequences of fmi3_sequence.rs against HaselPlatformReduced's FMI 3.0 functions.
#![no_main]

mod common;
// each target runs one FMU of the module
#[allow(dead_code)]
mod fmi3_sequence;

use fmi3_sequence::{Call, Fmu, run};

libfuzzer_sys::fuzz_target!(|calls: Vec<Call>| run(&Fmu::reduced(), &calls));
