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
# the slow model's library (feature reduced-fmu), likewise in a target folder of its own; it and
# the platform's export the functions of FMI 2.0 and 3.0, one build for both versions' FMUs
REDUCED_TARGET_DIR="$ROOT/target/reduced"
REDUCED_LIB="$REDUCED_TARGET_DIR/$FMU_TARGET/release/libhasel_fmu.so"
# the cargo profile of this machine's hasel command and of the Linux wheel that bundles it:
# release, what ships; ci/test.sh sets release-tests, the profile of its Rust suite, which then
# finds the dependencies and the library built (compiling them at both profiles cost about two
# minutes of a fresh run)
HOST_PROFILE="${HOST_PROFILE:-release}"
HASEL="$ROOT/target/$HOST_PROFILE/hasel"

step() { printf '\n== [%d s] %s\n' "$SECONDS" "$*"; }

# Installs those of the Debian packages named that are missing.
ensure_packages() {
    local missing=()
    for pkg in "$@"; do
        dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
    done
    if ((${#missing[@]})); then
        step "apt-get install ${missing[*]}"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
    fi
}

ensure_apt() {
    # libclang-dev: bindgen of the `fmi` crate (Rust import test) and of sundials-sys; libtbb12:
    # ecospy; libsundials-dev: native CVODE in hasel bench's `compare` feature
    ensure_packages libclang-dev libtbb12 libsundials-dev
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

# cargo install of a tool the scripts run, unoptimized: each does little work per run (wraps the
# linker, builds the book in 2 s, reads and writes a few thousand rows), and at opt-level 0 it
# compiles about three times faster (on two cores fmi-sim 103 s and mdBook 45 s, where a CI run
# had installed them at release in 318 s and 136 s; the book is the same, byte for byte).
install_tool() {
    CARGO_PROFILE_RELEASE_OPT_LEVEL=0 cargo install -q --locked "$@"
}

ensure_zigbuild() {
    if ! command -v cargo-zigbuild >/dev/null 2>&1; then
        step "cargo install cargo-zigbuild"
        install_tool cargo-zigbuild@0.24.1
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
        install_tool fmi-sim@0.7.0
    fi
}

# mdBook, the Rust project's own tool for books: builds book/ (ci/test.sh). Without its default
# features (the live server and file watcher, which a build does not use) it compiles faster.
ensure_mdbook() {
    if [[ "$(mdbook --version 2>/dev/null || true)" != "mdbook v0.5.4" ]]; then
        step "cargo install mdbook 0.5.4"
        install_tool mdbook@0.5.4 --no-default-features --features search
    fi
}

# A cdylib built with other features needs a target folder of its own (its file name would
# clash); seeded once from the main build's, so that only this crate compiles again, not its
# dependencies (a cold build of them takes minutes on two cores).
seed_target_dir() {
    local dir="$1" from=target triple="$FMU_TARGET" profile=release
    if [ ! -d "$dir/$triple/$profile" ] && [ -d "$from/$triple/$profile" ]; then
        mkdir -p "$dir/$triple" "$dir/$profile"
        cp -a "$from/$triple/$profile" "$dir/$triple/"
        for sub in build deps .fingerprint; do
            if [ -d "$from/$profile/$sub" ] && [ ! -d "$dir/$profile/$sub" ]; then cp -a "$from/$profile/$sub" "$dir/$profile/"; fi
        done
        # cargo's record of what rustc said of the host and target, so that it does not ask again:
        # in a fresh clone's CI run a seeded build's asking failed three times in a row (rustc
        # read a compiler message as its source on stdin), and never when the step ran alone
        if [ -f "$from/.rustc_info.json" ]; then cp -a "$from/.rustc_info.json" "$dir/"; fi
    fi
}

# One shared library of the FMUs, against glibc 2.17 (so it loads on older hosts), at opt-level
# 2 rather than the release profile's 3: a co-simulation step runs about 40 KB of code, more than
# the 32 KB first-level instruction cache, and the smaller code of opt-level 2 made the step
# through the C API 2-5 % faster here in both FMI versions
# (book/src/solver.md, "The FMU library at opt-level 2"). Without the feature tools, which only
# the hasel command needs, as the other platforms' (cross_cargo): on two cores the first build
# took 65 s instead of 143 s, each further one 23 s instead of 48 s.
zigbuild_fmu_lib() {
    CARGO_PROFILE_RELEASE_OPT_LEVEL=2 cargo zigbuild --release --lib --no-default-features \
        --target "$FMU_TARGET.2.17" "$@"
}

# Builds the FMUs' shared libraries against glibc 2.17 (so they load on older hosts): the
# platform's and the slow model's (each FMI 2.0's and 3.0's in one), the inverse FMU's, the CLI,
# and packs fmu/HaselPlatform.fmu, fmu/HaselPlatform-fmi3.fmu, fmu/HaselPlatformReduced.fmu,
# fmu/HaselPlatformReduced-fmi3.fmu and fmu/HaselInverse.fmu.
build_fmu() {
    ensure_venv
    ensure_zigbuild
    step "build the FMU library (FMI 2.0 and 3.0) against glibc 2.17 (cargo zigbuild)"
    zigbuild_fmu_lib
    step "build the hasel command ($HOST_PROFILE)"
    cargo build --profile "$HOST_PROFILE" --bin hasel
    step "pack fmu/HaselPlatform.fmu and fmu/HaselPlatform-fmi3.fmu"
    "$HASEL" fmu --lib "$FMU_LIB"
    step "build the inverse FMU's library (feature inverse-fmu) and pack fmu/HaselInverse.fmu"
    seed_target_dir "$INVERSE_TARGET_DIR"
    zigbuild_fmu_lib --features inverse-fmu --target-dir "$INVERSE_TARGET_DIR"
    "$HASEL" fmu --model inverse --lib "$INVERSE_LIB"
    step "build the slow model's library (feature reduced-fmu) and pack fmu/HaselPlatformReduced.fmu and -fmi3.fmu"
    seed_target_dir "$REDUCED_TARGET_DIR"
    zigbuild_fmu_lib --features reduced-fmu --target-dir "$REDUCED_TARGET_DIR"
    "$HASEL" fmu --model reduced --lib "$REDUCED_LIB"
}

# ---- the other platforms' libraries and commands (ci/platforms.sh; ci/test.sh builds some) ----
#
# Debian's rustc 1.96 (rustc-web) with the standard library's sources of the same version
# (rust-web-src) builds std for each target from source (-Zbuild-std; RUSTC_BOOTSTRAP lets the
# stable compiler take the flag); rustup's toolchain stays the default for everything else.
# Windows links with mingw-w64, macOS with LLVM's ld64.lld against stubs of libSystem.
WINDOWS_TARGET=x86_64-pc-windows-gnu
MAC_TARGETS=(x86_64-apple-darwin aarch64-apple-darwin)
CROSS_TARGETS=("$WINDOWS_TARGET" "${MAC_TARGETS[@]}")
# the targets of the hasel command's cross build (words): every one by default; ci/test.sh leaves
# out macOS x86_64, whose command is only checked, as arm64's is, but without a signature
CROSS_CLI_TARGETS="${CROSS_CLI_TARGETS:-${CROSS_TARGETS[*]}}"
CROSS_DIR="$ROOT/target/cross"
# the one cargo target folder of every cross build: the standard library and the dependencies,
# compiled once per target and profile, serve every set (with a folder per set, seeded by
# copying, cargo compiled them all again: a further library took 113 s, in the shared
# folder 11 s)
CROSS_BUILD_DIR="$CROSS_DIR/build"
# what is built, each copied into a folder of its own under CROSS_DIR: the three FMU libraries
# (the platform's and the slow model's, each for FMI 2.0 and 3.0, and the inverse's; without the
# feature tools, which only the hasel command needs) and the hasel command
declare -A CROSS_ARGS=([platform]="--lib --no-default-features"
    [reduced]="--lib --no-default-features --features reduced-fmu"
    [inverse]="--lib --no-default-features --features inverse-fmu" [cli]="--bin hasel")
# the cargo profile of the cross builds: release for what ships; CROSS_PROFILE=cross-test for a
# cheaper build to test (Cargo.toml says why)
CROSS_PROFILE="${CROSS_PROFILE:-release}"
# the linker's stub libraries for macOS (darwin_sdk) and the tools cross builds run by name
# (rust-objcopy, Debian's cargo), first on their PATH
DARWIN_SDK="$CROSS_DIR/darwin-sdk"
CROSS_BIN="$CROSS_DIR/bin"
LLVM_BIN=/usr/lib/llvm-16/bin
WHEELS="$ROOT/target/wheels"

ensure_cross_tools() {
    ensure_packages rustc-web cargo-web rust-web-src libstd-rust-web-dev gcc-mingw-w64-x86-64 lld-16 llvm-16
    local version
    version="$(/usr/bin/rustc --version | cut -d' ' -f2)"
    if [ ! -d "/usr/src/rustc-$version/library" ]; then
        echo "Debian's rustc is $version but /usr/src has no standard library sources of it (rust-web-src)" >&2
        return 1
    fi
}

# What tests/python/test_windows.py runs the Windows DLLs with: Wine (64-bit) and gcc (the
# Linux build of the same test importer); mingw-w64 comes with ensure_cross_tools.
ensure_wine() {
    ensure_packages wine wine64 gcc
}

# The stubs ld64.lld links the macOS libraries against, made from the libSystem.tbd of PyPI's
# ziglang (installed into the venv by ci/requirements.txt): a text description of
# /usr/lib/libSystem.B.dylib's exports. Its arm64 entries are for arm64e (the pointer-
# authenticating ABI of Apple's own binaries); ours are plain arm64, so they are renamed.
# libc, libm and libiconv (asked for by the libc crate) resolve to libSystem on macOS too. Also
# rust-objcopy, which rustc runs to strip a macOS binary (LLVM's objcopy under that name), and
# cargo as Debian's, the one of the standard library's sources (maturin runs `cargo` by name).
darwin_sdk() {
    local tbd
    tbd="$(find "$VENV/lib" -path '*/ziglang/lib/libc/darwin/libSystem.tbd' | head -n 1)"
    if [ -z "$tbd" ]; then
        echo "no libSystem.tbd in the venv's ziglang package (ci/requirements.txt)" >&2
        return 1
    fi
    mkdir -p "$DARWIN_SDK" "$CROSS_BIN"
    sed -E 's/arm64e(\.x1)?-/arm64-/g' "$tbd" > "$DARWIN_SDK/libSystem.tbd"
    for lib in libc libm libiconv; do ln -sf libSystem.tbd "$DARWIN_SDK/$lib.tbd"; done
    ln -sf "$LLVM_BIN/llvm-objcopy" "$CROSS_BIN/rust-objcopy"
    ln -sf /usr/bin/cargo "$CROSS_BIN/cargo"
}

# cross_env TRIPLE...: the environment of a cross build for the TRIPLEs (NAME=VALUE lines), at
# opt-level 2 for release as the Linux library (zigbuild_fmu_lib says why).
cross_env() {
    echo RUSTC=/usr/bin/rustc
    echo RUSTC_BOOTSTRAP=1
    echo CARGO_PROFILE_RELEASE_OPT_LEVEL=2
    echo "PATH=$CROSS_BIN:$PATH"
    local triple upper
    for triple in "$@"; do
        upper="${triple^^}"
        upper="${upper//-/_}"
        case "$triple" in
            *-windows-gnu) echo "CARGO_TARGET_${upper}_LINKER=x86_64-w64-mingw32-gcc" ;;
            *-apple-darwin) echo "CARGO_TARGET_${upper}_LINKER=$LLVM_BIN/ld64.lld"
                echo "CARGO_TARGET_${upper}_RUSTFLAGS=-Clinker-flavor=ld64.lld -Clink-arg=-L$DARWIN_SDK -Clink-arg=-lSystem" ;;
        esac
    done
}

# cross_cargo SET TRIPLE...: builds SET (the FMU library platform, reduced or inverse, or cli,
# the hasel command) for every TRIPLE in one cargo run (the targets' builds
# overlap on the two cores) in CROSS_BUILD_DIR, with the profile CROSS_PROFILE, and copies what it
# made to cross_file's place.
cross_cargo() {
    local set="$1" triple env file dest
    shift
    mapfile -t env < <(cross_env "$@")
    local targets=()
    for triple in "$@"; do targets+=(--target "$triple"); done
    # shellcheck disable=SC2086 # the arguments split into words
    env "${env[@]}" nice -n 10 cargo build -q --profile "$CROSS_PROFILE" "${targets[@]}" \
        -Zbuild-std=std,panic_unwind --target-dir "$CROSS_BUILD_DIR" ${CROSS_ARGS[$set]} < /dev/null
    for triple in "$@"; do
        file="$(cross_artifact "$triple" "$set")"
        dest="$(cross_file "$triple" "$set" "$file")"
        mkdir -p "$(dirname "$dest")"
        cp "$CROSS_BUILD_DIR/$triple/$CROSS_PROFILE/$file" "$dest"
    done
}

# cross_artifact TRIPLE SET: the name of what cross_cargo makes of SET for TRIPLE.
cross_artifact() {
    case "$2:$1" in
        cli:*-windows-gnu) echo hasel.exe ;;
        cli:*) echo hasel ;;
        *:*-windows-gnu) echo hasel_fmu.dll ;;
        *) echo libhasel_fmu.dylib ;;
    esac
}

# cross_file TRIPLE SET FILE: where cross_cargo put FILE of SET for TRIPLE.
cross_file() {
    echo "$CROSS_DIR/$2/$1/$CROSS_PROFILE/$3"
}

# cross_lib TRIPLE SET: the library cross_cargo built.
cross_lib() {
    cross_file "$1" "$2" "$(cross_artifact "$1" "$2")"
}

# darwin_universal SET: the universal macOS library of both architectures (FMI 2.0's darwin64).
darwin_universal() {
    local out="$CROSS_DIR/$1/universal/$CROSS_PROFILE/libhasel_fmu.dylib"
    mkdir -p "$(dirname "$out")"
    "$LLVM_BIN/llvm-lipo" -create "$(cross_lib "${MAC_TARGETS[0]}" "$1")" \
        "$(cross_lib "${MAC_TARGETS[1]}" "$1")" -output "$out"
    echo "$out"
}

# cross_libs SET FLAG: `hasel fmu` arguments (FLAG FILE ...) for the libraries of feature set SET
# built for other platforms, whichever are there: Windows's, and macOS's (for FMI 2.0, FLAG --lib,
# one universal library of both architectures; for FMI 3.0 one each).
cross_libs() {
    local set="$1" flag="$2" win mac=()
    win="$(cross_lib "$WINDOWS_TARGET" "$set")"
    if [ -f "$win" ]; then printf '%s\n' "$flag" "$win"; fi
    for triple in "${MAC_TARGETS[@]}"; do
        if [ -f "$(cross_lib "$triple" "$set")" ]; then mac+=("$(cross_lib "$triple" "$set")"); fi
    done
    if ((${#mac[@]} == 2)); then
        if [ "$flag" = --lib ]; then
            printf '%s\n' "$flag" "$(darwin_universal "$set")"
        else
            printf '%s\n' "$flag" "${mac[0]}" "$flag" "${mac[1]}"
        fi
    fi
}

# cross_build SET TRIPLE...: builds SET (cross_cargo) for the TRIPLEs.
cross_build() {
    local set="$1"
    shift
    ensure_cross_tools
    ensure_venv
    darwin_sdk
    step "build $set ($CROSS_PROFILE) for $* (Debian's rustc, std from source)"
    timed cross_cargo "$set" "$@"
}

# Packs the five FMUs with the Linux libraries of build_fmu and every other platform's that
# cross_build made (the same library in both versions' FMUs, but for macOS's: FMI 2.0 takes the
# universal one); `hasel fmu` says which went where.
pack_platforms() {
    local v2 v3 reduced reduced3 inverse
    mapfile -t v2 < <(cross_libs platform --lib)
    mapfile -t v3 < <(cross_libs platform --lib-fmi3)
    mapfile -t reduced < <(cross_libs reduced --lib)
    mapfile -t reduced3 < <(cross_libs reduced --lib-fmi3)
    mapfile -t inverse < <(cross_libs inverse --lib)
    step "pack fmu/HaselPlatform.fmu and fmu/HaselPlatform-fmi3.fmu with every platform's library built"
    "$HASEL" fmu --lib "$FMU_LIB" "${v2[@]}" --lib-fmi3 "$FMU_LIB" "${v3[@]}"
    step "pack fmu/HaselPlatformReduced.fmu and fmu/HaselPlatformReduced-fmi3.fmu with every platform's library built"
    "$HASEL" fmu --model reduced --lib "$REDUCED_LIB" "${reduced[@]}" \
        --lib-fmi3 "$REDUCED_LIB" "${reduced3[@]}"
    step "pack fmu/HaselInverse.fmu with every platform's library built"
    "$HASEL" fmu --model inverse --lib "$INVERSE_LIB" "${inverse[@]}"
}

# build_wheel [TRIPLE]: the Python wheel (python/pyproject.toml, maturin) of the hasel command and
# the FMUs in fmu/, into target/wheels: for Linux from build_fmu's build of the command (cargo finds
# it fresh, HOST_PROFILE), for TRIPLE from cross_build's (cli, the same profile and environment).
build_wheel() {
    local args=() env=()
    ensure_venv
    if (($#)); then
        darwin_sdk
        mapfile -t env < <(cross_env "$1")
        args=(--target "$1" -Z build-std=std,panic_unwind --target-dir "$CROSS_BUILD_DIR" --profile "$CROSS_PROFILE")
    else
        args=(--profile "$HOST_PROFILE")
    fi
    mkdir -p python/hasel_fmu/fmu
    cp fmu/HaselPlatform.fmu fmu/HaselPlatform-fmi3.fmu fmu/HaselPlatformReduced.fmu \
        fmu/HaselPlatformReduced-fmi3.fmu fmu/HaselInverse.fmu python/hasel_fmu/fmu/
    step "the Python wheel for ${1:-Linux} (maturin)"
    (cd python && env "${env[@]}" nice -n 10 maturin build -q "${args[@]}" --out "$WHEELS")
}

# The three FMU libraries for Windows and both macOS architectures and the hasel command for
# CROSS_CLI_TARGETS (target/cross/SET/TRIPLE/CROSS_PROFILE/), and the five FMUs packed with them.
build_cross() {
    local set
    for set in platform reduced inverse; do
        cross_build "$set" "${CROSS_TARGETS[@]}"
    done
    # shellcheck disable=SC2086 # the targets split into words
    cross_build cli $CROSS_CLI_TARGETS
    pack_platforms
}

# ci/platforms.sh: build_cross, and a wheel for each platform.
build_platforms() {
    local triple
    build_cross
    build_wheel
    for triple in "${CROSS_TARGETS[@]}"; do build_wheel "$triple"; done
}

# Runs a command and prints how long it took.
timed() {
    local start=$SECONDS
    "$@"
    echo "   ($((SECONDS - start)) s)"
}
