//! Random FMI 3.0 call sequences against an FMU's C entry points (HaselPlatform's FMI 3.0 build in
//! target fmi3_calls, HaselPlatformReduced's in reduced_fmi3_calls), right and wrong: two instances
//! (Co-Simulation or Model Exchange), NULL pointers, unknown value references, wrong array sizes,
//! NaN and infinite values, calls of every type's getters and setters, calls in the wrong state,
//! FMU states passed between instances, serialized states truncated or corrupted (also with a
//! recomputed checksum). The sequence keeps only the caller's side of the contract that no FMU can
//! check: no pointer is used after it was freed and every array holds as many elements as the size
//! passed with it.
//!
//! Under libFuzzer with AddressSanitizer (`bash ci/fuzz.sh`) a crash, an out-of-bounds access,
//! a leak at the end of a sequence or a call that hangs fails the run.

use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::ptr::{null, null_mut};

use crate::common::{Len, Real, Vr, Who, damage};
use arbitrary::Arbitrary;
use hasel_fmu::fmi_common::model_api::FmuCore;
use hasel_fmu::fmu::pack::FmiVersion;
use hasel_fmu::model::Params;
use libfuzzer_sys::fuzz_target;

type Instance = *mut c_void;
type FmuState = *mut c_void;
type Status = c_int;
const OK: Status = 0;

type LogMessage = unsafe extern "C" fn(*mut c_void, Status, *const c_char, *const c_char);

// The functions of fmi3Functions.h that this model's FMU serves or refuses.
unsafe extern "C" {
    fn fmi3GetVersion() -> *const c_char;
    fn fmi3SetDebugLogging(
        c: Instance,
        on: bool,
        n: usize,
        categories: *const *const c_char,
    ) -> Status;
    fn fmi3InstantiateModelExchange(
        name: *const c_char,
        token: *const c_char,
        resources: *const c_char,
        visible: bool,
        logging_on: bool,
        environment: *mut c_void,
        log: Option<LogMessage>,
    ) -> Instance;
    fn fmi3InstantiateCoSimulation(
        name: *const c_char,
        token: *const c_char,
        resources: *const c_char,
        visible: bool,
        logging_on: bool,
        event_mode_used: bool,
        early_return_allowed: bool,
        required_intermediate: *const u32,
        n_required_intermediate: usize,
        environment: *mut c_void,
        log: Option<LogMessage>,
        intermediate_update: *const c_void,
    ) -> Instance;
    fn fmi3FreeInstance(c: Instance);
    fn fmi3EnterInitializationMode(
        c: Instance,
        tol_on: bool,
        tol: f64,
        t0: f64,
        stop_on: bool,
        stop: f64,
    ) -> Status;
    fn fmi3ExitInitializationMode(c: Instance) -> Status;
    fn fmi3EnterEventMode(c: Instance) -> Status;
    fn fmi3Terminate(c: Instance) -> Status;
    fn fmi3Reset(c: Instance) -> Status;
    fn fmi3GetFloat64(c: Instance, vr: *const u32, nvr: usize, v: *mut f64, nv: usize) -> Status;
    fn fmi3SetFloat64(c: Instance, vr: *const u32, nvr: usize, v: *const f64, nv: usize) -> Status;
    fn fmi3GetFloat32(c: Instance, vr: *const u32, nvr: usize, v: *mut f32, nv: usize) -> Status;
    fn fmi3GetInt32(c: Instance, vr: *const u32, nvr: usize, v: *mut i32, nv: usize) -> Status;
    fn fmi3GetUInt64(c: Instance, vr: *const u32, nvr: usize, v: *mut u64, nv: usize) -> Status;
    fn fmi3GetBoolean(c: Instance, vr: *const u32, nvr: usize, v: *mut bool, nv: usize) -> Status;
    fn fmi3GetString(
        c: Instance,
        vr: *const u32,
        nvr: usize,
        v: *mut *const c_char,
        nv: usize,
    ) -> Status;
    fn fmi3SetInt32(c: Instance, vr: *const u32, nvr: usize, v: *const i32, nv: usize) -> Status;
    fn fmi3SetBoolean(c: Instance, vr: *const u32, nvr: usize, v: *const bool, nv: usize)
    -> Status;
    fn fmi3SetString(
        c: Instance,
        vr: *const u32,
        nvr: usize,
        v: *const *const c_char,
        nv: usize,
    ) -> Status;
    fn fmi3GetFMUState(c: Instance, s: *mut FmuState) -> Status;
    fn fmi3SetFMUState(c: Instance, s: FmuState) -> Status;
    fn fmi3FreeFMUState(c: Instance, s: *mut FmuState) -> Status;
    fn fmi3SerializedFMUStateSize(c: Instance, s: FmuState, size: *mut usize) -> Status;
    fn fmi3SerializeFMUState(c: Instance, s: FmuState, bytes: *mut u8, size: usize) -> Status;
    fn fmi3DeserializeFMUState(
        c: Instance,
        bytes: *const u8,
        size: usize,
        s: *mut FmuState,
    ) -> Status;
    fn fmi3GetDirectionalDerivative(
        c: Instance,
        unknowns: *const u32,
        n_unknowns: usize,
        knowns: *const u32,
        n_knowns: usize,
        seed: *const f64,
        n_seed: usize,
        sensitivity: *mut f64,
        n_sensitivity: usize,
    ) -> Status;
    fn fmi3GetAdjointDerivative(
        c: Instance,
        unknowns: *const u32,
        n_unknowns: usize,
        knowns: *const u32,
        n_knowns: usize,
        seed: *const f64,
        n_seed: usize,
        sensitivity: *mut f64,
        n_sensitivity: usize,
    ) -> Status;
    fn fmi3EnterConfigurationMode(c: Instance) -> Status;
    fn fmi3ExitConfigurationMode(c: Instance) -> Status;
    fn fmi3UpdateDiscreteStates(
        c: Instance,
        update_needed: *mut bool,
        terminate: *mut bool,
        nominals_changed: *mut bool,
        values_changed: *mut bool,
        next_time_defined: *mut bool,
        next_time: *mut f64,
    ) -> Status;
    fn fmi3EnterContinuousTimeMode(c: Instance) -> Status;
    fn fmi3CompletedIntegratorStep(
        c: Instance,
        no_prior: bool,
        enter_event_mode: *mut bool,
        terminate: *mut bool,
    ) -> Status;
    fn fmi3SetTime(c: Instance, t: f64) -> Status;
    fn fmi3SetContinuousStates(c: Instance, x: *const f64, n: usize) -> Status;
    fn fmi3GetContinuousStateDerivatives(c: Instance, dx: *mut f64, n: usize) -> Status;
    fn fmi3GetEventIndicators(c: Instance, z: *mut f64, n: usize) -> Status;
    fn fmi3GetContinuousStates(c: Instance, x: *mut f64, n: usize) -> Status;
    fn fmi3GetNominalsOfContinuousStates(c: Instance, x: *mut f64, n: usize) -> Status;
    fn fmi3GetNumberOfEventIndicators(c: Instance, n: *mut usize) -> Status;
    fn fmi3GetNumberOfContinuousStates(c: Instance, n: *mut usize) -> Status;
    fn fmi3EnterStepMode(c: Instance) -> Status;
    fn fmi3GetOutputDerivatives(
        c: Instance,
        vr: *const u32,
        nvr: usize,
        orders: *const i32,
        v: *mut f64,
        nv: usize,
    ) -> Status;
    fn fmi3DoStep(
        c: Instance,
        t: f64,
        h: f64,
        no_prior: bool,
        event_handling_needed: *mut bool,
        terminate: *mut bool,
        early_return: *mut bool,
        last_successful_time: *mut f64,
    ) -> Status;
}

/// Reads every string the FMU hands the logger, so AddressSanitizer checks each pointer.
unsafe extern "C" fn log_message(
    _env: *mut c_void,
    _status: Status,
    category: *const c_char,
    message: *const c_char,
) {
    for p in [category, message] {
        if !p.is_null() {
            std::hint::black_box(unsafe { CStr::from_ptr(p) }.to_bytes().len());
        }
    }
}

#[derive(Arbitrary, Debug)]
enum Call {
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

const STATE_SLOTS: usize = 4;

// The FMU under test: HaselPlatform, or with the feature `reduced` (target reduced_fmi3_calls)
// HaselPlatformReduced, whose functions the library's `reduced-fmu,fmi3` build exports instead.
#[cfg(not(feature = "reduced"))]
use hasel_fmu::fmu::{HaselCore as Core, pack::platform as spec};
#[cfg(feature = "reduced")]
use hasel_fmu::fmu::{HaselReducedCore as Core, pack::reduced as spec};

/// What the sequence holds between calls: the instances, their simulated time, FMU states.
struct World {
    instances: [Instance; 2],
    time: [f64; 2],
    states: [FmuState; STATE_SLOTS],
    owner: [usize; STATE_SLOTS],
    token: CString,
    states_expected: usize,
}

impl World {
    fn new() -> World {
        World {
            instances: [null_mut(); 2],
            time: [0.0; 2],
            states: [null_mut(); STATE_SLOTS],
            owner: [0; STATE_SLOTS],
            token: CString::new(FmiVersion::V3.token(&spec(&Params::default()))).unwrap(),
            states_expected: Core::model_structure().derivatives.len(),
        }
    }

    fn instance(&self, who: Who) -> Instance {
        match who {
            Who::First => self.instances[0],
            Who::Second => self.instances[1],
            Who::Null => null_mut(),
        }
    }

    fn index(who: Who) -> Option<usize> {
        match who {
            Who::First => Some(0),
            Who::Second => Some(1),
            Who::Null => None,
        }
    }

    fn len(&self, len: Len, right: usize) -> usize {
        match len {
            Len::Right => right,
            Len::Other(n) => n as usize,
        }
    }

    fn free_instance(&mut self, i: usize) {
        let c = self.instances[i];
        if c.is_null() {
            return;
        }
        for k in 0..STATE_SLOTS {
            if self.owner[k] == i && !self.states[k].is_null() {
                // a refused free leaves the pointer with us: `finish` frees it
                unsafe { fmi3FreeFMUState(c, &mut self.states[k]) };
            }
        }
        unsafe { fmi3FreeInstance(c) };
        self.instances[i] = null_mut();
        self.time[i] = 0.0;
    }

    /// A Co-Simulation instance of this FMU, quiet: for freeing states whose owner is gone.
    fn cleanup_instance(&self) -> Instance {
        unsafe {
            fmi3InstantiateCoSimulation(
                c"cleanup".as_ptr(),
                self.token.as_ptr(),
                null(),
                false,
                false,
                false,
                false,
                null(),
                0,
                null_mut(),
                None,
                null(),
            )
        }
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
                let Some(i) = World::index(who) else { return };
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
                    self.token.as_c_str()
                };
                let name = if null_name { null() } else { c"fuzz".as_ptr() };
                let log = if no_logger {
                    None
                } else {
                    Some(log_message as LogMessage)
                };
                self.instances[i] = unsafe {
                    if model_exchange {
                        fmi3InstantiateModelExchange(
                            name,
                            token.as_ptr(),
                            resources,
                            false,
                            logging_on,
                            null_mut(),
                            log,
                        )
                    } else {
                        fmi3InstantiateCoSimulation(
                            name,
                            token.as_ptr(),
                            resources,
                            false,
                            logging_on,
                            event_mode_used,
                            false,
                            null(),
                            0,
                            null_mut(),
                            log,
                            null(),
                        )
                    }
                };
            }
            Call::FreeInstance(who) => match World::index(who) {
                Some(i) => self.free_instance(i),
                None => unsafe { fmi3FreeInstance(null_mut()) },
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
                unsafe { fmi3SetDebugLogging(self.instance(who), on, names.len(), p) };
            }
            Call::EnterInitializationMode {
                who,
                tolerance,
                start,
                stop,
            } => {
                let t0 = start.get();
                let status = unsafe {
                    fmi3EnterInitializationMode(
                        self.instance(who),
                        tolerance.is_some(),
                        tolerance.map_or(0.0, Real::get),
                        t0,
                        stop.is_some(),
                        stop.map_or(0.0, Real::get),
                    )
                };
                if let (OK, Some(i)) = (status, World::index(who)) {
                    self.time[i] = t0;
                }
            }
            Call::ExitInitializationMode(who) => unsafe {
                fmi3ExitInitializationMode(self.instance(who));
            },
            Call::EnterEventMode(who) => unsafe {
                fmi3EnterEventMode(self.instance(who));
            },
            Call::Terminate(who) => unsafe {
                fmi3Terminate(self.instance(who));
            },
            Call::Reset(who) => {
                let status = unsafe { fmi3Reset(self.instance(who)) };
                if let (OK, Some(i)) = (status, World::index(who)) {
                    self.time[i] = 0.0;
                }
            }
            Call::Configuration { who, enter } => unsafe {
                if enter {
                    fmi3EnterConfigurationMode(self.instance(who));
                } else {
                    fmi3ExitConfigurationMode(self.instance(who));
                }
            },
            Call::GetFloat64 {
                who,
                ref vrs,
                values,
                null_ptr,
            } => {
                let vrs: Vec<u32> = vrs.iter().map(|v| v.get()).collect();
                let n = self.len(values, vrs.len());
                let mut out = vec![0.0; n];
                let p = if null_ptr {
                    null_mut()
                } else {
                    out.as_mut_ptr()
                };
                unsafe { fmi3GetFloat64(self.instance(who), vrs.as_ptr(), vrs.len(), p, n) };
            }
            Call::SetFloat64 {
                who,
                ref values,
                n_values,
                null_ptr,
            } => {
                let vrs: Vec<u32> = values.iter().map(|(v, _)| v.get()).collect();
                let n = self.len(n_values, vrs.len());
                let xs: Vec<f64> = (0..n)
                    .map(|k| values.get(k).map_or(1.0, |(_, x)| x.get()))
                    .collect();
                let p = if null_ptr { null() } else { xs.as_ptr() };
                unsafe { fmi3SetFloat64(self.instance(who), vrs.as_ptr(), vrs.len(), p, n) };
            }
            Call::OtherType {
                who,
                kind,
                ref vrs,
                value,
            } => {
                let c = self.instance(who);
                let vrs: Vec<u32> = vrs.iter().map(|v| v.get()).collect();
                let (p, n) = (vrs.as_ptr(), vrs.len());
                let mut ints = vec![value; n];
                let mut bools = vec![value % 2 == 0; n];
                let mut floats = vec![value as f32; n];
                let mut longs = vec![value as u64; n];
                let mut strings = vec![c"x".as_ptr(); n];
                unsafe {
                    match kind % 8 {
                        0 => fmi3GetInt32(c, p, n, ints.as_mut_ptr(), n),
                        1 => fmi3GetBoolean(c, p, n, bools.as_mut_ptr(), n),
                        2 => fmi3GetString(c, p, n, strings.as_mut_ptr(), n),
                        3 => fmi3GetFloat32(c, p, n, floats.as_mut_ptr(), n),
                        4 => fmi3GetUInt64(c, p, n, longs.as_mut_ptr(), n),
                        5 => fmi3SetInt32(c, p, n, ints.as_ptr(), n),
                        6 => fmi3SetBoolean(c, p, n, bools.as_ptr(), n),
                        _ => fmi3SetString(c, p, n, strings.as_ptr(), n),
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
                let i = World::index(who);
                let t = match (at_current_time, i) {
                    (true, Some(i)) => self.time[i],
                    _ => t.get(),
                };
                let (mut event, mut terminate, mut early) = (false, false, false);
                let mut last = 0.0;
                let status = unsafe {
                    if null_outputs {
                        fmi3DoStep(
                            self.instance(who),
                            t,
                            h.get(),
                            no_prior,
                            null_mut(),
                            null_mut(),
                            null_mut(),
                            null_mut(),
                        )
                    } else {
                        fmi3DoStep(
                            self.instance(who),
                            t,
                            h.get(),
                            no_prior,
                            &mut event,
                            &mut terminate,
                            &mut early,
                            &mut last,
                        )
                    }
                };
                if let (OK, Some(i)) = (status, i) {
                    self.time[i] = t + h.get();
                }
            }
            Call::EnterStepMode(who) => unsafe {
                fmi3EnterStepMode(self.instance(who));
            },
            Call::OutputDerivatives { who, ref values } => {
                let vrs: Vec<u32> = values.iter().map(|(v, _)| v.get()).collect();
                let orders: Vec<i32> = values.iter().map(|&(_, o)| i32::from(o)).collect();
                let mut out = vec![0.0; vrs.len()];
                unsafe {
                    fmi3GetOutputDerivatives(
                        self.instance(who),
                        vrs.as_ptr(),
                        vrs.len(),
                        orders.as_ptr(),
                        out.as_mut_ptr(),
                        out.len(),
                    )
                };
            }
            Call::GetFmuState {
                who,
                slot,
                null_ptr,
            } => {
                let k = slot as usize % STATE_SLOTS;
                let c = self.instance(who);
                if null_ptr {
                    unsafe { fmi3GetFMUState(c, null_mut()) };
                    return;
                }
                if !self.states[k].is_null() && World::index(who) != Some(self.owner[k]) {
                    return;
                }
                let status = unsafe { fmi3GetFMUState(c, &mut self.states[k]) };
                if let (OK, Some(i)) = (status, World::index(who)) {
                    self.owner[k] = i;
                }
            }
            Call::SetFmuState { who, slot } => {
                let s = self.states[slot as usize % STATE_SLOTS];
                unsafe { fmi3SetFMUState(self.instance(who), s) };
                // the restored time is unknown here: steps at the current time may now be
                // refused, which is part of what is fuzzed
            }
            Call::FreeFmuState { who, slot } => {
                let k = slot as usize % STATE_SLOTS;
                if World::index(who) != Some(self.owner[k]) && !self.states[k].is_null() {
                    unsafe { fmi3FreeFMUState(self.instance(who), null_mut()) };
                    return;
                }
                unsafe { fmi3FreeFMUState(self.instance(who), &mut self.states[k]) };
            }
            Call::Serialize {
                who,
                slot,
                size,
                ref corrupt,
                truncate,
                fix_checksum,
                into,
            } => {
                let c = self.instance(who);
                let s = self.states[slot as usize % STATE_SLOTS];
                let mut n = 0usize;
                if unsafe { fmi3SerializedFMUStateSize(c, s, &mut n) } != OK {
                    return;
                }
                let n = self.len(size, n);
                let mut bytes = vec![0u8; n];
                if unsafe { fmi3SerializeFMUState(c, s, bytes.as_mut_ptr(), n) } != OK {
                    return;
                }
                damage(&mut bytes, corrupt, truncate, fix_checksum);
                let k = into as usize % STATE_SLOTS;
                let Some(i) = World::index(who) else {
                    unsafe { fmi3DeserializeFMUState(c, bytes.as_ptr(), bytes.len(), null_mut()) };
                    return;
                };
                if !self.states[k].is_null() && self.owner[k] != i {
                    return;
                }
                let status = unsafe {
                    fmi3DeserializeFMUState(c, bytes.as_ptr(), bytes.len(), &mut self.states[k])
                };
                if status == OK {
                    self.owner[k] = i;
                }
            }
            Call::SetTime { who, t } => unsafe {
                fmi3SetTime(self.instance(who), t.get());
            },
            Call::SetContinuousStates { who, len, ref x } => {
                let c = self.instance(who);
                let n = self.len(len, self.states_expected);
                let mut got = vec![0.0; n];
                let valid = unsafe { fmi3GetContinuousStates(c, got.as_mut_ptr(), n) } == OK;
                let xs: Vec<f64> = (0..n)
                    .map(|k| match (x.get(k), valid) {
                        (Some(r), true) => got[k] * (1.0 + 1e-3 * r.get()),
                        (Some(r), false) => r.get(),
                        (None, _) => got[k],
                    })
                    .collect();
                unsafe { fmi3SetContinuousStates(c, xs.as_ptr(), n) };
            }
            Call::GetVector {
                who,
                kind,
                len,
                null_ptr,
            } => {
                let c = self.instance(who);
                let right = if kind % 4 == 2 {
                    0
                } else {
                    self.states_expected
                };
                let n = self.len(len, right);
                let mut v = vec![0.0; n];
                let p = if null_ptr { null_mut() } else { v.as_mut_ptr() };
                unsafe {
                    match kind % 4 {
                        0 => fmi3GetContinuousStates(c, p, n),
                        1 => fmi3GetContinuousStateDerivatives(c, p, n),
                        2 => fmi3GetEventIndicators(c, p, n),
                        _ => fmi3GetNominalsOfContinuousStates(c, p, n),
                    }
                };
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
                        fmi3GetNumberOfContinuousStates(self.instance(who), p)
                    } else {
                        fmi3GetNumberOfEventIndicators(self.instance(who), p)
                    }
                };
            }
            Call::UpdateDiscreteStates { who, null_ptr } => {
                let mut flags = [false; 5];
                let mut next = 0.0;
                let [a, b, c, d, e] = &mut flags;
                unsafe {
                    if null_ptr {
                        fmi3UpdateDiscreteStates(
                            self.instance(who),
                            null_mut(),
                            null_mut(),
                            null_mut(),
                            null_mut(),
                            null_mut(),
                            null_mut(),
                        )
                    } else {
                        fmi3UpdateDiscreteStates(self.instance(who), a, b, c, d, e, &mut next)
                    }
                };
            }
            Call::EnterContinuousTimeMode(who) => unsafe {
                fmi3EnterContinuousTimeMode(self.instance(who));
            },
            Call::CompletedIntegratorStep {
                who,
                no_prior,
                null_ptr,
            } => {
                let (mut event, mut terminate) = (false, false);
                unsafe {
                    if null_ptr {
                        fmi3CompletedIntegratorStep(
                            self.instance(who),
                            no_prior,
                            null_mut(),
                            null_mut(),
                        )
                    } else {
                        fmi3CompletedIntegratorStep(
                            self.instance(who),
                            no_prior,
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
                let unknowns: Vec<u32> = unknowns.iter().map(|v| v.get()).collect();
                let known_vrs: Vec<u32> = knowns.iter().map(|(v, _)| v.get()).collect();
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
                    fmi3GetAdjointDerivative
                } else {
                    fmi3GetDirectionalDerivative
                };
                unsafe {
                    f(
                        self.instance(who),
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
        for i in 0..2 {
            self.free_instance(i);
        }
        for k in 0..STATE_SLOTS {
            if !self.states[k].is_null() {
                let c = self.cleanup_instance();
                unsafe {
                    fmi3FreeFMUState(c, &mut self.states[k]);
                    fmi3FreeInstance(c);
                }
                assert!(self.states[k].is_null(), "fmi3FreeFMUState kept a state");
            }
        }
    }
}

fuzz_target!(|calls: Vec<Call>| {
    unsafe { std::hint::black_box(CStr::from_ptr(fmi3GetVersion())) };
    let mut world = World::new();
    for call in calls.iter().take(64) {
        world.run(call);
    }
    world.finish();
});
