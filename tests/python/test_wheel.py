"""The Linux wheel (python/pyproject.toml, built by maturin in ci/platforms.sh) installed into a fresh venv,
without the repository on any path: `pip install` puts `hasel` on the venv's PATH, and
hasel_fmu.fmu_path() names the installed FMUs (HaselPlatform and HaselPlatformReduced, FMI 2.0 and
3.0, and HaselInverse), which fmpy simulates."""
import os
import pathlib
import subprocess
import sys

import pytest
from conftest import platform_missing

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def venv(tmp_path_factory):
    wheels = sorted((ROOT / "target" / "wheels").glob("hasel_fmu-*linux*_x86_64.whl"), key=os.path.getmtime)
    if not wheels:
        platform_missing("no Linux wheel in target/wheels: `bash ci/platforms.sh` builds it")
    env = tmp_path_factory.mktemp("venv") / "env"
    subprocess.run([sys.executable, "-m", "venv", env], check=True)
    subprocess.run([env / "bin" / "python", "-m", "pip", "install", "-q", "--no-index", "--disable-pip-version-check",
                    wheels[-1]], check=True)
    return env


def test_pip_install_puts_hasel_on_path(venv, tmp_path):
    path = {**os.environ, "PATH": f"{venv / 'bin'}{os.pathsep}/usr/bin:/bin"}
    out = tmp_path / "run.csv"
    subprocess.run(["hasel", "simulate", "--t-end", "0.1", "--out", out], env=path, cwd=tmp_path, check=True,
                   capture_output=True)
    assert len(out.read_text().splitlines()) == 102


@pytest.mark.parametrize("model", ["HaselPlatform", "HaselPlatform-fmi3", "HaselPlatformReduced",
                                   "HaselPlatformReduced-fmi3", "HaselInverse"])
def test_fmu_path_names_the_installed_fmus_and_fmpy_runs_them(venv, tmp_path, model):
    from fmpy import simulate_fmu

    path = subprocess.run([venv / "bin" / "python", "-c", f"import hasel_fmu; print(hasel_fmu.fmu_path({model!r}))"],
                          cwd=tmp_path, check=True, capture_output=True, text=True).stdout.strip()
    assert pathlib.Path(path).is_relative_to(venv) and pathlib.Path(path).read_bytes() == \
        (ROOT / "fmu" / f"{model}.fmu").read_bytes()
    result = simulate_fmu(path, stop_time=0.1, output_interval=1e-3)
    assert len(result) == 101
