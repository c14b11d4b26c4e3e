"""The slow model's FMU (fmu/HaselPlatformReduced.fmu and its FMI 3.0 twin, src/model/reduced.rs)
through fmpy: the full FMU's interface, and Model Exchange driven the way a new user drives it
(issue 26): the plain input table, an input change at every output point without an input event,
with CVode at its default tolerance and with fmpy's fixed-step Euler at 1 ms."""
import math

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

STOP = 0.5
OUTPUTS = ["h1", "h2", "h3"]
# how far [m] a Model Exchange run may land from the same FMU's Co-Simulation run: 1 % of the
# 95 um stroke. Measured 0.43 um with CVode at the FMU's default tolerance (1e-6; 0.10 um at 1e-10,
# the rest being the input's interpolation between the table's rows against Co-Simulation's hold)
# and 0.49 um with Euler at 1 ms (its own first-order error)
BOUND_CVODE = 1e-6
BOUND_EULER = 1e-6


def plain_table():
    """The paper's sine every 1 ms, one row per time (issue 26)."""
    t = np.arange(0, STOP + 1e-9, 1e-3)
    sig = np.zeros(len(t), dtype=[("time", float), ("U1", float), ("U2", float), ("U3", float)])
    sig["time"] = t
    for i, u in enumerate(("U1", "U2", "U3")):
        sig[u] = 60 * np.sin(3 * np.pi * t + i * 2 * np.pi / 3)
    return sig


def heights(result):
    return np.column_stack([result[name] for name in OUTPUTS])


def by_causality(path):
    md = read_model_description(path)
    return {c: [v.name for v in md.modelVariables if v.causality == c]
            for c in ("input", "output", "parameter")}, md


@pytest.mark.parametrize("which", ["reduced_fmu_path", "reduced_fmu3_path"])
def test_interface_is_the_full_fmus(which, fmu_path, request):
    reduced, md = by_causality(request.getfixturevalue(which))
    full, _ = by_causality(fmu_path)
    assert reduced == full
    assert md.modelExchange.modelIdentifier == "HaselPlatformReduced"
    # of the paper's five states one angle per actuator, plus the effects' (0 while off)
    states = [d.variable.derivative.name for d in md.derivatives]
    paper = ("theta_", "l_p_", "p_", "Q1_", "Q2_")
    assert [n for n in states if n.startswith(paper)] == ["theta_1", "theta_2", "theta_3"]
    assert not any(v.name.startswith(paper[1:]) for v in md.modelVariables)
    # an importer reads an infinite start value as an error: a limit is switched off by 0
    infinite = [v.name for v in md.modelVariables
                if v.causality == "parameter" and not math.isfinite(float(v.start))]
    assert infinite == [], infinite


@pytest.fixture(scope="module")
def co_simulation(reduced_fmu_path):
    """The same FMU in Co-Simulation, the input held over each 1 ms step: the reference of the
    Model Exchange runs. It moves (a reference that stood still would prove nothing)."""
    h = heights(simulate_fmu(reduced_fmu_path, fmi_type="CoSimulation", stop_time=STOP,
                             output_interval=1e-3, input=plain_table(), output=OUTPUTS))
    assert np.ptp(h[:, 1]) > 50e-6
    return h


@pytest.mark.parametrize("which", ["reduced_fmu_path", "reduced_fmu3_path"])
def test_model_exchange_runs_with_cvode_at_its_default_tolerance(which, co_simulation, request):
    result = simulate_fmu(request.getfixturevalue(which), fmi_type="ModelExchange",
                          solver="CVode", output_interval=1e-3, stop_time=STOP,
                          input=plain_table(), output=OUTPUTS)
    assert result["time"][-1] == pytest.approx(STOP)
    h = heights(result)
    assert len(h) == len(co_simulation)
    worst = np.abs(h - co_simulation).max()
    print(f"CVode, default tolerance: |dh| <= {worst * 1e6:.4f} um against Co-Simulation")
    assert worst < BOUND_CVODE


@pytest.mark.parametrize("which", ["reduced_fmu_path", "reduced_fmu3_path"])
def test_model_exchange_runs_with_euler_at_1_ms(which, co_simulation, request):
    result = simulate_fmu(request.getfixturevalue(which), fmi_type="ModelExchange",
                          solver="Euler", step_size=1e-3, output_interval=1e-3, stop_time=STOP,
                          input=plain_table(), output=OUTPUTS)
    assert result["time"][-1] == pytest.approx(STOP)
    h = heights(result)
    worst = np.abs(h - co_simulation).max()
    print(f"Euler 1 ms: |dh| <= {worst * 1e6:.4f} um against Co-Simulation")
    assert worst < BOUND_EULER
