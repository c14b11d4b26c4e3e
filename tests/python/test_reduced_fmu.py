"""The slow model's FMU (fmu/HaselPlatformReduced.fmu and its FMI 3.0 twin, src/model/reduced.rs)
through fmpy and fmi-sim: the full FMU's interface, and Model Exchange driven the way a new user
drives it (issue 26): the plain input table, an input change at every output point without an input
event, with fmpy's CVode at its default tolerance, fmpy's fixed-step Euler at 1 ms and fmi-sim's
Euler at 1 ms; and the algorithm of the FMU Compliance Checker's Model Exchange test (explicit Euler,
its default 0.02 s step and 1 ms, over the default experiment's 10 s)."""
import ctypes
import math
import shutil

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Model
from test_fmi_sim import fmi_sim, readable_by_fmi_schema

STOP = 0.5
OUTPUTS = ["h1", "h2", "h3"]
# how far [m] a Model Exchange run may land from the same FMU's Co-Simulation run: 1 % of the
# 95 um stroke. Measured 0.47 um with CVode at the FMU's default tolerance (1e-6; 0.10 um at 1e-10,
# the rest being the input's interpolation between the table's rows against Co-Simulation's hold)
# and 0.49 um with Euler at 1 ms (its own first-order error)
BOUND_CVODE = 1e-6
BOUND_EULER = 1e-6


def plain_table(stop=STOP):
    """The paper's sine every 1 ms, one row per time (issue 26)."""
    t = np.arange(0, stop + 1e-9, 1e-3)
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


@pytest.mark.parametrize("which", ["reduced_fmu_path", "reduced_fmu3_path"])
def test_fmi_sim_model_exchange_runs_at_1_ms(which, co_simulation, request, tmp_path):
    """fmi-sim's Model Exchange is explicit Euler at its step (the FMI 3.0 FMU through the copy
    test_fmi_sim.py explains): the same algorithm as fmpy's Euler at 1 ms, so the same heights up
    to rounding (measured: bit for bit), and as far from Co-Simulation (measured 0.49 um)."""
    fmu = request.getfixturevalue(which)
    given = readable_by_fmi_schema(fmu, tmp_path) if which.endswith("3_path") else fmu
    sig = plain_table()
    rows = np.column_stack([sig[name] for name in ("time", "U1", "U2", "U3")])
    res = fmi_sim(given, tmp_path, "me", rows, ["-s", "0", "-f", str(STOP), "--step", "1e-3", "-n", "0"])
    assert len(res) == len(co_simulation) and res["time"][-1] == pytest.approx(STOP)
    h = heights(res)
    euler = heights(simulate_fmu(fmu, fmi_type="ModelExchange", solver="Euler", step_size=1e-3,
                                 output_interval=1e-3, stop_time=STOP, input=sig, output=OUTPUTS))
    worst = np.abs(h - co_simulation).max()
    print(f"fmi-sim ME, Euler 1 ms: |dh| <= {worst * 1e6:.4f} um against Co-Simulation, "
          f"{np.abs(h - euler).max():.1e} m against fmpy's Euler")
    assert np.abs(h - euler).max() <= 1e-12
    assert worst < BOUND_EULER


# The FMU Compliance Checker's Model Exchange test: explicit Euler at a fixed step over the default
# experiment (10 s), by default 500 steps (0.02 s). It is on no registry this project installs from
# (book/src/fmus.md, "The FMU Compliance Checker's test"), so its algorithm runs here through
# fmpy's Euler.
CHECKER_STOP = 10.0
CHECKER_STEP = 0.02


def largest_rate_slope(fmu_path, theta_rest, theta_60):
    """max |∂θ̇_i/∂θ_i| [1/s] over the angles from rest to the 60 V equilibrium and commands of
    0..60 V, by forward differences of the FMU's derivatives (Model Exchange, FMI 2.0); the effect
    states are off, so the actuators do not couple."""
    md = read_model_description(fmu_path)
    unzipped = extract(fmu_path)
    fmu = FMU2Model(guid=md.guid, unzipDirectory=unzipped,
                    modelIdentifier=md.modelExchange.modelIdentifier, instanceName="slope")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.enterContinuousTimeMode()
    n = len(md.derivatives)
    angles = [k for k, d in enumerate(md.derivatives) if d.variable.derivative.name.startswith("theta_")]
    inputs = [v.valueReference for v in md.modelVariables if v.name in ("U1", "U2", "U3")]

    def rates(theta, u):
        x = np.zeros(n)
        x[angles] = theta
        fmu.setReal(inputs, [u] * 3)
        fmu.setContinuousStates((ctypes.c_double * n)(*x), n)
        dx = (ctypes.c_double * n)()
        fmu.getDerivatives(dx, n)
        return np.array(dx[:])[angles]

    worst, dtheta = 0.0, 1e-9
    for s in np.linspace(0.0, 1.0, 101):
        theta = theta_rest + s * (theta_60 - theta_rest)
        for u in np.linspace(0.0, 60.0, 7):
            slope = (rates(theta + dtheta, u) - rates(theta, u)) / dtheta
            worst = max(worst, np.abs(slope).max())
    fmu.terminate()
    fmu.freeInstance()
    shutil.rmtree(unzipped, ignore_errors=True)
    return worst


@pytest.fixture(scope="module")
def height_range(reduced_fmu_path):
    """The heights at rest and held at 60 V long enough to settle (10 s, 49 of the slowest time
    constants, 1/4.9 s): with |U| <= 60 V each angle stays between the two, since θ̇ = g(θ, U²) is
    a scalar gradient flow per actuator whose force grows with U², and so does explicit Euler's
    θ + h g as long as it is increasing in θ, h |∂g/∂θ| <= 1, which `largest_rate_slope` checks
    for the checker's default step (measured 49.6 /s, so up to h = 20.2 ms)."""
    held = np.zeros(2, dtype=[("time", float), ("U1", float), ("U2", float), ("U3", float)])
    held["time"] = [0.0, CHECKER_STOP]
    for u in ("U1", "U2", "U3"):
        held[u] = 60.0
    angles = ["theta_1", "theta_2", "theta_3"]
    res = simulate_fmu(reduced_fmu_path, fmi_type="CoSimulation", stop_time=CHECKER_STOP,
                       output_interval=1e-3, input=held, output=OUTPUTS + angles)
    h = heights(res)
    assert np.abs(h[-1] - h[-2]).max() < 1e-12, "settled"
    theta = np.column_stack([res[name] for name in angles])
    slope = largest_rate_slope(reduced_fmu_path, theta[0], theta[-1])
    print(f"max |d theta_dot / d theta| from rest to 60 V: {slope:.2f} /s")
    assert CHECKER_STEP * slope <= 1.0
    return h[0], h[-1]


@pytest.mark.parametrize("which", ["reduced_fmu_path", "reduced_fmu3_path"])
@pytest.mark.parametrize("step", [CHECKER_STEP, 1e-3])
def test_compliance_checkers_model_exchange_algorithm(which, step, height_range, request):
    """fmpy's Euler at the checker's default step and at 1 ms, without input and with the paper's
    sine over 10 s: it completes (a discarded or failed call raises), stands still at rest without
    input and stays within the heights at rest and at 60 V (`height_range`; rounding aside, 1e-12 m)."""
    fmu = request.getfixturevalue(which)
    rest, at_60 = height_range
    run = dict(fmi_type="ModelExchange", solver="Euler", step_size=step, output_interval=step,
               stop_time=CHECKER_STOP, output=OUTPUTS)
    still = simulate_fmu(fmu, **run)
    assert still["time"][-1] == pytest.approx(CHECKER_STOP)
    assert np.abs(heights(still) - rest).max() <= 1e-12
    moving = simulate_fmu(fmu, input=plain_table(CHECKER_STOP), **run)
    assert len(moving) == round(CHECKER_STOP / step) + 1
    assert moving["time"][-1] == pytest.approx(CHECKER_STOP)
    h = heights(moving)
    print(f"Euler {step * 1e3:g} ms: heights {h.min(axis=0) * 1e6} .. {h.max(axis=0) * 1e6} um, "
          f"range {rest * 1e6} .. {at_60 * 1e6} um")
    assert np.ptp(h[:, 1]) > 50e-6
    assert (h >= rest - 1e-12).all() and (h <= at_60 + 1e-12).all()
