#!/usr/bin/env bash
# The FMUs and the hasel command for every platform, built and tested: the Linux build of
# ci/main.sh, then the three FMU libraries (the platform's and the slow model's, each FMI 2.0's and
# 3.0's in one, and the inverse's) and the hasel command for Windows x86_64 and macOS x86_64 and arm64,
# cross-built here (ci/lib.sh, build_platforms; the commands in target/cross/cli/TRIPLE/release/),
# fmu/HaselPlatform.fmu, fmu/HaselPlatform-fmi3.fmu, fmu/HaselPlatformReduced.fmu,
# fmu/HaselPlatformReduced-fmi3.fmu and fmu/HaselInverse.fmu packed with all of them, and a Python
# wheel for each platform in target/wheels (maturin: the command and the five FMUs), at the release
# profile: what ships.
# Then the platform tests (ci/test.sh runs them too, on builds of the cheap profile cross-test):
# the Windows FMUs and hasel.exe under Wine beside
# Linux's, the macOS binaries checked, the Linux wheel installed into a fresh venv. Installs what it
# needs: Debian's rustc-web with the standard library's sources, mingw-w64, lld-16, llvm-16 and
# wine; the macOS stubs come from the venv's ziglang package.
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
ensure_apt
build_fmu
build_platforms
ensure_wine
step "the other platforms' tests (tests/python/test_windows.py, test_macos.py, test_wheel.py)"
HASEL_PLATFORMS=required python -m pytest -q -p no:cacheprovider \
    tests/python/test_windows.py tests/python/test_macos.py tests/python/test_wheel.py
