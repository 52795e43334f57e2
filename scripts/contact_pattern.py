#!/usr/bin/env python3
"""Contact pattern (issue 27): the load per unit face width over the mesh position and the face,
the picture a test rig's marking compound gives, from a `fmu-build ste --csv` file (its
line_load_<s>_n_per_mm columns). One panel per torque; each column is one position of the sweep,
each row one axial section (gear 1's z, −b/2 at the bottom).

    .venv/bin/python scripts/contact_pattern.py STE.csv --face-width-mm 15 --png pattern.png
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from collections import defaultdict
from pathlib import Path


def read_pattern(path: Path) -> dict[float, tuple[list[float], list[list[float]]]]:
    """Per torque: the driven gear's angles (deg, ascending) and the line loads (N/mm) per
    position, one value per axial section."""
    by_torque = defaultdict(list)
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        columns = [c for c in reader.fieldnames if c.startswith("line_load_")]
        if not columns:
            sys.exit(f"{path}: no line_load_<s>_n_per_mm columns (written by fmu-build ste --csv)")
        columns.sort(key=lambda c: int(c.split("_")[2]))
        for row in reader:
            by_torque[float(row["torque_nm"])].append(
                (math.degrees(float(row["theta2_rad"])), [float(row[c]) for c in columns]))
    out = {}
    for torque, rows in by_torque.items():
        rows.sort()
        out[torque] = ([r[0] for r in rows], [r[1] for r in rows])
    return out


def section_means(loads: list[list[float]]) -> list[float]:
    """Each section's line load averaged over the positions (the face's load distribution)."""
    return [sum(col) / len(col) for col in zip(*loads)]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("csv", type=Path)
    parser.add_argument("--face-width-mm", type=float, required=True)
    parser.add_argument("--png", type=Path, required=True)
    parser.add_argument("--title", default="")
    args = parser.parse_args(argv)
    pattern = read_pattern(args.csv)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    torques = sorted(pattern)
    fig, axes = plt.subplots(1, len(torques), figsize=(4.5 * len(torques), 4), squeeze=False)
    b = args.face_width_mm
    for ax, torque in zip(axes[0], torques):
        angles, loads = pattern[torque]
        columns = list(zip(*loads))  # per section, over the positions
        image = ax.imshow(columns, origin="lower", aspect="auto", cmap="inferno",
                          extent=(angles[0], angles[-1], -b / 2, b / 2))
        fig.colorbar(image, ax=ax, label="load per face width (N/mm)")
        means = section_means(loads)
        k = max(means) / (sum(means) / len(means))
        ax.set_title(f"T₁ = {torque:g} N·m, K_Hβ {k:.2f}")
        ax.set_xlabel("θ₂ (deg)")
        ax.set_ylabel("face width z (mm, gear 1's)")
        print(f"T₁ {torque:g} N·m: section means (N/mm, −z to +z) " + ", ".join(f"{m:.1f}" for m in means)
              + f"; K_Hβ {k:.3f}")
    if args.title:
        fig.suptitle(args.title)
    fig.tight_layout()
    fig.savefig(args.png, dpi=120)
    print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
