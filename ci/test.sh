#!/usr/bin/env bash
# Every test: self-containment, formatting and lints, the Rust suite, then the packed FMU
# through fmpy, fmutool, libcosimpy, ecospy, fmi-sim (installed by ci/lib.sh) and ctypes, and
# the FMUs' Windows binaries and command, cross-built as ci/platforms.sh does, run under Wine, the
# macOS ones checked, and the Linux wheel installed into a fresh venv.
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
step "the repository refers to nothing outside it (ci/self_contained.py)"
python3 ci/self_contained.py
ensure_apt
step "formatting and lints (cargo fmt --check, cargo clippy -D warnings)"
cargo fmt --check
cargo clippy -q --release --all-targets -- -D warnings
build_fmu
# the other platforms' FMU libraries of both platform FMUs and the Windows hasel command, at the
# cheaper profile cross-test (Cargo.toml): the Windows ones run under Wine, the macOS ones are
# checked (tests/python/test_windows.py, test_macos.py); the inverse FMU's and the macOS commands
# take ci/platforms.sh (CI's time: README, "Windows and macOS")
export CROSS_PROFILE=cross-test
cross_build fmi2 "${CROSS_TARGETS[@]}"
cross_build fmi3 "${CROSS_TARGETS[@]}"
cross_build cli "$WINDOWS_TARGET"
pack_platforms
build_wheel
ensure_wine
step "Rust tests"
cargo test --release --all-targets
step "the library-solver comparison of hasel bench compiles lint-free (feature compare, diffsol)"
cargo clippy -q --release --features compare --bin hasel -- -D warnings
ensure_fmi_sim
step "Python tests of the packed FMU"
python -m pytest tests/python -q -p no:cacheprovider
