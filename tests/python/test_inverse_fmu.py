"""The inverse FMU (fmu/HaselInverse.fmu) through fmpy: its interface, the same heights and
voltages as `hasel inverse --method xy` step by step, and a tip it cannot reach discarded with
the reason logged (fmpy validate and fmutool: tests/python/test_fmu_fmpy.py)."""
import subprocess

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

MEAN = 50e-6  # m
STEP = 0.05  # s
OUTPUTS = ["h1", "h2", "h3", "U1", "U2", "U3"]


def test_interface_is_the_contract(inverse_fmu_path):
    md = read_model_description(inverse_fmu_path)
    assert md.fmiVersion == "2.0" and md.coSimulation.modelIdentifier == "HaselInverse"
    by = lambda c: [v.name for v in md.modelVariables if v.causality == c]  # noqa: E731
    assert by("input") == ["tip_x", "tip_y", "mean_height"]
    assert by("output") == OUTPUTS
    # its parameters are the platform's (the kinematics and the actuators)
    assert {"anchor_radius", "L", "Kb_1", "gamma2_3"} <= set(by("parameter"))
    # direct feedthrough: a master reads the feedforward of the inputs it has just set
    for output in md.outputs:
        assert [v.name for v in output.dependencies] == by("input"), output.variable.name


class Inverse:
    """The inverse FMU in co-simulation."""

    def __init__(self, path, unzipdir):
        md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(path, unzipdir=unzipdir),
                             modelIdentifier="HaselInverse", instanceName="inverse")
        self.fmu.instantiate(loggingOn=True)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def refs(self, *names):
        return [self.vr[n] for n in names]

    def set_tip(self, tip_x, tip_y):
        self.fmu.setReal(self.refs("tip_x", "tip_y", "mean_height"), [tip_x, tip_y, MEAN])

    def outputs(self):
        return np.array(self.fmu.getReal(self.refs(*OUTPUTS)))

    def step(self, t, tip_x, tip_y):
        """The outputs of the tip, read as a master does: inputs set, then a step over which
        they are held, then the outputs."""
        self.set_tip(tip_x, tip_y)
        self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=STEP)
        return self.outputs()


@pytest.fixture
def inverse(inverse_fmu_path, tmp_path):
    fmu = Inverse(inverse_fmu_path, str(tmp_path / "unzipped"))
    yield fmu
    fmu.fmu.terminate()
    fmu.fmu.freeInstance()


def test_the_fmu_gives_what_hasel_inverse_writes(inverse, hasel_path, tmp_path):
    t = np.arange(41) * STEP
    tip = np.c_[t, 40e-6 * np.cos(np.pi * t), 40e-6 * np.sin(np.pi * t)]
    path = tmp_path / "tip.csv"
    np.savetxt(path, tip, delimiter=",", header="t,tip_x,tip_y", comments="", fmt="%.17g")
    out = tmp_path / "inverse.csv"
    subprocess.run([hasel_path, "inverse", "--tip", str(path), "--method", "xy", "--mean-height", repr(MEAN),
                    "--out", str(out)], check=True, capture_output=True)
    cli = np.loadtxt(out, delimiter=",", skiprows=1)[:, 1:]
    fmu = np.array([inverse.step(tk, x, y) for tk, x, y in tip])
    # the CLI writes 13 significant digits
    np.testing.assert_allclose(fmu, cli, rtol=1e-12, atol=0)
    # the same before the step: the outputs follow the inputs as they are set
    inverse.set_tip(*tip[3, 1:])
    np.testing.assert_allclose(inverse.outputs(), cli[3], rtol=1e-12, atol=0)


def test_a_tip_out_of_reach_is_discarded_with_the_reason(inverse, capsys):
    before = inverse.step(0.0, 0.0, 0.0)
    with pytest.raises(FMICallException, match="discard"):
        inverse.step(STEP, 1e-3, 0.0)
    # fmpy prints the FMU's log messages
    log = capsys.readouterr().out
    assert "[DISCARD] fmi2DoStep" in log and "where the input gain ga = gamma1 cos(gamma2 theta) vanishes" in log, log
    # the outputs of that tip cannot be read either, and say why
    with pytest.raises(FMICallException, match="error"):
        inverse.outputs()
    assert "input gain" in capsys.readouterr().out
    assert inverse.fmu.getReal(inverse.refs("tip_x")) == [1e-3]
    assert np.isfinite(before).all()
