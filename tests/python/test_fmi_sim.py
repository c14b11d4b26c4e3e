"""fmi-sim, the simulator of the rust-fmi project (`cargo install fmi-sim`, version 0.7; ci/lib.sh
installs it), as a second, independent importer of both interfaces.

Co-Simulation: 2 s of the 1 ms ZOH reference input at 1 ms steps must reproduce the reference (0.01 um
on h, 0.02 um on the tip). Model Exchange: fmi-sim integrates with explicit Euler, which the
nanosecond electrical modes restrict to steps of a few nanoseconds, so it is an import check over a
short horizon: 10 us at 1 ns steps after a voltage step from rest, compared with fmpy's CVode run.

Nothing is skipped: a missing fmi-sim fails the test.
"""
import shutil
import subprocess

import numpy as np
from fmpy import simulate_fmu

OUTPUTS = ["h1", "h2", "h3", "tip_x", "tip_y", "tip_z"]


def fmi_sim(fmu_path, tmp_path, interface, input_rows, options):
    """Runs fmi-sim on the input rows (time, U1, U2, U3) and returns its output CSV as a record array."""
    exe = shutil.which("fmi-sim")
    assert exe, "fmi-sim is not installed: `cargo install --locked fmi-sim@0.7.0` (ci/lib.sh does)"
    inputs, output = tmp_path / f"{interface}_in.csv", tmp_path / f"{interface}_out.csv"
    np.savetxt(inputs, input_rows, delimiter=",", header="time,U1,U2,U3", comments="", fmt="%.17g")
    cmd = [exe, "--model", fmu_path, "-i", str(inputs), "-o", str(output), interface] + options
    result = subprocess.run(cmd, capture_output=True, text=True)
    assert result.returncode == 0, f"{' '.join(cmd)}\n{result.stdout}\n{result.stderr}"
    return np.genfromtxt(output, delimiter=",", names=True, deletechars="")


def test_fmi_sim_co_simulation_reproduces_the_zoh_reference(fmu_path, reference_dir, tmp_path):
    ref = np.genfromtxt(reference_dir / "zoh1ms_sine60_w3pi.csv", delimiter=",", names=True)
    rows = np.column_stack([ref["t"], ref["U1"], ref["U2"], ref["U3"]])
    res = fmi_sim(fmu_path, tmp_path, "cs", rows, ["--step", "1e-3", "-s", "0", "-f", "2", "-n", "0"])
    assert len(res) == len(ref) and np.allclose(res["time"], ref["t"], atol=1e-9)
    dh = max(np.max(np.abs(res[h] - ref[h])) for h in ("h1", "h2", "h3"))
    dtip = max(np.max(np.abs(res[c] - ref[c])) for c in ("tip_x", "tip_y", "tip_z"))
    print(f"fmi-sim CS vs zoh1ms reference: max |dh| = {dh * 1e6:.2e} um, max |dtip| = {dtip * 1e6:.2e} um")
    assert dh <= 0.01e-6 and dtip <= 0.02e-6


def test_fmi_sim_model_exchange_agrees_with_fmpy_over_microseconds(fmu_path, tmp_path):
    """A voltage step from rest: fmi-sim's explicit Euler (one step per output interval, 1 ns) over
    10 us, beside fmpy's CVode at rtol 1e-9. The outputs have moved by nanometres (the charges
    settle within nanoseconds, the film starts to turn); each agrees to 1e-3 of its motion."""
    u, t_end = [60.0, -30.0, 20.0], 1e-5
    rows = np.array([[0.0] + u, [t_end] + u])
    res = fmi_sim(fmu_path, tmp_path, "me", rows, ["-s", "0", "-f", str(t_end), "--output-interval", "1e-9"])
    signals = np.zeros(2, dtype=[("time", float), ("U1", float), ("U2", float), ("U3", float)])
    signals["time"] = [0.0, t_end]
    for i, name in enumerate(("U1", "U2", "U3")):
        signals[name] = u[i]
    ref = simulate_fmu(fmu_path, fmi_type="ModelExchange", solver="CVode", relative_tolerance=1e-9,
                       stop_time=t_end, output_interval=t_end / 10, input=signals, output=OUTPUTS)
    assert len(res) == 10_001 and np.isclose(res["time"][-1], t_end, rtol=1e-9)
    assert np.isclose(ref["time"][-1], t_end, rtol=1e-9)
    worst = 0.0
    for y in OUTPUTS:
        motion = abs(ref[y][-1] - ref[y][0])
        assert motion > 1e-10, f"{y} moved only {motion:e} m"
        assert res[y][0] == ref[y][0], f"{y}: both start at the rest state"
        worst = max(worst, abs(res[y][-1] - ref[y][-1]) / motion)
    print(f"fmi-sim ME (Euler, 1 ns) vs fmpy ME (CVode, rtol 1e-9) at 10 us: largest difference "
          f"{worst:.1e} of an output's motion")
    assert worst <= 1e-3
