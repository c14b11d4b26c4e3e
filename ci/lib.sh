# Shared set-up for ci/main.sh and ci/test.sh: installs what a fresh machine lacks, builds the
# FMU. Idempotent: each step is skipped when its result is already there.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
VENV="$ROOT/.venv"
FMU_TARGET=x86_64-unknown-linux-gnu
FMU_LIB="$ROOT/target/$FMU_TARGET/release/libhasel_fmu.so"
# the FMI 3.0 build (--features fmi3) in a target folder of its own: the cdylib's file name
# carries no feature hash, so the two builds would otherwise overwrite each other and rebuild
FMU3_LIB="$ROOT/target/fmi3/$FMU_TARGET/release/libhasel_fmu.so"

step() { printf '\n== %s\n' "$*"; }

ensure_apt() {
    # libclang-dev: bindgen of the `fmi` crate (Rust import test); libtbb12: ecospy
    local missing=()
    for pkg in libclang-dev libtbb12; do
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

# Builds the FMUs' shared libraries (FMI 2.0 and 3.0) against glibc 2.17 (so they load on
# older hosts), the CLI, and packs fmu/HaselPlatform.fmu and fmu/HaselPlatform-fmi3.fmu.
build_fmu() {
    ensure_venv
    ensure_zigbuild
    step "build the FMU library against glibc 2.17 (cargo zigbuild)"
    cargo zigbuild --release --lib --target "$FMU_TARGET.2.17"
    step "build the FMI 3.0 library against glibc 2.17 (cargo zigbuild --features fmi3)"
    cargo zigbuild --release --lib --target "$FMU_TARGET.2.17" --features fmi3 --target-dir target/fmi3
    step "build the hasel command"
    cargo build --release --bin hasel
    step "pack fmu/HaselPlatform.fmu and fmu/HaselPlatform-fmi3.fmu"
    ./target/release/hasel fmu --lib "$FMU_LIB" --lib-fmi3 "$FMU3_LIB"
}
