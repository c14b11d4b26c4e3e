"""The packed FMI 3.0 FMU through fmpy: validation, the same interface as the FMI 2.0 FMU, the 1 ms
ZOH reference in Co-Simulation (and the FMI 2.0 FMU's co-simulation reproduced bit for bit) and in
Model Exchange through fmpy's CVode."""
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from test_fmu_fmpy import OUTPUTS, load_reference, zoh_input


@pytest.mark.parametrize("which", ["fmu3_path", "reduced_fmu3_path"])
def test_fmpy_validate_finds_no_problem(which, request):
    assert validate_fmu(request.getfixturevalue(which)) == []


def test_same_variables_as_the_fmi2_fmu(fmu_path, fmu3_path):
    md2, md3 = read_model_description(fmu_path), read_model_description(fmu3_path)
    assert md3.fmiVersion == "3.0" and md3.coSimulation.modelIdentifier == "HaselPlatform"
    assert md3.instantiationToken and md3.modelExchange.modelIdentifier == "HaselPlatform"
    assert md3.coSimulation.canGetAndSetFMUstate and md3.coSimulation.canSerializeFMUstate
    v2 = [(v.name, v.valueReference, v.causality, v.variability, v.unit, v.description, v.start)
          for v in md2.modelVariables]
    v3 = [(v.name, v.valueReference, v.causality, v.variability, v.unit, v.description, v.start)
          for v in md3.modelVariables if v.causality != "independent"]
    assert v3 == v2
    assert all(v.type == "Float64" for v in md3.modelVariables)
    (time,) = [v for v in md3.modelVariables if v.causality == "independent"]
    assert time.name == "time" and time.unit == "s"
    assert [u.variable.name for u in md3.outputs] == OUTPUTS
    states = [d.variable.derivative.name for d in md3.derivatives]
    assert len(states) == 99 and states[:5] == ["theta_1", "l_p_1", "p_1", "Q1_1", "Q2_1"], states
    with zipfile.ZipFile(fmu3_path) as z:  # fmpy 0.3 does not read the 3.0 capability flags
        xml = z.read("modelDescription.xml").decode()
    assert xml.count('providesDirectionalDerivatives="true"') == 2  # ME and CS


def simulate(path, ref):
    return simulate_fmu(path, fmi_type="CoSimulation", start_time=0.0, stop_time=2.0, step_size=1e-3,
                        output_interval=1e-3, input=zoh_input(ref), output=OUTPUTS, validate=True)


def test_one_ms_steps_reproduce_the_reference_and_fmi2_bit_for_bit(fmu_path, fmu3_path, reference_dir):
    ref = load_reference(reference_dir, "zoh1ms_sine60_w3pi.csv")
    res3, res2 = simulate(fmu3_path, ref), simulate(fmu_path, ref)
    assert len(res3) == len(ref)
    assert np.allclose(res3["time"], ref["t"], atol=1e-9)
    dh = max(np.max(np.abs(res3[h] - ref[h])) for h in ("h1", "h2", "h3"))
    dtip = max(np.max(np.abs(res3[c] - ref[c])) for c in ("tip_x", "tip_y", "tip_z"))
    print(f"fmpy FMI 3.0 CS vs zoh1ms reference: max |dh| = {dh * 1e6:.2e} um, max |dtip| = {dtip * 1e6:.2e} um")
    assert dh <= 0.01e-6 and dtip <= 0.02e-6
    for y in OUTPUTS:
        assert np.array_equal(res3[y], res2[y]), y


def test_model_exchange_through_cvode_reproduces_the_reference(fmu3_path, reference_dir):
    """Inputs held over each 1 ms interval (a step at every sample: the time given twice), CVode
    at rtol 1e-9 over the first 0.5 s of the reference."""
    ref = load_reference(reference_dir, "zoh1ms_sine60_w3pi.csv")[:501]
    held = np.zeros(2 * len(ref) - 1, dtype=[("time", float), ("U1", float), ("U2", float), ("U3", float)])
    held["time"] = np.repeat(ref["t"], 2)[1:]
    for u in ("U1", "U2", "U3"):
        held[u] = np.repeat(ref[u], 2)[:-1]
    res = simulate_fmu(fmu3_path, fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-9,
                       stop_time=0.5, output_interval=1e-3, input=held, output=OUTPUTS, validate=True)
    # fmpy records before and after each input step; the outputs (states only) agree, keep the last
    _, last = np.unique(res["time"][::-1], return_index=True)
    res = res[::-1][last]
    assert np.allclose(res["time"], ref["t"], atol=1e-12)
    dh = max(np.max(np.abs(res[h] - ref[h])) for h in ("h1", "h2", "h3"))
    dtip = max(np.max(np.abs(res[c] - ref[c])) for c in ("tip_x", "tip_y", "tip_z"))
    print(f"fmpy FMI 3.0 ME (CVode, rtol 1e-9) vs zoh1ms reference: max |dh| = {dh * 1e6:.2e} um, "
          f"max |dtip| = {dtip * 1e6:.2e} um")
    assert dh <= 0.01e-6 and dtip <= 0.02e-6
