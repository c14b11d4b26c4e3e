"""The FMUs' Windows binaries, inspected and run.

Inspected: each DLL (win64 in the FMI 2.0 FMUs HaselPlatform, HaselPlatformReduced and HaselInverse,
x86_64-windows in the FMI 3.0 ones HaselPlatform-fmi3 and HaselPlatformReduced-fmi3) exports exactly
the FMI functions of its version and imports only Windows' own DLLs.

Run: tests/windows/cosim.c, a co-simulation importer in C, is built twice, with mingw-w64 for
Windows and with gcc for Linux, and runs HaselPlatform and the slow model's HaselPlatformReduced
(the same inputs and outputs), each in FMI 2.0 and 3.0. The Windows program loads the FMU's DLL
under Wine (Debian's wine64; a test-only stand-in for bcryptprimitives.dll, which Wine 8.0 lacks,
sits beside it), the Linux program the FMU's .so. Each calls the library wrongly first (NULLs, wrong
states, a wrong GUID or token, bytes that are no FMU state: errors, logged, no crash), then runs 2 s
of the paper's excitation at 1 ms steps with a replay from the FMU state and from its serialized
bytes (bit for bit), and prints the outputs. The resources are read from a folder whose name needs
percent-encoding in a URI ("my fmü"), with a changed parameter: the GUID or token given is that of
the changed parameter, so an instance is made only if the library found and read the file.

The two platforms' outputs agree within 1e-12 m (the heights move by ~1e-4 m; measured, FMI 2.0 and
3.0 alike: 6.8e-20 m for HaselPlatform, 2.0e-20 m for HaselPlatformReduced, last-bit differences
both, so the slow model is held to the same bound). Not bit for bit by requirement: under Wine the
DLL's sin, exp and pow are msvcrt's (Wine's own implementation), and the test program's excitation
uses them too; glibc's may round the last bit differently. The solver is deterministic and smooth in
its inputs, so such a difference stays near the rounding level unless it flips a step-size decision,
which would still keep the runs within the solver's error control; 1e-12 m is far below anything
physical and far above rounding.

The Windows builds come from `bash ci/test.sh` (profile cross-test) and `bash ci/platforms.sh` (release),
which both run these tests with HASEL_PLATFORMS=required; run alone on a Linux-only build, they skip,
saying so.

The hasel command for Windows (hasel.exe, cross-built by ci/platforms.sh) runs under
Wine too: `simulate`, its CSV compared with the Linux command's, and `identify`, its estimates
compared with Linux's in units of their standard errors (IDENTIFY_TOLERANCE says why).
"""
import json
import os
import pathlib
import re
import shutil
import struct
import subprocess
import zipfile

import pytest
from conftest import cross_built, platform_missing
from test_binary import exported_functions

ROOT = pathlib.Path(__file__).resolve().parents[2]
SOURCES = ROOT / "tests" / "windows"
MINGW = "x86_64-w64-mingw32-gcc"
# what the DLLs may import: the Windows API sets and system DLLs Rust's standard library uses
SYSTEM_DLLS = {
    "kernel32.dll", "msvcrt.dll", "ntdll.dll", "userenv.dll", "ws2_32.dll", "bcryptprimitives.dll",
    "advapi32.dll", "api-ms-win-core-synch-l1-2-0.dll",
}
TOLERANCE = 1e-12  # m


def need(tool):
    path = shutil.which(tool)
    if not path:
        platform_missing(f"{tool} is missing: `bash ci/platforms.sh` installs it (ci/lib.sh, ensure_wine)")
    return path


def dll_of(fmu, folder, tmp_path_factory):
    with zipfile.ZipFile(fmu) as z:
        member = next((n for n in z.namelist() if n.startswith(f"binaries/{folder}/")), None)
        if member is None:
            platform_missing(f"{fmu} has no binaries/{folder}/: `bash ci/platforms.sh` builds it")
        return pathlib.Path(z.extract(member, tmp_path_factory.mktemp("dll")))


# each FMU with a Windows DLL: (its fixture in conftest.py, the folder of its DLL)
DLLS = {
    "HaselPlatform 2.0": ("fmu_path", "win64"),
    "HaselPlatform 3.0": ("fmu3_path", "x86_64-windows"),
    "HaselPlatformReduced 2.0": ("reduced_fmu_path", "win64"),
    "HaselPlatformReduced 3.0": ("reduced_fmu3_path", "x86_64-windows"),
    "HaselInverse 2.0": ("inverse_fmu_path", "win64"),
}


@pytest.fixture(scope="module", params=list(DLLS))
def dll(request, tmp_path_factory):
    fixture, folder = DLLS[request.param]
    return dll_of(request.getfixturevalue(fixture), folder, tmp_path_factory), request.param


def pe_tables(path):
    """The DLLs `path` imports and the names it exports (objdump of mingw-w64's binutils)."""
    text = subprocess.run([need("x86_64-w64-mingw32-objdump"), "-p", str(path)], capture_output=True,
                          text=True, check=True).stdout
    imports = {m.lower() for m in re.findall(r"DLL Name: (\S+)", text)}
    exports = set(re.findall(r"^\s+\[\s*\d+\] (\w+)$", text.split("[Ordinal/Name Pointer] Table")[1],
                             re.MULTILINE))
    return imports, exports


def test_the_dll_exports_exactly_the_fmi_functions_and_imports_only_windows(dll):
    path, fmu = dll
    imports, exports = pe_tables(path)
    expected = exported_functions(fmu)
    assert exports == expected, (exports - expected, expected - exports)
    assert imports and imports <= SYSTEM_DLLS, imports - SYSTEM_DLLS


@pytest.fixture(scope="module")
def programs(tmp_path_factory):
    """cosim.exe with the bcryptprimitives.dll stand-in beside it, and the Linux cosim."""
    out = tmp_path_factory.mktemp("cosim")
    flags = ["-std=c11", "-O2", "-Wall", "-Wextra", "-Werror"]
    subprocess.run([need(MINGW), *flags, "-o", out / "cosim.exe", SOURCES / "cosim.c", "-lshell32"], check=True)
    subprocess.run([need(MINGW), *flags, "-shared", "-o", out / "bcryptprimitives.dll",
                    SOURCES / "bcryptprimitives.c", "-ladvapi32"], check=True)
    subprocess.run([need("gcc"), *flags, "-o", out / "cosim", SOURCES / "cosim.c", "-ldl", "-lm"], check=True)
    return out


@pytest.fixture(scope="module")
def wine_env(tmp_path_factory):
    need("wine")
    return {**os.environ, "WINEPREFIX": str(tmp_path_factory.mktemp("wineprefix")), "WINEDEBUG": "-all"}


def windows_path(path):
    """The path as Wine's Windows programs see it: drive Z: is the Linux root."""
    return "Z:" + str(path).replace("/", "\\")


def run(cmd, env=None):
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 0 and "all checks passed" in p.stdout, p.stdout[-3000:] + p.stderr[-3000:]
    assert "ok replay" in p.stdout, p.stdout[-3000:]
    misuse = [line for line in p.stdout.splitlines() if line.startswith("ok misuse")]
    assert len(misuse) >= 7, misuse
    return p.stdout


def outputs(stdout):
    """The printed rows: time and the six outputs, each decoded from the hexadecimal bits."""
    rows = [[struct.unpack("<d", bytes.fromhex(h)[::-1])[0] for h in line.split()[1:]]
            for line in stdout.splitlines() if line.startswith("y ")]
    assert len(rows) == 2000 and all(len(r) == 7 for r in rows)
    return rows


# the FMUs cosim.c runs, by `hasel describe --model` and FMI version: their fixtures in conftest.py
RUNS = {
    ("platform", "2"): "fmu_path",
    ("platform", "3"): "fmu3_path",
    ("reduced", "2"): "reduced_fmu_path",
    ("reduced", "3"): "reduced_fmu3_path",
}


@pytest.mark.parametrize("model,version", list(RUNS), ids=[f"{m}-{v}" for m, v in RUNS])
def test_the_windows_dll_runs_under_wine_as_the_linux_library_runs(model, version, request, programs, wine_env,
                                                                  hasel_path, tmp_path):
    fmu = request.getfixturevalue(RUNS[model, version])
    folder = tmp_path / "my fmü"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    binaries = {"2": ("linux64", "win64"), "3": ("x86_64-linux", "x86_64-windows")}[version]
    if not (folder / "binaries" / binaries[1]).is_dir():
        platform_missing(f"{fmu} has no binaries/{binaries[1]}/: `bash ci/platforms.sh` builds it")
    so, dll = (next((folder / "binaries" / b).iterdir()) for b in binaries)
    params = folder / "resources" / "parameters.toml"
    text, n = re.subn(r"(?m)^Kb_1 = \S+", "Kb_1 = 0.31", params.read_text())
    assert n == 1
    params.write_text(text)
    description = subprocess.run([hasel_path, "describe", "--model", model, "--fmi", version, "--params", params],
                                 capture_output=True, text=True, check=True).stdout
    key = "guid" if version == "2" else "instantiationToken"
    token = re.search(rf'{key}="([^"]+)"', description)[1]
    packed = re.search(rf'{key}="([^"]+)"', (folder / "modelDescription.xml").read_text())[1]
    assert token != packed  # only a library that read the changed parameter accepts it
    resources = folder / "resources"
    if version == "2":
        linux_location = resources.as_uri()
        windows_location = pathlib.PureWindowsPath(windows_path(resources)).as_uri()
        assert "%20" in windows_location and "%C3%BC" in windows_location
    else:
        linux_location, windows_location = f"{resources}/", windows_path(resources) + "\\"
    linux = outputs(run([programs / "cosim", version, so, token, linux_location]))
    windows = outputs(run(["wine", programs / "cosim.exe", version, windows_path(dll), token, windows_location],
                          env=wine_env))
    assert [r[0] for r in windows] == [r[0] for r in linux]
    worst = max(abs(a - b) for rl, rw in zip(linux, windows) for a, b in zip(rl[1:], rw[1:]))
    peak = max(abs(v) for r in linux for v in r[1:4])
    print(f"{model}, FMI {version}.0: Windows under Wine vs Linux, largest output difference {worst:.3g} m "
          f"(heights up to {peak:.3g} m)")
    assert worst <= TOLERANCE


@pytest.fixture(scope="module")
def hasel_exe(programs):
    """hasel.exe beside the bcryptprimitives.dll stand-in (built by ci/platforms.sh)."""
    exe = cross_built("x86_64-pc-windows-gnu", "hasel.exe")
    if exe is None:
        platform_missing("hasel.exe is missing: `bash ci/platforms.sh` builds it")
    return shutil.copy(exe, programs)


def wine_hasel(hasel_exe, wine_env, *args):
    return subprocess.run(["wine", hasel_exe, *map(str, args)], env=wine_env, check=True, capture_output=True,
                          text=True, timeout=300).stdout


def test_hasel_exe_simulates_under_wine_as_on_linux(hasel_exe, wine_env, hasel_path, tmp_path):
    """2 s of the paper's excitation, the CSV compared with the Linux command's. The inputs differ by a
    last bit of sin (msvcrt's under Wine), the outputs by as little (measured: 9e-17 m)."""
    wine_hasel(hasel_exe, wine_env, "simulate", "--t-end", "2", "--out", windows_path(tmp_path / "win.csv"))
    subprocess.run([hasel_path, "simulate", "--t-end", "2", "--out", tmp_path / "linux.csv"], check=True,
                   capture_output=True)
    rows = [[line.split(",") for line in (tmp_path / f).read_text().splitlines()] for f in ("win.csv", "linux.csv")]
    assert rows[0][0] == rows[1][0] and len(rows[0]) == len(rows[1]) == 2002
    worst = {name: max(abs(float(a[j]) - float(b[j])) for a, b in zip(rows[0][1:], rows[1][1:]))
             for j, name in enumerate(rows[0][0])}
    print("hasel.exe simulate under Wine vs Linux, largest difference per column:", worst)
    assert worst["t"] == 0 and max(worst[c] for c in ("U1", "U2", "U3")) <= 1e-12
    assert max(v for c, v in worst.items() if c[0] in "ht") <= TOLERANCE


# what identification may differ by between the platforms, as a fraction of each estimate's
# standard error: the simulations differ in last bits (exp and pow are msvcrt's under Wine), which
# can move where Levenberg-Marquardt stops by its convergence tolerance, not by anything the data
# could tell apart
IDENTIFY_TOLERANCE = 1e-3


def test_hasel_exe_identifies_under_wine_as_on_linux(hasel_exe, wine_env, hasel_path, tmp_path):
    """An experiment written by the Linux command (2 s, a stiffer actuator 1, 0.5 % noise), fitted by
    both commands on Kb_1 and b_1: the same estimates, standard errors and fit."""
    experiment = tmp_path / "exp.csv"
    subprocess.run([hasel_path, "synth", "--t-end", "2", "--set", "Kb_1=0.31", "--noise", "0.005",
                    "--out", experiment], check=True, capture_output=True)
    fit = ["--free", "Kb_1,b_1"]
    subprocess.run([hasel_path, "identify", experiment, *fit, "--out", tmp_path / "linux"], check=True,
                   capture_output=True)
    wine_hasel(hasel_exe, wine_env, "identify", windows_path(experiment), *fit, "--out",
               windows_path(tmp_path / "win"))
    linux, win = (json.loads((tmp_path / d / "identification.json").read_text()) for d in ("linux", "win"))
    assert (tmp_path / "win" / "report.md").exists() and (tmp_path / "win" / "fit_0.png").exists()
    assert win["fit"]["estimation"].keys() == linux["fit"]["estimation"].keys()
    worst = 0.0
    for name in ("Kb_1", "b_1"):
        lp, wp = linux["parameters"][name], win["parameters"][name]
        assert lp["estimated"] and wp["estimated"]
        worst = max(worst, abs(wp["value"] - lp["value"]) / lp["std_error"],
                    abs(wp["std_error"] - lp["std_error"]) / lp["std_error"])
    print(f"hasel.exe identify under Wine vs Linux: largest difference {worst:.3g} standard errors "
          f"(Kb_1 {linux['parameters']['Kb_1']['value']:.6g})")
    assert worst <= IDENTIFY_TOLERANCE
    for experiment, scores in linux["fit"]["estimation"].items():
        for output, score in scores.items():
            assert abs(win["fit"]["estimation"][experiment][output] - score) <= 0.01 + 1e-9  # one step of the printed 0.01 %
