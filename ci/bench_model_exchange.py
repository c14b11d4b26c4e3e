"""fmpy's Model Exchange run beside its Co-Simulation run: 10 s of the paper's excitation (60 V sine
at 3*pi rad/s, phases 0/120/240 degrees) held over each 1 ms, through CVode at two relative
tolerances and through 1 ms Co-Simulation steps; prints the wall times and how far each ME run is
from the CS one."""
import argparse
import time

import numpy as np
from fmpy import simulate_fmu

HEIGHTS = ["h1", "h2", "h3"]


def held_sine(t_end, dt=1e-3, omega=3 * np.pi):
    """The sine sampled every dt and held: for Co-Simulation one row per step, for Model Exchange
    two rows per change (fmpy takes two rows at the same time as a step there)."""
    t = np.arange(0.0, t_end + dt / 2, dt)
    u = [60.0 * np.sin(omega * t + 2 * np.pi * i / 3) for i in range(3)]
    cs = np.zeros(len(t), dtype=[("time", float), ("U1", float), ("U2", float), ("U3", float)])
    me = np.zeros(2 * len(t) - 1, dtype=cs.dtype)
    cs["time"], me["time"][0::2], me["time"][1::2] = t, t, t[1:]
    for i, name in enumerate(("U1", "U2", "U3")):
        cs[name], me[name][0::2], me[name][1::2] = u[i], u[i], u[i][:-1]
    return cs, me


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--fmu", default="fmu/HaselPlatform.fmu")
    ap.add_argument("--t-end", type=float, default=10.0)
    a = ap.parse_args()
    cs_input, me_input = held_sine(a.t_end)

    start = time.perf_counter()
    cs = simulate_fmu(a.fmu, fmi_type="CoSimulation", stop_time=a.t_end, step_size=1e-3, output_interval=1e-3,
                      input=cs_input, output=HEIGHTS)
    print(f"fmpy Co-Simulation, 1 ms steps, {a.t_end:g} s: {time.perf_counter() - start:.2f} s")
    for rtol in (1e-6, 1e-9):
        start = time.perf_counter()
        me = simulate_fmu(a.fmu, fmi_type="ModelExchange", solver="CVode", relative_tolerance=rtol,
                          stop_time=a.t_end, output_interval=1e-3, input=me_input, output=HEIGHTS)
        wall = time.perf_counter() - start
        _, last = np.unique(me["time"][::-1], return_index=True)  # one row per time (after events)
        me = me[len(me) - 1 - last]
        dh = max(np.max(np.abs(me[h] - cs[h])) for h in HEIGHTS)
        print(f"fmpy Model Exchange, CVode rtol {rtol:g}, {a.t_end:g} s: {wall:.2f} s, "
              f"max |dh| from Co-Simulation {dh * 1e6:.2e} um")


if __name__ == "__main__":
    main()
