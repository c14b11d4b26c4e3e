//! FMU states (FMI 3.0 standard, section 2.3.6): a snapshot of an instance, and its byte
//! format for `fmi3SerializeFMUState` / `fmi3DeserializeFMUState`.
//!
//! Format, in the shared frame of [`crate::fmi_common::fmu_state`]: magic `FMI3HSST`, a
//! postcard record (format version, instantiation token, interface, state-machine state,
//! experiment, the core's bytes), the checksum.

use serde::{Deserialize, Serialize};

use super::Fmi3;
use super::state_machine::{Experiment, Phase};
use super::types::InstanceKind;
use crate::fmi_common::fmu_state::{self, Format, check_origin, seal, unseal};
use crate::fmi_common::model_api::FmuCore;

const MAGIC: &[u8; 8] = b"FMI3HSST";
/// 2: a Co-Simulation run holds which integrator it steps with (Radau IIA or the explicit
/// pair, src/simulation/mod.rs), where 1 held Radau IIA alone. 3: Radau IIA's factors hold
/// where the nonzeros of their blocks beyond eight states are (src/solver/lu.rs).
const FORMAT_VERSION: u32 = 3;

/// An FMU state of this shell.
pub type Snapshot<M> = fmu_state::Snapshot<M, Phase>;

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

impl Format for Fmi3 {
    type Phase = Phase;

    /// The serialized bytes.
    fn to_bytes<M: FmuCore>(state: &Snapshot<M>) -> Vec<u8> {
        let record = Record {
            version: FORMAT_VERSION,
            token: state.token.clone(),
            model_exchange: state.kind == InstanceKind::ModelExchange,
            phase: state.phase,
            experiment: state.experiment,
            core: state.core.serialize_state(),
        };
        let bytes = postcard::to_stdvec(&record).expect("serializing to memory cannot fail");
        seal(MAGIC, &bytes)
    }

    /// Parses bytes of [`Format::to_bytes`] for the instance with `token`, `interface` and
    /// `core`.
    fn from_bytes<M: FmuCore>(
        bytes: &[u8],
        token: &str,
        interface: InstanceKind,
        core: &M,
    ) -> Result<Snapshot<M>, String> {
        let record: Record = postcard::from_bytes(unseal(MAGIC, bytes)?)
            .map_err(|e| format!("the serialized FMU state is malformed: {e}"))?;
        let state_interface = if record.model_exchange {
            InstanceKind::ModelExchange
        } else {
            InstanceKind::CoSimulation
        };
        check_origin(
            (record.version, FORMAT_VERSION),
            ("instantiationToken", &record.token, token),
            (state_interface, interface),
        )?;
        if !record.phase.belongs_to(interface) {
            return Err("the serialized FMU state has a state of the other interface".into());
        }
        Ok(Snapshot {
            token: record.token,
            kind: interface,
            phase: record.phase,
            experiment: record.experiment,
            core: core.deserialize_state(&record.core)?,
        })
    }
}
