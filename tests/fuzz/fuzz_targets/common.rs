//! What the call-sequence fuzzers of both FMI versions share: the arguments a sequence
//! chooses (reals, value references, array lengths, which instance) and their meaning. With
//! fmi2_sequence.rs and fmi3_sequence.rs also a module of tests/fuzz_replay.rs, which replays
//! the committed corpora through the same code in the ordinary build. Also what a sequence
//! reached ([`Reached`]) and the writer of inputs ([`Bytes`], [`Encode`]) with which the seeds of
//! the corpora are made (tests/fuzz_replay.rs, `write_seeds`).

use std::ffi::{CString, c_void};
use std::ptr::null_mut;

use arbitrary::Arbitrary;
use hasel_fmu::fmi_common::model_api::FmuCore;
use sha2::{Digest, Sha256};

/// The FMU a sequence runs against: its C functions `F` (a table of one FMI version's) and what
/// an importer reads from its description.
pub struct Fmu<F> {
    pub functions: F,
    /// The GUID (FMI 2.0) or instantiation token (FMI 3.0).
    pub token: CString,
    /// The number of continuous states.
    pub states: usize,
    /// The number of variables (value references 0..variables).
    pub variables: u32,
}

impl<F> Fmu<F> {
    pub fn new<Core: FmuCore>(functions: F, token: String, variables: usize) -> Fmu<F> {
        Fmu {
            functions,
            token: CString::new(token).unwrap(),
            states: Core::model_structure().derivatives.len(),
            variables: variables as u32,
        }
    }
}

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
    /// The value reference, for an FMU with `variables` variables (references 0..variables).
    pub fn get(self, variables: u32) -> u32 {
        match self {
            Vr::Known(k) => k as u32 % variables,
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

/// How many FMU states a sequence holds at once.
pub const STATE_SLOTS: usize = 4;

/// One FMI version's C functions on instances and FMU states, which the sequences of both
/// versions call alike ([`Held`]); each returns whether the call returned OK.
pub trait StateFunctions {
    unsafe fn get_state(&self, c: *mut c_void, state: *mut *mut c_void) -> bool;
    unsafe fn set_state(&self, c: *mut c_void, state: *mut c_void) -> bool;
    unsafe fn free_state(&self, c: *mut c_void, state: *mut *mut c_void);
    unsafe fn serialized_size(&self, c: *mut c_void, state: *mut c_void, n: &mut usize) -> bool;
    unsafe fn serialize(&self, c: *mut c_void, state: *mut c_void, bytes: &mut [u8]) -> bool;
    unsafe fn deserialize(&self, c: *mut c_void, bytes: &[u8], state: *mut *mut c_void) -> bool;
    unsafe fn free_instance(&self, c: *mut c_void);
    /// A quiet Co-Simulation instance of the FMU, for freeing states whose owner is gone.
    unsafe fn cleanup_instance(&self) -> *mut c_void;
    /// The time of instance `c` after it was set to a state taken at `taken_at`.
    unsafe fn restored_time(&self, c: *mut c_void, taken_at: f64) -> f64;
}

/// What a sequence holds between calls, whatever the FMI version: two instances, their
/// simulated time, and FMU states with the instance that owns (and frees) each.
pub struct Held {
    pub instances: [*mut c_void; 2],
    pub time: [f64; 2],
    pub states: [*mut c_void; STATE_SLOTS],
    pub owner: [usize; STATE_SLOTS],
    /// The time each FMU state was taken at.
    pub state_time: [f64; STATE_SLOTS],
}

impl Held {
    pub fn new() -> Held {
        Held {
            instances: [null_mut(); 2],
            time: [0.0; 2],
            states: [null_mut(); STATE_SLOTS],
            owner: [0; STATE_SLOTS],
            state_time: [0.0; STATE_SLOTS],
        }
    }

    pub fn instance(&self, who: Who) -> *mut c_void {
        Held::index(who).map_or(null_mut(), |i| self.instances[i])
    }

    pub fn index(who: Who) -> Option<usize> {
        match who {
            Who::First => Some(0),
            Who::Second => Some(1),
            Who::Null => None,
        }
    }

    /// `fmi*GetFMUState` into `slot`: into a free slot a new state; into a taken one the
    /// standard's update of that state in place (its owner must be the instance asked).
    pub fn get_state(&mut self, f: &impl StateFunctions, who: Who, slot: u8, null_ptr: bool) {
        let k = slot as usize % STATE_SLOTS;
        let c = self.instance(who);
        if null_ptr {
            unsafe { f.get_state(c, null_mut()) };
            return;
        }
        if !self.states[k].is_null() && Held::index(who) != Some(self.owner[k]) {
            return;
        }
        let ok = unsafe { f.get_state(c, &mut self.states[k]) };
        if let (true, Some(i)) = (ok, Held::index(who)) {
            self.owner[k] = i;
            self.state_time[k] = self.time[i];
        }
    }

    /// `fmi*SetFMUState` from `slot`.
    pub fn set_state(&mut self, f: &impl StateFunctions, who: Who, slot: u8) {
        let k = slot as usize % STATE_SLOTS;
        let ok = unsafe { f.set_state(self.instance(who), self.states[k]) };
        if let (true, Some(i)) = (ok, Held::index(who)) {
            self.time[i] = unsafe { f.restored_time(self.instances[i], self.state_time[k]) };
        }
    }

    /// `fmi*FreeFMUState` of `slot`; another instance's state only as a NULL handle.
    pub fn free_state(&mut self, f: &impl StateFunctions, who: Who, slot: u8) {
        let k = slot as usize % STATE_SLOTS;
        if Held::index(who) != Some(self.owner[k]) && !self.states[k].is_null() {
            unsafe { f.free_state(self.instance(who), null_mut()) };
            return;
        }
        unsafe { f.free_state(self.instance(who), &mut self.states[k]) };
    }

    /// Serializes the state in `slot` (with a buffer of the right size or another), damages
    /// the bytes as told ([`damage`]) and deserializes them into slot `into`.
    #[allow(clippy::too_many_arguments)]
    pub fn serialize(
        &mut self,
        f: &impl StateFunctions,
        who: Who,
        slot: u8,
        size: Len,
        corrupt: &[(u16, u8)],
        truncate: Option<u16>,
        fix_checksum: bool,
        into: u8,
        serialized: &mut Count,
    ) {
        let c = self.instance(who);
        let from = slot as usize % STATE_SLOTS;
        let s = self.states[from];
        let mut n = 0usize;
        if !unsafe { f.serialized_size(c, s, &mut n) } {
            return;
        }
        let n = match size {
            Len::Right => n,
            Len::Other(k) => k as usize,
        };
        let mut bytes = vec![0u8; n];
        let ok = unsafe { f.serialize(c, s, &mut bytes) };
        serialized.add(ok);
        if !ok {
            return;
        }
        damage(&mut bytes, corrupt, truncate, fix_checksum);
        let k = into as usize % STATE_SLOTS;
        let Some(i) = Held::index(who) else {
            unsafe { f.deserialize(c, &bytes, null_mut()) };
            return;
        };
        if !self.states[k].is_null() && self.owner[k] != i {
            return;
        }
        if unsafe { f.deserialize(c, &bytes, &mut self.states[k]) } {
            self.owner[k] = i;
            self.state_time[k] = self.state_time[from];
        }
    }

    /// Frees the FMU states of instance `i` and the instance: what an importer does at the end.
    pub fn free_instance(&mut self, f: &impl StateFunctions, i: usize) {
        let c = self.instances[i];
        if c.is_null() {
            return;
        }
        for k in 0..STATE_SLOTS {
            if self.owner[k] == i && !self.states[k].is_null() {
                // a refused free (the instance may be in a state that does not allow it)
                // leaves the pointer with us: `finish` frees it through a fresh instance
                unsafe { f.free_state(c, &mut self.states[k]) };
            }
        }
        unsafe { f.free_instance(c) };
        self.instances[i] = null_mut();
        self.time[i] = 0.0;
    }

    /// The end of a sequence: everything still held is freed, so leaks show.
    pub fn finish(&mut self, f: &impl StateFunctions) {
        for i in 0..2 {
            self.free_instance(f, i);
        }
        // states whose owner was replaced by a new instance: freed through any instance
        for k in 0..STATE_SLOTS {
            if !self.states[k].is_null() {
                unsafe {
                    let c = f.cleanup_instance();
                    f.free_state(c, &mut self.states[k]);
                    f.free_instance(c);
                }
                assert!(self.states[k].is_null(), "fmi*FreeFMUState kept a state");
            }
        }
    }
}

/// The arms of the calls on FMU states, which both versions' `Call` spell alike: a method
/// `run_state_call` of the sequence's `World` (whose `parts` gives what the calls act on) that
/// runs `call` if it is one of them.
macro_rules! state_calls {
    () => {
        fn run_state_call(&mut self, call: &Call) {
            let (held, shell, reached) = self.parts();
            match *call {
                Call::GetFmuState {
                    who,
                    slot,
                    null_ptr,
                } => held.get_state(&shell, who, slot, null_ptr),
                Call::SetFmuState { who, slot } => held.set_state(&shell, who, slot),
                Call::FreeFmuState { who, slot } => held.free_state(&shell, who, slot),
                Call::Serialize {
                    who,
                    slot,
                    size,
                    ref corrupt,
                    truncate,
                    fix_checksum,
                    into,
                } => held.serialize(
                    &shell,
                    who,
                    slot,
                    size,
                    corrupt,
                    truncate,
                    fix_checksum,
                    into,
                    &mut reached.serialize,
                ),
                _ => {}
            }
        }
    };
}
pub(crate) use state_calls;

/// How many of one kind of call a sequence made, and how many returned OK.
#[derive(Default, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Count {
    pub calls: u64,
    pub ok: u64,
}

impl Count {
    pub fn add(&mut self, ok: bool) {
        self.calls += 1;
        self.ok += u64::from(ok);
    }
}

/// How deep a sequence got: the calls that only succeed on an instance past initialization
/// (and the one that gets it there), counted by the interpreters and summed by the replay,
/// which asserts a floor on them so a corpus that stops reaching them fails.
#[derive(Default, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reached {
    /// `fmi*ExitInitializationMode`.
    pub exit_initialization: Count,
    /// `fmi*DoStep` (Co-Simulation).
    pub do_step: Count,
    /// `fmi2GetDerivatives` / `fmi3GetContinuousStateDerivatives` (Model Exchange).
    pub derivatives: Count,
    /// `fmi*SerializeFMU*state` (an FMU state written into bytes).
    pub serialize: Count,
}

impl std::ops::AddAssign for Reached {
    fn add_assign(&mut self, other: Reached) {
        for (a, b) in [
            (&mut self.exit_initialization, other.exit_initialization),
            (&mut self.do_step, other.do_step),
            (&mut self.derivatives, other.derivatives),
            (&mut self.serialize, other.serialize),
        ] {
            a.calls += b.calls;
            a.ok += b.ok;
        }
    }
}

/// An input in the byte format in which `arbitrary` 1.x decodes a value (what libFuzzer's Rust
/// harness, `fuzz_target!`, does with each input): integers little-endian in their width, a
/// `bool` one byte (its low bit), an `f64` its bits, an enum's variant `k` of `n` a `u32` whose
/// product with `n`, shifted right by 32, is `k`, then its fields in order; an `Option` a `bool`
/// then the value; a `Vec` each element after a byte 1, then a byte 0. A sequence (the whole
/// input) is its calls, each after a byte 1. The round trip (decode what is written, get the same
/// value) is checked by tests/fuzz_replay.rs for every kind of call.
#[derive(Default)]
pub struct Bytes(pub Vec<u8>);

impl Bytes {
    pub fn variant(&mut self, k: u32, n: u32) -> &mut Bytes {
        let x = ((u64::from(k) << 32).div_ceil(u64::from(n))) as u32;
        self.put(&x)
    }

    pub fn put<T: Encode + ?Sized>(&mut self, x: &T) -> &mut Bytes {
        x.encode(self);
        self
    }

    /// The input that decodes into the sequence `calls`.
    pub fn sequence<C: Encode>(calls: &[C]) -> Vec<u8> {
        let mut b = Bytes::default();
        for c in calls {
            b.put(&true).put(c);
        }
        b.0
    }
}

/// A value written as `arbitrary` reads it (see [`Bytes`]).
pub trait Encode {
    fn encode(&self, b: &mut Bytes);
}

macro_rules! encode_le {
    ($($t:ty),*) => {$(
        impl Encode for $t {
            fn encode(&self, b: &mut Bytes) {
                b.0.extend_from_slice(&self.to_le_bytes());
            }
        }
    )*};
}
encode_le!(u8, i8, u16, u32, i32, f64);

impl Encode for bool {
    fn encode(&self, b: &mut Bytes) {
        b.put(&u8::from(*self));
    }
}

impl<T: Encode> Encode for Option<T> {
    fn encode(&self, b: &mut Bytes) {
        b.put(&self.is_some());
        if let Some(x) = self {
            b.put(x);
        }
    }
}

impl<T: Encode> Encode for Vec<T> {
    fn encode(&self, b: &mut Bytes) {
        for x in self {
            b.put(&true).put(x);
        }
        b.put(&false);
    }
}

impl<A: Encode, B: Encode> Encode for (A, B) {
    fn encode(&self, b: &mut Bytes) {
        b.put(&self.0).put(&self.1);
    }
}

impl<A: Encode, B: Encode, C: Encode> Encode for (A, B, C) {
    fn encode(&self, b: &mut Bytes) {
        b.put(&self.0).put(&self.1).put(&self.2);
    }
}

impl Encode for Real {
    fn encode(&self, b: &mut Bytes) {
        match self {
            Real::Pick(k) => b.variant(0, 2).put(k),
            Real::Raw(x) => b.variant(1, 2).put(x),
        };
    }
}

impl Encode for Vr {
    fn encode(&self, b: &mut Bytes) {
        match self {
            Vr::Known(k) => b.variant(0, 2).put(k),
            Vr::Any(v) => b.variant(1, 2).put(v),
        };
    }
}

impl Encode for Len {
    fn encode(&self, b: &mut Bytes) {
        match self {
            Len::Right => b.variant(0, 2),
            Len::Other(n) => b.variant(1, 2).put(n),
        };
    }
}

impl Encode for Who {
    fn encode(&self, b: &mut Bytes) {
        b.variant(*self as u32, 3);
    }
}

/// The calls the seeds are made of, in one FMI version's terms (fmi2_sequence.rs and
/// fmi3_sequence.rs implement it for their `Call`), so [`seeds`] writes the sequences once.
pub trait SeedCalls: Sized {
    /// Instantiate (the right token, no resources), set up at time 0 and initialize: a
    /// Co-Simulation instance ends ready to step (out of Event Mode when `event_mode_used`, which
    /// only FMI 3.0 has), a Model Exchange one in Continuous-Time Mode.
    fn start(
        who: Who,
        model_exchange: bool,
        event_mode_used: bool,
        tolerance: Option<Real>,
    ) -> Vec<Self>;
    /// An event iteration: into Event Mode, the discrete states updated, and back to stepping
    /// or to Continuous-Time Mode (none for an FMI 2.0 Co-Simulation instance, which has none).
    fn event(who: Who, model_exchange: bool) -> Vec<Self>;
    fn set(who: Who, inputs: &[(u32, Real)]) -> Self;
    fn get(who: Who, outputs: &[u32]) -> Self;
    /// A step at the instance's current time.
    fn step(who: Who, h: Real) -> Self;
    fn get_state(who: Who, slot: u8) -> Self;
    fn set_state(who: Who, slot: u8) -> Self;
    /// The state in `slot` serialized and deserialized into `into`; `damaged`: a bit flipped
    /// behind a recomputed checksum.
    fn serialize(who: Who, slot: u8, into: u8, damaged: bool) -> Self;
    /// The vector `kind` (0 states, 1 derivatives, 2 event indicators, 3 nominals).
    fn vector(who: Who, kind: u8) -> Self;
    fn set_time(who: Who, t: Real) -> Self;
    /// The continuous states set to those got, perturbed.
    fn perturb_states(who: Who) -> Self;
    fn completed_integrator_step(who: Who) -> Self;
    fn terminate(who: Who) -> Self;
    fn reset(who: Who) -> Self;
    fn free(who: Who) -> Self;
}

/// The [`SeedCalls`] whose calls are the same in both versions' `Call` (variants and fields of
/// the same names), written once: used inside each version's `impl SeedCalls for Call`.
macro_rules! seed_calls_alike {
    () => {
        fn get_state(who: Who, slot: u8) -> Call {
            Call::GetFmuState {
                who,
                slot,
                null_ptr: false,
            }
        }

        fn set_state(who: Who, slot: u8) -> Call {
            Call::SetFmuState { who, slot }
        }

        fn serialize(who: Who, slot: u8, into: u8, damaged: bool) -> Call {
            Call::Serialize {
                who,
                slot,
                size: Len::Right,
                corrupt: if damaged { vec![(40, 1)] } else { vec![] },
                truncate: None,
                fix_checksum: damaged,
                into,
            }
        }

        fn vector(who: Who, kind: u8) -> Call {
            Call::GetVector {
                who,
                kind,
                len: Len::Right,
                null_ptr: false,
            }
        }

        fn set_time(who: Who, t: Real) -> Call {
            Call::SetTime { who, t }
        }

        fn completed_integrator_step(who: Who) -> Call {
            Call::CompletedIntegratorStep {
                who,
                no_prior: false,
                null_ptr: false,
            }
        }

        fn terminate(who: Who) -> Call {
            Call::Terminate(who)
        }

        fn reset(who: Who) -> Call {
            Call::Reset(who)
        }

        fn free(who: Who) -> Call {
            Call::FreeInstance(who)
        }
    };
}
pub(crate) use seed_calls_alike;

/// The seeds of a call-sequence corpus: sequences an importer makes, that take instances through
/// the whole life of an FMU (instantiate, set up, initialize, set inputs, step or integrate, get
/// outputs, get, set and serialize states, terminate, reset, free), for an FMU with the
/// value references `inputs` (set to their values) and `outputs` (read). The campaigns start
/// from them (`bash ci/fuzz.sh` writes them into the corpora first: tests/fuzz_replay.rs,
/// `write_seeds`), so the fuzzer mutates sequences that reach stepping and the solver instead of
/// having to find each step of the valid path by chance (no campaign without them got an instance
/// past initialization); the mutations keep sending every wrong call too.
pub fn seeds<C: SeedCalls>(inputs: &[(u32, Real)], outputs: &[u32]) -> Vec<(&'static str, Vec<C>)> {
    use Who::{First, Second};
    let mut co_simulation = C::start(First, false, false, Some(pick::MILLI));
    co_simulation.extend([
        C::set(First, inputs),
        C::step(First, pick::MILLI),
        C::get(First, outputs),
        C::step(First, pick::ONE),
        C::get(First, outputs),
        C::get_state(First, 0),
        C::serialize(First, 0, 1, false),
        C::set(First, inputs),
        C::step(First, pick::MILLI),
        C::set_state(First, 1),
        C::step(First, pick::MILLI),
        C::get(First, outputs),
        C::terminate(First),
        C::reset(First),
    ]);
    co_simulation.extend(C::start(First, false, false, None));
    co_simulation.extend([
        C::step(First, pick::TEN),
        C::get(First, outputs),
        C::free(First),
    ]);

    // two instances (the second with event mode used), a state passed between them, serialized
    // and damaged past its checksum
    let mut two = C::start(First, false, false, None);
    two.extend(C::start(Second, false, true, Some(pick::MILLI)));
    two.extend([
        C::set(First, inputs),
        C::step(First, pick::ONE),
        C::get_state(First, 2),
        C::step(Second, pick::MILLI),
    ]);
    two.extend(C::event(Second, false));
    two.extend([
        C::set_state(Second, 2),
        C::step(Second, pick::MILLI),
        C::serialize(First, 2, 3, true),
        C::serialize(Second, 2, 0, false),
        C::set_state(First, 0),
        C::step(First, pick::MILLI),
        C::get(Second, outputs),
    ]);

    // Model Exchange: an importer's integrator (explicit Euler) around the FMU
    let mut model_exchange = C::start(First, true, false, None);
    for t in [pick::MILLI, Real::Raw(2e-3), Real::Raw(3e-3)] {
        model_exchange.extend([
            C::set(First, inputs),
            C::vector(First, 0),
            C::vector(First, 1),
            C::set_time(First, t),
            C::perturb_states(First),
            C::completed_integrator_step(First),
            C::get(First, outputs),
        ]);
    }
    model_exchange.extend([
        C::vector(First, 3),
        C::vector(First, 2),
        C::get_state(First, 0),
        C::serialize(First, 0, 1, false),
        C::set_state(First, 1),
        C::vector(First, 1),
    ]);
    model_exchange.extend(C::event(First, true));
    model_exchange.extend([C::vector(First, 1), C::terminate(First)]);
    vec![
        ("co_simulation", co_simulation),
        ("two_instances", two),
        ("model_exchange", model_exchange),
    ]
}

/// The picks of [`Real`] a seed uses: its index in `Real::get`'s table.
pub mod pick {
    use super::Real;
    pub const ZERO: Real = Real::Pick(0);
    pub const MILLI: Real = Real::Pick(1);
    pub const ONE: Real = Real::Pick(3);
    pub const HALF: Real = Real::Pick(7);
    pub const TEN: Real = Real::Pick(8);
}
