"""Do two FMUs of the same pair give the same dynamics? An example-3-like run of each (issue 40's
"results unchanged" check between two builds of one spec, e.g. before and after a change to the
offline build).

    .venv/bin/python scripts/compare_dte.py BEFORE.fmu AFTER.fmu

Each FMU through the same plain fmpy loop: T₁ = 185 N·m ramped in 5 ms (half a cosine), gear 2
braked by a 20 N·m·s/rad viscous load fed back from ω₂, 250 communication steps of 0.1 ms.
Prints each run's DTE mean, RMS and peak-to-peak over steps 50–250 (µm), the end mesh force, and
the largest difference of the two DTE and mesh-force histories as a share of their range.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
from gearfmu.at_speed import Fmu  # noqa: E402

TORQUE_NM, RAMP_S, BRAKE_NMS = 185.0, 5e-3, 20.0
STEP_S, STEPS, SETTLED = 1e-4, 250, 50


def ramp(t: float) -> float:
    return TORQUE_NM * (0.5 - 0.5 * math.cos(math.pi * t / RAMP_S) if t < RAMP_S else 1.0)


def run(path: Path) -> np.ndarray:
    """(ω₂, DTE, mesh force) after each communication step."""
    fmu = Fmu(str(path))
    fmu.initialize({})
    w_2, rows = 0.0, []
    for k in range(STEPS):
        fmu.fmu.setReal([fmu.vr["tau_1"], fmu.vr["tau_2"]], [ramp(k * STEP_S), -BRAKE_NMS * w_2])
        fmu.fmu.doStep(currentCommunicationPoint=k * STEP_S, communicationStepSize=STEP_S)
        w_2, dte, force = fmu.get("w_2", "dte", "mesh_force")
        rows.append((w_2, dte, force))
    fmu.close()
    return np.array(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    args = parser.parse_args()
    before, after = run(args.before), run(args.after)
    for name, rows in (("before", before), ("after", after)):
        dte = rows[SETTLED:, 1] * 1e6
        print(f"{name}: DTE mean {dte.mean():.6f} µm, RMS {dte.std():.6f} µm, p-p {np.ptp(dte):.6f} µm; "
              f"end mesh force {rows[-1, 2]:.4f} N")
    for column, name in ((1, "DTE"), (2, "mesh force")):
        share = np.abs(before[:, column] - after[:, column]).max() / np.ptp(before[:, column])
        print(f"largest |difference| of the {name}: {share:.2e} of its range")


if __name__ == "__main__":
    main()
