#!/usr/bin/env bash
# Every test: self-containment, formatting and lints, the Rust suite, then the packed FMU
# through fmpy, fmutool, libcosimpy, ecospy, fmi-sim (installed by ci/lib.sh) and ctypes.
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
step "the repository refers to nothing outside it (ci/self_contained.py)"
python3 ci/self_contained.py
ensure_apt
step "formatting and lints (cargo fmt --check, cargo clippy -D warnings)"
cargo fmt --check
cargo clippy -q --release --all-targets -- -D warnings
build_fmu
step "Rust tests (tests/fuzz_replay.rs replays the committed fuzz corpora, tests/fuzz/corpus)"
cargo test --release --all-targets
ensure_fmi_sim
step "Python tests of the packed FMU"
python -m pytest tests/python -q -p no:cacheprovider
