"""Run any gear-pair FMU in fmpy against a brake and plot its DTE: the five-minute tour's last step.

Gear 1 is driven by a torque that rises smoothly (haversine) to T₁ — by default the torque the FMU
was built for — and gear 2 drives a viscous brake, τ₂ = −c·ω₂, fed back every communication step
(explicit coupling, as any FMI master does). The brake is sized so that the steady speed of
gear 2 is --speed-rad-s: c = T₁·(z₂/z₁)/ω₂. Prints the steady speeds against that closed form and
the DTE's mean and peak-to-peak over the last mesh cycle; writes a PNG of DTE and ω₂ against time.

    .venv/bin/python examples/brake_run.py out/SmallSpur.fmu --png out/small_spur_dte.png
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from gearfmu.sweep import operating_torque_nm


def teeth(md) -> tuple[int, int]:
    """z₁, z₂ from the FMU's description ("Gear pair NAME (z 23/41), …")."""
    text = md.description.split("(z ", 1)[1].split(")", 1)[0]
    z1, z2 = text.split("/")
    return int(z1), int(z2)


def brake_loop(slave, vr: dict, torque_nm: float, brake: float, t_end_s: float, step_s: float,
               ramp_s: float) -> list[tuple[float, float, float, float]]:
    """T₁ rising as a haversine over `ramp_s` to `torque_nm`; τ₂ = −brake·ω₂ with ω₂ read at each
    step's start (explicit coupling). Returns rows (t, ω₁, ω₂, DTE) at the step ends."""
    rows = []
    for k in range(int(round(t_end_s / step_s))):
        t = k * step_s  # the step's start; a running sum t += step_s is accepted too (round-off)
        rise = 1.0 if t >= ramp_s else 0.5 * (1.0 - math.cos(math.pi * t / ramp_s))
        w_2 = slave.getReal([vr["w_2"]])[0]
        slave.setReal([vr["tau_1"], vr["tau_2"]], [torque_nm * rise, -brake * w_2])
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=step_s)
        rows.append((t + step_s, *slave.getReal([vr["w_1"], vr["w_2"], vr["dte"]])))
    return rows


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("fmu", type=Path)
    parser.add_argument("--torque-nm", type=float, help="T₁ (default: the FMU's operating torque)")
    parser.add_argument("--speed-rad-s", type=float, default=40.0, help="steady speed of gear 2 the brake is sized for")
    parser.add_argument("--ramp-ms", type=float, default=2.0, help="rise time of T₁")
    parser.add_argument("--end-ms", type=float, default=12.0)
    parser.add_argument("--step-us", type=float, default=100.0, help="communication step")
    parser.add_argument("--png", type=Path)
    args = parser.parse_args(argv)

    md = read_model_description(str(args.fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    z1, z2 = teeth(md)
    torque = args.torque_nm if args.torque_nm is not None else operating_torque_nm(args.fmu)
    brake = torque * (z2 / z1) / args.speed_rad_s

    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(args.fmu)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="brake_run")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    h, ramp = args.step_us * 1e-6, args.ramp_ms * 1e-3
    rows = brake_loop(slave, vr, torque, brake, args.end_ms * 1e-3, h, ramp)
    t = rows[-1][0]
    slave.terminate()
    slave.freeInstance()

    # The last mesh cycle (one tooth of gear 2 passing), or the whole run after the ramp if shorter.
    cycle = min(2.0 * math.pi / (z2 * args.speed_rad_s), t - ramp)
    last = [r for r in rows if r[0] > t - cycle]
    w1 = sum(r[1] for r in last) / len(last)
    w2 = sum(r[2] for r in last) / len(last)
    dte = [r[3] * 1e6 for r in last]
    print(f"{md.modelName}: T₁ = {torque:.4g} N·m, brake c = {brake:.4g} N·m·s/rad")
    print(f"  ω₂ {w2:.4f} rad/s (closed form {args.speed_rad_s}), ω₁/ω₂ {w1 / w2:.5f} (z₂/z₁ {z2 / z1:.5f})")
    print(f"  DTE over the last mesh cycle ({cycle * 1e3:.2f} ms): mean {sum(dte) / len(dte):.3f} µm, peak-to-peak {max(dte) - min(dte):.3f} µm")
    if args.png:
        fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
        ax1.plot([r[0] * 1e3 for r in rows], [r[3] * 1e6 for r in rows])
        ax1.set_ylabel("DTE (µm)")
        ax1.set_title(f"{md.modelName}: T₁ = {torque:.4g} N·m against a viscous brake")
        ax2.plot([r[0] * 1e3 for r in rows], [r[2] for r in rows])
        ax2.set_ylabel("ω₂ (rad/s)")
        ax2.set_xlabel("time (ms)")
        fig.tight_layout()
        fig.savefig(args.png, dpi=120)
        print(f"  wrote {args.png}")


if __name__ == "__main__":
    main()
