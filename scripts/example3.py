"""Example 3 of the seed (paper Sect. 6.2) driven by fmpy, for any number of gear-pair FMUs.

185 N·m on gear 1 after a 5 ms haversine ramp, a viscous load of 20 N·m·s/rad on gear 2 (the
text's figures; Table 9's 190 and 110 contradict its 13.63 rad/s), from rest, 25 ms at a 0.1 ms
communication step. The load torque of each step uses gear 2's speed at the step's start
(explicit coupling, as a 1-D master would). Prints per FMU: the wall time of the loop, the
real-time factor, µs per doStep, the resident memory one instance adds, ω₂ at the end against
the closed form 185·(z₂/z₁)/20, and the DTE's mean, RMS about the mean and peak-to-peak over the last mesh cycle;
writes a PNG of DTE and ω₂ against time and, optionally, a CSV.

    .venv/bin/python scripts/example3.py out/KurokawaSpur.fmu out/KurokawaSpurLumped.fmu \\
        --png examples/results/example3_dte.png
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave


def rss_kib() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


def run(fmu: Path, t_end: float, comm_step: float, max_step: float | None = None, torque: float = 185.0,
        ramp: float = 5e-3, damping: float = 20.0) -> dict:
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = extract(str(fmu))
    rss0 = rss_kib()
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=fmu.stem)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    if max_step is not None:
        slave.setReal([vr["max_step"]], [max_step])
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    rss1 = rss_kib()
    n = int(round(t_end / comm_step))
    rows = np.empty((n + 1, 4))
    w_2 = 0.0
    rows[0] = (0.0, 0.0, 0.0, 0.0)
    wall = 0.0
    for k in range(n):
        t = k * comm_step
        tau_1 = torque * 0.5 * (1.0 - math.cos(math.pi * t / ramp)) if t < ramp else torque
        slave.setReal([vr["tau_1"], vr["tau_2"]], [tau_1, -damping * w_2])
        start = time.perf_counter()
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=comm_step)
        wall += time.perf_counter() - start
        phi_2, w_2, dte = slave.getReal([vr["phi_2"], vr["w_2"], vr["dte"]])
        rows[k + 1] = (t + comm_step, phi_2, w_2, dte)
    slave.terminate()
    slave.freeInstance()
    return {"name": md.description.split(",")[1].strip() if "," in md.description else fmu.stem,
            "rows": rows, "wall_s": wall, "steps": n, "rss_kib": rss1 - rss0, "teeth": None}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("fmus", type=Path, nargs="+")
    parser.add_argument("--t-end", type=float, default=25e-3)
    parser.add_argument("--comm-step", type=float, default=1e-4)
    parser.add_argument("--teeth", type=str, default="21,31", help="z1,z2 for the closed-form speed")
    parser.add_argument("--max-step", type=float, default=None, help="the FMUs' internal step bound (default: theirs)")
    parser.add_argument("--steady-from", type=float, default=15e-3,
                        help="start of the steady state for the DTE difference between FMUs (s)")
    parser.add_argument("--png", type=Path, default=None)
    parser.add_argument("--csv", type=Path, default=None)
    args = parser.parse_args(argv)
    z1, z2 = (float(x) for x in args.teeth.split(","))
    w_closed = 185.0 * z2 / z1 / 20.0
    pitch_2 = 2.0 * math.pi / z2
    results = [run(f, args.t_end, args.comm_step, args.max_step) for f in args.fmus]
    print(f"example 3: {args.t_end * 1e3:g} ms at H = {args.comm_step * 1e3:g} ms; closed-form ω₂ = {w_closed:.4f} rad/s")
    print("| FMU | wall (s) | real-time factor | µs per doStep | memory per instance (MiB) | ω₂ end (rad/s) | DTE mean last cycle (µm) | DTE RMS (µm) | DTE p-p (µm) |")
    print("|---|---|---|---|---|---|---|---|---|")
    base = None
    for f, r in zip(args.fmus, results):
        rows = r["rows"]
        last = rows[rows[:, 1] > rows[-1, 1] - pitch_2]
        dte = last[:, 3] * 1e6
        if base is None:
            base = r["wall_s"]
        print(f"| {f.name} | {r['wall_s']:.3f} | {r['wall_s'] / args.t_end:.1f} | {r['wall_s'] / r['steps'] * 1e6:.0f} | "
              f"{r['rss_kib'] / 1024:.1f} | {rows[-1, 2]:.4f} | {dte.mean():.3f} | {dte.std():.3f} | {np.ptp(dte):.3f} |")
    if len(results) > 1:
        print(f"wall-time ratio {args.fmus[0].name} / {args.fmus[1].name}: {results[0]['wall_s'] / results[1]['wall_s']:.1f}")
        # The DTE of each further FMU against the first's, sample by sample (the same
        # communication grid): over the whole run and in steady state (from --steady-from on).
        reference = results[0]["rows"]
        steady = reference[:, 0] >= args.steady_from
        for f, r in zip(args.fmus[1:], results[1:]):
            diff = (r["rows"][:, 3] - reference[:, 3]) * 1e6
            rms_ref = math.sqrt(np.mean((reference[steady, 3] * 1e6) ** 2))
            print(f"DTE difference {f.name} − {args.fmus[0].name}: RMS {math.sqrt(np.mean(diff ** 2)):.3f} µm over the run, "
                  f"{math.sqrt(np.mean(diff[steady] ** 2)):.3f} µm from t = {args.steady_from * 1e3:g} ms "
                  f"(the first's DTE there: RMS {rms_ref:.3f} µm); mean difference there {diff[steady].mean():+.3f} µm")
    if args.csv:
        header = "time_s," + ",".join(f"{f.stem}_w2_rad_s,{f.stem}_dte_m" for f in args.fmus)
        data = np.column_stack([results[0]["rows"][:, 0]] + [c for r in results for c in (r["rows"][:, 2], r["rows"][:, 3])])
        np.savetxt(args.csv, data, delimiter=",", header=header, comments="")
    if args.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
        for f, r in zip(args.fmus, results):
            rows = r["rows"]
            ax1.plot(rows[:, 0] * 1e3, rows[:, 3] * 1e6, label=f.stem, lw=0.8)
            ax2.plot(rows[:, 0] * 1e3, rows[:, 2], label=f.stem, lw=0.8)
        ax2.axhline(w_closed, color="k", ls=":", lw=0.8, label="closed form")
        ax1.set_ylabel("DTE (µm)")
        ax2.set_ylabel("ω₂ (rad/s)")
        ax2.set_xlabel("time (ms)")
        ax1.legend()
        ax2.legend()
        ax1.set_title("Example 3: 185 N·m (5 ms haversine ramp), 20 N·m·s/rad on gear 2")
        fig.tight_layout()
        args.png.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(args.png, dpi=120)
        print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
