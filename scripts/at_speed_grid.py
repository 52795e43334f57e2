#!/usr/bin/env python3
"""Issue 38's at-speed grid: mesh frequency × communication step × torque, each case a synchronous
start with a viscous brake on gear 2 fed back from w_2 (`gearfmu.at_speed.brake_case`).

Prints one row per case: completed, ω₂'s mean over the last 5 ms against its target, the DTE there,
µs per doStep and the real-time factor (wall inside doStep / simulated time), and the FMU's
message where a case fails. Exit status 1 if any case fails or misses ω₂ by ≥ 1 %.

    .venv/bin/python scripts/at_speed_grid.py out/KurokawaSpur.fmu --torque-nm 185,18.5
"""

import argparse
import csv
import math
import sys

sys.path.insert(0, __file__.rsplit("/scripts/", 1)[0] + "/python")
from gearfmu.at_speed import Fmu, brake_case  # noqa: E402


def floats(text: str) -> list[float]:
    return [float(x) for x in text.split(",") if x]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("fmu")
    p.add_argument("--mesh-hz", type=floats,
                   default=floats("500,1000,1500,2000,2500,2800,2900,3000,3100,3200,4000,5000"))
    p.add_argument("--steps-us", type=floats, default=floats("10,20,50,100,300,1000"))
    p.add_argument("--torque-nm", type=floats, required=True, help="T₁ values (N·m)")
    p.add_argument("--t-end", type=float, default=0.02, help="simulated time per case (s)")
    p.add_argument("--csv", help="write the rows here too")
    args = p.parse_args()

    fmu = Fmu(args.fmu)
    rows, bad = [], 0
    print(f"{'T1 N·m':>7} {'f_m Hz':>7} {'h µs':>6} {'ok':>3} {'ω₂ err':>9} {'DTE rms µm':>10} {'DTE pp µm':>9} "
          f"{'µs/doStep':>9} {'× real':>7}  message", flush=True)
    for torque in args.torque_nm:
        for f in args.mesh_hz:
            for h_us in args.steps_us:
                r = brake_case(fmu, f, h_us * 1e-6, torque, args.t_end)
                err = r.get("omega_2_error", math.nan)
                good = r["completed"] and abs(err) < 0.01
                bad += not good
                rows.append(r)
                print(f"{torque:7.1f} {f:7.0f} {h_us:6.0f} {'yes' if r['completed'] else 'NO':>3} {err:+9.2e} "
                      f"{r.get('dte_rms_m', math.nan) * 1e6:10.3f} {r.get('dte_pp_m', math.nan) * 1e6:9.3f} "
                      f"{r['us_per_doStep']:9.0f} {r['real_time_factor']:7.2f}  {r['error'][:300]}", flush=True)
    fmu.close()
    if args.csv:
        keys = sorted({k for r in rows for k in r})
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=keys)
            w.writeheader()
            w.writerows(rows)
    print(f"{len(rows) - bad} of {len(rows)} cases complete with ω₂ within 1 %")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
