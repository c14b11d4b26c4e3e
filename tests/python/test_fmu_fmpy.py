"""The packed FMU through fmpy: validation (of the inverse FMU too), the 1 ms ZOH reference in
Co-Simulation and in Model Exchange (fmpy's CVode), the state API."""
import ctypes
import pathlib
import subprocess
import sys

import numpy as np
import pytest
from fmpy import extract, instantiate_fmu, read_model_description, simulate_fmu
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


def held_input(ref):
    """The 1 ms zero-order hold as fmpy's Model Exchange loop applies it. fmpy interpolates a
    continuous input linearly between rows and takes two rows at the same time as a step there (an
    input event: CVode stops, the new value is set in Event Mode, CVode restarts), so each command
    gets a row at the start of its interval and one at its end."""
    n = len(ref)
    signals = np.zeros(2 * n - 1, dtype=[("time", float), ("U1", float), ("U2", float), ("U3", float)])
    signals["time"][0::2] = ref["t"]
    signals["time"][1::2] = ref["t"][1:]
    for u in ("U1", "U2", "U3"):
        signals[u][0::2] = ref[u]
        signals[u][1::2] = ref[u][:-1]
    return signals


@pytest.fixture(params=["fmu_path", "reduced_fmu_path", "inverse_fmu_path"])
def each_fmu(request):
    """The FMI 2.0 FMUs: the platform's, its slow model's (tests/python/test_reduced_fmu.py) and
    the inverse's (tests/python/test_inverse_fmu.py)."""
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
    # one binary, both interfaces, analytic directional derivatives in both
    assert md.modelExchange.modelIdentifier == "HaselPlatform"
    for interface in (md.modelExchange, md.coSimulation):
        assert interface.providesDirectionalDerivative
    # 99 states: the paper's 5 and 28 effect states per actuator, each with its der() variable
    states = [d.variable.derivative for d in md.derivatives]
    assert len(states) == 99 and states[0].name == "theta_1" and states[-1].name == "U_amp2_3"
    assert [d.variable.name for d in md.derivatives][:2] == ["der(theta_1)", "der(l_p_1)"]
    assert by_name["der(Q1_2)"].unit == "A" and by_name["der(theta_3)"].unit == "rad/s"


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


def test_model_exchange_with_cvode_reproduces_the_zoh_reference(fmu_path, reference_dir):
    ref = load_reference(reference_dir, "zoh1ms_sine60_w3pi.csv")
    res = simulate_fmu(
        fmu_path,
        fmi_type="ModelExchange",
        solver="CVode",
        relative_tolerance=1e-9,
        start_time=0.0,
        stop_time=2.0,
        output_interval=1e-3,
        input=held_input(ref),
        output=OUTPUTS,
        validate=True,
    )
    # fmpy records each input event twice, before and after it (the outputs do not depend on U)
    _, last = np.unique(res["time"][::-1], return_index=True)
    res = res[len(res) - 1 - last]
    assert len(res) == len(ref)
    assert np.allclose(res["time"], ref["t"], atol=1e-9)
    dh = max(np.max(np.abs(res[h] - ref[h])) for h in ("h1", "h2", "h3"))
    dtip = max(np.max(np.abs(res[c] - ref[c])) for c in ("tip_x", "tip_y", "tip_z"))
    print(f"fmpy ME (CVode, rtol 1e-9) vs zoh1ms reference: max |dh| = {dh * 1e6:.2e} um, max |dtip| = {dtip * 1e6:.2e} um")
    assert dh <= 0.01e-6 and dtip <= 0.02e-6


def test_model_exchange_needs_each_input_step_as_an_event(fmu_path, reference_dir):
    """fmpy's Model Exchange with the input table a user writes, one row per sample, moves the
    input between rows without stopping CVode: every change starts a transient of the
    nanosecond electrical modes inside a step, and CVode gives up about 1 ms in (issue 26;
    book/src/fmus.md, "Model Exchange in fmpy: inputs as events", says why and how). Written as
    input events (each change two rows at one time, `held_input`), the same run goes through.
    The day fmpy copes with the plain table, the first half of this test says so."""
    ref = load_reference(reference_dir, "zoh1ms_sine60_w3pi.csv")[:501]
    run = dict(fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-6, stop_time=0.5,
               output_interval=1e-3, output=["h1", "h2", "h3"])
    with pytest.raises(RuntimeError, match=r"CVode error \(code -3\).*At t = 0\.001"):
        simulate_fmu(fmu_path, input=zoh_input(ref), **run)
    res = simulate_fmu(fmu_path, input=held_input(ref), **run)
    assert res["time"][-1] == pytest.approx(0.5)
    assert abs(res["h1"][-1] - ref["h1"][500]) <= 0.01e-6


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


EFFECTS_WITH_STATES = {"R3": 2e4, "tau3": 0.5, "k_v": 0.05, "tau_v": 0.3, "k_v_1s": 0.02, "k_h": 0.04,
                       "theta_h": 2e-3, "tau_a": 0.02, "tau_a2": 0.005, "k_c": 40.0, "k3": 30.0}


def started(unzipdir, md, fmi_type, start_values):
    fmu = instantiate_fmu(unzipdir, md, fmi_type=fmi_type)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    if start_values:
        fmu.setReal([vr[n] for n in start_values], list(start_values.values()))
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    if fmi_type == "ModelExchange":
        fmu.newDiscreteStates()
        fmu.enterContinuousTimeMode()
    return fmu


@pytest.mark.parametrize("effects", [False, True], ids=["paper", "effects_with_states"])
def test_directional_derivatives_match_central_differences(fmu_path, effects, tmp_path):
    """fmi2GetDirectionalDerivative through the C API, every column (each state and input) of
    d(der(x), y)/d(x, U), against central differences of fmi2GetDerivatives and the outputs, at a
    state in motion reached by simulation; each row relative to its scale (a state's nominal, 1 um
    for an output), per column <= 1e-6. Co-Simulation and Model Exchange give the same numbers."""
    md = read_model_description(fmu_path)
    unzipdir = extract(fmu_path, unzipdir=str(tmp_path / "unzipped"))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    states = [d.variable.derivative.valueReference for d in md.derivatives]
    unknowns = [d.variable.valueReference for d in md.derivatives] + [vr[o] for o in OUTPUTS]
    inputs = [vr[u] for u in ("U1", "U2", "U3")]
    start_values = EFFECTS_WITH_STATES if effects else {}
    # a state in motion: 10 ms of commands, then 0.5 ms after all three changed
    cs = started(unzipdir, md, "CoSimulation", start_values)
    cs.setReal(inputs, [40.0, 30.0, 50.0])
    cs.doStep(0.0, 0.01)
    cs.setReal(inputs, [45.0, -20.0, 10.0])
    cs.doStep(0.01, 5e-4)
    x0, u0 = cs.getReal(states), cs.getReal(inputs)
    me = started(unzipdir, md, "ModelExchange", start_values)
    n = len(states)
    nominal = (ctypes.c_double * n)()
    me.getNominalsOfContinuousStates(nominal, n)
    row_scale = np.concatenate([np.array(nominal), np.full(len(OUTPUTS), 1e-6)])

    def evaluate(x, u):
        me.setContinuousStates((ctypes.c_double * n)(*x), n)
        me.setReal(inputs, list(u))
        dx = (ctypes.c_double * n)()
        me.getDerivatives(dx, n)
        return np.concatenate([np.array(dx), me.getReal([vr[o] for o in OUTPUTS])])

    knowns = [(k, states[k], nominal[k], x0[k]) for k in range(n)] + [(n + j, inputs[j], 1.0, 0.0) for j in range(3)]
    nonzero = 0
    for j, known, scale, at in knowns:
        evaluate(x0, u0)  # back at the simulated state
        dd = np.array(me.getDirectionalDerivative(unknowns, [known], [1.0]))
        assert np.array_equal(dd, np.array(cs.getDirectionalDerivative(unknowns, [known], [1.0])))
        # within a hundredth of the state: the hysteresis has kinks where d theta/dt or z_h is 0
        h = min(1e-6 * scale, 1e-2 * abs(at)) if at != 0 else 1e-6 * scale
        (xp, up), (xm, um) = [(list(x0), list(u0)) for _ in range(2)]
        if j < n:
            xp[j], xm[j] = x0[j] + h, x0[j] - h
        else:
            up[j - n], um[j - n] = u0[j - n] + h, u0[j - n] - h
        fd = (evaluate(xp, up) - evaluate(xm, um)) / (2 * h)
        size = np.max(np.abs(dd) * scale / row_scale)
        err = np.max(np.abs(dd - fd) * scale / row_scale)
        assert err <= 1e-6 * size, f"column {md.modelVariables[known].name}: error {err:.2e} of {size:.2e}"
        nonzero += size > 0
    # 15 states and 3 inputs move something; with the effects, 48 states
    assert nonzero == (51 if effects else 18)
    for fmu in (cs, me):
        fmu.terminate()
        fmu.freeInstance()
