"""Example 3 run long (issue 11's benchmark): ≥ 100 revolutions of gear 1 through fmpy, checked
for drift revolution by revolution.

Same loading as scripts/example3.py (185 N·m after a 5 ms haversine, 20 N·m·s/rad on gear 2, 0.1 ms
communication step). After the start-up (the first 5 revolutions), per revolution of gear 1: the
mean of ω₂, and the DTE's mean, RMS about the mean and peak-to-peak. A drift is the change of those
between revolutions 5–15 and the last ten; a sound integration leaves them at the steady state's
own revolution-to-revolution scatter.

    .venv/bin/python scripts/example3_long.py out/KurokawaSpur.fmu --revolutions 100 \\
        --csv examples/results/example3_long.csv
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from example3 import run  # noqa: E402


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("fmu", type=Path)
    parser.add_argument("--revolutions", type=float, default=100.0)
    parser.add_argument("--teeth", type=str, default="21,31", help="z1,z2")
    parser.add_argument("--csv", type=Path, default=None)
    args = parser.parse_args(argv)
    z1, z2 = (float(x) for x in args.teeth.split(","))
    w2 = 185.0 * z2 / z1 / 20.0
    w1 = w2 * z2 / z1
    t_end = (args.revolutions + 6.0) * 2.0 * math.pi / w1  # + start-up
    result = run(args.fmu, t_end, 1e-4)
    t, phi_2, w_2, dte = result["rows"].T
    # Gear 1's revolutions from gear 2's angle (the DTE is micrometres: its angle error is nil).
    revolution = np.floor(phi_2 * z2 / z1 / (2.0 * math.pi)).astype(int)
    rows = []
    for r in range(5, int(revolution.max())):
        sel = revolution == r
        d = dte[sel]
        rows.append((r, w_2[sel].mean(), d.mean(), d.std(), d.max() - d.min()))
    table = np.array(rows)
    if args.csv:
        args.csv.parent.mkdir(parents=True, exist_ok=True)
        np.savetxt(args.csv, table, delimiter=",", header="revolution,w2_mean_rad_s,dte_mean_m,dte_rms_m,dte_pp_m",
                   comments="")
    early, late = table[:10], table[-10:]
    print(f"{args.fmu.name}: {t_end:.2f} s simulated ({int(table[-1, 0])} revolutions of gear 1) "
          f"in {result['wall_s']:.1f} s wall ({result['wall_s'] / t_end:.1f} × slower than real time)")
    print("| quantity | revolutions 5–14 | last ten | change | revolution-to-revolution scatter (std) |")
    print("|---|---|---|---|---|")
    for col, name, scale, unit in [(1, "ω₂ mean", 1.0, "rad/s"), (2, "DTE mean", 1e6, "µm"),
                                   (3, "DTE RMS", 1e6, "µm"), (4, "DTE p-p", 1e6, "µm")]:
        a, b = early[:, col].mean() * scale, late[:, col].mean() * scale
        print(f"| {name} ({unit}) | {a:.5f} | {b:.5f} | {b - a:+.2e} | {table[:, col].std() * scale:.2e} |")
    print(f"closed-form ω₂ {w2:.5f} rad/s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
