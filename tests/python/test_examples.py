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


def test_designed_controllers_track_the_circle_closer_than_the_pi(fmu_path, hasel_path, tmp_path):
    out = tmp_path / "control_circle.png"
    result = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "control_circle.py"), "--fmu", fmu_path, "--hasel", hasel_path,
         "--t-end", "5", "--out", str(out)],
        capture_output=True, text=True, timeout=300,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    rms = {name: float(value) for name, value in
           re.findall(r"^([\w-]+): tip tracking error after the first period: RMS ([0-9.]+) um", result.stdout, re.M)}
    assert set(rms) == {"PI", "LQI", "passivity-based"}, result.stdout
    # each design beats the hand-tuned PI measured in this same run
    assert rms["LQI"] < rms["PI"], result.stdout
    assert rms["passivity-based"] < rms["PI"], result.stdout
    assert out.read_bytes().startswith(b"\x89PNG")
