"""The shared object inside each FMU: exactly the 44 FMI 2.0 functions exported, and nothing
but glibc (at most 2.17) and libgcc_s needed, so it loads in common hosts."""
import re
import subprocess
import zipfile

import pytest

FMI2_FUNCTIONS = {
    "fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2SetDebugLogging", "fmi2Instantiate",
    "fmi2FreeInstance", "fmi2SetupExperiment", "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode", "fmi2Terminate", "fmi2Reset", "fmi2GetReal", "fmi2GetInteger",
    "fmi2GetBoolean", "fmi2GetString", "fmi2SetReal", "fmi2SetInteger", "fmi2SetBoolean",
    "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative", "fmi2EnterEventMode", "fmi2NewDiscreteStates",
    "fmi2EnterContinuousTimeMode", "fmi2CompletedIntegratorStep", "fmi2SetTime",
    "fmi2SetContinuousStates", "fmi2GetDerivatives", "fmi2GetEventIndicators",
    "fmi2GetContinuousStates", "fmi2GetNominalsOfContinuousStates", "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives", "fmi2DoStep", "fmi2CancelStep", "fmi2GetStatus",
    "fmi2GetRealStatus", "fmi2GetIntegerStatus", "fmi2GetBooleanStatus", "fmi2GetStringStatus",
}

# glibc's own libraries (before glibc 2.34 pthread, dl and rt were separate files) and libgcc_s
ALLOWED_NEEDED = re.compile(r"^(libc|libm|libpthread|libdl|librt|libgcc_s|ld-linux-x86-64)\.so\.\d+$")


@pytest.fixture(scope="module", params=["HaselPlatform", "HaselInverse"])
def shared_object(request, tmp_path_factory):
    """The binary of each FMU: the platform's and the inverse's (the same library built with
    the feature inverse-fmu)."""
    path = request.getfixturevalue("fmu_path" if request.param == "HaselPlatform" else "inverse_fmu_path")
    with zipfile.ZipFile(path) as z:
        names = z.namelist()
        so = f"binaries/linux64/{request.param}.so"
        assert so in names, names
        assert all("\\" not in n for n in names)
        return z.extract(so, tmp_path_factory.mktemp("so"))


def run(*cmd):
    return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout


def test_exports_exactly_the_44_fmi2_functions(shared_object):
    assert len(FMI2_FUNCTIONS) == 44
    exported = {line.split()[-1] for line in run("nm", "-D", "--defined-only", shared_object).splitlines()}
    assert exported == FMI2_FUNCTIONS, (exported - FMI2_FUNCTIONS, FMI2_FUNCTIONS - exported)


def test_needs_only_glibc_and_libgcc(shared_object):
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[(.+?)\]", run("readelf", "-d", shared_object))
    assert needed and all(ALLOWED_NEEDED.match(n) for n in needed), needed


def test_needs_at_most_glibc_2_17(shared_object):
    versions = {tuple(int(x) for x in v.split(".")) for v in re.findall(r"GLIBC_([0-9.]+)", run("objdump", "-T", shared_object))}
    assert versions and max(versions) <= (2, 17), sorted(versions)
