//! The FMI 2.0 call sequences of fmi2_sequence.rs against HaselPlatformReduced's build (feature
//! reduced: the library's `reduced-fmu` build, which exports its fmi2* functions instead).
#![no_main]
#![feature(c_variadic)]

mod common;
mod fmi2_sequence;
