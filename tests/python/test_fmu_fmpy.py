"""The packed FMU through fmpy: validation (of the inverse FMU too), the 1 ms ZOH reference, the
state API."""
import pathlib
import subprocess
import sys

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

OUTPUTS = ["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"]


def load_reference(reference_dir, name):
    return np.genfromtxt(reference_dir / name, delimiter=",", names=True)


def zoh_input(ref):
    signals = np.zeros(len(ref), dtype=[("time", float), ("U1", float), ("U2", float), ("U3", float)])
    signals["time"] = ref["t"]
    for u in ("U1", "U2", "U3"):
        signals[u] = ref[u]
    return signals


@pytest.fixture(params=["fmu_path", "inverse_fmu_path"])
def each_fmu(request):
    """Both FMUs: the platform's and the inverse's (tests/python/test_inverse_fmu.py)."""
    return request.getfixturevalue(request.param)


def test_fmpy_validate_finds_no_problem(each_fmu):
    assert validate_fmu(each_fmu) == []


def test_fmutool_check_passes(each_fmu):
    # fmu-manipulation-toolbox installs its command beside this interpreter
    fmutool = str(pathlib.Path(sys.executable).with_name("fmutool"))
    result = subprocess.run([fmutool, "-input", each_fmu, "-check"], capture_output=True, text=True)
    log = result.stdout + result.stderr
    assert result.returncode == 0, log
    assert "compliant with FMI-2.0" in log and "No semantic error" in log, log


def test_interface_is_the_contract(fmu_path):
    md = read_model_description(fmu_path)
    assert md.fmiVersion == "2.0" and md.coSimulation.modelIdentifier == "HaselPlatform"
    by_name = {v.name: v for v in md.modelVariables}
    for u in ("U1", "U2", "U3"):
        assert by_name[u].causality == "input" and by_name[u].unit == "V" and float(by_name[u].start) == 0.0
    for y in OUTPUTS:
        assert by_name[y].causality == "output" and by_name[y].unit == "m"
    assert float(by_name["Kb_1"].start) == 0.305 and by_name["Kb_1"].variability == "fixed"
    ex = md.defaultExperiment
    assert (float(ex.startTime), float(ex.stopTime), float(ex.stepSize), float(ex.tolerance)) == (0, 10, 1e-3, 1e-6)
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate


def test_one_ms_steps_reproduce_the_zoh_reference(fmu_path, reference_dir):
    ref = load_reference(reference_dir, "zoh1ms_sine60_w3pi.csv")
    res = simulate_fmu(
        fmu_path,
        fmi_type="CoSimulation",
        start_time=0.0,
        stop_time=2.0,
        step_size=1e-3,
        output_interval=1e-3,
        input=zoh_input(ref),
        output=OUTPUTS,
        validate=True,
    )
    assert len(res) == len(ref)
    assert np.allclose(res["time"], ref["t"], atol=1e-9)
    dh = max(np.max(np.abs(res[h] - ref[h])) for h in ("h1", "h2", "h3"))
    dtip = max(np.max(np.abs(res[c] - ref[c])) for c in ("tip_x", "tip_y", "tip_z"))
    print(f"fmpy vs zoh1ms reference: max |dh| = {dh * 1e6:.2e} um, max |dtip| = {dtip * 1e6:.2e} um")
    assert dh <= 0.01e-6 and dtip <= 0.02e-6


def test_parameters_can_be_set_as_start_values(fmu_path):
    ref = simulate_fmu(fmu_path, stop_time=0.3, step_size=1e-3, output=["h2"], input=None)
    stiffer = simulate_fmu(fmu_path, stop_time=0.3, step_size=1e-3, output=["h2"], start_values={"Kb_2": 0.6})
    # the rest state sags less with a stiffer bending spring
    assert abs(stiffer["h2"][0]) < abs(ref["h2"][0])


def test_effects_are_parameters_and_their_states_variables(fmu_path):
    # amplifier_lag: the amplifier's output follows a 50 V command with its time constant
    lag = simulate_fmu(fmu_path, stop_time=0.1, step_size=1e-3, output=["U_amp_1", "h1"],
                       start_values={"tau_a": 0.03, "U1": 50.0})
    k = int(np.argmin(np.abs(lag["time"] - 0.03)))
    assert abs(lag["U_amp_1"][k] - 50.0 * (1.0 - np.exp(-1.0))) < 0.5
    # delay: nothing moves before the command arrives, then the actuator does
    late = simulate_fmu(fmu_path, stop_time=0.1, step_size=1e-3, output=["h1"],
                        start_values={"tau_d": 0.05, "U1": 60.0})
    before, after = late["h1"][late["time"] < 0.049], late["h1"][late["time"] > 0.09]
    assert np.ptp(before) < 1e-12 and after[-1] - before[0] > 0.5e-6
    # the states of effects that are off read 0
    off = simulate_fmu(fmu_path, stop_time=0.01, step_size=1e-3, output=["Q3_1", "z_v_2"])
    assert np.all(off["Q3_1"] == 0.0) and np.all(off["z_v_2"] == 0.0)
