//! The FMI 3.0 call sequences of fmi3_sequence.rs against HaselPlatformReduced's FMI 3.0 build
//! (features reduced and fmi3: the library's `reduced-fmu,fmi3` build).
#![no_main]

mod common;
mod fmi3_sequence;
