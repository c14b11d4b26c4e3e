//! What the call-sequence fuzzers of both FMI versions share: the arguments a sequence
//! chooses (reals, value references, array lengths, which instance) and their meaning.

use arbitrary::Arbitrary;
#[cfg(feature = "inverse")]
use hasel_fmu::fmu::inverse::variables::rows;
#[cfg(not(any(feature = "inverse", feature = "reduced")))]
use hasel_fmu::fmu::variables::rows;

/// HaselPlatformReduced's variable table (target reduced_calls, reduced_fmi3_calls).
#[cfg(feature = "reduced")]
fn rows() -> &'static [hasel_fmu::fmu::variables::Row] {
    hasel_fmu::fmu::variables::rows_of(hasel_fmu::model::Reduction::Slow)
}
use sha2::{Digest, Sha256};

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
    pub fn get(self) -> u32 {
        match self {
            Vr::Known(k) => k as u32 % rows().len() as u32,
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
