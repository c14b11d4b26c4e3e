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
fn replay<C: for<'a> Arbitrary<'a>>(target: &str, run: impl Fn(&[C])) {
    let start = Instant::now();
    let files = corpus(target);
    let mut ran = 0;
    for file in &files {
        let data = std::fs::read(file).unwrap();
        if data.len() < <Vec<C> as Arbitrary>::size_hint(0).0 {
            continue;
        }
        let Ok(calls) = Vec::<C>::arbitrary_take_rest(Unstructured::new(&data)) else {
            continue;
        };
        let before = panics();
        let failed = catch_unwind(AssertUnwindSafe(|| run(&calls))).is_err();
        if failed || panics() != before {
            panic!(
                "{target}: {} panics (the panic is printed above)",
                file.display()
            );
        }
        ran += 1;
    }
    eprintln!(
        "{target}: {ran} of {} files run as call sequences in {:.2} s",
        files.len(),
        start.elapsed().as_secs_f64()
    );
    // the corpus is what the campaign minimized: every file of it reached something
    assert!(
        ran * 10 >= files.len() * 9,
        "{target}: only {ran} of {} files decode into a call sequence",
        files.len()
    );
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
    replay("fmi2_calls", |calls| {
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
    replay("inverse_calls", |calls| {
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
    replay("reduced_calls", |calls| {
        fmi2_sequence::run(&fmu, logger(), calls)
    });
}

#[test]
fn fmi3_calls_replays() {
    let fmu = fmi3_sequence::Fmu::platform();
    replay("fmi3_calls", |calls| fmi3_sequence::run(&fmu, calls));
}

#[test]
fn reduced_fmi3_calls_replays() {
    let fmu = fmi3_sequence::Fmu::reduced();
    replay("reduced_fmi3_calls", |calls| {
        fmi3_sequence::run(&fmu, calls)
    });
}
