//! The FMI 2.0 call sequences of fmi2_sequence.rs against HaselInverse's build (feature inverse: the library's
//! inverse-fmu build, which exports the inverse FMU's fmi2* functions instead).
#![no_main]
#![feature(c_variadic)]

mod common;
mod fmi2_sequence;
