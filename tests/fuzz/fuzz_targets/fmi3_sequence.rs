//! Random FMI 3.0 call sequences against an FMU's C entry points (HaselPlatform's FMI 3.0 functions
//! in target fmi3_calls, HaselPlatformReduced's in reduced_fmi3_calls), right and wrong: two instances
//! (Co-Simulation or Model Exchange), NULL pointers, unknown value references, wrong array sizes,
//! NaN and infinite values, calls of every type's getters and setters, calls in the wrong state,
//! FMU states passed between instances, serialized states truncated or corrupted (also with a
//! recomputed checksum). The sequence keeps only the caller's side of the contract that no FMU can
//! check: no pointer is used after it was freed and every array holds as many elements as the size
//! passed with it.
//!
//! Under libFuzzer with AddressSanitizer (`bash ci/fuzz.sh`) a crash, an out-of-bounds access,
//! a leak at the end of a sequence, a call that hangs or any panic fails the run; [`run`] also
//! replays the committed corpora in every `cargo test` (tests/fuzz_replay.rs), as in
//! fmi2_sequence.rs.

use std::ffi::{CStr, c_char, c_void};
use std::ptr::{null, null_mut};

use crate::common::{
    Bytes, Encode, Held, Len, Reached, Real, SeedCalls, StateFunctions, Vr, Who, pick,
};
use arbitrary::Arbitrary;
use hasel_fmu::fmi3::types::*;
use hasel_fmu::fmu::pack::FmiVersion;
use hasel_fmu::model::Params;

const OK: fmi3Status = Fmi3Status::Ok;

/// The functions of `fmi3Functions.h` that the sequences call (all this model's FMU serves, and
/// some it refuses), as an importer holds them after loading its library: the library's macro
/// [`hasel_fmu::export_fmi3`] makes them for a core ([`functions!`]).
#[allow(non_snake_case)]
#[derive(Clone, Copy)]
pub struct Functions {
    pub fmi3GetVersion: unsafe extern "C" fn() -> *const c_char,
    pub fmi3SetDebugLogging: unsafe extern "C" fn(
        c: fmi3Instance,
        logging_on: fmi3Boolean,
        n_categories: usize,
        categories: *const fmi3String,
    ) -> fmi3Status,
    pub fmi3InstantiateModelExchange: unsafe extern "C" fn(
        name: fmi3String,
        token: fmi3String,
        resource_path: fmi3String,
        visible: fmi3Boolean,
        logging_on: fmi3Boolean,
        environment: fmi3InstanceEnvironment,
        log_message: fmi3LogMessageCallback,
    ) -> fmi3Instance,
    pub fmi3InstantiateCoSimulation: unsafe extern "C" fn(
        name: fmi3String,
        token: fmi3String,
        resource_path: fmi3String,
        visible: fmi3Boolean,
        logging_on: fmi3Boolean,
        event_mode_used: fmi3Boolean,
        early_return_allowed: fmi3Boolean,
        required_intermediate_variables: *const fmi3ValueReference,
        n_required_intermediate_variables: usize,
        environment: fmi3InstanceEnvironment,
        log_message: fmi3LogMessageCallback,
        intermediate_update: fmi3IntermediateUpdateCallback,
    ) -> fmi3Instance,
    pub fmi3FreeInstance: unsafe extern "C" fn(c: fmi3Instance),
    pub fmi3EnterInitializationMode: unsafe extern "C" fn(
        c: fmi3Instance,
        tol_defined: fmi3Boolean,
        tol: fmi3Float64,
        start: fmi3Float64,
        stop_defined: fmi3Boolean,
        stop: fmi3Float64,
    ) -> fmi3Status,
    pub fmi3ExitInitializationMode: unsafe extern "C" fn(c: fmi3Instance) -> fmi3Status,
    pub fmi3EnterEventMode: unsafe extern "C" fn(c: fmi3Instance) -> fmi3Status,
    pub fmi3Terminate: unsafe extern "C" fn(c: fmi3Instance) -> fmi3Status,
    pub fmi3Reset: unsafe extern "C" fn(c: fmi3Instance) -> fmi3Status,
    pub fmi3GetFloat64: unsafe extern "C" fn(
        c: fmi3Instance,
        vr: *const fmi3ValueReference,
        nvr: usize,
        values: *mut fmi3Float64,
        n_values: usize,
    ) -> fmi3Status,
    pub fmi3SetFloat64: unsafe extern "C" fn(
        c: fmi3Instance,
        vr: *const fmi3ValueReference,
        nvr: usize,
        values: *const fmi3Float64,
        n_values: usize,
    ) -> fmi3Status,
    pub fmi3GetFloat32: unsafe extern "C" fn(
        c: fmi3Instance,
        vr: *const fmi3ValueReference,
        nvr: usize,
        values: *mut fmi3Float32,
        n_values: usize,
    ) -> fmi3Status,
    pub fmi3GetInt32: unsafe extern "C" fn(
        c: fmi3Instance,
        vr: *const fmi3ValueReference,
        nvr: usize,
        values: *mut fmi3Int32,
        n_values: usize,
    ) -> fmi3Status,
    pub fmi3GetUInt64: unsafe extern "C" fn(
        c: fmi3Instance,
        vr: *const fmi3ValueReference,
        nvr: usize,
        values: *mut fmi3UInt64,
        n_values: usize,
    ) -> fmi3Status,
    pub fmi3GetBoolean: unsafe extern "C" fn(
        c: fmi3Instance,
        vr: *const fmi3ValueReference,
        nvr: usize,
        values: *mut fmi3Boolean,
        n_values: usize,
    ) -> fmi3Status,
    pub fmi3GetString: unsafe extern "C" fn(
        c: fmi3Instance,
        vr: *const fmi3ValueReference,
        nvr: usize,
        values: *mut fmi3String,
        n_values: usize,
    ) -> fmi3Status,
    pub fmi3SetInt32: unsafe extern "C" fn(
        c: fmi3Instance,
        vr: *const fmi3ValueReference,
        nvr: usize,
        values: *const fmi3Int32,
        n_values: usize,
    ) -> fmi3Status,
    pub fmi3SetBoolean: unsafe extern "C" fn(
        c: fmi3Instance,
        vr: *const fmi3ValueReference,
        nvr: usize,
        values: *const fmi3Boolean,
        n_values: usize,
    ) -> fmi3Status,
    pub fmi3SetString: unsafe extern "C" fn(
        c: fmi3Instance,
        vr: *const fmi3ValueReference,
        nvr: usize,
        values: *const fmi3String,
        n_values: usize,
    ) -> fmi3Status,
    pub fmi3GetFMUState:
        unsafe extern "C" fn(c: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status,
    pub fmi3SetFMUState: unsafe extern "C" fn(c: fmi3Instance, state: fmi3FMUState) -> fmi3Status,
    pub fmi3FreeFMUState:
        unsafe extern "C" fn(c: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status,
    pub fmi3SerializedFMUStateSize:
        unsafe extern "C" fn(c: fmi3Instance, state: fmi3FMUState, size: *mut usize) -> fmi3Status,
    pub fmi3SerializeFMUState: unsafe extern "C" fn(
        c: fmi3Instance,
        state: fmi3FMUState,
        bytes: *mut fmi3Byte,
        size: usize,
    ) -> fmi3Status,
    pub fmi3DeserializeFMUState: unsafe extern "C" fn(
        c: fmi3Instance,
        bytes: *const fmi3Byte,
        size: usize,
        state: *mut fmi3FMUState,
    ) -> fmi3Status,
    pub fmi3GetDirectionalDerivative: unsafe extern "C" fn(
        c: fmi3Instance,
        unknowns: *const fmi3ValueReference,
        n_unknowns: usize,
        knowns: *const fmi3ValueReference,
        n_knowns: usize,
        seed: *const fmi3Float64,
        n_seed: usize,
        sensitivity: *mut fmi3Float64,
        n_sensitivity: usize,
    ) -> fmi3Status,
    pub fmi3GetAdjointDerivative: unsafe extern "C" fn(
        c: fmi3Instance,
        unknowns: *const fmi3ValueReference,
        n_unknowns: usize,
        knowns: *const fmi3ValueReference,
        n_knowns: usize,
        seed: *const fmi3Float64,
        n_seed: usize,
        sensitivity: *mut fmi3Float64,
        n_sensitivity: usize,
    ) -> fmi3Status,
    pub fmi3EnterConfigurationMode: unsafe extern "C" fn(c: fmi3Instance) -> fmi3Status,
    pub fmi3ExitConfigurationMode: unsafe extern "C" fn(c: fmi3Instance) -> fmi3Status,
    pub fmi3UpdateDiscreteStates: unsafe extern "C" fn(
        c: fmi3Instance,
        discrete_states_need_update: *mut fmi3Boolean,
        terminate_simulation: *mut fmi3Boolean,
        nominals_changed: *mut fmi3Boolean,
        values_changed: *mut fmi3Boolean,
        next_event_time_defined: *mut fmi3Boolean,
        next_event_time: *mut fmi3Float64,
    ) -> fmi3Status,
    pub fmi3EnterContinuousTimeMode: unsafe extern "C" fn(c: fmi3Instance) -> fmi3Status,
    pub fmi3CompletedIntegratorStep: unsafe extern "C" fn(
        c: fmi3Instance,
        no_set_fmu_state_prior: fmi3Boolean,
        enter_event_mode: *mut fmi3Boolean,
        terminate_simulation: *mut fmi3Boolean,
    ) -> fmi3Status,
    pub fmi3SetTime: unsafe extern "C" fn(c: fmi3Instance, time: fmi3Float64) -> fmi3Status,
    pub fmi3SetContinuousStates:
        unsafe extern "C" fn(c: fmi3Instance, x: *const fmi3Float64, nx: usize) -> fmi3Status,
    pub fmi3GetContinuousStateDerivatives:
        unsafe extern "C" fn(c: fmi3Instance, dx: *mut fmi3Float64, nx: usize) -> fmi3Status,
    pub fmi3GetEventIndicators:
        unsafe extern "C" fn(c: fmi3Instance, z: *mut fmi3Float64, nz: usize) -> fmi3Status,
    pub fmi3GetContinuousStates:
        unsafe extern "C" fn(c: fmi3Instance, x: *mut fmi3Float64, nx: usize) -> fmi3Status,
    pub fmi3GetNominalsOfContinuousStates:
        unsafe extern "C" fn(c: fmi3Instance, nominals: *mut fmi3Float64, nx: usize) -> fmi3Status,
    pub fmi3GetNumberOfEventIndicators:
        unsafe extern "C" fn(c: fmi3Instance, n: *mut usize) -> fmi3Status,
    pub fmi3GetNumberOfContinuousStates:
        unsafe extern "C" fn(c: fmi3Instance, n: *mut usize) -> fmi3Status,
    pub fmi3EnterStepMode: unsafe extern "C" fn(c: fmi3Instance) -> fmi3Status,
    pub fmi3GetOutputDerivatives: unsafe extern "C" fn(
        c: fmi3Instance,
        vr: *const fmi3ValueReference,
        nvr: usize,
        orders: *const fmi3Int32,
        values: *mut fmi3Float64,
        n_values: usize,
    ) -> fmi3Status,
    pub fmi3DoStep: unsafe extern "C" fn(
        c: fmi3Instance,
        tc: fmi3Float64,
        h: fmi3Float64,
        no_set_fmu_state_prior: fmi3Boolean,
        event_handling_needed: *mut fmi3Boolean,
        terminate_simulation: *mut fmi3Boolean,
        early_return: *mut fmi3Boolean,
        last_successful_time: *mut fmi3Float64,
    ) -> fmi3Status,
}

/// The [`Functions`] of the core `$core` (a path from the crate root): the C functions the
/// FMU's library exports for FMI 3.0, made by the same macro without the exported symbol names, as in
/// fmi2_sequence.rs.
macro_rules! functions {
    ($core:ty) => {{
        #[allow(dead_code)]
        mod c {
            hasel_fmu::__fmi3_functions!([] $core);
        }
        Functions {
            fmi3GetVersion: c::fmi3GetVersion,
            fmi3SetDebugLogging: c::fmi3SetDebugLogging,
            fmi3InstantiateModelExchange: c::fmi3InstantiateModelExchange,
            fmi3InstantiateCoSimulation: c::fmi3InstantiateCoSimulation,
            fmi3FreeInstance: c::fmi3FreeInstance,
            fmi3EnterInitializationMode: c::fmi3EnterInitializationMode,
            fmi3ExitInitializationMode: c::fmi3ExitInitializationMode,
            fmi3EnterEventMode: c::fmi3EnterEventMode,
            fmi3Terminate: c::fmi3Terminate,
            fmi3Reset: c::fmi3Reset,
            fmi3GetFloat64: c::fmi3GetFloat64,
            fmi3SetFloat64: c::fmi3SetFloat64,
            fmi3GetFloat32: c::fmi3GetFloat32,
            fmi3GetInt32: c::fmi3GetInt32,
            fmi3GetUInt64: c::fmi3GetUInt64,
            fmi3GetBoolean: c::fmi3GetBoolean,
            fmi3GetString: c::fmi3GetString,
            fmi3SetInt32: c::fmi3SetInt32,
            fmi3SetBoolean: c::fmi3SetBoolean,
            fmi3SetString: c::fmi3SetString,
            fmi3GetFMUState: c::fmi3GetFMUState,
            fmi3SetFMUState: c::fmi3SetFMUState,
            fmi3FreeFMUState: c::fmi3FreeFMUState,
            fmi3SerializedFMUStateSize: c::fmi3SerializedFMUStateSize,
            fmi3SerializeFMUState: c::fmi3SerializeFMUState,
            fmi3DeserializeFMUState: c::fmi3DeserializeFMUState,
            fmi3GetDirectionalDerivative: c::fmi3GetDirectionalDerivative,
            fmi3GetAdjointDerivative: c::fmi3GetAdjointDerivative,
            fmi3EnterConfigurationMode: c::fmi3EnterConfigurationMode,
            fmi3ExitConfigurationMode: c::fmi3ExitConfigurationMode,
            fmi3UpdateDiscreteStates: c::fmi3UpdateDiscreteStates,
            fmi3EnterContinuousTimeMode: c::fmi3EnterContinuousTimeMode,
            fmi3CompletedIntegratorStep: c::fmi3CompletedIntegratorStep,
            fmi3SetTime: c::fmi3SetTime,
            fmi3SetContinuousStates: c::fmi3SetContinuousStates,
            fmi3GetContinuousStateDerivatives: c::fmi3GetContinuousStateDerivatives,
            fmi3GetEventIndicators: c::fmi3GetEventIndicators,
            fmi3GetContinuousStates: c::fmi3GetContinuousStates,
            fmi3GetNominalsOfContinuousStates: c::fmi3GetNominalsOfContinuousStates,
            fmi3GetNumberOfEventIndicators: c::fmi3GetNumberOfEventIndicators,
            fmi3GetNumberOfContinuousStates: c::fmi3GetNumberOfContinuousStates,
            fmi3EnterStepMode: c::fmi3EnterStepMode,
            fmi3GetOutputDerivatives: c::fmi3GetOutputDerivatives,
            fmi3DoStep: c::fmi3DoStep,
        }
    }};
}

/// The FMU a sequence runs against.
pub type Fmu = crate::common::Fmu<Functions>;

impl Fmu {
    /// HaselPlatform's FMI 3.0 functions (target fmi3_calls).
    pub fn platform() -> Fmu {
        use hasel_fmu::fmu::{HaselCore, pack, variables::rows};
        Fmu::new::<HaselCore>(
            functions!(hasel_fmu::fmu::HaselCore),
            FmiVersion::V3.token(&pack::platform(&Params::default())),
            rows().len(),
        )
    }

    /// HaselPlatformReduced's FMI 3.0 functions (target reduced_fmi3_calls).
    pub fn reduced() -> Fmu {
        use hasel_fmu::fmu::{HaselReducedCore, pack, variables::rows_of};
        use hasel_fmu::model::Reduction;
        Fmu::new::<HaselReducedCore>(
            functions!(hasel_fmu::fmu::HaselReducedCore),
            FmiVersion::V3.token(&pack::reduced(&Params::default())),
            rows_of(Reduction::Slow).len(),
        )
    }
}

/// Reads every string the FMU hands the logger, so AddressSanitizer checks each pointer.
unsafe extern "C" fn log_message(
    _env: fmi3InstanceEnvironment,
    _status: fmi3Status,
    category: *const c_char,
    message: *const c_char,
) {
    for p in [category, message] {
        if !p.is_null() {
            std::hint::black_box(unsafe { CStr::from_ptr(p) }.to_bytes().len());
        }
    }
}

/// One call of a sequence, with the arguments that matter.
#[derive(Arbitrary, Debug)]
pub enum Call {
    Instantiate {
        who: Who,
        model_exchange: bool,
        wrong_token: bool,
        null_name: bool,
        no_logger: bool,
        resources: u8,
        logging_on: bool,
        event_mode_used: bool,
    },
    FreeInstance(Who),
    SetDebugLogging {
        who: Who,
        on: bool,
        categories: Vec<u8>,
        null_ptr: bool,
    },
    EnterInitializationMode {
        who: Who,
        tolerance: Option<Real>,
        start: Real,
        stop: Option<Real>,
    },
    ExitInitializationMode(Who),
    EnterEventMode(Who),
    Terminate(Who),
    Reset(Who),
    Configuration {
        who: Who,
        enter: bool,
    },
    GetFloat64 {
        who: Who,
        vrs: Vec<Vr>,
        values: Len,
        null_ptr: bool,
    },
    SetFloat64 {
        who: Who,
        values: Vec<(Vr, Real)>,
        n_values: Len,
        null_ptr: bool,
    },
    OtherType {
        who: Who,
        kind: u8,
        vrs: Vec<Vr>,
        value: i32,
    },
    DoStep {
        who: Who,
        at_current_time: bool,
        t: Real,
        h: Real,
        no_prior: bool,
        null_outputs: bool,
    },
    EnterStepMode(Who),
    OutputDerivatives {
        who: Who,
        values: Vec<(Vr, i8)>,
    },
    GetFmuState {
        who: Who,
        slot: u8,
        null_ptr: bool,
    },
    SetFmuState {
        who: Who,
        slot: u8,
    },
    FreeFmuState {
        who: Who,
        slot: u8,
    },
    Serialize {
        who: Who,
        slot: u8,
        size: Len,
        corrupt: Vec<(u16, u8)>,
        truncate: Option<u16>,
        fix_checksum: bool,
        into: u8,
    },
    SetTime {
        who: Who,
        t: Real,
    },
    SetContinuousStates {
        who: Who,
        len: Len,
        x: Vec<Real>,
    },
    GetVector {
        who: Who,
        kind: u8,
        len: Len,
        null_ptr: bool,
    },
    Counts {
        who: Who,
        states: bool,
        null_ptr: bool,
    },
    UpdateDiscreteStates {
        who: Who,
        null_ptr: bool,
    },
    EnterContinuousTimeMode(Who),
    CompletedIntegratorStep {
        who: Who,
        no_prior: bool,
        null_ptr: bool,
    },
    Derivative {
        who: Who,
        adjoint: bool,
        unknowns: Vec<Vr>,
        knowns: Vec<(Vr, Real)>,
        n_seed: Len,
        n_sensitivity: Len,
    },
}

/// A call written as `arbitrary`'s derive reads it ([`Bytes`]): its variant (of the 27, in the
/// order declared), then its fields in order. A new variant or field goes here too, or
/// tests/fuzz_replay.rs (`seeds_are_written_as_decoded`) fails.
impl Encode for Call {
    fn encode(&self, b: &mut Bytes) {
        const N: u32 = 27;
        match self {
            Call::Instantiate {
                who,
                model_exchange,
                wrong_token,
                null_name,
                no_logger,
                resources,
                logging_on,
                event_mode_used,
            } => b
                .variant(0, N)
                .put(who)
                .put(model_exchange)
                .put(wrong_token)
                .put(null_name)
                .put(no_logger)
                .put(resources)
                .put(logging_on)
                .put(event_mode_used),
            Call::FreeInstance(who) => b.variant(1, N).put(who),
            Call::SetDebugLogging {
                who,
                on,
                categories,
                null_ptr,
            } => b
                .variant(2, N)
                .put(who)
                .put(on)
                .put(categories)
                .put(null_ptr),
            Call::EnterInitializationMode {
                who,
                tolerance,
                start,
                stop,
            } => b.variant(3, N).put(who).put(tolerance).put(start).put(stop),
            Call::ExitInitializationMode(who) => b.variant(4, N).put(who),
            Call::EnterEventMode(who) => b.variant(5, N).put(who),
            Call::Terminate(who) => b.variant(6, N).put(who),
            Call::Reset(who) => b.variant(7, N).put(who),
            Call::Configuration { who, enter } => b.variant(8, N).put(who).put(enter),
            Call::GetFloat64 {
                who,
                vrs,
                values,
                null_ptr,
            } => b.variant(9, N).put(who).put(vrs).put(values).put(null_ptr),
            Call::SetFloat64 {
                who,
                values,
                n_values,
                null_ptr,
            } => b
                .variant(10, N)
                .put(who)
                .put(values)
                .put(n_values)
                .put(null_ptr),
            Call::OtherType {
                who,
                kind,
                vrs,
                value,
            } => b.variant(11, N).put(who).put(kind).put(vrs).put(value),
            Call::DoStep {
                who,
                at_current_time,
                t,
                h,
                no_prior,
                null_outputs,
            } => b
                .variant(12, N)
                .put(who)
                .put(at_current_time)
                .put(t)
                .put(h)
                .put(no_prior)
                .put(null_outputs),
            Call::EnterStepMode(who) => b.variant(13, N).put(who),
            Call::OutputDerivatives { who, values } => b.variant(14, N).put(who).put(values),
            Call::GetFmuState {
                who,
                slot,
                null_ptr,
            } => b.variant(15, N).put(who).put(slot).put(null_ptr),
            Call::SetFmuState { who, slot } => b.variant(16, N).put(who).put(slot),
            Call::FreeFmuState { who, slot } => b.variant(17, N).put(who).put(slot),
            Call::Serialize {
                who,
                slot,
                size,
                corrupt,
                truncate,
                fix_checksum,
                into,
            } => b
                .variant(18, N)
                .put(who)
                .put(slot)
                .put(size)
                .put(corrupt)
                .put(truncate)
                .put(fix_checksum)
                .put(into),
            Call::SetTime { who, t } => b.variant(19, N).put(who).put(t),
            Call::SetContinuousStates { who, len, x } => b.variant(20, N).put(who).put(len).put(x),
            Call::GetVector {
                who,
                kind,
                len,
                null_ptr,
            } => b.variant(21, N).put(who).put(kind).put(len).put(null_ptr),
            Call::Counts {
                who,
                states,
                null_ptr,
            } => b.variant(22, N).put(who).put(states).put(null_ptr),
            Call::UpdateDiscreteStates { who, null_ptr } => b.variant(23, N).put(who).put(null_ptr),
            Call::EnterContinuousTimeMode(who) => b.variant(24, N).put(who),
            Call::CompletedIntegratorStep {
                who,
                no_prior,
                null_ptr,
            } => b.variant(25, N).put(who).put(no_prior).put(null_ptr),
            Call::Derivative {
                who,
                adjoint,
                unknowns,
                knowns,
                n_seed,
                n_sensitivity,
            } => b
                .variant(26, N)
                .put(who)
                .put(adjoint)
                .put(unknowns)
                .put(knowns)
                .put(n_seed)
                .put(n_sensitivity),
        };
    }
}

/// The calls of the seeds ([`crate::common::seeds`]) in FMI 3.0.
impl SeedCalls for Call {
    crate::common::seed_calls_alike!();

    fn start(
        who: Who,
        model_exchange: bool,
        event_mode_used: bool,
        tolerance: Option<Real>,
    ) -> Vec<Call> {
        let mut calls = vec![
            Call::Instantiate {
                who,
                model_exchange,
                wrong_token: false,
                null_name: false,
                no_logger: false,
                resources: 0,
                logging_on: false,
                event_mode_used,
            },
            Call::EnterInitializationMode {
                who,
                tolerance,
                start: pick::ZERO,
                stop: None,
            },
            Call::ExitInitializationMode(who),
        ];
        // initialization ends in Event Mode
        let update = Call::UpdateDiscreteStates {
            who,
            null_ptr: false,
        };
        if model_exchange {
            calls.extend([
                update,
                Call::EnterContinuousTimeMode(who),
                Call::Counts {
                    who,
                    states: true,
                    null_ptr: false,
                },
            ]);
        } else if event_mode_used {
            calls.extend([update, Call::EnterStepMode(who)]);
        }
        calls
    }

    fn event(who: Who, model_exchange: bool) -> Vec<Call> {
        vec![
            Call::EnterEventMode(who),
            Call::UpdateDiscreteStates {
                who,
                null_ptr: false,
            },
            if model_exchange {
                Call::EnterContinuousTimeMode(who)
            } else {
                Call::EnterStepMode(who)
            },
        ]
    }

    fn set(who: Who, inputs: &[(u32, Real)]) -> Call {
        Call::SetFloat64 {
            who,
            values: inputs.iter().map(|&(v, x)| (Vr::Any(v), x)).collect(),
            n_values: Len::Right,
            null_ptr: false,
        }
    }

    fn get(who: Who, outputs: &[u32]) -> Call {
        Call::GetFloat64 {
            who,
            vrs: outputs.iter().map(|&v| Vr::Any(v)).collect(),
            values: Len::Right,
            null_ptr: false,
        }
    }

    fn step(who: Who, h: Real) -> Call {
        Call::DoStep {
            who,
            at_current_time: true,
            t: pick::ZERO,
            h,
            no_prior: false,
            null_outputs: false,
        }
    }

    fn perturb_states(who: Who) -> Call {
        Call::SetContinuousStates {
            who,
            len: Len::Right,
            x: vec![pick::MILLI],
        }
    }
}

/// What the sequence holds between calls: the instances, their simulated time, FMU states.
struct World<'a> {
    fmu: &'a Fmu,
    /// The FMU's functions (a copy of `fmu.functions`, for short calls).
    f: Functions,
    held: Held,
    reached: Reached,
}

/// The FMI 3.0 functions on instances and FMU states, with what instantiating one needs.
struct Shell<'a> {
    f: &'a Functions,
    token: &'a CStr,
}

impl StateFunctions for Shell<'_> {
    unsafe fn get_state(&self, c: *mut c_void, state: *mut *mut c_void) -> bool {
        unsafe { (self.f.fmi3GetFMUState)(c, state) == OK }
    }
    unsafe fn set_state(&self, c: *mut c_void, state: *mut c_void) -> bool {
        unsafe { (self.f.fmi3SetFMUState)(c, state) == OK }
    }
    unsafe fn free_state(&self, c: *mut c_void, state: *mut *mut c_void) {
        unsafe { (self.f.fmi3FreeFMUState)(c, state) };
    }
    unsafe fn serialized_size(&self, c: *mut c_void, state: *mut c_void, n: &mut usize) -> bool {
        unsafe { (self.f.fmi3SerializedFMUStateSize)(c, state, n) == OK }
    }
    unsafe fn serialize(&self, c: *mut c_void, state: *mut c_void, bytes: &mut [u8]) -> bool {
        let n = bytes.len();
        unsafe { (self.f.fmi3SerializeFMUState)(c, state, bytes.as_mut_ptr(), n) == OK }
    }
    unsafe fn deserialize(&self, c: *mut c_void, bytes: &[u8], state: *mut *mut c_void) -> bool {
        unsafe { (self.f.fmi3DeserializeFMUState)(c, bytes.as_ptr(), bytes.len(), state) == OK }
    }
    unsafe fn free_instance(&self, c: *mut c_void) {
        unsafe { (self.f.fmi3FreeInstance)(c) };
    }
    unsafe fn cleanup_instance(&self) -> *mut c_void {
        unsafe {
            (self.f.fmi3InstantiateCoSimulation)(
                c"cleanup".as_ptr(),
                self.token.as_ptr(),
                null(),
                0,
                0,
                0,
                0,
                null(),
                0,
                null_mut(),
                None,
                None,
            )
        }
    }
    /// The time the state was taken at: FMI 3.0 has no call to ask the FMU.
    unsafe fn restored_time(&self, _: *mut c_void, taken_at: f64) -> f64 {
        taken_at
    }
}

impl World<'_> {
    fn new(fmu: &Fmu) -> World<'_> {
        World {
            fmu,
            f: fmu.functions,
            held: Held::new(),
            reached: Reached::default(),
        }
    }

    /// The instances and FMU states held, the functions that act on them, and what the
    /// sequence reached.
    fn parts(&mut self) -> (&mut Held, Shell<'_>, &mut Reached) {
        let shell = Shell {
            f: &self.f,
            token: &self.fmu.token,
        };
        (&mut self.held, shell, &mut self.reached)
    }

    crate::common::state_calls!();

    fn len(&self, len: Len, right: usize) -> usize {
        match len {
            Len::Right => right,
            Len::Other(n) => n as usize,
        }
    }

    fn free_instance(&mut self, i: usize) {
        let (held, shell, _) = self.parts();
        held.free_instance(&shell, i);
    }

    fn run(&mut self, call: &Call) {
        match *call {
            Call::Instantiate {
                who,
                model_exchange,
                wrong_token,
                null_name,
                no_logger,
                resources,
                logging_on,
                event_mode_used,
            } => {
                let Some(i) = Held::index(who) else { return };
                self.free_instance(i);
                let resources: &CStr = match resources % 4 {
                    0 => c"",
                    1 => c"/nonexistent/resources/",
                    2 => c"not a path",
                    _ => c"/tmp/",
                };
                let resources = if resources.is_empty() {
                    null()
                } else {
                    resources.as_ptr()
                };
                let token = if wrong_token {
                    c"{0}"
                } else {
                    self.fmu.token.as_c_str()
                };
                let name = if null_name { null() } else { c"fuzz".as_ptr() };
                let log: fmi3LogMessageCallback = if no_logger { None } else { Some(log_message) };
                self.held.instances[i] = unsafe {
                    if model_exchange {
                        (self.f.fmi3InstantiateModelExchange)(
                            name,
                            token.as_ptr(),
                            resources,
                            0,
                            u8::from(logging_on),
                            null_mut(),
                            log,
                        )
                    } else {
                        (self.f.fmi3InstantiateCoSimulation)(
                            name,
                            token.as_ptr(),
                            resources,
                            0,
                            u8::from(logging_on),
                            u8::from(event_mode_used),
                            0,
                            null(),
                            0,
                            null_mut(),
                            log,
                            None,
                        )
                    }
                };
            }
            Call::FreeInstance(who) => match Held::index(who) {
                Some(i) => self.free_instance(i),
                None => unsafe { (self.f.fmi3FreeInstance)(null_mut()) },
            },
            Call::SetDebugLogging {
                who,
                on,
                ref categories,
                null_ptr,
            } => {
                const NAMES: [&CStr; 4] = [c"logAll", c"logCalls", c"logStatusError", c"nonsense"];
                let names: Vec<*const c_char> = categories
                    .iter()
                    .map(|&k| NAMES[k as usize % NAMES.len()].as_ptr())
                    .collect();
                let p = if null_ptr { null() } else { names.as_ptr() };
                unsafe {
                    (self.f.fmi3SetDebugLogging)(
                        self.held.instance(who),
                        u8::from(on),
                        names.len(),
                        p,
                    )
                };
            }
            Call::EnterInitializationMode {
                who,
                tolerance,
                start,
                stop,
            } => {
                let t0 = start.get();
                let status = unsafe {
                    (self.f.fmi3EnterInitializationMode)(
                        self.held.instance(who),
                        u8::from(tolerance.is_some()),
                        tolerance.map_or(0.0, Real::get),
                        t0,
                        u8::from(stop.is_some()),
                        stop.map_or(0.0, Real::get),
                    )
                };
                if let (OK, Some(i)) = (status, Held::index(who)) {
                    self.held.time[i] = t0;
                }
            }
            Call::ExitInitializationMode(who) => {
                let status =
                    unsafe { (self.f.fmi3ExitInitializationMode)(self.held.instance(who)) };
                self.reached.exit_initialization.add(status == OK);
            }
            Call::EnterEventMode(who) => unsafe {
                (self.f.fmi3EnterEventMode)(self.held.instance(who));
            },
            Call::Terminate(who) => unsafe {
                (self.f.fmi3Terminate)(self.held.instance(who));
            },
            Call::Reset(who) => {
                let status = unsafe { (self.f.fmi3Reset)(self.held.instance(who)) };
                if let (OK, Some(i)) = (status, Held::index(who)) {
                    self.held.time[i] = 0.0;
                }
            }
            Call::Configuration { who, enter } => unsafe {
                if enter {
                    (self.f.fmi3EnterConfigurationMode)(self.held.instance(who));
                } else {
                    (self.f.fmi3ExitConfigurationMode)(self.held.instance(who));
                }
            },
            Call::GetFloat64 {
                who,
                ref vrs,
                values,
                null_ptr,
            } => {
                let vrs: Vec<u32> = vrs.iter().map(|v| v.get(self.fmu.variables)).collect();
                let n = self.len(values, vrs.len());
                let mut out = vec![0.0; n];
                let p = if null_ptr {
                    null_mut()
                } else {
                    out.as_mut_ptr()
                };
                unsafe {
                    (self.f.fmi3GetFloat64)(self.held.instance(who), vrs.as_ptr(), vrs.len(), p, n)
                };
            }
            Call::SetFloat64 {
                who,
                ref values,
                n_values,
                null_ptr,
            } => {
                let vrs: Vec<u32> = values
                    .iter()
                    .map(|(v, _)| v.get(self.fmu.variables))
                    .collect();
                let n = self.len(n_values, vrs.len());
                let xs: Vec<f64> = (0..n)
                    .map(|k| values.get(k).map_or(1.0, |(_, x)| x.get()))
                    .collect();
                let p = if null_ptr { null() } else { xs.as_ptr() };
                unsafe {
                    (self.f.fmi3SetFloat64)(self.held.instance(who), vrs.as_ptr(), vrs.len(), p, n)
                };
            }
            Call::OtherType {
                who,
                kind,
                ref vrs,
                value,
            } => {
                let c = self.held.instance(who);
                let vrs: Vec<u32> = vrs.iter().map(|v| v.get(self.fmu.variables)).collect();
                let (p, n) = (vrs.as_ptr(), vrs.len());
                let mut ints = vec![value; n];
                let mut bools = vec![u8::from(value % 2 == 0); n];
                let mut floats = vec![value as f32; n];
                let mut longs = vec![value as u64; n];
                let mut strings = vec![c"x".as_ptr(); n];
                unsafe {
                    match kind % 8 {
                        0 => (self.f.fmi3GetInt32)(c, p, n, ints.as_mut_ptr(), n),
                        1 => (self.f.fmi3GetBoolean)(c, p, n, bools.as_mut_ptr(), n),
                        2 => (self.f.fmi3GetString)(c, p, n, strings.as_mut_ptr(), n),
                        3 => (self.f.fmi3GetFloat32)(c, p, n, floats.as_mut_ptr(), n),
                        4 => (self.f.fmi3GetUInt64)(c, p, n, longs.as_mut_ptr(), n),
                        5 => (self.f.fmi3SetInt32)(c, p, n, ints.as_ptr(), n),
                        6 => (self.f.fmi3SetBoolean)(c, p, n, bools.as_ptr(), n),
                        _ => (self.f.fmi3SetString)(c, p, n, strings.as_ptr(), n),
                    }
                };
            }
            Call::DoStep {
                who,
                at_current_time,
                t,
                h,
                no_prior,
                null_outputs,
            } => {
                let i = Held::index(who);
                let t = match (at_current_time, i) {
                    (true, Some(i)) => self.held.time[i],
                    _ => t.get(),
                };
                let (mut event, mut terminate, mut early) = (0, 0, 0);
                let mut last = 0.0;
                let status = unsafe {
                    if null_outputs {
                        (self.f.fmi3DoStep)(
                            self.held.instance(who),
                            t,
                            h.get(),
                            u8::from(no_prior),
                            null_mut(),
                            null_mut(),
                            null_mut(),
                            null_mut(),
                        )
                    } else {
                        (self.f.fmi3DoStep)(
                            self.held.instance(who),
                            t,
                            h.get(),
                            u8::from(no_prior),
                            &mut event,
                            &mut terminate,
                            &mut early,
                            &mut last,
                        )
                    }
                };
                self.reached.do_step.add(status == OK);
                if let (OK, Some(i)) = (status, i) {
                    self.held.time[i] = t + h.get();
                }
            }
            Call::EnterStepMode(who) => unsafe {
                (self.f.fmi3EnterStepMode)(self.held.instance(who));
            },
            Call::OutputDerivatives { who, ref values } => {
                let vrs: Vec<u32> = values
                    .iter()
                    .map(|(v, _)| v.get(self.fmu.variables))
                    .collect();
                let orders: Vec<i32> = values.iter().map(|&(_, o)| i32::from(o)).collect();
                let mut out = vec![0.0; vrs.len()];
                unsafe {
                    (self.f.fmi3GetOutputDerivatives)(
                        self.held.instance(who),
                        vrs.as_ptr(),
                        vrs.len(),
                        orders.as_ptr(),
                        out.as_mut_ptr(),
                        out.len(),
                    )
                };
            }
            Call::GetFmuState { .. }
            | Call::SetFmuState { .. }
            | Call::FreeFmuState { .. }
            | Call::Serialize { .. } => self.run_state_call(call),
            Call::SetTime { who, t } => unsafe {
                (self.f.fmi3SetTime)(self.held.instance(who), t.get());
            },
            Call::SetContinuousStates { who, len, ref x } => {
                let c = self.held.instance(who);
                let n = self.len(len, self.fmu.states);
                let mut got = vec![0.0; n];
                let valid =
                    unsafe { (self.f.fmi3GetContinuousStates)(c, got.as_mut_ptr(), n) } == OK;
                let xs: Vec<f64> = (0..n)
                    .map(|k| match (x.get(k), valid) {
                        (Some(r), true) => got[k] * (1.0 + 1e-3 * r.get()),
                        (Some(r), false) => r.get(),
                        (None, _) => got[k],
                    })
                    .collect();
                unsafe { (self.f.fmi3SetContinuousStates)(c, xs.as_ptr(), n) };
            }
            Call::GetVector {
                who,
                kind,
                len,
                null_ptr,
            } => {
                let c = self.held.instance(who);
                let right = if kind % 4 == 2 { 0 } else { self.fmu.states };
                let n = self.len(len, right);
                let mut v = vec![0.0; n];
                let p = if null_ptr { null_mut() } else { v.as_mut_ptr() };
                let status = unsafe {
                    match kind % 4 {
                        0 => (self.f.fmi3GetContinuousStates)(c, p, n),
                        1 => (self.f.fmi3GetContinuousStateDerivatives)(c, p, n),
                        2 => (self.f.fmi3GetEventIndicators)(c, p, n),
                        _ => (self.f.fmi3GetNominalsOfContinuousStates)(c, p, n),
                    }
                };
                if kind % 4 == 1 {
                    self.reached.derivatives.add(status == OK);
                }
            }
            Call::Counts {
                who,
                states,
                null_ptr,
            } => {
                let mut n = 0usize;
                let p = if null_ptr {
                    null_mut()
                } else {
                    &mut n as *mut usize
                };
                unsafe {
                    if states {
                        (self.f.fmi3GetNumberOfContinuousStates)(self.held.instance(who), p)
                    } else {
                        (self.f.fmi3GetNumberOfEventIndicators)(self.held.instance(who), p)
                    }
                };
            }
            Call::UpdateDiscreteStates { who, null_ptr } => {
                let mut flags = [0; 5];
                let mut next = 0.0;
                let [a, b, c, d, e] = &mut flags;
                unsafe {
                    if null_ptr {
                        (self.f.fmi3UpdateDiscreteStates)(
                            self.held.instance(who),
                            null_mut(),
                            null_mut(),
                            null_mut(),
                            null_mut(),
                            null_mut(),
                            null_mut(),
                        )
                    } else {
                        (self.f.fmi3UpdateDiscreteStates)(
                            self.held.instance(who),
                            a,
                            b,
                            c,
                            d,
                            e,
                            &mut next,
                        )
                    }
                };
            }
            Call::EnterContinuousTimeMode(who) => unsafe {
                (self.f.fmi3EnterContinuousTimeMode)(self.held.instance(who));
            },
            Call::CompletedIntegratorStep {
                who,
                no_prior,
                null_ptr,
            } => {
                let (mut event, mut terminate) = (0, 0);
                unsafe {
                    if null_ptr {
                        (self.f.fmi3CompletedIntegratorStep)(
                            self.held.instance(who),
                            u8::from(no_prior),
                            null_mut(),
                            null_mut(),
                        )
                    } else {
                        (self.f.fmi3CompletedIntegratorStep)(
                            self.held.instance(who),
                            u8::from(no_prior),
                            &mut event,
                            &mut terminate,
                        )
                    }
                };
            }
            Call::Derivative {
                who,
                adjoint,
                ref unknowns,
                ref knowns,
                n_seed,
                n_sensitivity,
            } => {
                let unknowns: Vec<u32> =
                    unknowns.iter().map(|v| v.get(self.fmu.variables)).collect();
                let known_vrs: Vec<u32> = knowns
                    .iter()
                    .map(|(v, _)| v.get(self.fmu.variables))
                    .collect();
                // directional: seeds per known, results per unknown; adjoint the other way
                let (seeds_right, out_right) = if adjoint {
                    (unknowns.len(), known_vrs.len())
                } else {
                    (known_vrs.len(), unknowns.len())
                };
                let n_seed = self.len(n_seed, seeds_right);
                let seeds: Vec<f64> = (0..n_seed)
                    .map(|k| knowns.get(k).map_or(1.0, |(_, x)| x.get()))
                    .collect();
                let mut out = vec![0.0; self.len(n_sensitivity, out_right)];
                let f = if adjoint {
                    self.f.fmi3GetAdjointDerivative
                } else {
                    self.f.fmi3GetDirectionalDerivative
                };
                unsafe {
                    f(
                        self.held.instance(who),
                        unknowns.as_ptr(),
                        unknowns.len(),
                        known_vrs.as_ptr(),
                        known_vrs.len(),
                        seeds.as_ptr(),
                        seeds.len(),
                        out.as_mut_ptr(),
                        out.len(),
                    )
                };
            }
        }
    }

    /// The end of a sequence: everything still held is freed, so leaks show.
    fn finish(&mut self) {
        let (held, shell, _) = self.parts();
        held.finish(&shell);
    }
}

/// Runs a sequence (its first 64 calls) against `fmu`, then frees what it still holds: what
/// the fuzz targets do with each input, and the replay with each file of their corpora. Returns
/// how deep it got.
pub fn run(fmu: &Fmu, calls: &[Call]) -> Reached {
    unsafe { std::hint::black_box(CStr::from_ptr((fmu.functions.fmi3GetVersion)())) };
    let mut world = World::new(fmu);
    for call in calls.iter().take(64) {
        world.run(call);
    }
    world.finish();
    world.reached
}
