#!/usr/bin/env python3
"""Make the antenna tip of the HaselPlatform FMU follow a circle, with a PI controller in Python.

    python examples/fmpy_controller.py --fmu fmu/HaselPlatform.fmu --t-end 7 --out tip_circle.png

The FMU is driven through fmpy's low-level API (FMU2Slave) in 1 ms co-simulation steps; the
controller runs between the steps: read h1..h3, compute U1..U3, set them, fmi2DoStep.

Reference. 0 .. 1 s: all three heights go to the operating point h0 = 50 um; at 1 s the tip's
position there is the circle's centre. Then the tip follows a circle of radius 40 um, period 2 s
(the radius ramps up over the first period so the start has no jump).

Inverse kinematics (closed form, small tilt). The ball joints sit at p_i = r (cos a_i, sin a_i),
r = 20 mm, a_i = 90, 210, 330 deg. The platform plane z = h0 + sx x + sy y passes through them,
so h_i = h0 + r (sx cos a_i + sy sin a_i). The antenna of length L = 50 mm stands on the plane's
normal n ~ (-sx, -sy, 1), so for small slopes tip_x = -L sx and tip_y = -L sy. Together:

    h_i = h0 - (r / L) (dx cos a_i + dy sin a_i),   (dx, dy) = desired tip - centre.

A 40 um circle at the tip thus asks for +-16 um at the actuators. r, L and a_i are read from the
FMU's parameters, not hard-coded.

Control. The electrostatic force goes as U^2, the sign of U does not matter, and an actuator can
only push up. So each actuator gets a PI on its height error whose output is v = U^2 (to which
the height responds about linearly, h ~ 0.03 um/V^2 at low voltage), and U = sqrt(max(0, v)).
The integral finds the operating voltage; it is frozen while v is clamped at 0 (anti-windup).
Since the input is held over the step, the setpoint is the reference at the step's end. With
KP = 1e9 V^2/m and KI = 1e10 V^2/(m s) the tip stays within about 1 um of the circle; much
higher gains (3x) make the lightly damped actuator 2 oscillate at the step rate.
"""
import argparse
import math
import pathlib
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402

STEP = 1e-3  # s, communication step
H0 = 50e-6  # m, operating height of all three actuators
RADIUS = 40e-6  # m, tip circle
PERIOD = 2.0  # s
T_SETTLE = 1.0  # s, time at the operating point before the circle starts
KP = 1e9  # V^2/m: 1 um of height error asks for 1000 V^2 more
KI = 1e10  # V^2/(m s)


class PiOnSquaredVoltage:
    """PI per actuator with output v = U^2 >= 0 and a conditional-integration anti-windup."""

    def __init__(self, kp, ki, n=3):
        self.kp, self.ki, self.integral = kp, ki, np.zeros(n)

    def __call__(self, error, dt):
        clamped = self.kp * error + self.ki * self.integral < 0
        self.integral += np.where(clamped & (error < 0), 0.0, error * dt)
        v = self.kp * error + self.ki * self.integral
        return np.sqrt(np.maximum(v, 0.0))


def circle(tau):
    """Desired tip offset from the centre, tau seconds after the circle started."""
    rho = RADIUS * min(1.0, tau / PERIOD)
    phase = 2 * math.pi * tau / PERIOD
    return rho * np.array([math.cos(phase), math.sin(phase)])


class CircleHeights:
    """The heights that put the tip on the circle (the inverse kinematics above), read from the FMU."""

    def __init__(self, r, L, angles):
        self.r, self.L, self.angles = r, L, np.asarray(angles)

    def __call__(self, t):
        """Reference heights h1..h3 [m] at time t: H0 while settling, then the circle."""
        if t < T_SETTLE - STEP / 2:
            return np.full(3, H0)
        d = circle(t - T_SETTLE)
        return H0 - (self.r / self.L) * (d[0] * np.cos(self.angles) + d[1] * np.sin(self.angles))


def run_circle(fmu_path, make_controller, t_end, name="controlled"):
    """Drive the FMU in STEP co-simulation steps with `controller(t, h) -> U`, made by
    `make_controller(reference, get)` (reference: CircleHeights; get(*names): the FMU's values
    at the start of the run). Returns rows t, reference tip x y, tip x y, U1..U3 from T_SETTLE on
    and the circle's centre (the tip at the operating point)."""
    md = read_model_description(fmu_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    refs = lambda *names: [vr[n] for n in names]  # noqa: E731
    # the unpacked FMU goes when the run ends, whatever the end
    with tempfile.TemporaryDirectory(prefix="hasel-fmu-") as unzipdir:
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu_path, unzipdir=unzipdir),
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        get = lambda *names: np.array(fmu.getReal(refs(*names)))  # noqa: E731
        r, L = get("anchor_radius", "L")
        reference = CircleHeights(r, L, get("anchor_angle_1", "anchor_angle_2", "anchor_angle_3"))
        controller = make_controller(reference, get)
        fmu.exitInitializationMode()

        centre = None
        log = []  # t, reference x y, tip x y, U1..U3
        t = 0.0
        for _ in range(round(t_end / STEP)):
            h = get("h1", "h2", "h3")
            if centre is None and t >= T_SETTLE - STEP / 2:
                centre = get("tip_x", "tip_y")  # the tip at the operating point
            u = controller(t, h)
            fmu.setReal(refs("U1", "U2", "U3"), list(u))
            fmu.doStep(currentCommunicationPoint=t, communicationStepSize=STEP)
            t += STEP
            if centre is not None:  # the tip at the end of the step against the reference then
                log.append([t, *(centre + circle(t - T_SETTLE)), *get("tip_x", "tip_y"), *u])
        fmu.terminate()
        fmu.freeInstance()
        return np.array(log), centre


def tracking_error(log):
    """RMS and maximum distance [m] of the tip from the circle after the first period."""
    time, ref, got = log[:, 0], log[:, 1:3], log[:, 3:5]
    err = np.hypot(*(got - ref).T)
    steady = time > T_SETTLE + PERIOD
    if not steady.any():
        raise SystemExit(f"--t-end must exceed {T_SETTLE + PERIOD} s to measure after the first period")
    return math.sqrt(np.mean(err[steady] ** 2)), err[steady].max(), err


def make_pi(reference, get):
    """The hand-tuned PI above; since the input is held over the step, its setpoint is the
    reference at the step's end."""
    pi = PiOnSquaredVoltage(KP, KI)
    return lambda t, h: pi(reference(t + STEP) - h, STEP)


def main():
    default_fmu = pathlib.Path(__file__).resolve().parents[1] / "fmu" / "HaselPlatform.fmu"
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--fmu", default=str(default_fmu), help="path of HaselPlatform.fmu")
    parser.add_argument("--t-end", type=float, default=T_SETTLE + 3 * PERIOD, help="stop time [s]")
    parser.add_argument("--out", default="tip_circle.png", help="PNG to write")
    args = parser.parse_args()

    log, centre = run_circle(args.fmu, make_pi, args.t_end)
    time, ref, got, volts = log[:, 0], log[:, 1:3], log[:, 3:5], log[:, 5:8]
    rms, worst, err = tracking_error(log)
    print(f"centre of the circle: ({centre[0] * 1e6:.3f}, {centre[1] * 1e6:.3f}) um; "
          f"voltages {volts.min():.1f} .. {volts.max():.1f} V")
    print(f"tip tracking error after the first period: RMS {rms * 1e6:.3f} um, max {worst * 1e6:.3f} um")

    fig, (ax_xy, ax_err) = plt.subplots(1, 2, figsize=(11, 4.8))
    ax_xy.plot(ref[:, 0] * 1e6, ref[:, 1] * 1e6, "k--", lw=1, label="reference")
    ax_xy.plot(got[:, 0] * 1e6, got[:, 1] * 1e6, "C0", lw=1, label="tip (FMU)")
    ax_xy.set(xlabel="tip x [um]", ylabel="tip y [um]", title="Tip path", aspect="equal")
    ax_xy.legend(loc="upper right")
    ax_err.plot(time, err * 1e6, "C3", lw=1)
    ax_err.axvline(T_SETTLE + PERIOD, color="gray", ls=":", label="end of the first period")
    ax_err.set(xlabel="t [s]", ylabel="|tip - reference| [um]",
               title=f"Tracking error (RMS after the first period {rms * 1e6:.2f} um)")
    ax_err.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
