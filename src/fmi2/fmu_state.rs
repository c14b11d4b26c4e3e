//! FMU states (FMI 2.0 standard, section 2.1.8): a snapshot of an instance, and its byte
//! format for `fmi2SerializeFMUstate` / `fmi2DeSerializeFMUstate`.
//!
//! Format (little endian): magic `FMI2RSST`, format version `u32`, GUID (`u32` length +
//! UTF-8), interface `u8` (0 Model Exchange, 1 Co-Simulation, as `fmi2Type`), phase `u8`, experiment (flag `u8`; start `f64`, stop and tolerance each as flag
//! `u8` + `f64`), core bytes (`u64` length + bytes), and the first 8 bytes of the SHA-256 of
//! everything before. A buffer of another model, a truncated or a corrupted one is rejected
//! with a message.

use sha2::{Digest, Sha256};

use super::state_machine::{Experiment, Phase};
use crate::fmi_common::model_api::{FmuCore, InstanceKind};

const MAGIC: &[u8; 8] = b"FMI2RSST";
const FORMAT_VERSION: u32 = 2;
const CHECKSUM_LEN: usize = 8;

/// Everything an FMU state restores: the core and the wrapper's state-machine data.
#[derive(Clone)]
pub struct Snapshot<M> {
    /// GUID of the instance it was taken from; only instances with the same GUID accept it.
    pub guid: String,
    /// Only instances of the same interface accept it.
    pub kind: InstanceKind,
    pub phase: Phase,
    pub experiment: Option<Experiment>,
    pub core: M,
}

fn checksum(bytes: &[u8]) -> [u8; CHECKSUM_LEN] {
    let mut out = [0; CHECKSUM_LEN];
    out.copy_from_slice(&Sha256::digest(bytes)[..CHECKSUM_LEN]);
    out
}

fn put_opt(out: &mut Vec<u8>, x: Option<f64>) {
    out.push(u8::from(x.is_some()));
    out.extend_from_slice(&x.unwrap_or(0.0).to_le_bytes());
}

impl<M: FmuCore> Snapshot<M> {
    /// The serialized bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let core = self.core.serialize_state();
        let mut out = Vec::with_capacity(64 + self.guid.len() + core.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(self.guid.len() as u32).to_le_bytes());
        out.extend_from_slice(self.guid.as_bytes());
        out.push(u8::from(self.kind == InstanceKind::CoSimulation));
        out.push(self.phase as u8);
        out.push(u8::from(self.experiment.is_some()));
        let e = self.experiment.unwrap_or_default();
        out.extend_from_slice(&e.start_time.to_le_bytes());
        put_opt(&mut out, e.stop_time);
        put_opt(&mut out, e.tolerance);
        out.extend_from_slice(&(core.len() as u64).to_le_bytes());
        out.extend_from_slice(&core);
        let sum = checksum(&out);
        out.extend_from_slice(&sum);
        out
    }

    /// Parses bytes of [`Snapshot::to_bytes`] for the instance with `guid`, `kind` and `core`.
    pub fn from_bytes(
        bytes: &[u8],
        guid: &str,
        kind: InstanceKind,
        core: &M,
    ) -> Result<Self, String> {
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            return Err(
                "the bytes are not a serialized FMU state of this FMU type (bad magic)".into(),
            );
        }
        if bytes.len() < MAGIC.len() + CHECKSUM_LEN {
            return Err(format!(
                "the serialized FMU state is truncated ({} bytes)",
                bytes.len()
            ));
        }
        let (body, sum) = bytes.split_at(bytes.len() - CHECKSUM_LEN);
        let mut r = Reader {
            bytes: &body[MAGIC.len()..],
        };
        let version = r.u32()?;
        if version != FORMAT_VERSION {
            return Err(format!(
                "serialized FMU state has format version {version}, expected {FORMAT_VERSION}"
            ));
        }
        let guid_len = r.u32()? as usize;
        let state_guid = std::str::from_utf8(r.take(guid_len)?)
            .map_err(|_| "serialized FMU state has a malformed GUID".to_string())?;
        if state_guid != guid {
            return Err(format!(
                "serialized FMU state belongs to GUID {state_guid}, this instance has GUID {guid}"
            ));
        }
        if checksum(body) != sum {
            return Err(
                "serialized FMU state is corrupted (checksum mismatch) or truncated".into(),
            );
        }
        let state_kind = if r.flag()? {
            InstanceKind::CoSimulation
        } else {
            InstanceKind::ModelExchange
        };
        if state_kind != kind {
            return Err(format!(
                "serialized FMU state is of a {state_kind:?} instance, this one is {kind:?}"
            ));
        }
        let phase = Phase::from_u8(r.u8()?)
            .filter(|p| p.belongs_to(kind))
            .ok_or("serialized FMU state has an unknown phase")?;
        let has_experiment = r.flag()?;
        let experiment = Experiment {
            start_time: r.f64()?,
            stop_time: r.opt_f64()?,
            tolerance: r.opt_f64()?,
        };
        let core_len =
            usize::try_from(r.u64()?).map_err(|_| "serialized core state too long".to_string())?;
        let core = core.deserialize_state(r.take(core_len)?)?;
        if !r.bytes.is_empty() {
            return Err(format!(
                "serialized FMU state has {} unexpected trailing bytes",
                r.bytes.len()
            ));
        }
        Ok(Snapshot {
            guid: guid.to_string(),
            kind,
            phase,
            experiment: has_experiment.then_some(experiment),
            core,
        })
    }
}

/// Bounds-checked reading of the serialized fields.
struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        if n > self.bytes.len() {
            return Err(format!(
                "serialized FMU state is truncated: {n} bytes needed, {} left",
                self.bytes.len()
            ));
        }
        let (head, tail) = self.bytes.split_at(n);
        self.bytes = tail;
        Ok(head)
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let mut a = [0; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.array::<1>()?[0])
    }
    fn flag(&mut self) -> Result<bool, String> {
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(format!("serialized FMU state has an invalid flag byte {b}")),
        }
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(self.array()?))
    }
    fn opt_f64(&mut self) -> Result<Option<f64>, String> {
        let present = self.flag()?;
        let x = self.f64()?;
        Ok(present.then_some(x))
    }
}
