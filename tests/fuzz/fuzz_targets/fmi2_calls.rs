//! The FMI 2.0 call sequences of fmi2_sequence.rs against HaselPlatform's FMI 2.0 build.
#![no_main]
#![feature(c_variadic)]

mod common;
mod fmi2_sequence;
