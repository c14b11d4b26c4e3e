#!/usr/bin/env bash
# Benchmarks that print their figures: the solver (hasel bench), the packed FMU through a
# Rust importer (the fmi crate) and through fmpy, and uncertainty studies (examples/studies/bench.py).
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
ensure_apt
build_fmu
step "solver: hasel bench"
./target/release/hasel bench
step "identification: hasel bench --identify"
./target/release/hasel bench --identify
step "FMUs (FMI 2.0 and 3.0) through the Rust fmi crate"
cargo run -q --release --example bench_fmu -- fmu/HaselPlatform.fmu fmu/HaselPlatform-fmi3.fmu
step "FMU through fmpy (Python's per-call overhead dominates)"
python ci/demo.py --fmu fmu/HaselPlatform.fmu --out out/fmu_demo.png
step "uncertainty studies: serial, hasel simulate --samples, LocalCluster of 2 workers, per-task overhead"
python examples/studies/bench.py --fmu fmu/HaselPlatform.fmu --hasel target/release/hasel
