"""Two independent FMI importers, fmpy and the Rust `fmi` crate (examples/fmi_crate_run.rs),
drive the same .fmu through the same scenario and must get the same outputs bit for bit.

Evidence: a different client (design §5). The scenario: 250 steps of 0.1 ms, tau_1 = 185 N·m,
tau_2 = -20·w_2 from the previous step's output.
"""

from __future__ import annotations

import subprocess

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave

from conftest import REPO_ROOT, build_workspace

OUTPUTS = ["phi_1", "phi_2", "w_1", "w_2", "dte", "mesh_force"]


def run_with_fmpy(case) -> np.ndarray:
    md = read_model_description(str(case.fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(
        guid=md.guid,
        unzipDirectory=str(case.unzip_dir),
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="fmpy-client",
    )
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    rows, h, w_2 = [], 1e-4, 0.0
    for k in range(250):
        t = k * h
        slave.setReal([vr["tau_1"], vr["tau_2"]], [185.0, -20.0 * w_2])
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        values = slave.getReal([vr[o] for o in OUTPUTS])
        w_2 = values[3]
        rows.append([t + h, *values])
    slave.terminate()
    slave.freeInstance()
    return np.array(rows)


def run_with_fmi_crate(case, tmp_path) -> np.ndarray:
    build_workspace()  # examples/fmi_crate_run.rs, built with the workspace's other targets
    csv = tmp_path / f"{case.name}-fmi-crate.csv"
    cmd = [str(REPO_ROOT / "target" / "release" / "examples" / "fmi_crate_run"), str(case.fmu_path), str(csv)]
    proc = subprocess.run(cmd, cwd=REPO_ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    lines = csv.read_text().splitlines()
    assert lines[0] == "time," + ",".join(OUTPUTS)
    # Rust writes {:?}, the shortest representation that round-trips: float() recovers the bits.
    return np.array([[float(x) for x in line.split(",")] for line in lines[1:]])


def test_fmpy_and_fmi_crate_agree_bit_for_bit(fmi_case, tmp_path):
    a = run_with_fmpy(fmi_case)
    b = run_with_fmi_crate(fmi_case, tmp_path)
    assert a.shape == b.shape == (250, 1 + len(OUTPUTS))
    assert np.array_equal(a, b), f"max difference {np.max(np.abs(a - b))}"
    # And the run is not trivial: gear 2 turned and the mesh carried load.
    assert a[-1, 4] > 10.0 and a[-1, 6] > 1000.0
