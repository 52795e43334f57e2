#!/usr/bin/env python3
"""Issue 38's run-up: a PI-controlled motor inertia drives gear 1 through a torsional shaft the
master integrates, gear 2 carries a constant load, the speed target ramps through the mesh
resonance (`gearfmu.at_speed.run_up`). Each FMU runs through the same loop at each coupling step;
the reference (``--reference``, the `--dynamics full --integrator rk4` build of the same spec) runs
at its default max_step and at halved steps until its DTE peak moves by < 0.5 %, and each FMU's
peak DTE peak-to-peak and its mesh frequency are reported against the converged reference.

    .venv/bin/python scripts/at_speed_runup.py out/KurokawaSpur.fmu out/KurokawaSpurLumped.fmu \\
        --reference out/KurokawaSpurFull.fmu --load-nm 185 --steps-us 20,100 [--param mesh_damping_ratio=0]
"""

import argparse
import json
import sys

sys.path.insert(0, __file__.rsplit("/scripts/", 1)[0] + "/python")
from gearfmu.at_speed import Fmu, run_up  # noqa: E402


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("fmus", nargs="+")
    p.add_argument("--reference", help="the full-dynamics FMU of the same spec")
    p.add_argument("--load-nm", type=float, required=True)
    p.add_argument("--steps-us", default="20,100")
    p.add_argument("--f-start-hz", type=float, default=400.0)
    p.add_argument("--f-end-hz", type=float, default=4000.0)
    p.add_argument("--ramp-s", type=float, default=0.5)
    p.add_argument("--param", action="append", default=[], help="NAME=VALUE: an FMU parameter for every run "
                   "(e.g. mesh_damping_ratio=0)")
    p.add_argument("--json", help="write every result here")
    args = p.parse_args()
    params = dict((k, float(v)) for k, v in (kv.split("=") for kv in args.param))
    steps = [float(x) * 1e-6 for x in args.steps_us.split(",")]
    common = dict(f_start_hz=args.f_start_hz, f_end_hz=args.f_end_hz, ramp_s=args.ramp_s, load_nm=args.load_nm)
    results, bad = [], 0

    def show(label: str, r: dict, ref: dict | None = None) -> None:
        line = (f"{label:48s} h {r['step_s'] * 1e6:5.0f} µs  "
                + (f"peak DTE p-p {r['peak_dte_pp_m'] * 1e6:7.3f} µm at {r['peak_frequency_hz']:6.0f} Hz  "
                   if r["completed"] else f"FAILED at {r.get('reached_hz', 0):.0f} Hz: {r['error'][:300]}  ")
                + f"× real {r['real_time_factor']:6.2f}")
        if ref and r["completed"]:
            line += (f"  vs reference: p-p {r['peak_dte_pp_m'] / ref['peak_dte_pp_m'] - 1:+.2%}, "
                     f"frequency {r['peak_frequency_hz'] / ref['peak_frequency_hz'] - 1:+.2%}")
        print(line, flush=True)

    for h in steps:
        ref = None
        if args.reference:
            fmu = Fmu(args.reference)
            max_step = fmu.start["max_step"]
            previous = None
            while True:
                r = run_up(fmu, h, parameters={**params, "max_step": max_step}, **common)
                r.update(fmu=args.reference, max_step_s=max_step)
                show(f"reference, max_step {max_step * 1e6:.3g} µs", r)
                results.append(r)
                if not r["completed"]:
                    bad += 1
                    break
                if previous and abs(r["peak_dte_pp_m"] / previous["peak_dte_pp_m"] - 1) < 0.005:
                    ref = r
                    break
                previous, max_step = r, max_step / 2
            fmu.close()
        for path in args.fmus:
            fmu = Fmu(path)
            r = run_up(fmu, h, parameters=dict(params), **common)
            r.update(fmu=path)
            if ref and r["completed"]:
                r["peak_pp_error"] = r["peak_dte_pp_m"] / ref["peak_dte_pp_m"] - 1
                r["peak_frequency_error"] = r["peak_frequency_hz"] / ref["peak_frequency_hz"] - 1
            show(path, r, ref)
            bad += not r["completed"]
            results.append(r)
            fmu.close()
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
