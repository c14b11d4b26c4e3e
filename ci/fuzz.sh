#!/usr/bin/env bash
# The fuzz campaigns (tests/fuzz): libFuzzer through cargo-fuzz, nightly Rust, AddressSanitizer
# with leak detection, one campaign per target for a bounded time:
#   - the FMI call sequences of every FMU the project builds: fmi2_calls, fmi3_calls (the
#     platform's FMI 2.0 and 3.0 builds), inverse_calls (HaselInverse's FMI 2.0 build),
#     reduced_calls and reduced_fmi3_calls (HaselPlatformReduced's FMI 2.0 and 3.0 functions);
#   - every reader of a user's file (tests/fuzz/checks.rs): csv_input, csv_experiment,
#     params_toml, heights_toml, identification_json, and the serialized FMU states fed to the
#     deserializers directly, fmi2_state and fmi3_state.
# A crash, a broken promise, a memory error, a leak, an input slower than -timeout or an
# allocation beyond -malloc_limit_mb stops it with the reproducing input saved under
# tests/fuzz/artifacts/<target>/. After a clean campaign the target's corpus is minimized
# (libFuzzer's -merge=1). tests/fuzz_replay.rs replays every target's committed corpus in every
# `cargo test` (so in ci/test.sh, in a few seconds), through the same code in the ordinary build
# on stable Rust: the readers' checks (tests/fuzz/checks.rs) and the call sequences
# (fmi2_sequence.rs, fmi3_sequence.rs) of all five FMUs; only what the sanitizer sees (memory
# errors, leaks) and the bounds on time and memory per input need a campaign.
#
#   bash ci/fuzz.sh [SECONDS] [TARGET...]   (default 300 s each, all targets; prints per target
#                                           the executions, coverage (cov, ft) and corpus size)
#
# The campaigns are not part of ci/test.sh: the instrumented nightly build alone takes minutes.
# What a campaign finds becomes a regression test of the normal suite.
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
SECONDS_TO_RUN="${1:-300}"
shift || true
TARGETS=("$@")
if [ ${#TARGETS[@]} -eq 0 ]; then
    TARGETS=(csv_input csv_experiment params_toml heights_toml identification_json fmi2_state
        fmi3_state fmi2_calls fmi3_calls inverse_calls reduced_calls reduced_fmi3_calls)
fi
mkdir -p out
if ! rustup toolchain list | grep -q '^nightly'; then
    step "rustup toolchain install nightly (cargo-fuzz needs -Z sanitizer flags)"
    rustup toolchain install nightly --profile minimal
fi
if ! command -v cargo-fuzz >/dev/null 2>&1; then
    step "cargo install cargo-fuzz"
    cargo install -q --locked cargo-fuzz@0.13.2
fi
FUZZ=(--fuzz-dir tests/fuzz --release --debug-assertions)
# the seeds of the call-sequence corpora (tests/fuzz_replay.rs, `write_seeds`): valid sequences
# through initialization, steps, the importer's integration and FMU states, from which the
# campaigns mutate (without them no campaign got an instance past initialization)
if [[ " ${TARGETS[*]} " == *_calls\ * ]]; then
    step "write the seeds of the call-sequence corpora"
    nice -n 19 cargo test -q --release --test fuzz_replay -- --ignored write_seeds >/dev/null
fi
for target in "${TARGETS[@]}"; do
    # the bounds per input: a sequence may simulate (20 s), a reader of a few kilobytes may not
    # take long (5 s); no input may make one allocation above 256 MB or hold more than 1 GB. Every
    # target runs on one build of the library (default features): a call-sequence target makes its
    # FMU's C functions with the library's own macro (fuzz_targets/fmi2_sequence.rs says why)
    timeout=5
    case "$target" in
        *_calls) timeout=20 ;;
    esac
    step "fuzz $target for $SECONDS_TO_RUN s (libFuzzer, AddressSanitizer, leak detection)"
    corpus="tests/fuzz/corpus/$target"
    mkdir -p "$corpus"
    # cargo's own status kept beside the log: a campaign whose build failed found nothing
    { status=0
      nice -n 19 cargo +nightly fuzz run "${FUZZ[@]}" "$target" -- \
        -max_total_time="$SECONDS_TO_RUN" -timeout="$timeout" -rss_limit_mb=1024 \
        -malloc_limit_mb=256 -detect_leaks=1 -print_final_stats=1 2>&1 || status=$?
      echo "$status" >"out/fuzz-$target.status"; } | tee "out/fuzz-$target.log" |
        grep -E '^(#[0-9]+.*(DONE|pulse)|stat::|==[0-9]+==ERROR|SUMMARY|artifact_prefix|Test unit written)' || true
    fuzz_status="$(cat "out/fuzz-$target.status")"
    bin="tests/fuzz/target/x86_64-unknown-linux-gnu/release/$target"
    # a slow unit (libFuzzer writes one above 10 s) is no finding: the bound is -timeout, and on a
    # shared core a 0.3 s sequence took that long; each is replayed here, its time printed
    for slow in "tests/fuzz/artifacts/$target"/slow-unit-*; do
        [ -e "$slow" ] || continue
        took="$( { TIMEFORMAT=%R; time "$bin" -runs=1 "$slow" >/dev/null 2>&1; } 2>&1)"
        echo "fuzz $target: slow unit $slow replays in $took s (the bound is $timeout s)"
    done
    if grep -qE '==[0-9]+==ERROR|^SUMMARY|Test unit written to [^ ]*/(crash|leak|timeout|oom)-|deadly signal|panicked at' "out/fuzz-$target.log"; then
        echo "fuzz $target FOUND A PROBLEM: see out/fuzz-$target.log and tests/fuzz/artifacts/$target/"
        exit 1
    fi
    if [ "$fuzz_status" -ne 0 ]; then
        echo "fuzz $target: cargo fuzz exited with status $fuzz_status (a build that failed?): see out/fuzz-$target.log"
        exit 1
    fi
    echo "fuzz $target: no crash, no broken promise, no memory error, no leak, no hang in $SECONDS_TO_RUN s"
    # minimized by the binary just run (libFuzzer's -merge=1, what `cargo fuzz cmin` does):
    # `cargo fuzz cmin` builds with other settings than `run` and rebuilt the library each time
    rm -rf "$corpus.min" && mkdir "$corpus.min"
    nice -n 19 "$bin" -merge=1 -timeout="$timeout" -rss_limit_mb=1024 "$corpus.min" "$corpus" \
        >"out/cmin-$target.log" 2>&1
    rm -rf "$corpus" && mv "$corpus.min" "$corpus"
    # a mutated input may spell a climb out of the repository (dot-dot-slash), which
    # ci/self_contained.py refuses in every tracked file: such inputs are not kept
    python3 ci/self_contained.py --drop "$corpus"
    # the files' bytes, as committed (du would count the folder's own entries too)
    echo "corpus $target: $(ls "$corpus" | wc -l) files, $(find "$corpus" -type f -printf '%s\n' | awk '{s += $1} END {print int(s / 1024)}') KB"
done
