"""`hasel fmu --from`: a fitted parameter set packed into the FMU a user already has (the wheel's,
or one of fmu/), without building the libraries: the same binaries, the new start values."""
import subprocess
import zipfile

import numpy as np
from fmpy import read_model_description, simulate_fmu


def start_of(fmu, name):
    md = read_model_description(fmu)
    return float(next(v.start for v in md.modelVariables if v.name == name))


def run(hasel_path, *args):
    return subprocess.run([hasel_path, *map(str, args)], capture_output=True, text=True)


def test_a_fitted_parameter_set_is_packed_into_the_fmu_a_user_has(hasel_path, fmu_path, fmu3_path, tmp_path):
    fitted = tmp_path / "fitted.toml"
    fitted.write_text("b_1 = 0.02\nKb_2 = 0.25\n")
    for source, version in ((fmu_path, "2.0"), (fmu3_path, "3.0")):
        out = tmp_path / f"device-{version}.fmu"
        done = run(hasel_path, "fmu", "--params", fitted, "--from", source, "--out", out)
        assert done.returncode == 0, done.stderr
        assert f"FMI {version}" in done.stdout and str(source) in done.stdout
        assert read_model_description(str(out)).fmiVersion == version
        assert start_of(str(out), "b_1") == 0.02 and start_of(str(out), "Kb_2") == 0.25
        # the same binaries, byte for byte
        with zipfile.ZipFile(source) as a, zipfile.ZipFile(out) as b:
            libs = [n for n in a.namelist() if n.startswith("binaries/") and not n.endswith("/")]
            assert libs and all(a.read(n) == b.read(n) for n in libs)
        plain = simulate_fmu(source, stop_time=1.0, output_interval=1e-2, start_values={"U1": 60.0})
        fitted_run = simulate_fmu(str(out), stop_time=1.0, output_interval=1e-2, start_values={"U1": 60.0})
        # a tenth of actuator 1's damping: it rises several times faster
        assert fitted_run["h1"][10] > 2 * plain["h1"][10] > 0


def test_an_fmu_of_another_model_is_refused_and_nothing_is_written(hasel_path, inverse_fmu_path, fmu_path, tmp_path):
    out = tmp_path / "x.fmu"
    done = run(hasel_path, "fmu", "--from", inverse_fmu_path, "--out", out)
    assert done.returncode != 0
    assert f"{inverse_fmu_path}: binaries/" in done.stderr and "not a library of HaselPlatform" in done.stderr
    done = run(hasel_path, "fmu", "--from", fmu_path, "--fmi", "3", "--out", out)
    assert done.returncode != 0 and "is an FMI 2.0 FMU" in done.stderr
    not_zip = tmp_path / "not.fmu"
    not_zip.write_text("no zip")
    done = run(hasel_path, "fmu", "--from", not_zip, "--out", out)
    assert done.returncode != 0 and f"{not_zip}: not an FMU (a zip archive)" in done.stderr
    assert not out.exists()
