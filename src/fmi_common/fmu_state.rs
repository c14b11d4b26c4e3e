//! What FMU states of both versions share (FMI 2.0 section 2.1.8, FMI 3.0 section 2.3.6): the
//! snapshot of an instance (the core and the shell's state-machine data) and the frame of its
//! serialized bytes: a magic of eight bytes, the version's record, and the first 8 bytes of the
//! SHA-256 of everything before, so that a buffer of another FMU, a truncated or a corrupted one
//! is rejected with a message before its record is read. Each version writes its own magic and
//! record (`fmi2::fmu_state`, `fmi3::fmu_state`).

use sha2::{Digest, Sha256};

use super::model_api::{FmuCore, InstanceKind};
use super::state_machine::Experiment;

/// A version's FMU states: the states of its state machine and the record of its serialized
/// bytes between the magic and the checksum.
pub trait Format {
    /// The states of the version's state machine.
    type Phase: Copy;

    /// An FMU state's serialized bytes.
    fn to_bytes<M: FmuCore>(state: &Snapshot<M, Self::Phase>) -> Vec<u8>;

    /// An FMU state from bytes of [`Format::to_bytes`], for the instance with `token`, `kind`
    /// and `core`.
    fn from_bytes<M: FmuCore>(
        bytes: &[u8],
        token: &str,
        kind: InstanceKind,
        core: &M,
    ) -> Result<Snapshot<M, Self::Phase>, String>;
}

/// The length of the checksum at the end of the bytes.
const CHECKSUM_LEN: usize = 8;

/// Everything an FMU state restores: the core and the shell's state-machine data (`P`: the
/// version's state).
#[derive(Clone)]
pub struct Snapshot<M, P> {
    /// GUID (FMI 2.0) or instantiationToken (FMI 3.0) of the instance it was taken from; only
    /// instances with the same one accept it.
    pub token: String,
    /// Only instances of the same interface accept it.
    pub kind: InstanceKind,
    pub phase: P,
    pub experiment: Option<Experiment>,
    pub core: M,
}

fn checksum(bytes: &[u8]) -> [u8; CHECKSUM_LEN] {
    let mut out = [0; CHECKSUM_LEN];
    out.copy_from_slice(&Sha256::digest(bytes)[..CHECKSUM_LEN]);
    out
}

/// The serialized bytes of a `record`: `magic`, the record, the checksum.
pub fn seal(magic: &[u8; 8], record: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(magic.len() + record.len() + CHECKSUM_LEN);
    out.extend_from_slice(magic);
    out.extend_from_slice(record);
    let sum = checksum(&out);
    out.extend_from_slice(&sum);
    out
}

/// The record of bytes of [`seal`] with `magic`, after checking the magic, the length and the
/// checksum.
pub fn unseal<'a>(magic: &[u8; 8], bytes: &'a [u8]) -> Result<&'a [u8], String> {
    if !bytes.starts_with(magic) {
        return Err("the bytes are not a serialized FMU state of this FMU (bad magic)".into());
    }
    if bytes.len() < magic.len() + CHECKSUM_LEN {
        return Err(format!(
            "the serialized FMU state is truncated ({} bytes)",
            bytes.len()
        ));
    }
    let (body, sum) = bytes.split_at(bytes.len() - CHECKSUM_LEN);
    if checksum(body) != sum {
        return Err(
            "the serialized FMU state is corrupted or truncated (checksum mismatch)".into(),
        );
    }
    Ok(&body[magic.len()..])
}

/// Checks that a serialized state of `format` version `version`, taken from an instance with
/// `state_token` of kind `state_kind`, fits this one (`token`, `kind`); `token_name` is the
/// token's name in the version ("GUID", "instantiationToken").
pub fn check_origin(
    (version, format): (u32, u32),
    (token_name, state_token, token): (&str, &str, &str),
    (state_kind, kind): (InstanceKind, InstanceKind),
) -> Result<(), String> {
    if version != format {
        return Err(format!(
            "the serialized FMU state has format version {version}, expected {format}"
        ));
    }
    if state_token != token {
        return Err(format!(
            "the serialized FMU state belongs to {token_name} {state_token}, this instance has {token}"
        ));
    }
    if state_kind != kind {
        return Err(format!(
            "the serialized FMU state is of a {state_kind:?} instance, this one is {kind:?}"
        ));
    }
    Ok(())
}
