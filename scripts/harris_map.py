#!/usr/bin/env python3
"""Harris map (issue 27): the static transmission error's peak-to-peak against the amount of a
linear tip relief on both gears, at three loads, from `fmu-build ste` (PMOR-Hertz statics).

The relief is "long": from each tip down to the highest point of single-tooth contact, a roll
length (ε_α − 1)·p_b. Harris's picture: at each load the peak-to-peak falls to a minimum near
the relief that equals the pair's single-tooth-pair deflection at that load, and rises past it.
The estimate printed beside each minimum is the deflection of one tooth pair carrying the whole
load, from the unmodified statics' own zones: the single-contact STE less the part every zone
shares (the bodies' twist and what the double zone also carries): the zone contrast times the
double/single stiffness ratio over (ratio − 1), i.e. F/k_single of the mesh alone.

    .venv/bin/python scripts/harris_map.py examples/kurokawa_spur.toml [--torques 100,185,370]
        [--amounts 0,5,10,...] [--csv out/harris.csv] [--png out/harris.png]
"""

from __future__ import annotations

import argparse
import csv
import re
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FMU_BUILD = REPO / "target" / "release" / "fmu-build"


def pair_figures(spec: Path) -> tuple[float, float]:
    """(ε_α, base pitch in mm) from `fmu-build inspect`."""
    text = subprocess.run([str(FMU_BUILD), "inspect", str(spec), "--mesh-law", "analytic"],
                          check=True, capture_output=True, text=True).stdout
    eps = float(re.search(r"ε_α ([0-9.]+)", text).group(1))
    pb = float(re.search(r"base pitch\s+([0-9.]+) mm", text).group(1))
    return eps, pb


def with_tip_relief(spec_text: str, amount_um: float, length_mm: float) -> str:
    """The spec with a linear tip relief on both gears (appended as [gearN.modification])."""
    if amount_um == 0.0:
        return spec_text
    block = (f"tip_relief_um = {amount_um}\ntip_relief_length_mm = {length_mm:.4f}\n"
             'tip_relief_shape = "linear"\n')
    return spec_text + "".join(f"\n[gear{i}.modification]\n{block}" for i in (1, 2))


def ste_rows(spec: Path, torques: str, angles: int, out_csv: Path) -> list[dict]:
    subprocess.run([str(FMU_BUILD), "ste", str(spec), "--torque-nm", torques, "--angles", str(angles),
                    "--csv", str(out_csv)], check=True, capture_output=True, text=True)
    with open(out_csv) as f:
        return list(csv.DictReader(f))


def zone_figures(rows: list[dict], torque: float) -> dict:
    """Peak-to-peak, single and double zone means (m) at one torque."""
    ste = [(float(r["ste_m"]), int(r["pairs_in_contact"])) for r in rows if float(r["torque_nm"]) == torque]
    values = [s for s, _ in ste]
    single = [s for s, n in ste if n == 1]
    double = [s for s, n in ste if n >= 2]
    mean = lambda xs: sum(xs) / len(xs) if xs else float("nan")
    return {"pp": max(values) - min(values), "single": mean(single), "double": mean(double)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("spec", type=Path)
    parser.add_argument("--torques", default="100,185,370")
    parser.add_argument("--amounts", default="0,4,8,12,16,20,24,28,32,40,48")
    parser.add_argument("--angles", type=int, default=60)
    parser.add_argument("--csv", type=Path)
    parser.add_argument("--png", type=Path)
    args = parser.parse_args(argv)
    torques = [float(t) for t in args.torques.split(",")]
    amounts = [float(a) for a in args.amounts.split(",")]
    eps, pb = pair_figures(args.spec)
    length = (eps - 1.0) * pb
    print(f"ε_α {eps}, p_b {pb} mm: long tip relief over {length:.3f} mm of roll length on both gears")
    text = args.spec.read_text()
    table = {}  # (amount, torque) -> figures
    with tempfile.TemporaryDirectory() as tmp:
        for amount in amounts:
            spec = Path(tmp) / f"relief_{amount}.toml"
            spec.write_text(with_tip_relief(text, amount, length))
            rows = ste_rows(spec, args.torques, args.angles, Path(tmp) / "ste.csv")
            for t in torques:
                table[(amount, t)] = zone_figures(rows, t)
            print(f"  C_a {amount:5.1f} µm: p-p " + ", ".join(f"{table[(amount, t)]['pp'] * 1e6:.3f}" for t in torques)
                  + " µm", flush=True)
    print("torque (N·m) | minimum p-p (µm) at C_a (µm) | p-p without relief | single-pair deflection estimate (µm)")
    for t in torques:
        base = table[(0.0, t)]
        best = min(amounts, key=lambda a: table[(a, t)]["pp"])
        # Without relief the single zone carries F on one pair, the double zone F/2 on each (about):
        # δ_single − δ_double = F/k − F/(2k) = F/(2k), so F/k = 2·(contrast).
        estimate = 2.0 * (base["single"] - base["double"])
        print(f"{t:8.0f} | {table[(best, t)]['pp'] * 1e6:7.3f} at {best:5.1f} | {base['pp'] * 1e6:7.3f} | {estimate * 1e6:7.3f}")
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["tip_relief_um", "torque_nm", "ste_pp_m", "single_zone_m", "double_zone_m"])
            for (a, t), fig in sorted(table.items()):
                w.writerow([a, t, fig["pp"], fig["single"], fig["double"]])
    if args.png:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 4.5))
        for t in torques:
            ax.plot(amounts, [table[(a, t)]["pp"] * 1e6 for a in amounts], "o-", label=f"T₁ = {t:g} N·m")
            base = table[(0.0, t)]
            ax.axvline(2e6 * (base["single"] - base["double"]), ls=":", color=ax.lines[-1].get_color())
        ax.set_xlabel("linear tip relief C_a on both gears (µm), over (ε_α − 1)·p_b")
        ax.set_ylabel("STE peak-to-peak (µm)")
        ax.set_title(f"Harris map, {args.spec.stem} (dotted: single-pair deflection estimate)")
        ax.legend()
        fig.tight_layout()
        fig.savefig(args.png, dpi=120)
        print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
