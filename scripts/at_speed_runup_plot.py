#!/usr/bin/env python3
"""The resonance as a drivetrain meets it: run-ups and run-downs through the mesh resonance
(`gearfmu.at_speed.run_up`, the ramp in both directions: the contact-loss jump is hysteretic, and
each instant of a ramp continues from the last one's state), one FMU per curve, DTE peak-to-peak
per 50 Hz bin of the mesh frequency, drawn over each other.

    .venv/bin/python scripts/at_speed_runup_plot.py out/KurokawaSpur.fmu out/KurokawaSpurLumped.fmu \\
        out/KurokawaSpurFull.fmu --labels "PMOR-Hertz,lumped,full reference" --load-nm 185 \\
        --f-low-hz 2000 --f-high-hz 3600 --png examples/results/at_speed_runup.png
"""

import argparse
import sys

sys.path.insert(0, __file__.rsplit("/scripts/", 1)[0] + "/python")
from gearfmu.at_speed import Fmu, run_up  # noqa: E402


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("fmus", nargs="+")
    p.add_argument("--labels", help="comma-separated, one per FMU")
    p.add_argument("--load-nm", type=float, required=True)
    p.add_argument("--f-low-hz", type=float, default=2000.0)
    p.add_argument("--f-high-hz", type=float, default=3600.0)
    p.add_argument("--ramp-s", type=float, default=0.22)
    p.add_argument("--step-us", type=float, default=20.0)
    p.add_argument("--param", action="append", default=[], help="NAME=VALUE for every FMU (e.g. mesh_damping_ratio=0)")
    p.add_argument("--png", required=True)
    args = p.parse_args()
    labels = args.labels.split(",") if args.labels else args.fmus
    params = {k: float(v) for k, v in (x.split("=") for x in args.param)}

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    failed = 0
    for path, label, color in zip(args.fmus, labels, ["C0", "C1", "k", "C2", "C3"]):
        fmu = Fmu(path)
        for f0, f1, style, word in [(args.f_low_hz, args.f_high_hz, "-", "up"),
                                    (args.f_high_hz, args.f_low_hz, "--", "down")]:
            r = run_up(fmu, args.step_us * 1e-6, f_start_hz=f0, f_end_hz=f1, ramp_s=args.ramp_s,
                       load_nm=args.load_nm, parameters=params)
            if not r["completed"]:
                failed += 1
                print(f"{label} {word}: FAILED {r['error'][:300]}")
                continue
            bins = sorted(r["dte_pp_by_bin"].items())
            ax.plot([b for b, _ in bins], [v * 1e6 for _, v in bins], style, color=color, label=f"{label}, {word}")
            print(f"{label} {word}: peak {r['peak_dte_pp_m'] * 1e6:.2f} µm at {r['peak_frequency_hz']:.0f} Hz, "
                  f"× real {r['real_time_factor']:.1f}", flush=True)
        fmu.close()
    ax.set_xlabel("mesh frequency (Hz)")
    ax.set_ylabel("DTE peak-to-peak per 50 Hz bin (µm)")
    extra = ", ".join(f"{k} = {v:g}" for k, v in params.items())
    ax.set_title(f"Run-up and run-down, {args.load_nm:g} N·m, {args.step_us:g} µs coupling"
                 + (f", {extra}" if extra else ""))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.png, dpi=120)
    print(f"wrote {args.png}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
