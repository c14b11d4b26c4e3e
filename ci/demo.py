"""Show the packed FMU working: co-simulate it with fmpy (1 ms steps, the paper's 60 V sine at
3*pi rad/s on the three actuators with phases 0, 120, 240 degrees, held over each step), print
what it did and how fast, and draw h_i(t) and the tip's XY path."""
import argparse
import pathlib
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from fmpy import simulate_fmu  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--fmu", default="fmu/HaselPlatform.fmu")
    ap.add_argument("--t-end", type=float, default=10.0)
    ap.add_argument("--out", default="out/fmu_demo.png")
    a = ap.parse_args()

    dt, omega = 1e-3, 3 * np.pi
    t = np.arange(0.0, a.t_end + dt / 2, dt)
    signals = np.zeros(len(t), dtype=[("time", float), ("U1", float), ("U2", float), ("U3", float)])
    signals["time"] = t
    for i, u in enumerate(("U1", "U2", "U3")):
        signals[u] = 60.0 * np.sin(omega * t + 2 * np.pi * i / 3)

    start = time.perf_counter()
    res = simulate_fmu(a.fmu, fmi_type="CoSimulation", stop_time=a.t_end, step_size=dt, output_interval=dt,
                       input=signals, output=["h1", "h2", "h3", "tip_x", "tip_y"])
    wall = time.perf_counter() - start

    steady = res["time"] >= a.t_end / 2
    um = 1e6
    strokes = [np.ptp(res[h][steady]) * um for h in ("h1", "h2", "h3")]
    print(f"{len(res) - 1} communication steps of {dt * 1e3:g} ms through fmpy in {wall:.2f} s")
    print("steady peak-to-peak strokes h1/h2/h3: " + " / ".join(f"{s:.1f}" for s in strokes) + " um")
    print(f"steady tip path: {np.ptp(res['tip_x'][steady]) * um:.1f} x {np.ptp(res['tip_y'][steady]) * um:.1f} um (X x Y)")

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 5))
    for h in ("h1", "h2", "h3"):
        ax1.plot(res["time"], res[h] * um, label=h)
    ax1.set(xlabel="t [s]", ylabel="h [um]", title="Actuator heights (HaselPlatform.fmu, fmpy)")
    ax1.legend()
    ax2.plot(res["tip_x"] * um, res["tip_y"] * um, color="0.3")
    ax2.set(xlabel="tip x [um]", ylabel="tip y [um]", title="Antenna tip path", aspect="equal")
    fig.tight_layout()
    out = pathlib.Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
