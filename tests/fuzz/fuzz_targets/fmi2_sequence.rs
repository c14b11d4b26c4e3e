//! Random FMI 2.0 call sequences against an FMU's C entry points (HaselPlatform's in target
//! fmi2_calls, HaselInverse's in inverse_calls, HaselPlatformReduced's in reduced_calls), as an
//! importer would make them, right and wrong: two instances (Co-Simulation or Model Exchange), NULL
//! pointers, unknown value references, wrong array sizes, NaN and infinite values, calls in the
//! wrong state, FMU states passed between instances, serialized states truncated or corrupted (also
//! with a recomputed checksum, so the decoder behind it is reached). The sequence keeps only the
//! caller's side of the contract that no FMU can check: no pointer is used after it was freed and
//! every array holds as many elements as the size passed with it.
//!
//! Under libFuzzer with AddressSanitizer (`bash ci/fuzz.sh`) a crash, an out-of-bounds access,
//! a leak at the end of a sequence, a call that hangs or any panic (libfuzzer-sys aborts on one,
//! even one the FMU's shell catches) fails the run. The same interpreter, [`run`], replays the
//! committed corpora in every `cargo test` (tests/fuzz_replay.rs, stable Rust, no sanitizer),
//! which fails on a panic, caught or not, and on a broken assertion of [`World::finish`].

use std::ffi::{CStr, c_char, c_void};
use std::ptr::{null, null_mut};

use crate::common::{
    Bytes, Encode, Held, Len, Reached, Real, SeedCalls, StateFunctions, Vr, Who, pick,
};
use arbitrary::Arbitrary;
use hasel_fmu::fmi2::types::*;
use hasel_fmu::fmu::pack::guid;
use hasel_fmu::model::Params;

const OK: fmi2Status = Fmi2Status::Ok;

/// The 44 functions of `fmi2Functions.h` of one FMU, as an importer holds them after loading
/// its library: the library's macro [`hasel_fmu::export_fmi2`] makes them for a core
/// ([`functions!`]), the same code the FMU's binary exports.
#[allow(non_snake_case)]
#[derive(Clone, Copy)]
pub struct Functions {
    pub fmi2GetTypesPlatform: unsafe extern "C" fn() -> *const c_char,
    pub fmi2GetVersion: unsafe extern "C" fn() -> *const c_char,
    pub fmi2SetDebugLogging: unsafe extern "C" fn(
        c: fmi2Component,
        logging_on: fmi2Boolean,
        n_categories: usize,
        categories: *const fmi2String,
    ) -> fmi2Status,
    pub fmi2Instantiate: unsafe extern "C" fn(
        name: fmi2String,
        fmu_type: fmi2Type,
        guid: fmi2String,
        resources: fmi2String,
        functions: *const fmi2CallbackFunctions,
        visible: fmi2Boolean,
        logging_on: fmi2Boolean,
    ) -> fmi2Component,
    pub fmi2FreeInstance: unsafe extern "C" fn(c: fmi2Component),
    pub fmi2SetupExperiment: unsafe extern "C" fn(
        c: fmi2Component,
        tol_defined: fmi2Boolean,
        tol: fmi2Real,
        start: fmi2Real,
        stop_defined: fmi2Boolean,
        stop: fmi2Real,
    ) -> fmi2Status,
    pub fmi2EnterInitializationMode: unsafe extern "C" fn(c: fmi2Component) -> fmi2Status,
    pub fmi2ExitInitializationMode: unsafe extern "C" fn(c: fmi2Component) -> fmi2Status,
    pub fmi2Terminate: unsafe extern "C" fn(c: fmi2Component) -> fmi2Status,
    pub fmi2Reset: unsafe extern "C" fn(c: fmi2Component) -> fmi2Status,
    pub fmi2GetReal: unsafe extern "C" fn(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *mut fmi2Real,
    ) -> fmi2Status,
    pub fmi2GetInteger: unsafe extern "C" fn(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *mut fmi2Integer,
    ) -> fmi2Status,
    pub fmi2GetBoolean: unsafe extern "C" fn(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *mut fmi2Boolean,
    ) -> fmi2Status,
    pub fmi2GetString: unsafe extern "C" fn(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *mut fmi2String,
    ) -> fmi2Status,
    pub fmi2SetReal: unsafe extern "C" fn(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *const fmi2Real,
    ) -> fmi2Status,
    pub fmi2SetInteger: unsafe extern "C" fn(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *const fmi2Integer,
    ) -> fmi2Status,
    pub fmi2SetBoolean: unsafe extern "C" fn(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *const fmi2Boolean,
    ) -> fmi2Status,
    pub fmi2SetString: unsafe extern "C" fn(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *const fmi2String,
    ) -> fmi2Status,
    pub fmi2GetFMUstate:
        unsafe extern "C" fn(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status,
    pub fmi2SetFMUstate: unsafe extern "C" fn(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status,
    pub fmi2FreeFMUstate:
        unsafe extern "C" fn(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status,
    pub fmi2SerializedFMUstateSize:
        unsafe extern "C" fn(c: fmi2Component, state: fmi2FMUstate, size: *mut usize) -> fmi2Status,
    pub fmi2SerializeFMUstate: unsafe extern "C" fn(
        c: fmi2Component,
        state: fmi2FMUstate,
        bytes: *mut fmi2Byte,
        size: usize,
    ) -> fmi2Status,
    pub fmi2DeSerializeFMUstate: unsafe extern "C" fn(
        c: fmi2Component,
        bytes: *const fmi2Byte,
        size: usize,
        state: *mut fmi2FMUstate,
    ) -> fmi2Status,
    pub fmi2GetDirectionalDerivative: unsafe extern "C" fn(
        c: fmi2Component,
        v_unknown_ref: *const fmi2ValueReference,
        n_unknown: usize,
        v_known_ref: *const fmi2ValueReference,
        n_known: usize,
        dv_known: *const fmi2Real,
        dv_unknown: *mut fmi2Real,
    ) -> fmi2Status,
    pub fmi2EnterEventMode: unsafe extern "C" fn(c: fmi2Component) -> fmi2Status,
    pub fmi2NewDiscreteStates:
        unsafe extern "C" fn(c: fmi2Component, event_info: *mut fmi2EventInfo) -> fmi2Status,
    pub fmi2EnterContinuousTimeMode: unsafe extern "C" fn(c: fmi2Component) -> fmi2Status,
    pub fmi2CompletedIntegratorStep: unsafe extern "C" fn(
        c: fmi2Component,
        no_set_fmu_state_prior_to_current_point: fmi2Boolean,
        enter_event_mode: *mut fmi2Boolean,
        terminate_simulation: *mut fmi2Boolean,
    ) -> fmi2Status,
    pub fmi2SetTime: unsafe extern "C" fn(c: fmi2Component, time: fmi2Real) -> fmi2Status,
    pub fmi2SetContinuousStates:
        unsafe extern "C" fn(c: fmi2Component, x: *const fmi2Real, nx: usize) -> fmi2Status,
    pub fmi2GetDerivatives:
        unsafe extern "C" fn(c: fmi2Component, derivatives: *mut fmi2Real, nx: usize) -> fmi2Status,
    pub fmi2GetEventIndicators: unsafe extern "C" fn(
        c: fmi2Component,
        event_indicators: *mut fmi2Real,
        ni: usize,
    ) -> fmi2Status,
    pub fmi2GetContinuousStates:
        unsafe extern "C" fn(c: fmi2Component, x: *mut fmi2Real, nx: usize) -> fmi2Status,
    pub fmi2GetNominalsOfContinuousStates:
        unsafe extern "C" fn(c: fmi2Component, x_nominal: *mut fmi2Real, nx: usize) -> fmi2Status,
    pub fmi2SetRealInputDerivatives: unsafe extern "C" fn(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        order: *const fmi2Integer,
        value: *const fmi2Real,
    ) -> fmi2Status,
    pub fmi2GetRealOutputDerivatives: unsafe extern "C" fn(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        order: *const fmi2Integer,
        value: *mut fmi2Real,
    ) -> fmi2Status,
    pub fmi2DoStep: unsafe extern "C" fn(
        c: fmi2Component,
        tc: fmi2Real,
        h: fmi2Real,
        no_set_prior: fmi2Boolean,
    ) -> fmi2Status,
    pub fmi2CancelStep: unsafe extern "C" fn(c: fmi2Component) -> fmi2Status,
    pub fmi2GetStatus: unsafe extern "C" fn(
        c: fmi2Component,
        kind: fmi2StatusKind,
        value: *mut fmi2Status,
    ) -> fmi2Status,
    pub fmi2GetRealStatus: unsafe extern "C" fn(
        c: fmi2Component,
        kind: fmi2StatusKind,
        value: *mut fmi2Real,
    ) -> fmi2Status,
    pub fmi2GetIntegerStatus: unsafe extern "C" fn(
        c: fmi2Component,
        kind: fmi2StatusKind,
        value: *mut fmi2Integer,
    ) -> fmi2Status,
    pub fmi2GetBooleanStatus: unsafe extern "C" fn(
        c: fmi2Component,
        kind: fmi2StatusKind,
        value: *mut fmi2Boolean,
    ) -> fmi2Status,
    pub fmi2GetStringStatus: unsafe extern "C" fn(
        c: fmi2Component,
        kind: fmi2StatusKind,
        value: *mut fmi2String,
    ) -> fmi2Status,
}

/// The [`Functions`] of the core `$core` (a path from the crate root): the C functions the
/// FMU's build exports, made by the same macro without the exported symbol names. So the fuzz
/// targets and the replay of their corpora (tests/fuzz_replay.rs) reach every FMU from one build
/// of the library, whatever its features select for export.
macro_rules! functions {
    ($core:ty) => {{
        #[allow(dead_code)]
        mod c {
            hasel_fmu::__fmi2_functions!([] $core);
        }
        Functions {
            fmi2GetTypesPlatform: c::fmi2GetTypesPlatform,
            fmi2GetVersion: c::fmi2GetVersion,
            fmi2SetDebugLogging: c::fmi2SetDebugLogging,
            fmi2Instantiate: c::fmi2Instantiate,
            fmi2FreeInstance: c::fmi2FreeInstance,
            fmi2SetupExperiment: c::fmi2SetupExperiment,
            fmi2EnterInitializationMode: c::fmi2EnterInitializationMode,
            fmi2ExitInitializationMode: c::fmi2ExitInitializationMode,
            fmi2Terminate: c::fmi2Terminate,
            fmi2Reset: c::fmi2Reset,
            fmi2GetReal: c::fmi2GetReal,
            fmi2GetInteger: c::fmi2GetInteger,
            fmi2GetBoolean: c::fmi2GetBoolean,
            fmi2GetString: c::fmi2GetString,
            fmi2SetReal: c::fmi2SetReal,
            fmi2SetInteger: c::fmi2SetInteger,
            fmi2SetBoolean: c::fmi2SetBoolean,
            fmi2SetString: c::fmi2SetString,
            fmi2GetFMUstate: c::fmi2GetFMUstate,
            fmi2SetFMUstate: c::fmi2SetFMUstate,
            fmi2FreeFMUstate: c::fmi2FreeFMUstate,
            fmi2SerializedFMUstateSize: c::fmi2SerializedFMUstateSize,
            fmi2SerializeFMUstate: c::fmi2SerializeFMUstate,
            fmi2DeSerializeFMUstate: c::fmi2DeSerializeFMUstate,
            fmi2GetDirectionalDerivative: c::fmi2GetDirectionalDerivative,
            fmi2EnterEventMode: c::fmi2EnterEventMode,
            fmi2NewDiscreteStates: c::fmi2NewDiscreteStates,
            fmi2EnterContinuousTimeMode: c::fmi2EnterContinuousTimeMode,
            fmi2CompletedIntegratorStep: c::fmi2CompletedIntegratorStep,
            fmi2SetTime: c::fmi2SetTime,
            fmi2SetContinuousStates: c::fmi2SetContinuousStates,
            fmi2GetDerivatives: c::fmi2GetDerivatives,
            fmi2GetEventIndicators: c::fmi2GetEventIndicators,
            fmi2GetContinuousStates: c::fmi2GetContinuousStates,
            fmi2GetNominalsOfContinuousStates: c::fmi2GetNominalsOfContinuousStates,
            fmi2SetRealInputDerivatives: c::fmi2SetRealInputDerivatives,
            fmi2GetRealOutputDerivatives: c::fmi2GetRealOutputDerivatives,
            fmi2DoStep: c::fmi2DoStep,
            fmi2CancelStep: c::fmi2CancelStep,
            fmi2GetStatus: c::fmi2GetStatus,
            fmi2GetRealStatus: c::fmi2GetRealStatus,
            fmi2GetIntegerStatus: c::fmi2GetIntegerStatus,
            fmi2GetBooleanStatus: c::fmi2GetBooleanStatus,
            fmi2GetStringStatus: c::fmi2GetStringStatus,
        }
    }};
}

/// The logger of an importer written in C: variadic, printf-style (`fmi2CallbackLogger`).
/// Defining one in Rust takes the nightly feature `c_variadic`, so it is the caller's: the fuzz
/// targets define it (fmi2_logger.rs), the replay on stable Rust passes one declared with the
/// arguments the FMU passes (tests/fuzz_replay.rs says why that is sound). Both hand what they
/// got to [`read_log`].
pub type Logger = fmi2CallbackLogger;

/// Reads every string the FMU hands the logger (so AddressSanitizer checks each pointer under
/// `cargo fuzz`); `text` is the argument of the format "%s", the only format the FMU logs with.
pub fn read_log(name: fmi2String, category: fmi2String, message: fmi2String, text: fmi2String) {
    for p in [name, category, message, text] {
        if !p.is_null() {
            std::hint::black_box(unsafe { CStr::from_ptr(p) }.to_bytes().len());
        }
    }
}

/// The FMU a sequence runs against.
pub type Fmu = crate::common::Fmu<Functions>;

impl Fmu {
    /// HaselPlatform (target fmi2_calls).
    pub fn platform() -> Fmu {
        use hasel_fmu::fmu::{HaselCore, pack, variables::rows};
        Fmu::new::<HaselCore>(
            functions!(hasel_fmu::fmu::HaselCore),
            guid(&pack::platform(&Params::default())),
            rows().len(),
        )
    }

    /// HaselInverse, stateless and Co-Simulation only (target inverse_calls).
    pub fn inverse() -> Fmu {
        use hasel_fmu::fmu::inverse::{InverseCore, variables::rows};
        use hasel_fmu::fmu::pack;
        Fmu::new::<InverseCore>(
            functions!(hasel_fmu::fmu::inverse::InverseCore),
            guid(&pack::inverse(&Params::default())),
            rows().len(),
        )
    }

    /// HaselPlatformReduced, the slow model (target reduced_calls).
    pub fn reduced() -> Fmu {
        use hasel_fmu::fmu::{HaselReducedCore, pack, variables::rows_of};
        use hasel_fmu::model::Reduction;
        Fmu::new::<HaselReducedCore>(
            functions!(hasel_fmu::fmu::HaselReducedCore),
            guid(&pack::reduced(&Params::default())),
            rows_of(Reduction::Slow).len(),
        )
    }
}

unsafe extern "C" fn allocate(n: usize, size: usize) -> *mut c_void {
    unsafe { libc_calloc(n, size) }
}

unsafe extern "C" fn free(p: *mut c_void) {
    unsafe { libc_free(p) }
}

unsafe extern "C" {
    #[link_name = "calloc"]
    fn libc_calloc(n: usize, size: usize) -> *mut c_void;
    #[link_name = "free"]
    fn libc_free(p: *mut c_void);
}

/// One call of a sequence, with the arguments that matter.
#[derive(Arbitrary, Debug)]
pub enum Call {
    Instantiate {
        who: Who,
        model_exchange: bool,
        wrong_guid: bool,
        null_name: bool,
        null_callbacks: bool,
        resources: u8,
        logging_on: bool,
    },
    FreeInstance(Who),
    SetDebugLogging {
        who: Who,
        on: bool,
        categories: Vec<u8>,
        null_ptr: bool,
    },
    SetupExperiment {
        who: Who,
        tolerance: Option<Real>,
        start: Real,
        stop: Option<Real>,
    },
    EnterInitializationMode(Who),
    ExitInitializationMode(Who),
    Terminate(Who),
    Reset(Who),
    GetReal {
        who: Who,
        vrs: Vec<Vr>,
        null_ptr: bool,
    },
    SetReal {
        who: Who,
        values: Vec<(Vr, Real)>,
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
    },
    CancelStep(Who),
    Status {
        who: Who,
        kind: u8,
        status_kind: i8,
        null_ptr: bool,
    },
    InputOutputDerivatives {
        who: Who,
        set: bool,
        values: Vec<(Vr, i8, Real)>,
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
        from_get: bool,
    },
    GetVector {
        who: Who,
        kind: u8,
        len: Len,
        null_ptr: bool,
    },
    EnterEventMode(Who),
    NewDiscreteStates {
        who: Who,
        null_ptr: bool,
    },
    EnterContinuousTimeMode(Who),
    CompletedIntegratorStep {
        who: Who,
        no_prior: bool,
        null_ptr: bool,
    },
    DirectionalDerivative {
        who: Who,
        unknowns: Vec<Vr>,
        knowns: Vec<(Vr, Real)>,
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
                wrong_guid,
                null_name,
                null_callbacks,
                resources,
                logging_on,
            } => b
                .variant(0, N)
                .put(who)
                .put(model_exchange)
                .put(wrong_guid)
                .put(null_name)
                .put(null_callbacks)
                .put(resources)
                .put(logging_on),
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
            Call::SetupExperiment {
                who,
                tolerance,
                start,
                stop,
            } => b.variant(3, N).put(who).put(tolerance).put(start).put(stop),
            Call::EnterInitializationMode(who) => b.variant(4, N).put(who),
            Call::ExitInitializationMode(who) => b.variant(5, N).put(who),
            Call::Terminate(who) => b.variant(6, N).put(who),
            Call::Reset(who) => b.variant(7, N).put(who),
            Call::GetReal { who, vrs, null_ptr } => b.variant(8, N).put(who).put(vrs).put(null_ptr),
            Call::SetReal {
                who,
                values,
                null_ptr,
            } => b.variant(9, N).put(who).put(values).put(null_ptr),
            Call::OtherType {
                who,
                kind,
                vrs,
                value,
            } => b.variant(10, N).put(who).put(kind).put(vrs).put(value),
            Call::DoStep {
                who,
                at_current_time,
                t,
                h,
                no_prior,
            } => b
                .variant(11, N)
                .put(who)
                .put(at_current_time)
                .put(t)
                .put(h)
                .put(no_prior),
            Call::CancelStep(who) => b.variant(12, N).put(who),
            Call::Status {
                who,
                kind,
                status_kind,
                null_ptr,
            } => b
                .variant(13, N)
                .put(who)
                .put(kind)
                .put(status_kind)
                .put(null_ptr),
            Call::InputOutputDerivatives { who, set, values } => {
                b.variant(14, N).put(who).put(set).put(values)
            }
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
            Call::SetContinuousStates {
                who,
                len,
                x,
                from_get,
            } => b.variant(20, N).put(who).put(len).put(x).put(from_get),
            Call::GetVector {
                who,
                kind,
                len,
                null_ptr,
            } => b.variant(21, N).put(who).put(kind).put(len).put(null_ptr),
            Call::EnterEventMode(who) => b.variant(22, N).put(who),
            Call::NewDiscreteStates { who, null_ptr } => b.variant(23, N).put(who).put(null_ptr),
            Call::EnterContinuousTimeMode(who) => b.variant(24, N).put(who),
            Call::CompletedIntegratorStep {
                who,
                no_prior,
                null_ptr,
            } => b.variant(25, N).put(who).put(no_prior).put(null_ptr),
            Call::DirectionalDerivative {
                who,
                unknowns,
                knowns,
            } => b.variant(26, N).put(who).put(unknowns).put(knowns),
        };
    }
}

/// The calls of the seeds ([`crate::common::seeds`]) in FMI 2.0.
impl SeedCalls for Call {
    crate::common::seed_calls_alike!();

    fn start(who: Who, model_exchange: bool, _: bool, tolerance: Option<Real>) -> Vec<Call> {
        let mut calls = vec![
            Call::Instantiate {
                who,
                model_exchange,
                wrong_guid: false,
                null_name: false,
                null_callbacks: false,
                resources: 0,
                logging_on: false,
            },
            Call::SetupExperiment {
                who,
                tolerance,
                start: pick::ZERO,
                stop: None,
            },
            Call::EnterInitializationMode(who),
            Call::ExitInitializationMode(who),
        ];
        if model_exchange {
            calls.extend([
                Call::NewDiscreteStates {
                    who,
                    null_ptr: false,
                },
                Call::EnterContinuousTimeMode(who),
            ]);
        }
        calls
    }

    fn event(who: Who, model_exchange: bool) -> Vec<Call> {
        if !model_exchange {
            return vec![];
        }
        vec![
            Call::EnterEventMode(who),
            Call::NewDiscreteStates {
                who,
                null_ptr: false,
            },
            Call::EnterContinuousTimeMode(who),
        ]
    }

    fn set(who: Who, inputs: &[(u32, Real)]) -> Call {
        Call::SetReal {
            who,
            values: inputs.iter().map(|&(v, x)| (Vr::Any(v), x)).collect(),
            null_ptr: false,
        }
    }

    fn get(who: Who, outputs: &[u32]) -> Call {
        Call::GetReal {
            who,
            vrs: outputs.iter().map(|&v| Vr::Any(v)).collect(),
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
        }
    }

    fn perturb_states(who: Who) -> Call {
        Call::SetContinuousStates {
            who,
            len: Len::Right,
            x: vec![pick::MILLI],
            from_get: true,
        }
    }
}

/// What the sequence holds between calls: the instances, their simulated time, FMU states.
struct World<'a> {
    fmu: &'a Fmu,
    /// The FMU's functions (a copy of `fmu.functions`, for short calls).
    f: Functions,
    held: Held,
    callbacks: fmi2CallbackFunctions,
    reached: Reached,
}

/// The FMI 2.0 functions on instances and FMU states, with what instantiating one needs.
struct Shell<'a> {
    f: &'a Functions,
    token: &'a CStr,
    callbacks: &'a fmi2CallbackFunctions,
}

impl StateFunctions for Shell<'_> {
    unsafe fn get_state(&self, c: *mut c_void, state: *mut *mut c_void) -> bool {
        unsafe { (self.f.fmi2GetFMUstate)(c, state) == OK }
    }
    unsafe fn set_state(&self, c: *mut c_void, state: *mut c_void) -> bool {
        unsafe { (self.f.fmi2SetFMUstate)(c, state) == OK }
    }
    unsafe fn free_state(&self, c: *mut c_void, state: *mut *mut c_void) {
        unsafe { (self.f.fmi2FreeFMUstate)(c, state) };
    }
    unsafe fn serialized_size(&self, c: *mut c_void, state: *mut c_void, n: &mut usize) -> bool {
        unsafe { (self.f.fmi2SerializedFMUstateSize)(c, state, n) == OK }
    }
    unsafe fn serialize(&self, c: *mut c_void, state: *mut c_void, bytes: &mut [u8]) -> bool {
        let n = bytes.len();
        unsafe { (self.f.fmi2SerializeFMUstate)(c, state, bytes.as_mut_ptr().cast(), n) == OK }
    }
    unsafe fn deserialize(&self, c: *mut c_void, bytes: &[u8], state: *mut *mut c_void) -> bool {
        unsafe {
            (self.f.fmi2DeSerializeFMUstate)(c, bytes.as_ptr().cast(), bytes.len(), state) == OK
        }
    }
    unsafe fn free_instance(&self, c: *mut c_void) {
        unsafe { (self.f.fmi2FreeInstance)(c) };
    }
    unsafe fn cleanup_instance(&self) -> *mut c_void {
        unsafe {
            (self.f.fmi2Instantiate)(
                c"cleanup".as_ptr(),
                1,
                self.token.as_ptr(),
                null(),
                self.callbacks,
                0,
                0,
            )
        }
    }
    /// The FMU's own: `fmi2GetRealStatus(fmi2LastSuccessfulTime)`.
    unsafe fn restored_time(&self, c: *mut c_void, _: f64) -> f64 {
        let mut t = 0.0;
        unsafe { (self.f.fmi2GetRealStatus)(c, 2, &mut t) };
        t
    }
}

impl World<'_> {
    fn new(fmu: &Fmu, logger: Logger) -> World<'_> {
        World {
            fmu,
            f: fmu.functions,
            held: Held::new(),
            callbacks: fmi2CallbackFunctions {
                logger,
                allocate_memory: Some(allocate),
                free_memory: Some(free),
                step_finished: None,
                component_environment: null_mut(),
            },
            reached: Reached::default(),
        }
    }

    /// The instances and FMU states held, the functions that act on them, and what the
    /// sequence reached.
    fn parts(&mut self) -> (&mut Held, Shell<'_>, &mut Reached) {
        let shell = Shell {
            f: &self.f,
            token: &self.fmu.token,
            callbacks: &self.callbacks,
        };
        (&mut self.held, shell, &mut self.reached)
    }

    crate::common::state_calls!();

    fn len(&self, len: Len) -> usize {
        match len {
            Len::Right => self.fmu.states,
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
                wrong_guid,
                null_name,
                null_callbacks,
                resources,
                logging_on,
            } => {
                let Some(i) = Held::index(who) else { return };
                self.free_instance(i);
                let resources: &CStr = match resources % 4 {
                    0 => c"",
                    1 => c"file:///nonexistent/resources",
                    2 => c"not a uri",
                    _ => c"file:///tmp",
                };
                let guid = if wrong_guid {
                    c"{0}"
                } else {
                    self.fmu.token.as_c_str()
                };
                self.held.instances[i] = unsafe {
                    (self.f.fmi2Instantiate)(
                        if null_name { null() } else { c"fuzz".as_ptr() },
                        i32::from(!model_exchange),
                        guid.as_ptr(),
                        if resources.is_empty() {
                            null()
                        } else {
                            resources.as_ptr()
                        },
                        if null_callbacks {
                            null()
                        } else {
                            &self.callbacks
                        },
                        0,
                        i32::from(logging_on),
                    )
                };
            }
            Call::FreeInstance(who) => {
                if let Some(i) = Held::index(who) {
                    self.free_instance(i);
                } else {
                    unsafe { (self.f.fmi2FreeInstance)(null_mut()) };
                }
            }
            Call::SetDebugLogging {
                who,
                on,
                ref categories,
                null_ptr,
            } => {
                const NAMES: [&CStr; 4] = [c"logAll", c"logCalls", c"logError", c"nonsense"];
                let names: Vec<*const c_char> = categories
                    .iter()
                    .map(|&k| NAMES[k as usize % NAMES.len()].as_ptr())
                    .collect();
                let ptr = if null_ptr { null() } else { names.as_ptr() };
                unsafe {
                    (self.f.fmi2SetDebugLogging)(
                        self.held.instance(who),
                        i32::from(on),
                        names.len(),
                        ptr,
                    )
                };
            }
            Call::SetupExperiment {
                who,
                tolerance,
                start,
                stop,
            } => {
                let c = self.held.instance(who);
                let t0 = start.get();
                let status = unsafe {
                    (self.f.fmi2SetupExperiment)(
                        c,
                        i32::from(tolerance.is_some()),
                        tolerance.map_or(0.0, Real::get),
                        t0,
                        i32::from(stop.is_some()),
                        stop.map_or(0.0, Real::get),
                    )
                };
                if let (OK, Some(i)) = (status, Held::index(who)) {
                    self.held.time[i] = t0;
                }
            }
            Call::EnterInitializationMode(who) => unsafe {
                (self.f.fmi2EnterInitializationMode)(self.held.instance(who));
            },
            Call::ExitInitializationMode(who) => {
                let status =
                    unsafe { (self.f.fmi2ExitInitializationMode)(self.held.instance(who)) };
                self.reached.exit_initialization.add(status == OK);
            }
            Call::Terminate(who) => unsafe {
                (self.f.fmi2Terminate)(self.held.instance(who));
            },
            Call::Reset(who) => {
                let status = unsafe { (self.f.fmi2Reset)(self.held.instance(who)) };
                if let (OK, Some(i)) = (status, Held::index(who)) {
                    self.held.time[i] = 0.0;
                }
            }
            Call::GetReal {
                who,
                ref vrs,
                null_ptr,
            } => {
                let vrs: Vec<u32> = vrs.iter().map(|v| v.get(self.fmu.variables)).collect();
                let mut values = vec![0.0; vrs.len()];
                let out = if null_ptr {
                    null_mut()
                } else {
                    values.as_mut_ptr()
                };
                unsafe {
                    (self.f.fmi2GetReal)(self.held.instance(who), vrs.as_ptr(), vrs.len(), out)
                };
            }
            Call::SetReal {
                who,
                ref values,
                null_ptr,
            } => {
                let vrs: Vec<u32> = values
                    .iter()
                    .map(|(v, _)| v.get(self.fmu.variables))
                    .collect();
                let xs: Vec<f64> = values.iter().map(|(_, x)| x.get()).collect();
                let ptr = if null_ptr { null() } else { xs.as_ptr() };
                unsafe {
                    (self.f.fmi2SetReal)(self.held.instance(who), vrs.as_ptr(), vrs.len(), ptr)
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
                let mut strings = vec![c"x".as_ptr(); n];
                unsafe {
                    match kind % 6 {
                        0 => (self.f.fmi2GetInteger)(c, p, n, ints.as_mut_ptr()),
                        1 => (self.f.fmi2GetBoolean)(c, p, n, ints.as_mut_ptr()),
                        2 => (self.f.fmi2GetString)(c, p, n, strings.as_mut_ptr()),
                        3 => (self.f.fmi2SetInteger)(c, p, n, ints.as_ptr()),
                        4 => (self.f.fmi2SetBoolean)(c, p, n, ints.as_ptr()),
                        _ => (self.f.fmi2SetString)(c, p, n, strings.as_ptr()),
                    }
                };
            }
            Call::DoStep {
                who,
                at_current_time,
                t,
                h,
                no_prior,
            } => {
                let i = Held::index(who);
                let t = match (at_current_time, i) {
                    (true, Some(i)) => self.held.time[i],
                    _ => t.get(),
                };
                let h = h.get();
                let status = unsafe {
                    (self.f.fmi2DoStep)(self.held.instance(who), t, h, i32::from(no_prior))
                };
                self.reached.do_step.add(status == OK);
                if let (OK, Some(i)) = (status, i) {
                    self.held.time[i] = t + h;
                }
            }
            Call::CancelStep(who) => unsafe {
                (self.f.fmi2CancelStep)(self.held.instance(who));
            },
            Call::Status {
                who,
                kind,
                status_kind,
                null_ptr,
            } => {
                let c = self.held.instance(who);
                let k = fmi2StatusKind::from(status_kind);
                let mut status = OK;
                let mut real = 0.0;
                let mut int = 0;
                let mut string = null();
                unsafe {
                    match (kind % 5, null_ptr) {
                        (_, true) => (self.f.fmi2GetStatus)(c, k, null_mut()),
                        (0, _) => (self.f.fmi2GetStatus)(c, k, &mut status),
                        (1, _) => (self.f.fmi2GetRealStatus)(c, k, &mut real),
                        (2, _) => (self.f.fmi2GetIntegerStatus)(c, k, &mut int),
                        (3, _) => (self.f.fmi2GetBooleanStatus)(c, k, &mut int),
                        _ => (self.f.fmi2GetStringStatus)(c, k, &mut string),
                    }
                };
                if !string.is_null() {
                    std::hint::black_box(unsafe { CStr::from_ptr(string) }.to_bytes().len());
                }
            }
            Call::InputOutputDerivatives {
                who,
                set,
                ref values,
            } => {
                let c = self.held.instance(who);
                let vrs: Vec<u32> = values
                    .iter()
                    .map(|(v, _, _)| v.get(self.fmu.variables))
                    .collect();
                let orders: Vec<i32> = values.iter().map(|&(_, o, _)| i32::from(o)).collect();
                let mut xs: Vec<f64> = values.iter().map(|(_, _, x)| x.get()).collect();
                let n = vrs.len();
                unsafe {
                    if set {
                        (self.f.fmi2SetRealInputDerivatives)(
                            c,
                            vrs.as_ptr(),
                            n,
                            orders.as_ptr(),
                            xs.as_ptr(),
                        )
                    } else {
                        (self.f.fmi2GetRealOutputDerivatives)(
                            c,
                            vrs.as_ptr(),
                            n,
                            orders.as_ptr(),
                            xs.as_mut_ptr(),
                        )
                    }
                };
            }
            Call::GetFmuState { .. }
            | Call::SetFmuState { .. }
            | Call::FreeFmuState { .. }
            | Call::Serialize { .. } => self.run_state_call(call),
            Call::SetTime { who, t } => {
                let status = unsafe { (self.f.fmi2SetTime)(self.held.instance(who), t.get()) };
                if let (OK, Some(i)) = (status, Held::index(who)) {
                    self.held.time[i] = t.get();
                }
            }
            Call::SetContinuousStates {
                who,
                len,
                ref x,
                from_get,
            } => {
                let c = self.held.instance(who);
                let n = self.len(len);
                let mut xs: Vec<f64> = (0..n).map(|k| x.get(k).map_or(0.0, |r| r.get())).collect();
                if from_get {
                    // a valid state, perturbed where the sequence says
                    let mut got = vec![0.0; n];
                    if unsafe { (self.f.fmi2GetContinuousStates)(c, got.as_mut_ptr(), n) } == OK {
                        for (k, g) in got.iter().enumerate() {
                            xs[k] = if x.get(k).is_some() {
                                g * (1.0 + 1e-3 * xs[k])
                            } else {
                                *g
                            };
                        }
                    }
                }
                unsafe { (self.f.fmi2SetContinuousStates)(c, xs.as_ptr(), n) };
            }
            Call::GetVector {
                who,
                kind,
                len,
                null_ptr,
            } => {
                let c = self.held.instance(who);
                let n = match (kind % 4, len) {
                    (2, Len::Right) => 0, // no event indicators
                    _ => self.len(len),
                };
                let mut v = vec![0.0; n];
                let p = if null_ptr { null_mut() } else { v.as_mut_ptr() };
                let status = unsafe {
                    match kind % 4 {
                        0 => (self.f.fmi2GetContinuousStates)(c, p, n),
                        1 => (self.f.fmi2GetDerivatives)(c, p, n),
                        2 => (self.f.fmi2GetEventIndicators)(c, p, n),
                        _ => (self.f.fmi2GetNominalsOfContinuousStates)(c, p, n),
                    }
                };
                if kind % 4 == 1 {
                    self.reached.derivatives.add(status == OK);
                }
            }
            Call::EnterEventMode(who) => unsafe {
                (self.f.fmi2EnterEventMode)(self.held.instance(who));
            },
            Call::NewDiscreteStates { who, null_ptr } => {
                let mut info = fmi2EventInfo {
                    new_discrete_states_needed: 0,
                    terminate_simulation: 0,
                    nominals_of_continuous_states_changed: 0,
                    values_of_continuous_states_changed: 0,
                    next_event_time_defined: 0,
                    next_event_time: 0.0,
                };
                let p = if null_ptr {
                    null_mut()
                } else {
                    &mut info as *mut fmi2EventInfo
                };
                unsafe { (self.f.fmi2NewDiscreteStates)(self.held.instance(who), p) };
            }
            Call::EnterContinuousTimeMode(who) => unsafe {
                (self.f.fmi2EnterContinuousTimeMode)(self.held.instance(who));
            },
            Call::CompletedIntegratorStep {
                who,
                no_prior,
                null_ptr,
            } => {
                let (mut event, mut terminate) = (0, 0);
                let (e, t) = if null_ptr {
                    (null_mut(), null_mut())
                } else {
                    (&mut event as *mut i32, &mut terminate as *mut i32)
                };
                unsafe {
                    (self.f.fmi2CompletedIntegratorStep)(
                        self.held.instance(who),
                        i32::from(no_prior),
                        e,
                        t,
                    )
                };
            }
            Call::DirectionalDerivative {
                who,
                ref unknowns,
                ref knowns,
            } => {
                let unknowns: Vec<u32> =
                    unknowns.iter().map(|v| v.get(self.fmu.variables)).collect();
                let known_vrs: Vec<u32> = knowns
                    .iter()
                    .map(|(v, _)| v.get(self.fmu.variables))
                    .collect();
                let seeds: Vec<f64> = knowns.iter().map(|(_, x)| x.get()).collect();
                let mut out = vec![0.0; unknowns.len()];
                unsafe {
                    (self.f.fmi2GetDirectionalDerivative)(
                        self.held.instance(who),
                        unknowns.as_ptr(),
                        unknowns.len(),
                        known_vrs.as_ptr(),
                        known_vrs.len(),
                        seeds.as_ptr(),
                        out.as_mut_ptr(),
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

/// Runs a sequence (its first 64 calls) against `fmu`, whose instances log to `logger`, then
/// frees what it still holds: what the fuzz targets do with each input, and the replay with each
/// file of their corpora. Returns how deep it got.
pub fn run(fmu: &Fmu, logger: Logger, calls: &[Call]) -> Reached {
    unsafe {
        std::hint::black_box(CStr::from_ptr((fmu.functions.fmi2GetTypesPlatform)()));
        std::hint::black_box(CStr::from_ptr((fmu.functions.fmi2GetVersion)()));
    }
    let mut world = World::new(fmu, logger);
    for call in calls.iter().take(64) {
        world.run(call);
    }
    world.finish();
    world.reached
}
