#!/usr/bin/env bash
# Every test: self-containment, formatting and lints, the Rust suite, then the packed FMU
# through fmpy, fmutool, libcosimpy, ecospy, fmi-sim (installed by ci/lib.sh) and ctypes, and
# the FMUs' Windows binaries, cross-built as ci/platforms.sh does, run under Wine.
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
step "the repository refers to nothing outside it (ci/self_contained.py)"
python3 ci/self_contained.py
ensure_apt
step "formatting and lints (cargo fmt --check, cargo clippy -D warnings)"
cargo fmt --check
cargo clippy -q --release --all-targets -- -D warnings
build_fmu
# the Windows libraries that tests/python/test_windows.py runs under Wine; the macOS ones and the
# inverse FMU's other platforms take ci/platforms.sh (each cold target costs minutes more than
# CI's budget leaves: README, "Windows and macOS")
cross_build fmi2 "$WINDOWS_TARGET"
cross_build fmi3 "$WINDOWS_TARGET"
pack_platforms
ensure_wine
step "Rust tests"
cargo test --release --all-targets
step "the library-solver comparison of hasel bench compiles lint-free (feature compare, diffsol)"
cargo clippy -q --release --features compare --bin hasel -- -D warnings
ensure_fmi_sim
step "Python tests of the packed FMU"
python -m pytest tests/python -q -p no:cacheprovider
