//! FMU states (FMI 3.0 standard, section 2.3.6): a snapshot of an instance, and its byte
//! format for `fmi3SerializeFMUState` / `fmi3DeserializeFMUState`.
//!
//! Format: magic `FMI3HSST`, then a postcard record (format version, instantiation token,
//! interface, state-machine state, experiment, the core's bytes), then the first 8 bytes of
//! the SHA-256 of everything before. A buffer of another FMU, a truncated or a corrupted one
//! is rejected with a message.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::state_machine::{Experiment, Phase};
use super::types::{InstanceKind, kind_name};
use crate::fmi_common::model_api::FmuCore;

const MAGIC: &[u8; 8] = b"FMI3HSST";
const FORMAT_VERSION: u32 = 1;
const CHECKSUM_LEN: usize = 8;

/// Everything an FMU state restores: the core and the shell's state-machine data.
#[derive(Clone)]
pub struct Snapshot<M> {
    /// Token of the instance it was taken from; only instances with that token accept it.
    pub token: String,
    pub interface: InstanceKind,
    pub phase: Phase,
    pub experiment: Option<Experiment>,
    pub core: M,
}

/// The serialized record between magic and checksum.
#[derive(Serialize, Deserialize)]
struct Record {
    version: u32,
    token: String,
    model_exchange: bool,
    phase: Phase,
    experiment: Option<Experiment>,
    core: Vec<u8>,
}

fn checksum(bytes: &[u8]) -> [u8; CHECKSUM_LEN] {
    let mut out = [0; CHECKSUM_LEN];
    out.copy_from_slice(&Sha256::digest(bytes)[..CHECKSUM_LEN]);
    out
}

impl<M: FmuCore> Snapshot<M> {
    /// The serialized bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let record = Record {
            version: FORMAT_VERSION,
            token: self.token.clone(),
            model_exchange: self.interface == InstanceKind::ModelExchange,
            phase: self.phase,
            experiment: self.experiment,
            core: self.core.serialize_state(),
        };
        let mut out = MAGIC.to_vec();
        postcard::to_io(&record, &mut out).expect("serializing to memory cannot fail");
        let sum = checksum(&out);
        out.extend_from_slice(&sum);
        out
    }

    /// Parses bytes of [`Snapshot::to_bytes`] for the instance with `token`, `interface` and
    /// `core`.
    pub fn from_bytes(
        bytes: &[u8],
        token: &str,
        interface: InstanceKind,
        core: &M,
    ) -> Result<Self, String> {
        if !bytes.starts_with(MAGIC) {
            return Err("the bytes are not a serialized FMU state of this FMU (bad magic)".into());
        }
        if bytes.len() < MAGIC.len() + CHECKSUM_LEN {
            return Err(format!(
                "the serialized FMU state is truncated ({} bytes)",
                bytes.len()
            ));
        }
        let (body, sum) = bytes.split_at(bytes.len() - CHECKSUM_LEN);
        if checksum(body) != sum {
            return Err("the serialized FMU state is corrupted or truncated (checksum)".into());
        }
        let record: Record = postcard::from_bytes(&body[MAGIC.len()..])
            .map_err(|e| format!("the serialized FMU state is malformed: {e}"))?;
        if record.version != FORMAT_VERSION {
            return Err(format!(
                "the serialized FMU state has format version {}, expected {FORMAT_VERSION}",
                record.version
            ));
        }
        if record.token != token {
            return Err(format!(
                "the serialized FMU state belongs to instantiationToken {}, this instance has {token}",
                record.token
            ));
        }
        let state_interface = if record.model_exchange {
            InstanceKind::ModelExchange
        } else {
            InstanceKind::CoSimulation
        };
        if state_interface != interface || !record.phase.belongs_to(interface) {
            return Err(format!(
                "the serialized FMU state is of a {} instance, this one is {}",
                kind_name(state_interface),
                kind_name(interface)
            ));
        }
        Ok(Snapshot {
            token: record.token,
            interface,
            phase: record.phase,
            experiment: record.experiment,
            core: core.deserialize_state(&record.core)?,
        })
    }
}
