#!/usr/bin/env bash
# Benchmarks that print their figures, and the long test cases: the solver (hasel bench), the
# diagnosis's cases recorded mid-run in a drawn lab protocol (tests/diagnose.rs), the packed FMU through a
# Rust importer (the fmi crate) and through fmpy (Co-Simulation and Model Exchange), and uncertainty
# studies (examples/studies/bench.py).
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
ensure_apt
build_fmu
step "the library-solver comparison compiles lint-free (feature compare: diffsol, SUNDIALS)"
cargo clippy -q --release --features compare --bin hasel -- -D warnings
step "solver: hasel bench, with the library solvers beside it (diffsol, native SUNDIALS CVODE)"
cargo run -q --release --features compare --bin hasel -- bench
step "the diagnosis's long cases, kept out of ci/test.sh for its time (tests/diagnose.rs, ignored there)"
cargo test -q --profile release-tests --test diagnose -- --ignored
step "identification: hasel bench --identify"
./target/release/hasel bench --identify
step "FMUs (FMI 2.0 and 3.0) through the Rust fmi crate (Co-Simulation; Model Exchange derivatives and Jacobian)"
cargo run -q --release --example bench_fmu -- fmu/HaselPlatform.fmu fmu/HaselPlatform-fmi3.fmu
step "FMU through fmpy (Python's per-call overhead dominates)"
python ci/demo.py --fmu fmu/HaselPlatform.fmu --out out/fmu_demo.png
step "fmpy: Model Exchange with CVode beside Co-Simulation"
python ci/bench_model_exchange.py --fmu fmu/HaselPlatform.fmu
step "uncertainty studies: serial, hasel simulate --samples, LocalCluster of 2 workers, per-task overhead"
python examples/studies/bench.py --fmu fmu/HaselPlatform.fmu --hasel target/release/hasel
