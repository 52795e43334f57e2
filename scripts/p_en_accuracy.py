"""The PMOR-Hertz statics' SVD truncation chosen by accuracy (issue 12, item 2): mean and
peak-to-peak STE against the full attachment basis (p_en = 1: every attachment vector kept), for
both example pairs on their own meshes at every torque of the paper's Tables 4 and 7, 41 positions
over a pitch. Prints one Markdown table per pair; each cell is the signed error in %.

    .venv/bin/python scripts/p_en_accuracy.py [--p-en 0.99,0.999,0.9999]
"""

from __future__ import annotations

import argparse
import re
import subprocess

CASES = {
    "kurokawa_spur.toml": "20.79,61.709,123.417,185.126,246.834,308.543,370.251",
    "kurokawa_helical.toml": "21.07,229.433,344.149,458.866,917.731,1491.313,1835.462",
}
LINE = re.compile(r"T₁ ([0-9.]+) N·m .*mean STE ([0-9.]+) µm, peak-to-peak ([0-9.]+) µm")
NSV = re.compile(r"gear (\d): .*n_sv (\d+)")


def ste(spec: str, torques: str, p_en: float) -> tuple[dict[float, tuple[float, float]], list[str]]:
    out = subprocess.run(["./target/release/fmu-build", "ste", f"examples/{spec}", "--torque-nm", torques,
                          "--angles", "41", "--p-en", str(p_en),
                          "--across", "4", "--profile", "8", "--rim", "4"], check=True, capture_output=True, text=True).stdout
    rows = {float(m[1]): (float(m[2]), float(m[3])) for m in LINE.finditer(out)}
    return rows, [m[2] for m in NSV.finditer(out)]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--p-en", default="0.99,0.999,0.9999")
    args = parser.parse_args(argv)
    levels = [float(x) for x in args.p_en.split(",")]
    for spec, torques in CASES.items():
        full, nsv_full = ste(spec, torques, 1.0)
        results = [ste(spec, torques, p) for p in levels]
        print(f"\n{spec} (full basis: n_sv {'/'.join(nsv_full)})\n")
        head = " | ".join(f"p_en {p} (n_sv {'/'.join(n)}): mean / p-p" for p, (_, n) in zip(levels, results))
        print(f"| T₁ (N·m) | full: mean / p-p (µm) | {head} |")
        print("|---" * (2 + len(levels)) + "|")
        for t, (mean, pp) in sorted(full.items()):
            cells = []
            for rows, _ in results:
                m, p = rows[t]
                cells.append(f"{(m / mean - 1) * 100:+.2f} % / {(p / pp - 1) * 100:+.2f} %")
            print(f"| {t:g} | {mean:.3f} / {pp:.3f} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
