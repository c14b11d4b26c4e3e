"""Shared fixtures: the packed FMUs (FMI 2.0, 3.0, the slow model's and the inverse), the hasel
command and the reference data."""
import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def cross_built(triple, name):
    """The hasel command `name` cross-built for `triple` (ci/lib.sh, cross_build cli): the newer of
    the profiles release and cross-test (ci/platforms.sh); None if neither is there."""
    found = [p for p in (ROOT / "target" / "cross" / "cli" / triple / profile / name
                         for profile in ("release", "cross-test")) if p.exists()]
    return max(found, key=lambda p: p.stat().st_mtime, default=None)


def platform_missing(why):
    """A build or tool of another platform is missing: a failure where `bash ci/test.sh` or `bash
    ci/platforms.sh` runs the tests (they build and install them all, HASEL_PLATFORMS=required), a
    skip that says so where pytest runs alone on a Linux-only build."""
    if os.environ.get("HASEL_PLATFORMS") == "required":
        pytest.fail(why)
    pytest.skip(why)


def built(variable, default, how):
    """The file named by the environment `variable`, else `default`; a clear failure if missing."""
    path = pathlib.Path(os.environ.get(variable, default))
    if not path.exists():
        pytest.fail(f"{path} is missing: build it with {how} first")
    return str(path)


@pytest.fixture(scope="session")
def fmu_path():
    return built("HASEL_FMU", ROOT / "fmu" / "HaselPlatform.fmu", "`bash ci/main.sh` (or `hasel fmu`)")


@pytest.fixture(scope="session")
def fmu3_path():
    return built("HASEL_FMU3", ROOT / "fmu" / "HaselPlatform-fmi3.fmu", "`bash ci/main.sh` (or `hasel fmu`)")


@pytest.fixture(scope="session")
def reduced_fmu_path():
    return built("HASEL_REDUCED_FMU", ROOT / "fmu" / "HaselPlatformReduced.fmu",
                 "`bash ci/main.sh` (or `hasel fmu --model reduced`)")


@pytest.fixture(scope="session")
def reduced_fmu3_path():
    return built("HASEL_REDUCED_FMU3", ROOT / "fmu" / "HaselPlatformReduced-fmi3.fmu",
                 "`bash ci/main.sh` (or `hasel fmu --model reduced`)")


@pytest.fixture(scope="session")
def reference_dir():
    return ROOT / "tests" / "data" / "reference"


@pytest.fixture(scope="session")
def hasel_path():
    return built("HASEL", ROOT / "target" / "release" / "hasel", "`cargo build --release --bin hasel`")


@pytest.fixture(scope="session")
def inverse_fmu_path():
    return built("HASEL_INVERSE_FMU", ROOT / "fmu" / "HaselInverse.fmu",
                 "`bash ci/main.sh` (or `hasel fmu --model inverse`)")
