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
//! a leak at the end of a sequence or a call that hangs fails the run.

use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::ptr::{null, null_mut};

use crate::common::{Len, Real, Vr, Who, damage};
use arbitrary::Arbitrary;
use hasel_fmu::fmi_common::model_api::FmuCore;
use hasel_fmu::fmu::pack::guid;
use hasel_fmu::model::Params;
use libfuzzer_sys::fuzz_target;

type Component = *mut c_void;
type FmuState = *mut c_void;
type Status = c_int;
const OK: Status = 0;

/// `fmi2CallbackFunctions`, as an importer declares it.
#[repr(C)]
struct Callbacks {
    logger: Option<
        unsafe extern "C" fn(*mut c_void, *const c_char, Status, *const c_char, *const c_char, ...),
    >,
    allocate: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    free: Option<unsafe extern "C" fn(*mut c_void)>,
    step_finished: Option<unsafe extern "C" fn(*mut c_void, Status)>,
    environment: *mut c_void,
}

/// `fmi2EventInfo`.
#[repr(C)]
#[derive(Default)]
struct EventInfo {
    new_discrete_states_needed: i32,
    terminate_simulation: i32,
    nominals_changed: i32,
    values_changed: i32,
    next_event_time_defined: i32,
    next_event_time: f64,
}

// The 44 functions of fmi2Functions.h, linked from the hasel-fmu library.
unsafe extern "C" {
    fn fmi2GetTypesPlatform() -> *const c_char;
    fn fmi2GetVersion() -> *const c_char;
    fn fmi2SetDebugLogging(
        c: Component,
        on: i32,
        n: usize,
        categories: *const *const c_char,
    ) -> Status;
    fn fmi2Instantiate(
        name: *const c_char,
        kind: c_int,
        guid: *const c_char,
        resources: *const c_char,
        callbacks: *const Callbacks,
        visible: i32,
        logging_on: i32,
    ) -> Component;
    fn fmi2FreeInstance(c: Component);
    fn fmi2SetupExperiment(
        c: Component,
        tol_on: i32,
        tol: f64,
        t0: f64,
        stop_on: i32,
        stop: f64,
    ) -> Status;
    fn fmi2EnterInitializationMode(c: Component) -> Status;
    fn fmi2ExitInitializationMode(c: Component) -> Status;
    fn fmi2Terminate(c: Component) -> Status;
    fn fmi2Reset(c: Component) -> Status;
    fn fmi2GetReal(c: Component, vr: *const u32, n: usize, v: *mut f64) -> Status;
    fn fmi2GetInteger(c: Component, vr: *const u32, n: usize, v: *mut i32) -> Status;
    fn fmi2GetBoolean(c: Component, vr: *const u32, n: usize, v: *mut i32) -> Status;
    fn fmi2GetString(c: Component, vr: *const u32, n: usize, v: *mut *const c_char) -> Status;
    fn fmi2SetReal(c: Component, vr: *const u32, n: usize, v: *const f64) -> Status;
    fn fmi2SetInteger(c: Component, vr: *const u32, n: usize, v: *const i32) -> Status;
    fn fmi2SetBoolean(c: Component, vr: *const u32, n: usize, v: *const i32) -> Status;
    fn fmi2SetString(c: Component, vr: *const u32, n: usize, v: *const *const c_char) -> Status;
    fn fmi2GetFMUstate(c: Component, s: *mut FmuState) -> Status;
    fn fmi2SetFMUstate(c: Component, s: FmuState) -> Status;
    fn fmi2FreeFMUstate(c: Component, s: *mut FmuState) -> Status;
    fn fmi2SerializedFMUstateSize(c: Component, s: FmuState, size: *mut usize) -> Status;
    fn fmi2SerializeFMUstate(c: Component, s: FmuState, bytes: *mut c_char, size: usize) -> Status;
    fn fmi2DeSerializeFMUstate(
        c: Component,
        bytes: *const c_char,
        size: usize,
        s: *mut FmuState,
    ) -> Status;
    fn fmi2GetDirectionalDerivative(
        c: Component,
        unknowns: *const u32,
        n_unknowns: usize,
        knowns: *const u32,
        n_knowns: usize,
        dv_known: *const f64,
        dv_unknown: *mut f64,
    ) -> Status;
    fn fmi2EnterEventMode(c: Component) -> Status;
    fn fmi2NewDiscreteStates(c: Component, info: *mut EventInfo) -> Status;
    fn fmi2EnterContinuousTimeMode(c: Component) -> Status;
    fn fmi2CompletedIntegratorStep(
        c: Component,
        no_prior: i32,
        enter_event_mode: *mut i32,
        terminate: *mut i32,
    ) -> Status;
    fn fmi2SetTime(c: Component, t: f64) -> Status;
    fn fmi2SetContinuousStates(c: Component, x: *const f64, n: usize) -> Status;
    fn fmi2GetDerivatives(c: Component, dx: *mut f64, n: usize) -> Status;
    fn fmi2GetEventIndicators(c: Component, z: *mut f64, n: usize) -> Status;
    fn fmi2GetContinuousStates(c: Component, x: *mut f64, n: usize) -> Status;
    fn fmi2GetNominalsOfContinuousStates(c: Component, x: *mut f64, n: usize) -> Status;
    fn fmi2SetRealInputDerivatives(
        c: Component,
        vr: *const u32,
        n: usize,
        order: *const i32,
        v: *const f64,
    ) -> Status;
    fn fmi2GetRealOutputDerivatives(
        c: Component,
        vr: *const u32,
        n: usize,
        order: *const i32,
        v: *mut f64,
    ) -> Status;
    fn fmi2DoStep(c: Component, t: f64, h: f64, no_prior: i32) -> Status;
    fn fmi2CancelStep(c: Component) -> Status;
    fn fmi2GetStatus(c: Component, kind: c_int, v: *mut Status) -> Status;
    fn fmi2GetRealStatus(c: Component, kind: c_int, v: *mut f64) -> Status;
    fn fmi2GetIntegerStatus(c: Component, kind: c_int, v: *mut i32) -> Status;
    fn fmi2GetBooleanStatus(c: Component, kind: c_int, v: *mut i32) -> Status;
    fn fmi2GetStringStatus(c: Component, kind: c_int, v: *mut *const c_char) -> Status;
}

/// Reads every string the FMU hands the logger, so AddressSanitizer checks each pointer.
unsafe extern "C" fn logger(
    _env: *mut c_void,
    name: *const c_char,
    _status: Status,
    category: *const c_char,
    message: *const c_char,
    mut args: ...
) {
    for p in [name, category, message] {
        if !p.is_null() {
            std::hint::black_box(unsafe { CStr::from_ptr(p) }.to_bytes().len());
        }
    }
    // the FMU logs through the format "%s" with one string argument
    if !message.is_null() && unsafe { CStr::from_ptr(message) } == c"%s" {
        let text: *const c_char = unsafe { args.next_arg() };
        std::hint::black_box(unsafe { CStr::from_ptr(text) }.to_bytes().len());
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

#[derive(Arbitrary, Debug)]
enum Call {
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

const STATE_SLOTS: usize = 4;

// The FMU under test: HaselPlatform, or with the feature `inverse` (target inverse_calls) the
// stateless HaselInverse, with `reduced` (target reduced_calls) HaselPlatformReduced, whose
// functions the library's `inverse-fmu` and `reduced-fmu` builds export instead.
#[cfg(feature = "inverse")]
use hasel_fmu::fmu::inverse::{InverseCore as Core, spec};
#[cfg(not(any(feature = "inverse", feature = "reduced")))]
use hasel_fmu::fmu::{HaselCore as Core, pack::platform as spec};
#[cfg(feature = "reduced")]
use hasel_fmu::fmu::{HaselReducedCore as Core, pack::reduced as spec};

/// What the sequence holds between calls: the instances, their simulated time, FMU states.
struct World {
    instances: [Component; 2],
    time: [f64; 2],
    states: [FmuState; STATE_SLOTS],
    /// The owner of each FMU state, which is also the instance that frees it.
    owner: [usize; STATE_SLOTS],
    callbacks: Callbacks,
    guid: CString,
    states_expected: usize,
}

impl World {
    fn new() -> World {
        World {
            instances: [null_mut(); 2],
            time: [0.0; 2],
            states: [null_mut(); STATE_SLOTS],
            owner: [0; STATE_SLOTS],
            callbacks: Callbacks {
                logger: Some(logger),
                allocate: Some(allocate),
                free: Some(free),
                step_finished: None,
                environment: null_mut(),
            },
            guid: CString::new(guid(&spec(&Params::default()))).unwrap(),
            states_expected: Core::model_structure().derivatives.len(),
        }
    }

    fn component(&self, who: Who) -> Component {
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

    fn len(&self, len: Len) -> usize {
        match len {
            Len::Right => self.states_expected,
            Len::Other(n) => n as usize,
        }
    }

    /// Frees the FMU states of instance `i` and the instance: what an importer does at the end.
    fn free_instance(&mut self, i: usize) {
        let c = self.instances[i];
        if c.is_null() {
            return;
        }
        for k in 0..STATE_SLOTS {
            if self.owner[k] == i && !self.states[k].is_null() {
                // a refused free (the instance may be in a state that does not allow it)
                // leaves the pointer with us: `finish` frees it through a fresh instance
                unsafe { fmi2FreeFMUstate(c, &mut self.states[k]) };
            }
        }
        unsafe { fmi2FreeInstance(c) };
        self.instances[i] = null_mut();
        self.time[i] = 0.0;
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
                let Some(i) = World::index(who) else { return };
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
                    self.guid.as_c_str()
                };
                self.instances[i] = unsafe {
                    fmi2Instantiate(
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
                if let Some(i) = World::index(who) {
                    self.free_instance(i);
                } else {
                    unsafe { fmi2FreeInstance(null_mut()) };
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
                    fmi2SetDebugLogging(self.component(who), i32::from(on), names.len(), ptr)
                };
            }
            Call::SetupExperiment {
                who,
                tolerance,
                start,
                stop,
            } => {
                let c = self.component(who);
                let t0 = start.get();
                let status = unsafe {
                    fmi2SetupExperiment(
                        c,
                        i32::from(tolerance.is_some()),
                        tolerance.map_or(0.0, Real::get),
                        t0,
                        i32::from(stop.is_some()),
                        stop.map_or(0.0, Real::get),
                    )
                };
                if let (OK, Some(i)) = (status, World::index(who)) {
                    self.time[i] = t0;
                }
            }
            Call::EnterInitializationMode(who) => unsafe {
                fmi2EnterInitializationMode(self.component(who));
            },
            Call::ExitInitializationMode(who) => unsafe {
                fmi2ExitInitializationMode(self.component(who));
            },
            Call::Terminate(who) => unsafe {
                fmi2Terminate(self.component(who));
            },
            Call::Reset(who) => {
                let status = unsafe { fmi2Reset(self.component(who)) };
                if let (OK, Some(i)) = (status, World::index(who)) {
                    self.time[i] = 0.0;
                }
            }
            Call::GetReal {
                who,
                ref vrs,
                null_ptr,
            } => {
                let vrs: Vec<u32> = vrs.iter().map(|v| v.get()).collect();
                let mut values = vec![0.0; vrs.len()];
                let out = if null_ptr {
                    null_mut()
                } else {
                    values.as_mut_ptr()
                };
                unsafe { fmi2GetReal(self.component(who), vrs.as_ptr(), vrs.len(), out) };
            }
            Call::SetReal {
                who,
                ref values,
                null_ptr,
            } => {
                let vrs: Vec<u32> = values.iter().map(|(v, _)| v.get()).collect();
                let xs: Vec<f64> = values.iter().map(|(_, x)| x.get()).collect();
                let ptr = if null_ptr { null() } else { xs.as_ptr() };
                unsafe { fmi2SetReal(self.component(who), vrs.as_ptr(), vrs.len(), ptr) };
            }
            Call::OtherType {
                who,
                kind,
                ref vrs,
                value,
            } => {
                let c = self.component(who);
                let vrs: Vec<u32> = vrs.iter().map(|v| v.get()).collect();
                let (p, n) = (vrs.as_ptr(), vrs.len());
                let mut ints = vec![value; n];
                let mut strings = vec![c"x".as_ptr(); n];
                unsafe {
                    match kind % 6 {
                        0 => fmi2GetInteger(c, p, n, ints.as_mut_ptr()),
                        1 => fmi2GetBoolean(c, p, n, ints.as_mut_ptr()),
                        2 => fmi2GetString(c, p, n, strings.as_mut_ptr()),
                        3 => fmi2SetInteger(c, p, n, ints.as_ptr()),
                        4 => fmi2SetBoolean(c, p, n, ints.as_ptr()),
                        _ => fmi2SetString(c, p, n, strings.as_ptr()),
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
                let i = World::index(who);
                let t = match (at_current_time, i) {
                    (true, Some(i)) => self.time[i],
                    _ => t.get(),
                };
                let h = h.get();
                let status = unsafe { fmi2DoStep(self.component(who), t, h, i32::from(no_prior)) };
                if let (OK, Some(i)) = (status, i) {
                    self.time[i] = t + h;
                }
            }
            Call::CancelStep(who) => unsafe {
                fmi2CancelStep(self.component(who));
            },
            Call::Status {
                who,
                kind,
                status_kind,
                null_ptr,
            } => {
                let c = self.component(who);
                let k = c_int::from(status_kind);
                let mut status = 0;
                let mut real = 0.0;
                let mut int = 0;
                let mut string = null();
                unsafe {
                    match (kind % 5, null_ptr) {
                        (_, true) => fmi2GetStatus(c, k, null_mut()),
                        (0, _) => fmi2GetStatus(c, k, &mut status),
                        (1, _) => fmi2GetRealStatus(c, k, &mut real),
                        (2, _) => fmi2GetIntegerStatus(c, k, &mut int),
                        (3, _) => fmi2GetBooleanStatus(c, k, &mut int),
                        _ => fmi2GetStringStatus(c, k, &mut string),
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
                let c = self.component(who);
                let vrs: Vec<u32> = values.iter().map(|(v, _, _)| v.get()).collect();
                let orders: Vec<i32> = values.iter().map(|&(_, o, _)| i32::from(o)).collect();
                let mut xs: Vec<f64> = values.iter().map(|(_, _, x)| x.get()).collect();
                let n = vrs.len();
                unsafe {
                    if set {
                        fmi2SetRealInputDerivatives(
                            c,
                            vrs.as_ptr(),
                            n,
                            orders.as_ptr(),
                            xs.as_ptr(),
                        )
                    } else {
                        fmi2GetRealOutputDerivatives(
                            c,
                            vrs.as_ptr(),
                            n,
                            orders.as_ptr(),
                            xs.as_mut_ptr(),
                        )
                    }
                };
            }
            Call::GetFmuState {
                who,
                slot,
                null_ptr,
            } => {
                let k = slot as usize % STATE_SLOTS;
                let c = self.component(who);
                if null_ptr {
                    unsafe { fmi2GetFMUstate(c, null_mut()) };
                    return;
                }
                // into a free slot a new state; into a taken one the standard's update
                // of that state in place (its owner must be the instance asked)
                if !self.states[k].is_null() && World::index(who) != Some(self.owner[k]) {
                    return;
                }
                let status = unsafe { fmi2GetFMUstate(c, &mut self.states[k]) };
                if let (OK, Some(i)) = (status, World::index(who)) {
                    self.owner[k] = i;
                }
            }
            Call::SetFmuState { who, slot } => {
                let s = self.states[slot as usize % STATE_SLOTS];
                let status = unsafe { fmi2SetFMUstate(self.component(who), s) };
                if let (OK, Some(i)) = (status, World::index(who)) {
                    let mut t = 0.0;
                    unsafe { fmi2GetRealStatus(self.instances[i], 2, &mut t) };
                    self.time[i] = t;
                }
            }
            Call::FreeFmuState { who, slot } => {
                let k = slot as usize % STATE_SLOTS;
                if World::index(who) != Some(self.owner[k]) && !self.states[k].is_null() {
                    // another instance's state: only a NULL handle may go elsewhere
                    unsafe { fmi2FreeFMUstate(self.component(who), null_mut()) };
                    return;
                }
                unsafe { fmi2FreeFMUstate(self.component(who), &mut self.states[k]) };
            }
            Call::Serialize {
                who,
                slot,
                size,
                ref corrupt,
                truncate,
                fix_checksum,
                into,
            } => self.serialize(who, slot, size, corrupt, truncate, fix_checksum, into),
            Call::SetTime { who, t } => {
                let status = unsafe { fmi2SetTime(self.component(who), t.get()) };
                if let (OK, Some(i)) = (status, World::index(who)) {
                    self.time[i] = t.get();
                }
            }
            Call::SetContinuousStates {
                who,
                len,
                ref x,
                from_get,
            } => {
                let c = self.component(who);
                let n = self.len(len);
                let mut xs: Vec<f64> = (0..n).map(|k| x.get(k).map_or(0.0, |r| r.get())).collect();
                if from_get {
                    // a valid state, perturbed where the sequence says
                    let mut got = vec![0.0; n];
                    if unsafe { fmi2GetContinuousStates(c, got.as_mut_ptr(), n) } == OK {
                        for (k, g) in got.iter().enumerate() {
                            xs[k] = if x.get(k).is_some() {
                                g * (1.0 + 1e-3 * xs[k])
                            } else {
                                *g
                            };
                        }
                    }
                }
                unsafe { fmi2SetContinuousStates(c, xs.as_ptr(), n) };
            }
            Call::GetVector {
                who,
                kind,
                len,
                null_ptr,
            } => {
                let c = self.component(who);
                let n = match (kind % 4, len) {
                    (2, Len::Right) => 0, // no event indicators
                    _ => self.len(len),
                };
                let mut v = vec![0.0; n];
                let p = if null_ptr { null_mut() } else { v.as_mut_ptr() };
                unsafe {
                    match kind % 4 {
                        0 => fmi2GetContinuousStates(c, p, n),
                        1 => fmi2GetDerivatives(c, p, n),
                        2 => fmi2GetEventIndicators(c, p, n),
                        _ => fmi2GetNominalsOfContinuousStates(c, p, n),
                    }
                };
            }
            Call::EnterEventMode(who) => unsafe {
                fmi2EnterEventMode(self.component(who));
            },
            Call::NewDiscreteStates { who, null_ptr } => {
                let mut info = EventInfo::default();
                let p = if null_ptr {
                    null_mut()
                } else {
                    &mut info as *mut EventInfo
                };
                unsafe { fmi2NewDiscreteStates(self.component(who), p) };
            }
            Call::EnterContinuousTimeMode(who) => unsafe {
                fmi2EnterContinuousTimeMode(self.component(who));
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
                    fmi2CompletedIntegratorStep(self.component(who), i32::from(no_prior), e, t)
                };
            }
            Call::DirectionalDerivative {
                who,
                ref unknowns,
                ref knowns,
            } => {
                let unknowns: Vec<u32> = unknowns.iter().map(|v| v.get()).collect();
                let known_vrs: Vec<u32> = knowns.iter().map(|(v, _)| v.get()).collect();
                let seeds: Vec<f64> = knowns.iter().map(|(_, x)| x.get()).collect();
                let mut out = vec![0.0; unknowns.len()];
                unsafe {
                    fmi2GetDirectionalDerivative(
                        self.component(who),
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

    /// Serializes the state in `slot` (with a buffer of the right size or another), damages
    /// the bytes as told and deserializes them into slot `into`.
    #[allow(clippy::too_many_arguments)]
    fn serialize(
        &mut self,
        who: Who,
        slot: u8,
        size: Len,
        corrupt: &[(u16, u8)],
        truncate: Option<u16>,
        fix_checksum: bool,
        into: u8,
    ) {
        let c = self.component(who);
        let s = self.states[slot as usize % STATE_SLOTS];
        let mut n = 0usize;
        if unsafe { fmi2SerializedFMUstateSize(c, s, &mut n) } != OK {
            return;
        }
        let n = match size {
            Len::Right => n,
            Len::Other(k) => k as usize,
        };
        let mut bytes = vec![0u8; n];
        if unsafe { fmi2SerializeFMUstate(c, s, bytes.as_mut_ptr().cast(), n) } != OK {
            return;
        }
        damage(&mut bytes, corrupt, truncate, fix_checksum);
        let k = into as usize % STATE_SLOTS;
        let Some(i) = World::index(who) else {
            unsafe { fmi2DeSerializeFMUstate(c, bytes.as_ptr().cast(), bytes.len(), null_mut()) };
            return;
        };
        if !self.states[k].is_null() && self.owner[k] != i {
            return;
        }
        let status = unsafe {
            fmi2DeSerializeFMUstate(c, bytes.as_ptr().cast(), bytes.len(), &mut self.states[k])
        };
        if status == OK {
            self.owner[k] = i;
        }
    }

    /// The end of a sequence: everything still held is freed, so leaks show.
    fn finish(&mut self) {
        for i in 0..2 {
            self.free_instance(i);
        }
        // states whose owner was replaced by a new instance: freed through any instance
        for k in 0..STATE_SLOTS {
            if !self.states[k].is_null() {
                let c = unsafe {
                    fmi2Instantiate(
                        c"cleanup".as_ptr(),
                        1,
                        self.guid.as_ptr(),
                        null(),
                        &self.callbacks,
                        0,
                        0,
                    )
                };
                unsafe {
                    fmi2FreeFMUstate(c, &mut self.states[k]);
                    fmi2FreeInstance(c);
                }
                assert!(self.states[k].is_null(), "fmi2FreeFMUstate kept a state");
            }
        }
    }
}

fuzz_target!(|calls: Vec<Call>| {
    unsafe {
        std::hint::black_box(CStr::from_ptr(fmi2GetTypesPlatform()));
        std::hint::black_box(CStr::from_ptr(fmi2GetVersion()));
    }
    let mut world = World::new();
    for call in calls.iter().take(64) {
        world.run(call);
    }
    world.finish();
});
