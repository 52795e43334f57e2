#!/usr/bin/env python3
"""Steady response through the mesh resonance against a reference FMU: the brake case of
`gearfmu.at_speed` (synchronous start, constant T₁, brake fed back from w_2) at each mesh
frequency, the DTE RMS about the mean over the last 5 ms of the run, for each FMU and each
parameter set; printed as a table with each FMU's relative difference to the first (the reference).

    .venv/bin/python scripts/at_speed_fidelity.py out/KurokawaSpurFull.fmu out/KurokawaSpur.fmu \\
        --mesh-hz 1800:5400:300 --param mesh_damping_ratio=0.05 --param mesh_damping_ratio=0
"""

import argparse
import sys

import numpy as np

sys.path.insert(0, __file__.rsplit("/scripts/", 1)[0] + "/python")
from gearfmu.at_speed import Fmu, brake_case  # noqa: E402


def frequencies(text: str) -> list[float]:
    if ":" in text:
        lo, hi, step = (float(x) for x in text.split(":"))
        return list(np.arange(lo, hi + 0.5 * step, step))
    return [float(x) for x in text.split(",")]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("reference")
    p.add_argument("fmus", nargs="+")
    p.add_argument("--mesh-hz", type=frequencies, required=True, help="LO:HI:STEP or a comma list")
    p.add_argument("--torque-nm", type=float, default=185.0)
    p.add_argument("--step-us", type=float, default=10.0)
    p.add_argument("--t-end", type=float, default=0.04)
    p.add_argument("--param", action="append", default=[""], help="NAME=VALUE[,NAME=VALUE]: one parameter set")
    args = p.parse_args()
    sets = [dict((k, float(v)) for k, v in (kv.split("=") for kv in s.split(",") if kv)) for s in args.param]
    if len(sets) > 1:
        sets = sets[1:]   # the empty default only where none is given
    print("DTE RMS about the mean over the last 5 ms (µm); relative difference to the reference")
    print(f"{'FMU':40s} {'parameters':28s} " + " ".join(f"{f:>8.0f}" for f in args.mesh_hz))
    worst = 0.0
    for params in sets:
        label = ",".join(f"{k}={v:g}" for k, v in params.items()) or "defaults"
        ref = None
        for path in [args.reference, *args.fmus]:
            fmu = Fmu(path)
            rms = np.array([brake_case(fmu, f, args.step_us * 1e-6, args.torque_nm, args.t_end, params).get(
                "dte_rms_m", np.nan) for f in args.mesh_hz])
            fmu.close()
            print(f"{path[-40:]:40s} {label:28s} " + " ".join(f"{x * 1e6:8.3f}" for x in rms), flush=True)
            if ref is None:
                ref = rms
            else:
                rel = rms / ref - 1.0
                worst = max(worst, float(np.nanmax(np.abs(rel))))
                print(f"{'  vs reference':40s} {label:28s} " + " ".join(f"{x:+8.1%}" for x in rel), flush=True)
    print(f"largest pointwise difference: {worst:.1%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
