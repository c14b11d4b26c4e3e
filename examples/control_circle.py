#!/usr/bin/env python3
"""The tip circle of examples/fmpy_controller.py under three controllers, side by side.

    python examples/control_circle.py --fmu fmu/HaselPlatform.fmu --hasel target/release/hasel \
        --t-end 7 --out book/src/figures/control_circle.png

- PI: the hand-tuned PI on U^2 of examples/fmpy_controller.py, the baseline;
- LQI: designed with python-control from `hasel linearize`'s reduced model (examples/control_lqi.py);
- passivity-based: energy shaping and damping injection on the port-Hamiltonian linearization
  (examples/control_passivity.py; its stability argument in book/src/control_passivity.md).

The two designs start from the equilibrium where all three heights are H0, found with
`hasel linearize` (examples/linear_design.py). Each runs against the FMU through fmpy on the same
circle, and each one's tip tracking error after the first period is printed (RMS and maximum).
"""
import argparse
import pathlib
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import control_lqi  # noqa: E402
import control_passivity  # noqa: E402
from fmpy_controller import H0, PERIOD, T_SETTLE, make_pi, run_circle, tracking_error  # noqa: E402
from linear_design import operating_point  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--fmu", default=str(ROOT / "fmu" / "HaselPlatform.fmu"), help="path of HaselPlatform.fmu")
    parser.add_argument("--hasel", default=str(ROOT / "target" / "release" / "hasel"), help="the hasel command")
    parser.add_argument("--t-end", type=float, default=T_SETTLE + 3 * PERIOD, help="stop time [s]")
    parser.add_argument("--out", default="control_circle.png", help="PNG to write")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as work:
        lin, reduced = operating_point(args.hasel, H0, work)
    print("operating point: U0 = " + ", ".join(f"{u:.3f}" for u in lin["u0"]) + f" V (h = {H0 * 1e6:.0f} um); "
          f"reduced model of order {reduced['order']}")
    controllers = {
        "PI": make_pi,
        "LQI": lambda reference, get: control_lqi.Lqi(lin, reduced, reference),
        "passivity-based": control_passivity.make(lin),
    }
    fig, (ax_xy, ax_err) = plt.subplots(1, 2, figsize=(12, 4.8))
    first = True
    for colour, (name, make) in zip(("C0", "C1", "C2"), controllers.items()):
        log, _ = run_circle(args.fmu, make, args.t_end, name=name)
        time, ref, got, volts = log[:, 0], log[:, 1:3], log[:, 3:5], log[:, 5:8]
        rms, worst, err = tracking_error(log)
        print(f"{name}: tip tracking error after the first period: RMS {rms * 1e6:.4f} um, "
              f"max {worst * 1e6:.4f} um; voltages {volts.min():.1f} .. {volts.max():.1f} V")
        if first:
            ax_xy.plot(ref[:, 0] * 1e6, ref[:, 1] * 1e6, "k--", lw=1, label="reference")
            first = False
        ax_xy.plot(got[:, 0] * 1e6, got[:, 1] * 1e6, colour, lw=1, label=name)
        ax_err.semilogy(time, err * 1e6, colour, lw=1, label=f"{name} (RMS {rms * 1e6:.3f} um)")
    ax_xy.set(xlabel="tip x [um]", ylabel="tip y [um]", title="Tip path (FMU through fmpy)", aspect="equal")
    ax_xy.legend(loc="upper right")
    ax_err.axvline(T_SETTLE + PERIOD, color="gray", ls=":", label="end of the first period")
    ax_err.set(xlabel="t [s]", ylabel="|tip - reference| [um]", title="Tracking error (RMS after the first period)")
    ax_err.legend(loc="lower left")
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
