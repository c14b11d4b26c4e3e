#!/usr/bin/env bash
# Every test: the Rust suite (model, solver, FMI shell, CLI, FMU import), then the packed FMU
# through fmpy, fmutool, libcosimpy, ecospy and ctypes.
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
ensure_apt
build_fmu
step "Rust tests"
cargo test --release --all-targets
step "the library-solver comparison of hasel bench compiles (feature compare, diffsol)"
cargo check -q --features compare --bin hasel
step "Python tests of the packed FMU"
python -m pytest tests/python -q -p no:cacheprovider
