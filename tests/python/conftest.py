"""Shared fixtures: the packed FMU and the reference data."""
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
def reference_dir():
    return ROOT / "tests" / "data" / "reference"


@pytest.fixture(scope="session")
def hasel_path():
    path = pathlib.Path(os.environ.get("HASEL", ROOT / "target" / "release" / "hasel"))
    if not path.exists():
        pytest.fail(f"{path} is missing: build it with `cargo build --release --bin hasel` first")
    return str(path)
