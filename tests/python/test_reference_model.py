"""The standard PMOR reference FMU (``fmu-build build --model pmor-penalty``, issue 28) as a user
meets it: built from the spur example on a coarse mesh (4/8/4, seconds), validated by fmpy and
driven by an fmpy loop of our own.

* Example 3 (185 N·m haversine ramp, a viscous brake of 20 N·m·s/rad fed back from ``w_2``)
  completes; evidence: the steady state's closed form ω₂ = T₁z₂/(z₁c), and the DTE's mean over
  the last mesh cycle against ``fmu-build ste --method penalty`` on the same mesh (the statics
  the reference model's shapes come from, reduced separately).
* The model carries the drive flanks only: a torque that presses the coast flanks together
  ends the step in fmi2Error with the reason logged, not a pair that falls through its backlash.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
SPEC = REPO_ROOT / "examples" / "kurokawa_spur.toml"
COARSE = ("--across", "4", "--profile", "8", "--rim", "4", "--profile-grading", "uniform")


def _run(*args: str) -> str:
    """`fmu-build args…` through the session's build cache (conftest); fails the test on an error."""
    from conftest import _fmu_build

    return _fmu_build(*args).stdout


@pytest.fixture(scope="module")
def reference_fmu(gear_fmus, tmp_path_factory) -> Path:
    """``gear_fmus`` first: it builds the workspace (the fmu-build binary and the FMU library)."""
    path = tmp_path_factory.mktemp("reference") / "KurokawaSpurPenalty.fmu"
    out = _run("build", str(SPEC), "-o", str(path), "--model", "pmor-penalty", *COARSE)
    assert "standard PMOR reference" in out, out
    return path


def _slave(fmu: Path, name: str, callbacks=None, logging_on=False):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    slave.instantiate(callbacks=callbacks, loggingOn=logging_on)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return md, vr, slave


def test_fmpy_validates_the_reference_fmu(reference_fmu):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(reference_fmu)) == []


def test_example_3_reaches_the_closed_form_speed_and_the_penalty_statics_mean(reference_fmu):
    md, vr, slave = _slave(reference_fmu, "example3")
    assert "standard PMOR reference model" in md.description
    h, w_2, rows = 1e-4, 0.0, []
    for k in range(250):
        t = k * h
        tau_1 = 185.0 * 0.5 * (1.0 - math.cos(math.pi * t / 5e-3)) if t < 5e-3 else 185.0
        slave.setReal([vr["tau_1"], vr["tau_2"]], [tau_1, -20.0 * w_2])
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        phi_2, w_2, dte = slave.getReal([vr["phi_2"], vr["w_2"], vr["dte"]])
        rows.append((phi_2, w_2, dte))
    slave.terminate()
    slave.freeInstance()
    rows = np.array(rows)
    closed_form = 185.0 * 31 / 21 / 20.0
    last_cycle = rows[rows[:, 0] > rows[-1, 0] - 2 * math.pi / 31]
    dte_mean = last_cycle[:, 2].mean() * 1e6
    ste = _run("ste", str(SPEC), "--torque-nm", "185", "--angles", "40", "--method", "penalty", *COARSE)
    ste_mean = float(re.search(r"mean STE ([0-9.]+) µm", ste).group(1))
    print(f"reference FMU, example 3: ω₂ {rows[-1, 1]:.4f} rad/s (closed form {closed_form:.4f}); "
          f"DTE mean over the last mesh cycle {dte_mean:.3f} µm, penalty statics {ste_mean:.3f} µm")
    assert abs(rows[-1, 1] / closed_form - 1.0) < 5e-3, rows[-1, 1]
    assert abs(dte_mean / ste_mean - 1.0) < 0.03


def test_coast_flank_contact_is_an_error_with_the_reason(reference_fmu, log_capture):
    from fmpy.fmi1 import FMICallException

    name = "reference_reversal"
    md, vr, slave = _slave(reference_fmu, name, callbacks=log_capture.callbacks, logging_on=True)
    with pytest.raises(FMICallException):
        for k in range(300):
            slave.setReal([vr["tau_1"], vr["tau_2"]], [-300.0, 0.0])
            slave.doStep(currentCommunicationPoint=k * 1e-4, communicationStepSize=1e-4)
    messages = [m for (_, _, m) in log_capture.for_instance(name)]
    assert any("drive-flank contact only" in m for m in messages), messages[-3:]
    slave.freeInstance()
