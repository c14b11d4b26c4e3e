# Shared set-up for ci/main.sh and ci/test.sh: installs what a fresh machine lacks, builds the
# FMU. Idempotent: each step is skipped when its result is already there.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
VENV="$ROOT/.venv"
FMU_TARGET=x86_64-unknown-linux-gnu
FMU_LIB="$ROOT/target/$FMU_TARGET/release/libhasel_fmu.so"
# the inverse FMU's build of the same library (feature inverse-fmu), in a target folder of its own
# so that neither build undoes the other
INVERSE_TARGET_DIR="$ROOT/target/inverse"
INVERSE_LIB="$INVERSE_TARGET_DIR/$FMU_TARGET/release/libhasel_fmu.so"
# the FMI 3.0 build (--features fmi3), likewise in a target folder of its own
FMU3_TARGET_DIR="$ROOT/target/fmi3"
FMU3_LIB="$FMU3_TARGET_DIR/$FMU_TARGET/release/libhasel_fmu.so"

step() { printf '\n== %s\n' "$*"; }

ensure_apt() {
    # libclang-dev: bindgen of the `fmi` crate (Rust import test) and of sundials-sys; libtbb12:
    # ecospy; libsundials-dev: native CVODE in hasel bench's `compare` feature
    local missing=()
    for pkg in libclang-dev libtbb12 libsundials-dev; do
        dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
    done
    if ((${#missing[@]})); then
        step "apt-get install ${missing[*]}"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
    fi
}

ensure_venv() {
    if [ ! -x "$VENV/bin/python" ] || ! cmp -s ci/requirements.txt "$VENV/.requirements"; then
        step "Python venv with fmpy and the other importers (ci/requirements.txt)"
        python3 -m venv "$VENV"
        "$VENV/bin/pip" install -q --disable-pip-version-check -r ci/requirements.txt
        cp ci/requirements.txt "$VENV/.requirements"
    fi
    export PATH="$VENV/bin:$PATH"
}

ensure_zigbuild() {
    if ! command -v cargo-zigbuild >/dev/null 2>&1; then
        step "cargo install cargo-zigbuild"
        cargo install -q --locked cargo-zigbuild@0.24.1
    fi
}

# fmi-sim, the simulator of the rust-fmi project: the second, independent importer of
# tests/python/test_fmi_sim.py. It compiles from source (arrow and the fmi bindings).
ensure_fmi_sim() {
    # fmi-sim 0.7 prints its version as an error: on stderr, with a non-zero exit status
    local version
    version="$(fmi-sim --version 2>&1 || true)"
    if [[ "$version" != *"fmi-sim 0.7.0"* ]]; then
        step "cargo install fmi-sim 0.7.0"
        cargo install -q --locked fmi-sim@0.7.0
    fi
}

# A cdylib built with other features needs a target folder of its own (its file name would
# clash); seeded once from the main build's artifacts, so that only this crate compiles again,
# not its dependencies (a cold build of them takes minutes on two cores).
seed_target_dir() {
    local dir="$1"
    if [ ! -d "$dir/$FMU_TARGET" ] && [ -d "target/$FMU_TARGET" ]; then
        mkdir -p "$dir/release"
        cp -a "target/$FMU_TARGET" "$dir/"
        for sub in build deps .fingerprint; do
            if [ -d "target/release/$sub" ]; then cp -a "target/release/$sub" "$dir/release/"; fi
        done
    fi
}

# One shared library of the FMUs, against glibc 2.17 (so it loads on older hosts), at opt-level
# 2 rather than the release profile's 3: a co-simulation step runs about 40 KB of code, more than
# the 32 KB first-level instruction cache, and the smaller code of opt-level 2 made the step
# through the C API 2-5 % faster here in both FMI versions (README, "The solver").
zigbuild_fmu_lib() {
    CARGO_PROFILE_RELEASE_OPT_LEVEL=2 cargo zigbuild --release --lib --target "$FMU_TARGET.2.17" "$@"
}

# Builds the FMUs' shared libraries against glibc 2.17 (so they load on older hosts): the
# platform's for FMI 2.0 and 3.0 and the inverse FMU's, the CLI, and packs fmu/HaselPlatform.fmu,
# fmu/HaselPlatform-fmi3.fmu and fmu/HaselInverse.fmu.
build_fmu() {
    ensure_venv
    ensure_zigbuild
    step "build the FMU library against glibc 2.17 (cargo zigbuild)"
    zigbuild_fmu_lib
    step "build the FMI 3.0 library against glibc 2.17 (cargo zigbuild --features fmi3)"
    seed_target_dir "$FMU3_TARGET_DIR"
    zigbuild_fmu_lib --features fmi3 --target-dir "$FMU3_TARGET_DIR"
    step "build the hasel command"
    cargo build --release --bin hasel
    step "pack fmu/HaselPlatform.fmu and fmu/HaselPlatform-fmi3.fmu"
    ./target/release/hasel fmu --lib "$FMU_LIB" --lib-fmi3 "$FMU3_LIB"
    step "build the inverse FMU's library (feature inverse-fmu) and pack fmu/HaselInverse.fmu"
    seed_target_dir "$INVERSE_TARGET_DIR"
    zigbuild_fmu_lib --features inverse-fmu --target-dir "$INVERSE_TARGET_DIR"
    ./target/release/hasel fmu --model inverse --lib "$INVERSE_LIB"
}
