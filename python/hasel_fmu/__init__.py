"""The FMUs installed with the hasel command (the wheel's package data).

    from fmpy import simulate_fmu
    from hasel_fmu import fmu_path
    simulate_fmu(fmu_path(), stop_time=2.0)
"""
import pathlib

FMU_DIR = pathlib.Path(__file__).resolve().parent / "fmu"
MODELS = ("HaselPlatform", "HaselPlatform-fmi3", "HaselPlatformReduced", "HaselPlatformReduced-fmi3",
          "HaselInverse")


def fmu_path(model="HaselPlatform"):
    """The path of the installed FMU `model`: HaselPlatform (FMI 2.0), HaselPlatform-fmi3 (FMI 3.0),
    the slow model's HaselPlatformReduced (FMI 2.0) and HaselPlatformReduced-fmi3 (FMI 3.0), or
    HaselInverse (FMI 2.0)."""
    if model not in MODELS:
        raise ValueError(f"no FMU {model!r}; the wheel has {', '.join(MODELS)}")
    return str(FMU_DIR / f"{model}.fmu")
