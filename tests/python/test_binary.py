"""The shared objects inside the FMUs: exactly the 44 FMI 2.0 functions (the platform's and the
inverse's), or exactly the 75 FMI 3.0 functions, exported, and nothing but glibc (at most 2.17) and
libgcc_s needed, so they load in common hosts."""
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

# fmi3Functions.h: the common functions, Model Exchange, Co-Simulation and Scheduled Execution
FMI3_FUNCTIONS = {"fmi3" + f for f in """
    GetVersion SetDebugLogging InstantiateModelExchange InstantiateCoSimulation
    InstantiateScheduledExecution FreeInstance EnterInitializationMode ExitInitializationMode
    EnterEventMode Terminate Reset
    GetFloat32 GetFloat64 GetInt8 GetUInt8 GetInt16 GetUInt16 GetInt32 GetUInt32 GetInt64 GetUInt64
    GetBoolean GetString GetBinary GetClock
    SetFloat32 SetFloat64 SetInt8 SetUInt8 SetInt16 SetUInt16 SetInt32 SetUInt32 SetInt64 SetUInt64
    SetBoolean SetString SetBinary SetClock
    GetNumberOfVariableDependencies GetVariableDependencies
    GetFMUState SetFMUState FreeFMUState SerializedFMUStateSize SerializeFMUState DeserializeFMUState
    GetDirectionalDerivative GetAdjointDerivative EnterConfigurationMode ExitConfigurationMode
    GetIntervalDecimal GetIntervalFraction GetShiftDecimal GetShiftFraction
    SetIntervalDecimal SetIntervalFraction SetShiftDecimal SetShiftFraction
    EvaluateDiscreteStates UpdateDiscreteStates
    EnterContinuousTimeMode CompletedIntegratorStep SetTime SetContinuousStates
    GetContinuousStateDerivatives GetEventIndicators GetContinuousStates
    GetNominalsOfContinuousStates GetNumberOfEventIndicators GetNumberOfContinuousStates
    EnterStepMode GetOutputDerivatives DoStep ActivateModelPartition
""".split()}

def exported_functions(fmu):
    """The C functions the library of `fmu` (e.g. "HaselPlatform 3.0") exports: the inverse's
    FMI 2.0's; the platform's and the slow model's FMI 2.0's and 3.0's, one build serving both
    versions' FMUs (the prefixes keep them apart)."""
    return FMI2_FUNCTIONS if fmu.startswith("HaselInverse") else FMI2_FUNCTIONS | FMI3_FUNCTIONS


# glibc's own libraries (before glibc 2.34 pthread, dl and rt were separate files) and libgcc_s
ALLOWED_NEEDED = re.compile(r"^(libc|libm|libpthread|libdl|librt|libgcc_s|ld-linux-x86-64)\.so\.\d+$")


def extract(fmu, member, tmp_path_factory):
    with zipfile.ZipFile(fmu) as z:
        names = z.namelist()
        assert member in names, names
        assert all("\\" not in n for n in names)
        return z.extract(member, tmp_path_factory.mktemp("so"))


@pytest.fixture(scope="module", params=["HaselPlatform 2.0", "HaselPlatform 3.0", "HaselInverse 2.0"])
def shared_object(request, tmp_path_factory):
    """The binary of each FMU: the platform's for FMI 2.0 and 3.0 (one library in both) and the
    inverse's (the same crate built with the feature inverse-fmu), with the FMU's name."""
    fixture, member = {
        "HaselPlatform 2.0": ("fmu_path", "binaries/linux64/HaselPlatform.so"),
        "HaselPlatform 3.0": ("fmu3_path", "binaries/x86_64-linux/HaselPlatform.so"),
        "HaselInverse 2.0": ("inverse_fmu_path", "binaries/linux64/HaselInverse.so"),
    }[request.param]
    return extract(request.getfixturevalue(fixture), member, tmp_path_factory), request.param


def run(*cmd):
    return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout


def test_exports_exactly_the_fmi_functions(shared_object):
    path, fmu = shared_object
    assert len(FMI2_FUNCTIONS) == 44 and len(FMI3_FUNCTIONS) == 75
    exported = {line.split()[-1] for line in run("nm", "-D", "--defined-only", path).splitlines()}
    expected = exported_functions(fmu)
    assert exported == expected, (exported - expected, expected - exported)


def test_needs_only_glibc_and_libgcc(shared_object):
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[(.+?)\]", run("readelf", "-d", shared_object[0]))
    assert needed and all(ALLOWED_NEEDED.match(n) for n in needed), needed


def test_needs_at_most_glibc_2_17(shared_object):
    versions = {tuple(int(x) for x in v.split(".")) for v in re.findall(r"GLIBC_([0-9.]+)", run("objdump", "-T", shared_object[0]))}
    assert versions and max(versions) <= (2, 17), sorted(versions)
