//! The committed fuzz corpora (tests/fuzz/corpus/<target>/, minimized by libFuzzer's merge)
//! replayed in the ordinary build, stable Rust and no sanitizer: what a campaign (`bash
//! ci/fuzz.sh`) once found or reached stays checked by every `cargo test`. Every target of
//! tests/fuzz/fuzz_targets is replayed, through the code the target runs:
//!
//! - the readers of a user's file (`csv_input`, `csv_experiment`, `params_toml`, `heights_toml`,
//!   `identification_json`) and the serialized FMU states fed to the decoders (`fmi2_state`,
//!   `fmi3_state`): the checks of tests/fuzz/checks.rs;
//! - the FMI call sequences of every FMU (`fmi2_calls`, `inverse_calls`, `reduced_calls` in FMI
//!   2.0, `fmi3_calls`, `reduced_fmi3_calls` in FMI 3.0): each file decoded into a sequence as
//!   libFuzzer's Rust harness decodes it and run by the targets' interpreter
//!   (tests/fuzz/fuzz_targets/fmi2_sequence.rs, fmi3_sequence.rs). The interpreter reaches each
//!   FMU's C functions through the library's own macro for them, without the exported symbol
//!   names, so this one build (default features) serves all five FMUs; the features that select
//!   which FMU a cdylib exports add no other code (src/fmu/mod.rs).
//!
//! Each call-sequence replay also counts how deep its corpus gets (how many
//! `ExitInitializationMode`, `DoStep`, Model Exchange derivative and state serialization calls
//! return OK) and fails below a floor: the first campaigns' corpora never got an instance past
//! initialization. The seeds every campaign starts from (valid sequences through the life of an
//! FMU, `common::seeds`) are written by `write_seeds` and checked here: written as the harness
//! decodes them, and reaching stepping on every FMU.
//!
//! A sequence fails the replay where its target fails a campaign, but for what only the
//! instrumented build sees: a panic anywhere, even one the FMU's shell catches at the C boundary
//! and turns into an error status (libfuzzer-sys aborts on any panic; here a panic hook counts
//! them), a panic unwinding out of a C function (the process aborts), a broken assertion of the
//! interpreter (a state `fmi*FreeFMUstate` kept), and a hang (the test never ends). Not here: the
//! memory errors and leaks AddressSanitizer finds, and the campaigns' bounds on time and memory
//! per input.

#[path = "fuzz/checks.rs"]
mod checks;
#[path = "fuzz/fuzz_targets/common.rs"]
mod common;
#[path = "fuzz/fuzz_targets/fmi2_sequence.rs"]
mod fmi2_sequence;
#[path = "fuzz/fuzz_targets/fmi3_sequence.rs"]
mod fmi3_sequence;

use std::cell::Cell;
use std::ffi::{CStr, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Once;
use std::time::Instant;

use arbitrary::{Arbitrary, Unstructured};
use common::{Bytes, Encode, Reached};
use hasel_fmu::fmi2::types::{fmi2Status, fmi2String};

/// The files of a target's corpus.
fn corpus(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz/corpus")
        .join(target);
    let mut files = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|f| f.unwrap().path())
        .collect::<Vec<_>>();
    files.sort();
    assert!(!files.is_empty(), "{target}: empty corpus");
    files
}

#[test]
fn every_corpus_replays_through_its_check() {
    for (target, check) in checks::TARGETS {
        for file in corpus(target) {
            let data = std::fs::read(&file).unwrap();
            if std::panic::catch_unwind(|| check(&data)).is_err() {
                panic!("{target}: {} fails its check", file.display());
            }
        }
    }
}

thread_local! {
    /// The panics of this thread so far, caught or not.
    static PANICS: Cell<u64> = const { Cell::new(0) };
}

/// The panics of the current thread so far, counted by a panic hook (installed on the first
/// call) that then hands the panic to the hook before it, which prints it.
fn panics() -> u64 {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let before = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            PANICS.with(|n| n.set(n.get() + 1));
            before(info);
        }));
    });
    PANICS.with(Cell::get)
}

/// Replays the corpus of a call-sequence target: each file decoded into calls as
/// `libfuzzer_sys::fuzz_target!` decodes it (too short for the type, or not decodable: skipped,
/// as libFuzzer skips it), then run. A panic, caught or not, fails the replay and names the file.
/// Then how deep the corpus gets must reach `floor`: at least as many calls of each kind that
/// only succeed past initialization returned OK (a corpus whose sequences stop at the state
/// machine's door, as the first campaigns' did, fails here).
fn replay<C: for<'a> Arbitrary<'a>>(target: &str, floor: Floor, run: impl Fn(&[C]) -> Reached) {
    let start = Instant::now();
    let files = corpus(target);
    let mut ran = 0;
    let mut reached = Reached::default();
    for file in &files {
        let data = std::fs::read(file).unwrap();
        if data.len() < <Vec<C> as Arbitrary>::size_hint(0).0 {
            continue;
        }
        let Ok(calls) = Vec::<C>::arbitrary_take_rest(Unstructured::new(&data)) else {
            continue;
        };
        let before = panics();
        let result = catch_unwind(AssertUnwindSafe(|| run(&calls)));
        if let Ok(r) = result {
            reached += r;
        }
        if result.is_err() || panics() != before {
            panic!(
                "{target}: {} panics (the panic is printed above)",
                file.display()
            );
        }
        ran += 1;
    }
    eprintln!(
        "{target}: {ran} of {} files run as call sequences in {:.2} s; OK of calls: \
         ExitInitializationMode {}/{}, DoStep {}/{}, derivatives {}/{}, serialize {}/{}",
        files.len(),
        start.elapsed().as_secs_f64(),
        reached.exit_initialization.ok,
        reached.exit_initialization.calls,
        reached.do_step.ok,
        reached.do_step.calls,
        reached.derivatives.ok,
        reached.derivatives.calls,
        reached.serialize.ok,
        reached.serialize.calls,
    );
    for (what, got, least) in [
        (
            "ExitInitializationMode",
            reached.exit_initialization.ok,
            floor.exit_initialization,
        ),
        ("DoStep", reached.do_step.ok, floor.do_step),
        (
            "GetDerivatives (Model Exchange)",
            reached.derivatives.ok,
            floor.derivatives,
        ),
        ("SerializeFMUstate", reached.serialize.ok, floor.serialize),
    ] {
        assert!(
            got >= least,
            "{target}: the corpus no longer reaches deep: {got} {what} calls return OK, \
             fewer than {least}"
        );
    }
    // the corpus is what the campaign minimized: every file of it reached something
    assert!(
        ran * 10 >= files.len() * 9,
        "{target}: only {ran} of {} files decode into a call sequence",
        files.len()
    );
}

/// The least number of OK calls of each kind a target's corpus must make (see [`replay`]).
struct Floor {
    exit_initialization: u64,
    do_step: u64,
    derivatives: u64,
    serialize: u64,
}

/// The floors of the call-sequence targets: about half of what the committed corpora reach
/// (book/src/tests.md, "Fuzzing"), so a minimization or a change of the interpreter that loses the
/// deep sequences fails, and one that merely reshuffles them does not.
mod floor {
    use super::Floor;
    const fn floor(
        exit_initialization: u64,
        do_step: u64,
        derivatives: u64,
        serialize: u64,
    ) -> Floor {
        Floor {
            exit_initialization,
            do_step,
            derivatives,
            serialize,
        }
    }
    pub const FMI2_CALLS: Floor = floor(48, 56, 16, 19);
    // Co-Simulation only: no derivatives
    pub const INVERSE_CALLS: Floor = floor(115, 82, 0, 39);
    pub const REDUCED_CALLS: Floor = floor(101, 103, 28, 30);
    pub const FMI3_CALLS: Floor = floor(71, 66, 28, 20);
    pub const REDUCED_FMI3_CALLS: Floor = floor(79, 51, 37, 21);
}

/// The FMI 2.0 logger, declared with the fixed arguments the FMU passes: `fmi2CallbackLogger`
/// is C-variadic, and stable Rust cannot define a C-variadic function (the fuzz targets, on
/// nightly, define one with the feature `c_variadic`: tests/fuzz/fuzz_targets/fmi2_logger.rs).
/// The FMU calls its logger only with the format "%s" and the message as its one argument
/// (src/fmi2/logging.rs), so `text` is read only when `message` is "%s".
unsafe extern "C" fn fixed_logger(
    _env: *mut c_void,
    name: fmi2String,
    _status: fmi2Status,
    category: fmi2String,
    message: fmi2String,
    text: fmi2String,
) {
    let text = if !message.is_null() && unsafe { CStr::from_ptr(message) } == c"%s" {
        text
    } else {
        std::ptr::null()
    };
    fmi2_sequence::read_log(name, category, message, text);
}

/// [`fixed_logger`] as `fmi2CallbackLogger`.
///
/// Sound on the platforms this is compiled for (the `cfg` of the FMI 2.0 replays): in the
/// x86-64 System V and AArch64 Linux (AAPCS64) calling conventions a variadic call passes its
/// arguments, the variadic ones included, in the registers a call of the function with those
/// arguments fixed would use (x86-64 adds the count of vector registers in %al, which a callee
/// with fixed arguments ignores), and the FMU passes one pointer after the format. (Apple's
/// AArch64 passes variadic arguments on the stack, hence the `cfg`.) The FMU's own unit tests
/// use the same logger (src/fmi2/tests/mod.rs).
#[cfg(all(
    target_os = "linux",
    any(target_arch = "x86_64", target_arch = "aarch64")
))]
fn logger() -> fmi2_sequence::Logger {
    type Fixed = unsafe extern "C" fn(
        *mut c_void,
        fmi2String,
        fmi2Status,
        fmi2String,
        fmi2String,
        fmi2String,
    );
    type Variadic =
        unsafe extern "C" fn(*mut c_void, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
    Some(unsafe { std::mem::transmute::<Fixed, Variadic>(fixed_logger as Fixed) })
}

#[cfg(all(
    target_os = "linux",
    any(target_arch = "x86_64", target_arch = "aarch64")
))]
#[test]
fn fmi2_calls_replays() {
    let fmu = fmi2_sequence::Fmu::platform();
    replay("fmi2_calls", floor::FMI2_CALLS, |calls| {
        fmi2_sequence::run(&fmu, logger(), calls)
    });
}

#[cfg(all(
    target_os = "linux",
    any(target_arch = "x86_64", target_arch = "aarch64")
))]
#[test]
fn inverse_calls_replays() {
    let fmu = fmi2_sequence::Fmu::inverse();
    replay("inverse_calls", floor::INVERSE_CALLS, |calls| {
        fmi2_sequence::run(&fmu, logger(), calls)
    });
}

#[cfg(all(
    target_os = "linux",
    any(target_arch = "x86_64", target_arch = "aarch64")
))]
#[test]
fn reduced_calls_replays() {
    let fmu = fmi2_sequence::Fmu::reduced();
    replay("reduced_calls", floor::REDUCED_CALLS, |calls| {
        fmi2_sequence::run(&fmu, logger(), calls)
    });
}

#[test]
fn fmi3_calls_replays() {
    let fmu = fmi3_sequence::Fmu::platform();
    replay("fmi3_calls", floor::FMI3_CALLS, |calls| {
        fmi3_sequence::run(&fmu, calls)
    });
}

#[test]
fn reduced_fmi3_calls_replays() {
    let fmu = fmi3_sequence::Fmu::reduced();
    replay("reduced_fmi3_calls", floor::REDUCED_FMI3_CALLS, |calls| {
        fmi3_sequence::run(&fmu, calls)
    });
}

/// The inputs the seeds set, by value reference, with their values: the first three variables
/// of each FMU, the voltages of the platform's two models (kV), the inverse FMU's tip position
/// and mean height (m); and the outputs they read, the next six variables of all three.
fn seed_inputs(target: &str) -> [(u32, common::Real); 3] {
    use common::{Real::Raw, pick};
    match target {
        "inverse_calls" => [(0, Raw(20e-6)), (1, Raw(-10e-6)), (2, Raw(70e-6))],
        _ => [(0, pick::HALF), (1, pick::ONE), (2, pick::HALF)],
    }
}
const SEED_OUTPUTS: [u32; 6] = [3, 4, 5, 6, 7, 8];

/// The byte writer of the seeds ([`common::Bytes`]) against `arbitrary`'s reader: any input
/// decodes into calls that, written back, decode into the same calls (every kind of call, every
/// field, checked on a few thousand pseudo-random inputs), and each seed decodes into itself.
fn round_trip<C: for<'a> Arbitrary<'a> + Encode + std::fmt::Debug>(seeds: &[(&str, Vec<C>)]) {
    let mut x = 0x2545_f491_4f6c_dd1d_u64;
    let mut kinds = std::collections::BTreeSet::new();
    for n in 0..4000 {
        let bytes: Vec<u8> = (0..(n % 300))
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                // mostly a 1 where a sequence asks "one more?", so sequences get long
                if x.is_multiple_of(5) {
                    1
                } else {
                    (x >> 24) as u8
                }
            })
            .collect();
        let calls = Vec::<C>::arbitrary_take_rest(Unstructured::new(&bytes)).unwrap();
        for c in &calls {
            kinds.insert(
                format!("{c:?}")
                    .split([' ', '('])
                    .next()
                    .unwrap()
                    .to_string(),
            );
        }
        let again = Bytes::sequence(&calls);
        let decoded = Vec::<C>::arbitrary_take_rest(Unstructured::new(&again)).unwrap();
        assert_eq!(format!("{decoded:?}"), format!("{calls:?}"));
    }
    assert_eq!(
        kinds.len(),
        27,
        "not every kind of call was written back: {kinds:?}"
    );
    for (name, calls) in seeds {
        let decoded = Vec::<C>::arbitrary_take_rest(Unstructured::new(&Bytes::sequence(calls)));
        assert_eq!(
            format!("{:?}", decoded.unwrap()),
            format!("{calls:?}"),
            "seed {name}"
        );
    }
}

#[test]
fn seeds_are_written_as_decoded() {
    round_trip(&common::seeds::<fmi2_sequence::Call>(
        &seed_inputs("fmi2_calls"),
        &SEED_OUTPUTS,
    ));
    round_trip(&common::seeds::<fmi3_sequence::Call>(
        &seed_inputs("fmi3_calls"),
        &SEED_OUTPUTS,
    ));
}

/// What the seeds of each target reach, all of them together.
fn seeds_reach() -> Vec<(&'static str, Reached)> {
    let mut out = Vec::new();
    #[cfg(all(
        target_os = "linux",
        any(target_arch = "x86_64", target_arch = "aarch64")
    ))]
    for (target, fmu) in [
        ("fmi2_calls", fmi2_sequence::Fmu::platform()),
        ("inverse_calls", fmi2_sequence::Fmu::inverse()),
        ("reduced_calls", fmi2_sequence::Fmu::reduced()),
    ] {
        let mut r = Reached::default();
        for (_, calls) in common::seeds::<fmi2_sequence::Call>(&seed_inputs(target), &SEED_OUTPUTS)
        {
            r += fmi2_sequence::run(&fmu, logger(), &calls);
        }
        out.push((target, r));
    }
    for (target, fmu) in [
        ("fmi3_calls", fmi3_sequence::Fmu::platform()),
        ("reduced_fmi3_calls", fmi3_sequence::Fmu::reduced()),
    ] {
        let mut r = Reached::default();
        for (_, calls) in common::seeds::<fmi3_sequence::Call>(&seed_inputs(target), &SEED_OUTPUTS)
        {
            r += fmi3_sequence::run(&fmu, &calls);
        }
        out.push((target, r));
    }
    out
}

/// The seeds take every FMU past initialization: every ExitInitializationMode they make returns
/// OK, and so does every step, derivative and serialization of the FMUs that have them (the
/// inverse FMU is Co-Simulation only).
#[test]
fn seeds_reach_stepping() {
    for (target, r) in seeds_reach() {
        eprintln!("{target}: seeds reach {r:?}");
        if target == "inverse_calls" {
            // its Model Exchange instance is refused at instantiation
            assert_eq!(
                r.exit_initialization.ok + 1,
                r.exit_initialization.calls,
                "{target}"
            );
        } else {
            assert_eq!(
                r.exit_initialization.ok, r.exit_initialization.calls,
                "{target}"
            );
            assert_eq!(r.derivatives.ok, r.derivatives.calls, "{target}");
        }
        assert_eq!(r.do_step.ok, r.do_step.calls, "{target}");
        assert!(r.do_step.ok > 0 && r.serialize.ok > 0, "{target}: {r:?}");
    }
}

/// Writes the seeds into the corpora (tests/fuzz/corpus/<target>/seed-<name>), which `bash
/// ci/fuzz.sh` does before its campaigns; the campaign's minimization then keeps what of them
/// adds coverage, under libFuzzer's names.
#[test]
#[ignore = "writes files: run by ci/fuzz.sh"]
fn write_seeds() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz/corpus");
    for target in ["fmi2_calls", "inverse_calls", "reduced_calls"] {
        for (name, calls) in
            common::seeds::<fmi2_sequence::Call>(&seed_inputs(target), &SEED_OUTPUTS)
        {
            let file = dir.join(target).join(format!("seed-{name}"));
            std::fs::write(file, Bytes::sequence(&calls)).unwrap();
        }
    }
    for target in ["fmi3_calls", "reduced_fmi3_calls"] {
        for (name, calls) in
            common::seeds::<fmi3_sequence::Call>(&seed_inputs(target), &SEED_OUTPUTS)
        {
            let file = dir.join(target).join(format!("seed-{name}"));
            std::fs::write(file, Bytes::sequence(&calls)).unwrap();
        }
    }
}
