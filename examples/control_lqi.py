"""LQI tracking of the tip circle, designed with python-control from `hasel linearize`.

The plant is the reduced model of `reduced.json` at the operating point where all three heights
are H0 (examples/linear_design.py), from U1..U3 to h1..h3. As in the PI example, its input is taken
as v = U^2 (B / (2 U0)), to which the heights respond more linearly than to U, and U = sqrt(v).
The design, all in discrete time at the FMU's communication step (zero-order hold, control.c2d):

- feedforward: the reference heights are sinusoids, h_ref - H0 = Re(c rho(t) e^(j w t)), so the
  input that makes the linear model follow them is Re(Gd(e^(j w T))^-1 c rho e^(j w t)), and the
  model driven by it gives the reference state x_ref;
- feedback: LQR on the deviation from x_ref augmented with the integral of the height error
  (control.dlqr), the state estimated from the measured heights by a Kalman predictor
  (control.dlqe); the integral takes up what the linear model misses (the rest of the U^2 force's
  nonlinearity, the geometry's);
- the estimate starts from the rest state (the model's steady state under v = 0), v is clamped
  at 0 and the integral frozen while it is.
"""
import math

import control
import numpy as np

from fmpy_controller import PERIOD, RADIUS, STEP, T_SETTLE

Q_HEIGHT = 1e-6  # m: height error of the reference state's weight
Q_INTEGRAL = 1e-6 * 0.002  # m s: integral error of its weight
R_INPUT = 3000.0  # V^2: input deviation of its weight
PROCESS_NOISE = 1e-3  # the Kalman predictor's process noise relative to the input scale
SENSOR_NOISE = 1e-9  # m, the heights' assumed noise


class Lqi:
    """LQI on v = U^2 with model feedforward; `controller(t, h) -> U` for run_circle."""

    def __init__(self, lin, reduced, reference):
        self.reference = reference
        self.u0 = np.array(lin["u0"])
        self.v0 = self.u0**2
        self.h0 = np.array(lin["y0"][:3])
        a, b, c = (np.array(reduced[k]) for k in ("A", "B", "C"))
        plant = control.ss(a, b / (2 * self.u0), c[:3], np.zeros((3, 3)))
        self.plant = control.c2d(plant, STEP, "zoh")
        ad, bd, cd = self.plant.A, self.plant.B, self.plant.C
        n = ad.shape[0]
        # [x; z] with z[k+1] = z[k] + T (r - C x): the LQR of the augmented system
        aa = np.block([[ad, np.zeros((n, 3))], [-STEP * cd, np.eye(3)]])
        ba = np.vstack([bd, np.zeros((3, 3))])
        qa = np.block([[cd.T @ cd / Q_HEIGHT**2, np.zeros((n, 3))],
                       [np.zeros((3, n)), np.eye(3) / Q_INTEGRAL**2]])
        self.k, _, _ = control.dlqr(aa, ba, qa, np.eye(3) / R_INPUT**2)
        self.l_obs, _, _ = control.dlqe(ad, bd, cd, np.eye(3) * (PROCESS_NOISE * R_INPUT) ** 2,
                                        np.eye(3) * SENSOR_NOISE**2)
        # the steady response to a sinusoid of frequency w, as seen at the sampling instants
        omega = 2 * math.pi / PERIOD
        gain = self.plant(np.exp(1j * omega * STEP))
        angles = reference.angles
        c_ref = -(reference.r / reference.L) * np.exp(-1j * angles)  # h_ref - H0 = Re(c rho e^(j w tau))
        self.ff_phasor = np.linalg.solve(gain, c_ref)
        self.omega = omega
        # the rest state (v = 0) as the model's steady state: the estimate to start from
        self.x_hat = np.linalg.solve(np.eye(n) - ad, bd @ (-self.v0))
        self.x_ref = np.zeros(n)
        self.z = np.zeros(3)

    def feedforward(self, t):
        """δv that makes the discrete linear model's heights follow the circle [V^2]."""
        tau = t - T_SETTLE
        if tau < -STEP / 2:
            return np.zeros(3)
        rho = min(1.0, tau / PERIOD) * RADIUS
        return (self.ff_phasor * rho * np.exp(1j * self.omega * tau)).real

    def __call__(self, t, h):
        ad, bd, cd = self.plant.A, self.plant.B, self.plant.C
        y = h - self.h0
        r = self.reference(t) - self.h0
        dv_ff = self.feedforward(t)
        dv = dv_ff - self.k @ np.concatenate([self.x_hat - self.x_ref, self.z])
        v = np.maximum(self.v0 + dv, 0.0)
        if np.all(v > 0):  # anti-windup: integrate only while v is not clamped
            self.z += STEP * (r - y)
        dv = v - self.v0
        self.x_hat = ad @ self.x_hat + bd @ dv + self.l_obs @ (y - cd @ self.x_hat)
        self.x_ref = ad @ self.x_ref + bd @ dv_ff
        return np.sqrt(v)
