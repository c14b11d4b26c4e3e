//! The FMI 3.0 call sequences of fmi3_sequence.rs against HaselPlatform's FMI 3.0 build.
#![no_main]

mod common;
mod fmi3_sequence;
