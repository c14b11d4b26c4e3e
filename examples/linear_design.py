"""The linear model the designed controllers of examples/control_circle.py start from.

`hasel linearize --u U1,U2,U3 --out DIR` writes the equilibrium under constant voltages and the
linearization there (DIR/linearization.json, DIR/reduced.json;
book/src/control.md, "Designed controllers in closed loop"). The circle is centred on the
operating point where all three heights are H0, so the voltages that hold it are found here by
Newton on U with the reduced model's DC gain, one `hasel linearize` per step.
"""
import json
import pathlib
import subprocess

import numpy as np

U_START = np.array([45.0, 45.0, 45.0])  # V, first guess of the operating voltages


def linearize(hasel, u, out_dir):
    """`hasel linearize --u U --out out_dir`: the linearization and the reduced model (dicts)."""
    out_dir = pathlib.Path(out_dir)
    subprocess.run([str(hasel), "linearize", "--u", ",".join(f"{x:.17g}" for x in u), "--out", str(out_dir)],
                   check=True, capture_output=True, text=True)
    return (json.loads((out_dir / "linearization.json").read_text()),
            json.loads((out_dir / "reduced.json").read_text()))


def heights_dc_gain(reduced):
    """dh/dU at DC of the reduced model [m/V]: -C A^-1 B on the height rows h1..h3."""
    a, b, c = (np.array(reduced[k]) for k in ("A", "B", "C"))
    return -c[:3] @ np.linalg.solve(a, b)


def operating_point(hasel, h0, out_dir, tol=1e-11, max_steps=10):
    """The linearization at the equilibrium whose three heights are h0 [m]."""
    u = U_START.copy()
    for _ in range(max_steps):
        lin, reduced = linearize(hasel, u, out_dir)
        miss = h0 - np.array(lin["y0"][:3])
        if np.abs(miss).max() < tol:
            return lin, reduced
        u = u + np.linalg.solve(heights_dc_gain(reduced), miss)
    raise SystemExit(f"no operating point at h = {h0 * 1e6} um after {max_steps} steps (last U = {u} V)")
