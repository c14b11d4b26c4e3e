"""The packed FMI 3.0 FMU through fmpy: validation, the same interface as the FMI 2.0 FMU, the 1 ms
ZOH reference, and the FMI 2.0 FMU's co-simulation reproduced bit for bit."""
import numpy as np
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from test_fmu_fmpy import OUTPUTS, load_reference, zoh_input


def test_fmpy_validate_finds_no_problem(fmu3_path):
    assert validate_fmu(fmu3_path) == []


def test_same_variables_as_the_fmi2_fmu(fmu_path, fmu3_path):
    md2, md3 = read_model_description(fmu_path), read_model_description(fmu3_path)
    assert md3.fmiVersion == "3.0" and md3.coSimulation.modelIdentifier == "HaselPlatform"
    assert md3.instantiationToken and md3.modelExchange is None
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
    assert {u.variable.name for u in md3.initialUnknowns} == set(OUTPUTS)


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
