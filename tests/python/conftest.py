"""Shared fixtures: the packed FMUs (FMI 2.0 and 3.0) and the reference data."""
import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def fmu_path():
    path = pathlib.Path(os.environ.get("HASEL_FMU", ROOT / "fmu" / "HaselPlatform.fmu"))
    if not path.exists():
        pytest.fail(f"{path} is missing: build it with `bash ci/main.sh` (or `hasel fmu`) first")
    return str(path)


@pytest.fixture(scope="session")
def fmu3_path():
    path = pathlib.Path(os.environ.get("HASEL_FMU3", ROOT / "fmu" / "HaselPlatform-fmi3.fmu"))
    if not path.exists():
        pytest.fail(f"{path} is missing: build it with `bash ci/main.sh` (or `hasel fmu`) first")
    return str(path)


@pytest.fixture(scope="session")
def reference_dir():
    return ROOT / "tests" / "data" / "reference"
