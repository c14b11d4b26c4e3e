#!/usr/bin/env bash
# The sequence fuzzer of the FMU's C entry points (tests/fuzz): libFuzzer through cargo-fuzz,
# nightly Rust, AddressSanitizer with leak detection. Random FMI call sequences with random
# arguments run for a bounded time; a crash, a memory error, a leak or a call slower than the
# per-sequence bound stops it with the reproducing input saved under tests/fuzz/artifacts/.
#
#   bash ci/fuzz.sh [SECONDS]   (default 300; prints what it ran: sequences, coverage, corpus)
#
# Not part of ci/test.sh: the instrumented nightly build alone takes minutes. What it finds
# becomes a regression test of the normal suite (src/fmi2/tests, tests/python/test_fmu_misuse.py).
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
SECONDS_TO_RUN="${1:-300}"
mkdir -p out
if ! rustup toolchain list | grep -q '^nightly'; then
    step "rustup toolchain install nightly (cargo-fuzz needs -Z sanitizer flags)"
    rustup toolchain install nightly --profile minimal
fi
if ! command -v cargo-fuzz >/dev/null 2>&1; then
    step "cargo install cargo-fuzz"
    cargo install -q --locked cargo-fuzz@0.13.2
fi
FUZZ=(cargo +nightly fuzz run --fuzz-dir tests/fuzz --release --debug-assertions)
# each target with the library build whose C functions it calls
for target in fmi2_calls fmi3_calls; do
    features=()
    if [ "$target" = fmi3_calls ]; then features=(--features fmi3); fi
    step "fuzz $target for $SECONDS_TO_RUN s (libFuzzer, AddressSanitizer, leak detection)"
    mkdir -p "tests/fuzz/corpus/$target"
    "${FUZZ[@]}" "${features[@]}" "$target" -- -max_total_time="$SECONDS_TO_RUN" -timeout=20 -detect_leaks=1 \
        -print_final_stats=1 2>&1 | tee "out/fuzz-$target.log" | grep -E '^(#[0-9]+.*(DONE|pulse)|stat::|==[0-9]+==ERROR|SUMMARY|artifact_prefix|Test unit written)' || true
    if grep -qE '==[0-9]+==ERROR|^SUMMARY|Test unit written|deadly signal' "out/fuzz-$target.log"; then
        echo "fuzz $target FOUND A PROBLEM: see out/fuzz-$target.log and tests/fuzz/artifacts/$target/"
        exit 1
    fi
    echo "fuzz $target: no crash, no memory error, no leak, no hang in $SECONDS_TO_RUN s"
done
