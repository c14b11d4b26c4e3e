//! What the call-sequence fuzzers of both FMI versions share: the arguments a sequence
//! chooses (reals, value references, array lengths, which instance) and their meaning. With
//! fmi2_sequence.rs and fmi3_sequence.rs also a module of tests/fuzz_replay.rs, which replays
//! the committed corpora through the same code in the ordinary build.

use std::ffi::CString;

use arbitrary::Arbitrary;
use hasel_fmu::fmi_common::model_api::FmuCore;
use sha2::{Digest, Sha256};

/// The FMU a sequence runs against: its C functions `F` (a table of one FMI version's) and what
/// an importer reads from its description.
pub struct Fmu<F> {
    pub functions: F,
    /// The GUID (FMI 2.0) or instantiation token (FMI 3.0).
    pub token: CString,
    /// The number of continuous states.
    pub states: usize,
    /// The number of variables (value references 0..variables).
    pub variables: u32,
}

impl<F> Fmu<F> {
    pub fn new<Core: FmuCore>(functions: F, token: String, variables: usize) -> Fmu<F> {
        Fmu {
            functions,
            token: CString::new(token).unwrap(),
            states: Core::model_structure().derivatives.len(),
            variables: variables as u32,
        }
    }
}

/// A real number: one of the values that matter to this model, or any bit pattern.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Real {
    Pick(u8),
    Raw(f64),
}

impl Real {
    pub fn get(self) -> f64 {
        const PICKS: [f64; 14] = [
            0.0,
            1e-3,
            -1e-3,
            1.0,
            60.0,
            -60.0,
            1e-9,
            0.5,
            10.0,
            1e9,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            -0.0,
        ];
        match self {
            Real::Pick(k) => PICKS[k as usize % PICKS.len()],
            Real::Raw(x) => x,
        }
    }
}

/// A value reference: mostly one of the model's, sometimes any number.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Vr {
    Known(u8),
    Any(u32),
}

impl Vr {
    /// The value reference, for an FMU with `variables` variables (references 0..variables).
    pub fn get(self, variables: u32) -> u32 {
        match self {
            Vr::Known(k) => k as u32 % variables,
            Vr::Any(v) => v,
        }
    }
}

/// An array length: the right one for the call, or another.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Len {
    Right,
    Other(u8),
}

/// The instance (of two) a call goes to; `Null` passes a NULL component.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Who {
    First,
    Second,
    Null,
}

/// Damages serialized FMU-state bytes: flips the bits given, cuts them short, and optionally
/// recomputes the trailing checksum (the first 8 bytes of the SHA-256 of what precedes it, the
/// format of both shells) so the damage reaches the decoder behind the check.
pub fn damage(bytes: &mut Vec<u8>, flips: &[(u16, u8)], truncate: Option<u16>, fix_checksum: bool) {
    for &(at, x) in flips {
        if !bytes.is_empty() {
            let k = at as usize % bytes.len();
            bytes[k] ^= x;
        }
    }
    if let Some(m) = truncate {
        bytes.truncate(m as usize);
    }
    if fix_checksum && bytes.len() > 8 {
        let body = bytes.len() - 8;
        let sum = Sha256::digest(&bytes[..body]);
        bytes[body..].copy_from_slice(&sum[..8]);
    }
}
