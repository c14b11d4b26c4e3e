"""The examples users start from run as documented and do what they say."""
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_fmpy_controller_makes_the_tip_follow_the_circle(fmu_path, tmp_path):
    out = tmp_path / "controller.png"
    result = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "fmpy_controller.py"), "--fmu", fmu_path, "--t-end", "5", "--out", str(out)],
        capture_output=True, text=True, timeout=300,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    rms = float(re.search(r"RMS ([0-9.]+) um", result.stdout).group(1))
    # a 40 um circle followed to within a micrometre
    assert rms < 1.0, result.stdout
    assert out.read_bytes().startswith(b"\x89PNG")
