//! FMU states (FMI 2.0 standard, section 2.1.8): a snapshot of an instance, and its byte
//! format for `fmi2SerializeFMUstate` / `fmi2DeSerializeFMUstate`.
//!
//! Format, in the shared frame of [`crate::fmi_common::fmu_state`]: magic `FMI2RSST`, then
//! (little endian) format version `u32`, GUID (`u32` length + UTF-8), interface `u8` (0 Model
//! Exchange, 1 Co-Simulation, as `fmi2Type`), phase `u8`, experiment (flag `u8`; start `f64`,
//! stop and tolerance each as flag `u8` + `f64`), core bytes (`u64` length + bytes), the
//! checksum.

use super::Fmi2;
use super::state_machine::{Experiment, Phase};
use crate::fmi_common::fmu_state::{self, Format, check_origin, seal, unseal};
use crate::fmi_common::model_api::{FmuCore, InstanceKind};

const MAGIC: &[u8; 8] = b"FMI2RSST";
/// 3: a Co-Simulation run holds which integrator it steps with (Radau IIA or the explicit
/// pair, src/simulation/mod.rs), where 2 held Radau IIA alone. 4: Radau IIA's factors hold
/// where the nonzeros of their blocks beyond eight states are (src/solver/lu.rs).
const FORMAT_VERSION: u32 = 4;

/// An FMU state of this shell.
pub type Snapshot<M> = fmu_state::Snapshot<M, Phase>;

fn put_opt(out: &mut Vec<u8>, x: Option<f64>) {
    out.push(u8::from(x.is_some()));
    out.extend_from_slice(&x.unwrap_or(0.0).to_le_bytes());
}

impl Format for Fmi2 {
    type Phase = Phase;

    /// The serialized bytes.
    fn to_bytes<M: FmuCore>(state: &Snapshot<M>) -> Vec<u8> {
        let core = state.core.serialize_state();
        let mut out = Vec::with_capacity(56 + state.token.len() + core.len());
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(state.token.len() as u32).to_le_bytes());
        out.extend_from_slice(state.token.as_bytes());
        out.push(u8::from(state.kind == InstanceKind::CoSimulation));
        out.push(state.phase as u8);
        out.push(u8::from(state.experiment.is_some()));
        let e = state.experiment.unwrap_or_default();
        out.extend_from_slice(&e.start_time.to_le_bytes());
        put_opt(&mut out, e.stop_time);
        put_opt(&mut out, e.tolerance);
        out.extend_from_slice(&(core.len() as u64).to_le_bytes());
        out.extend_from_slice(&core);
        seal(MAGIC, &out)
    }

    /// Parses bytes of [`Format::to_bytes`] for the instance with `guid`, `kind` and `core`.
    fn from_bytes<M: FmuCore>(
        bytes: &[u8],
        guid: &str,
        kind: InstanceKind,
        core: &M,
    ) -> Result<Snapshot<M>, String> {
        let mut r = Reader {
            bytes: unseal(MAGIC, bytes)?,
        };
        let version = r.u32()?;
        let guid_len = r.u32()? as usize;
        let state_guid = std::str::from_utf8(r.take(guid_len)?)
            .map_err(|_| "serialized FMU state has a malformed GUID".to_string())?;
        let state_kind = if r.flag()? {
            InstanceKind::CoSimulation
        } else {
            InstanceKind::ModelExchange
        };
        check_origin(
            (version, FORMAT_VERSION),
            ("GUID", state_guid, guid),
            (state_kind, kind),
        )?;
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
            token: guid.to_string(),
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
