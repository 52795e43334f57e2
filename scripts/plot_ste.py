"""Static transmission error curves from `fmu-build ste` CSVs, like the paper's Figs. 15, 16, 19.

STE (µm) against the driven gear's angle (deg), one curve per torque (colour) and method (line
style). The background marks how many tooth pairs carry load at the lightest torque of the first
file: 1 = single contact, 2 = double contact (spur); 2 and 3 for a helical pair. The zone
boundaries move with load (deflection brings the next pair in early), which the curves show.

Usage: plot_ste.py A.csv [B.csv ...] --png out.png [--title "..."]
"""

import argparse
import csv
import math
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLUMNS = ["method", "torque_nm", "theta1_rad", "theta2_rad", "ste_m", "mesh_force_n", "pairs_in_contact", "k_h_beta"]
STYLES = {"pmor-hertz": "-", "penalty": "--"}


def read_cases(path):
    """Rows of one CSV grouped by (method, torque), each sorted by the driven gear's angle."""
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        # The fixed columns, then one line_load_<s>_n_per_mm per axial section.
        if reader.fieldnames[: len(COLUMNS)] != COLUMNS:
            sys.exit(f"{path}: expected the columns {','.join(COLUMNS)} first, found {reader.fieldnames}")
        curves = defaultdict(list)
        for row in reader:
            theta2_deg = math.degrees(float(row["theta2_rad"]))
            curves[(row["method"], float(row["torque_nm"]))].append(
                (theta2_deg, float(row["ste_m"]) * 1e6, int(row["pairs_in_contact"]))
            )
    for points in curves.values():
        points.sort()
    return curves


def shade_contact_zones(ax, points):
    """Background bands where the number of loaded pairs is constant, labelled with it."""
    if len(points) < 2:
        return
    angles = [p[0] for p in points]
    step = (angles[-1] - angles[0]) / (len(angles) - 1)
    edges = [angles[0] - step / 2] + [(a + b) / 2 for a, b in zip(angles, angles[1:])] + [angles[-1] + step / 2]
    greys = {1: "0.80", 2: "0.93", 3: "0.86", 4: "0.95"}
    start = 0
    for i in range(1, len(points) + 1):
        if i == len(points) or points[i][2] != points[start][2]:
            n = points[start][2]
            ax.axvspan(edges[start], edges[i], color=greys.get(n, "1.0"), zorder=0, lw=0)
            ax.text(
                (edges[start] + edges[i]) / 2, 0.97, str(n), transform=ax.get_xaxis_transform(),
                ha="center", va="top", fontsize=9, color="0.3",
            )
            start = i


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("csv", nargs="+")
    parser.add_argument("--png", required=True)
    parser.add_argument("--title", default="Static transmission error")
    args = parser.parse_args()

    curves = {}
    for path in args.csv:
        for key, points in read_cases(path).items():
            curves[key] = points
    if not curves:
        sys.exit("no cases in the CSV files")
    torques = sorted({t for _, t in curves})
    methods = list(dict.fromkeys(m for m, _ in curves))
    colours = plt.get_cmap("viridis")

    fig, ax = plt.subplots(figsize=(10.5, 5))
    shade_contact_zones(ax, curves[(methods[0], torques[0])])
    for (method, torque), points in sorted(curves.items()):
        c = colours(torques.index(torque) / max(1, len(torques) - 1) * 0.9)
        ax.plot(
            [p[0] for p in points], [p[1] for p in points], STYLES.get(method, ":"), color=c,
            label=f"{method}, {torque:g} N·m",
        )
    ax.set_xlabel("driven gear angle θ₂ (deg)")
    ax.set_ylabel("STE (µm, along the line of action)")
    ax.set_title(f"{args.title}\n(background: pairs in contact, {methods[0]} at {torques[0]:g} N·m)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    fig.savefig(args.png, dpi=120)


if __name__ == "__main__":
    main()
