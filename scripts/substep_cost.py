"""µs per integrator sub-step (RK4 or velocity Verlet) of each FMU, measured through fmi2DoStep (issue 13: the per-call bound).

Usage: .venv/bin/python scripts/substep_cost.py out/KurokawaSpur.fmu out/KurokawaSpurPmor.fmu
Each FMU: 185 N·m on gear 1 against its static load on gear 2, five calls of h = 10⁴·max_step.
The bounds MAX_SUBSTEPS_* in src/fmu/gear_pair.rs are ~10 s of work at these rates.
"""

import sys
import time

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

N_SUBSTEPS = 10_000

for path in sys.argv[1:]:
    md = read_model_description(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(path),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="cost")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    max_step = fmu.getReal([vr["max_step"]])[0]
    fmu.setReal([vr["tau_1"], vr["tau_2"]], [185.0, -185.0 * 31 / 21])
    t, rates = 0.0, []
    for _ in range(5):
        h = N_SUBSTEPS * max_step
        start = time.perf_counter()
        fmu.doStep(t, h)
        rates.append((time.perf_counter() - start) / N_SUBSTEPS * 1e6)
        t += h
    print(f"{path}: max_step {max_step:g} s, µs per sub-step " + " ".join(f"{r:.3f}" for r in rates))
    fmu.terminate()
    fmu.freeInstance()
