"""Passivity-based tracking of the tip circle: energy shaping and damping injection.

Designed on the port-Hamiltonian linearization of `hasel linearize` at the operating point where
all three heights are H0, from the source voltages w_i = ga(theta_i) U_i, where it is exactly
port-Hamiltonian (A = (J - R) Q, B = g_w; book/src/control.md, "Port-Hamiltonian structure").
Why the closed loop is stable: book/src/control_passivity.md. Per actuator:

1. the charges are 1e5 times faster than the slow mechanics, so they are taken at their
   quasi-static value (singular perturbation), which leaves the mechanical PH system
   I theta'' = -k dtheta - b theta' + beta dw on the invariant curve (l_p slaved to theta),
   with I, k, b and beta read off (J - R) Q and g_w;
2. energy shaping: the feedforward dw_ff = (I alpha_ref + b omega_ref + k dtheta_ref) / beta makes
   the reference a solution, and -k_s (theta - theta_ref) / beta adds the stiffness k_s, so the
   shaped energy 1/2 (k + k_s) (theta - theta_ref)^2 has its minimum on the reference;
3. damping injection: -k_d (omega - omega_ref) / beta adds the damping k_d;
4. w is commanded through U = w / ga(theta) with the measured angle, which takes the modulated
   source term ga'(theta) U dtheta out: the plant the design sees is the PH one. As for U^2 in the
   PI example, the force goes as w^2, so w = sqrt(w0^2 + 2 w0 dw).

theta = asin(2 h / Lv) comes from the measured height (model.md, "Shell geometry and C2"), omega
from its difference over the step; the gains put the shaped mechanics' slow pole at LAMBDA for
every actuator.
"""
import math

import numpy as np

from fmpy_controller import STEP

LAMBDA = 300.0  # rad/s: the shaped slow pole, about (k + k_s) / (b + k_d) (I is small)
DAMPING = 0.5  # k_d = DAMPING * b: the injected damping relative to the film's own
MECH, ELEC = [0, 1, 2], [3, 4]  # theta, l_p, p and Q1, Q2 in an actuator's block of the state


def slow_mechanics(lin, i):
    """I [kg m], k [N m/rad], b [N m s/rad], beta [N m/V] of actuator i from (J - R) Q and g_w,
    the charges eliminated at their quasi-static value and l_p on the invariant curve."""
    ph = lin["port_hamiltonian"]
    block = slice(5 * i, 5 * i + 5)
    a = ((np.array(ph["J"]) - np.array(ph["R"])) @ np.array(ph["Q"]))[block, block]
    g = np.array(ph["g_w"])[block, i]
    # charges at rest under (theta, l_p, p, w): 0 = A_em x_m + A_ee q + g_e w
    elim = a[np.ix_(MECH, ELEC)] @ np.linalg.inv(a[np.ix_(ELEC, ELEC)])
    a_s = a[np.ix_(MECH, MECH)] - elim @ a[np.ix_(ELEC, MECH)]
    g_s = g[MECH] - elim @ g[ELEC]
    d = a_s[1, 2] / a_s[0, 2]  # l_p' = d theta': the lever of model.md
    inertia = 1.0 / a_s[0, 2]
    k = -(a_s[2, 0] + d * a_s[2, 1])
    b = -a_s[2, 2] * inertia
    return inertia, k, b, g_s[2]


class PassivityBased:
    """Energy shaping and damping injection per actuator; `controller(t, h) -> U` for run_circle."""

    def __init__(self, lin, reference, lv, gamma1, gamma2):
        self.reference, self.lv = reference, lv
        self.gamma1, self.gamma2 = np.asarray(gamma1), np.asarray(gamma2)
        self.theta0 = np.array([lin["x0"][5 * i] for i in range(3)])
        self.w0 = self.ga(self.theta0) * np.array(lin["u0"])
        self.inertia, self.k, self.b, self.beta = np.array([slow_mechanics(lin, i) for i in range(3)]).T
        self.k_d = DAMPING * self.b
        self.k_s = LAMBDA * (self.b + self.k_d) - self.k
        if np.any(self.k_s < 0):
            raise SystemExit(f"LAMBDA = {LAMBDA} is below an actuator's own slow pole k / b")
        self.theta_prev = None

    def ga(self, theta):
        """Input gain ga = gamma1 cos(gamma2 theta) (model.md, "Dynamics")."""
        return self.gamma1 * np.cos(self.gamma2 * theta)

    def angle(self, h):
        """theta from h = 1/2 Lv sin(theta) (model.md, "Shell geometry and C2")."""
        return np.arcsin(2 * np.asarray(h) / self.lv)

    def __call__(self, t, h):
        theta = self.angle(h)
        omega = np.zeros(3) if self.theta_prev is None else (theta - self.theta_prev) / STEP
        self.theta_prev = theta
        # the reference over the held step: angle at its end, rate and acceleration at its middle
        th_end, th_mid, th_start = (self.angle(self.reference(s)) for s in (t + STEP, t + STEP / 2, t))
        omega_ref = (th_end - th_start) / STEP
        alpha_ref = (th_end - 2 * th_mid + th_start) / (STEP / 2) ** 2
        dw_ff = (self.inertia * alpha_ref + self.b * omega_ref + self.k * (th_end - self.theta0)) / self.beta
        dw = dw_ff - (self.k_s * (theta - th_start) + self.k_d * (omega - omega_ref)) / self.beta
        w = np.sqrt(np.maximum(self.w0**2 + 2 * self.w0 * dw, 0.0))
        return w / self.ga(theta)


def make(lin):
    """The controller factory run_circle takes: Lv and the input gains read from the FMU."""
    def make_controller(reference, get):
        return PassivityBased(lin, reference, get("Lv")[0], get("gamma1_1", "gamma1_2", "gamma1_3"),
                              get("gamma2_1", "gamma2_2", "gamma2_3"))
    return make_controller
