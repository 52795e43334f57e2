#!/usr/bin/env python3
"""Why the FE face load factor K_Hβ exceeds ISO 6336-1's (issue 27): a face-width and bore study.

ISO 6336-1 method C takes the mesh as a Winkler foundation along the face: each strip of face
width carries c_γβ times its own gap, so a linear misalignment f gives a linear load and
K_Hβ − 1 = f·c_γβ / (2 F_m/b). Run with the FE's own mean mesh stiffness c in place of c_γβ, the
same foundation gives the *Winkler figure* printed here, reduced to what the largest of n
axial sections sees (its mean, at b/(2n) from the end: a factor 1 − 1/n).

The FE pair is not such a foundation. Part of its compliance acts on the mean load only: the gear
body's torsion between the bore and the teeth (a tilting load puts no net torque on it), and,
on a narrow face, the tooth's own bending, which its plate action spreads over the face. Both
make the pair stiffer against a tilting load than against a uniform one, so the load runs to the
closing end more than the Winkler figure says. The study tests that account two ways, at a
constant line load (the torque scaled with b) and a constant section width (b/n = 3.75 mm):

- a wider face (b/m from 2.5 to 20): the plate action fades, the ratio R = FE/Winkler falls;
- a bore near the tooth root (45/75 mm instead of 20/25 mm): the body's torsion all but goes,
  and R falls towards 1.

    .venv/bin/python scripts/face_load_study.py examples/kurokawa_spur.toml
        [--widths-mm 15,30,60] [--torque-nm 185] [--misalignment-um 10] [--stiff-body-at-mm 60]
"""

from __future__ import annotations

import argparse
import re
import subprocess
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FMU_BUILD = REPO / "target" / "release" / "fmu-build"
SECTION_WIDTH_MM = 3.75


def variant(spec_text: str, width_mm: float, base_width_mm: float, torque_nm: float,
            misalignment_um: float, bores_mm: tuple[float, float] | None) -> str:
    """The spec at face width b, the torque T·b/b₀ (the same line load), misaligned."""
    text = re.sub(r"(?m)^face_width_mm = .*$",
                  f"face_width_mm = {width_mm}\nmisalignment_um = {misalignment_um}", spec_text)
    text = re.sub(r"(?m)^torque_nm = .*$", f"torque_nm = {torque_nm * width_mm / base_width_mm}", text)
    if bores_mm is not None:
        bores = iter(bores_mm)
        text = re.sub(r"(?m)^bore_radius_mm = .*$", lambda _: f"bore_radius_mm = {next(bores)}", text)
    return text


def run(spec: Path, sections: int) -> dict:
    out = subprocess.run([str(FMU_BUILD), "ste", str(spec), "--angles", "20", "--slices", str(sections)],
                         check=True, capture_output=True, text=True).stdout
    stiffness = float(re.search(r"mean mesh stiffness ([0-9.]+) N", out).group(1))
    line_load = float(re.search(r"w = ([0-9.]+) N/mm", out).group(1))
    k_fe = float(re.search(r"K_Hβ \(largest over mean.*?\): ([0-9.]+)", out).group(1))
    k_iso = float(re.search(r"ISO 6336-1 \(F_βy = [0-9.]+ µm from mounting.misalignment_um\): ([0-9.]+)", out).group(1))
    return {"c": stiffness, "w": line_load, "k_fe": k_fe, "k_iso": k_iso}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("spec", type=Path)
    parser.add_argument("--widths-mm", default="15,30,60")
    parser.add_argument("--misalignment-um", type=float, default=10.0)
    parser.add_argument("--torque-nm", type=float, default=185.0, help="at the spec's face width")
    parser.add_argument("--stiff-body-at-mm", type=float, default=60.0,
                        help="the face width of the run with bores near the root (0: none)")
    parser.add_argument("--stiff-bores-mm", default="45,75")
    args = parser.parse_args()
    text = args.spec.read_text()
    base = float(re.search(r"(?m)^face_width_mm = (.*)$", text).group(1))
    cases = [(float(b), None) for b in args.widths_mm.split(",")]
    if args.stiff_body_at_mm > 0:
        cases.append((args.stiff_body_at_mm, tuple(float(r) for r in args.stiff_bores_mm.split(","))))
    print(f"misalignment {args.misalignment_um} µm, sections of {SECTION_WIDTH_MM} mm, {args.torque_nm} N·m × b/{base} mm")
    print("b (mm) | b/m | bores (mm) | sections | c FE (N/(mm·µm)) | K_Hβ FE | Winkler on c | R = (K−1)/(Winkler−1) | ISO")
    module = float(re.search(r"(?m)^module_mm = (.*)$", text).group(1))
    with tempfile.TemporaryDirectory() as tmp:
        for width, bores in cases:
            sections = max(1, round(width / SECTION_WIDTH_MM))
            spec = Path(tmp) / f"b{width}.toml"
            spec.write_text(variant(text, width, base, args.torque_nm, args.misalignment_um, bores))
            r = run(spec, sections)
            winkler = args.misalignment_um * r["c"] / (2.0 * r["w"]) * (1.0 - 1.0 / sections)
            label = "spec" if bores is None else ",".join(f"{x:g}" for x in bores)
            print(f"{width:g} | {width / module:.1f} | {label} | {sections} | {r['c']:.2f} | {r['k_fe']:.3f} | "
                  f"{1 + winkler:.3f} | {(r['k_fe'] - 1) / winkler:.2f} | {r['k_iso']:.3f}", flush=True)


if __name__ == "__main__":
    main()
