#!/usr/bin/env bash
# The main job: build fmu/HaselPlatform.fmu and show it working through fmpy.
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
ensure_apt
build_fmu
step "validate with fmpy"
fmpy validate fmu/HaselPlatform.fmu
step "co-simulate the FMU with fmpy: 10 s of the paper's excitation at 1 ms steps"
python ci/demo.py --fmu fmu/HaselPlatform.fmu --out out/fmu_demo.png
