#!/usr/bin/env bash
# The FMUs and the hasel command for every platform: the Linux build of ci/main.sh, then the three
# FMU libraries and the hasel command for Windows x86_64 and macOS x86_64 and arm64, cross-built here
# (ci/lib.sh, build_platforms; the commands in target/cross/cli/TRIPLE/release/), fmu/HaselPlatform.fmu,
# fmu/HaselPlatform-fmi3.fmu and fmu/HaselInverse.fmu packed with all of them, and a Python wheel for
# each platform in target/wheels (maturin: the command and the three FMUs). Installs what it needs:
# Debian's rustc-web with the standard library's sources, mingw-w64, lld-16 and llvm-16; the macOS
# stubs come from the venv's ziglang package.
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
ensure_apt
build_fmu
build_platforms
