#!/usr/bin/env bash
# Every test: self-containment, formatting and lints, the Rust suite, the book and the API
# documentation, and beside them the packed FMUs
# through fmpy, fmutool, libcosimpy, ecospy, fmi-sim (installed by ci/lib.sh) and ctypes, and the
# other platforms' binaries: the FMUs' libraries (the platform's and the slow model's, each FMI 2.0
# and 3.0 in one, and the inverse's) and the hasel command cross-built for Windows and macOS at the
# cheap profile cross-test (Cargo.toml says why; CROSS_PROFILE=release tests the shipping build),
# the Windows ones run under Wine, the macOS ones checked, the Linux wheel installed.
CROSS_PROFILE="${CROSS_PROFILE:-cross-test}"
# the hasel command for Windows, which runs under Wine, and for macOS arm64, whose signature is
# checked; macOS x86_64's (checked as arm64's, less the signature: about 70 s to build) is left to
# ci/platforms.sh. tests/python/test_macos.py reads the list.
export CROSS_CLI_TARGETS="${CROSS_CLI_TARGETS:-x86_64-pc-windows-gnu aarch64-apple-darwin}"
# the hasel command (and the Linux wheel) at the Rust suite's profile, so that the suite builds on
# them (ci/lib.sh, HOST_PROFILE); the Python tests run that command (HASEL)
HOST_PROFILE="${HOST_PROFILE:-release-tests}"
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
step "the repository refers to nothing outside it (ci/self_contained.py)"
python3 ci/self_contained.py
ensure_apt
step "formatting and lints (cargo fmt --check, cargo clippy -D warnings)"
cargo fmt --check
# at the Rust suite's profile, whose build then finds the build scripts (bindgen's among them)
# compiled and run
cargo clippy -q --profile "$HOST_PROFILE" --all-targets -- -D warnings
build_fmu
build_cross
build_wheel
ensure_wine
ensure_mdbook
ensure_fmi_sim
# The Python suite runs beside the Rust suite: it is one process that mostly keeps one core busy
# (an FMU, a simulator, Wine), while the Rust suite's diagnoses keep both; its report follows the
# Rust suite's and the book's. Nothing in either writes what the other reads, and no diagnosis
# of the Rust suite has a time budget: side by side, neither's results change.
step "Python tests of the packed FMUs, the other platforms' among them: started, beside the Rust tests (report below)"
PYTHON_LOG="$ROOT/target/python-tests.log"
HASEL="$HASEL" HASEL_PLATFORMS=required python -m pytest tests/python -q -p no:cacheprovider \
    > "$PYTHON_LOG" 2>&1 &
python_tests=$!
trap 'kill "$python_tests" 2>/dev/null || true' EXIT
# tests/fuzz_replay.rs replays the committed corpus of every fuzz target (tests/fuzz/corpus: the
# readers' files, the FMI call sequences of all five FMUs) through the targets' own code, in about a
# second; only the sanitizer's findings need a campaign (ci/fuzz.sh)
step "Rust tests (tests/fuzz_replay.rs replays every fuzz target's committed corpus)"
cargo test --profile release-tests --all-targets
step "the book (mdbook build book; tests/docs.rs above checked its links and the code's citations), the API documentation without a warning (the library's and the CLI's), its examples"
mdbook build book
RUSTDOCFLAGS="-D warnings" cargo doc -q --no-deps --lib --bins
cargo test -q --profile release-tests --doc
step "Python tests of the packed FMUs: the report"
python_status=0
wait "$python_tests" || python_status=$?
cat "$PYTHON_LOG"
exit "$python_status"
