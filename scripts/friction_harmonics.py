"""Tooth friction's effect on the DTE and the mesh efficiency, through fmpy (issue 42).

Each gear-pair FMU given (lumped, its law and friction contacts from the FE statics, or PMOR-Hertz),
μ = 0 and 0.05, two runs:

* example 3: 185 N·m after a 5 ms haversine ramp, a viscous load of 20 N·m·s/rad, from rest, 25 ms
  (it ends at about 67 Hz mesh frequency); the last mesh cycle is analysed;
* at speed: the operating torque held on gear 1, gear 2 braked to a steady mesh frequency
  (`--mesh-hz`, default 1500 Hz), from the static equilibrium; 40 mesh cycles settle, the next
  20 are analysed.

Per run it prints the DTE's amplitude at the mesh frequency's first four harmonics (a discrete
Fourier transform over whole mesh cycles) and the mean mesh efficiency, 1 − ΔE_loss/∫τ₁ω₁dt
over the analysed cycles; it writes a PNG of the harmonics side by side.

    target/release/fmu-build build examples/kurokawa_spur.toml -o out/KurokawaSpur.fmu \\
        --lumped-fmu out/KurokawaSpurLumped.fmu
    .venv/bin/python scripts/friction_harmonics.py examples/kurokawa_spur.toml out/KurokawaSpur.fmu \\
        out/KurokawaSpurLumped.fmu --png docs/explanation/friction_harmonics.png
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

HARMONICS = 4


def open_slave(fmu: Path, unzipped: str, name: str, parameters: dict, start_at_equilibrium: bool,
               inputs: tuple[float, float]):
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=name)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    for key, value in parameters.items():
        slave.setReal([vr[key]], [value])
    slave.setBoolean([vr["start_at_equilibrium"]], [start_at_equilibrium])
    slave.setReal([vr["tau_1"], vr["tau_2"]], list(inputs))
    slave.exitInitializationMode()
    return slave, vr


def run(slave, vr, steps: int, h: float, torques) -> np.ndarray:
    """Rows t, w_1, w_2, dte, mesh_energy_loss, τ₁ (the τ₁ of the step that ends there): the
    start, then after each step; `torques(t, w_2)` -> (τ₁, τ₂)."""
    refs = [vr[n] for n in ("w_1", "w_2", "dte", "mesh_energy_loss")]
    rows = np.empty((steps + 1, 6))
    rows[0] = (0.0, *slave.getReal(refs), 0.0)
    w_2 = rows[0, 2]
    for k in range(steps):
        t = k * h
        tau = torques(t, w_2)
        slave.setReal([vr["tau_1"], vr["tau_2"]], list(tau))
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        w_1, w_2, dte, loss = slave.getReal(refs)
        rows[k + 1] = (t + h, w_1, w_2, dte, loss, tau[0])
    slave.terminate()
    slave.freeInstance()
    return rows


def analyse(rows: np.ndarray, z1: int, cycles_from: float) -> dict:
    """The DTE's harmonics and the mean efficiency over the whole mesh cycles from `cycles_from`
    (a roll count in mesh cycles, z₁·φ₁/2π) to the run's last whole cycle."""
    t, w_1, dte, loss, tau_1 = rows[:, 0], rows[:, 1], rows[:, 3], rows[:, 4], rows[:, 5]
    h = t[1] - t[0]
    # Mesh cycles rolled, z₁·φ₁/2π, by the trapezoid of ω₁ (φ₁ from the start).
    cycles = z1 * np.concatenate([[0.0], np.cumsum(0.5 * (w_1[1:] + w_1[:-1]) * h)]) / (2 * math.pi)
    last = math.floor(cycles[-1])
    start = max(math.ceil(cycles_from), last - 20) if cycles_from < last else last - 1
    i0, i1 = int(np.searchsorted(cycles, start)), int(np.searchsorted(cycles, last))
    n_cycles = last - start
    # The DTE against the roll (mesh cycles), resampled evenly: harmonics per mesh cycle.
    grid = np.linspace(start, last, 64 * n_cycles, endpoint=False)
    signal = np.interp(grid, cycles[i0:i1 + 1], dte[i0:i1 + 1])
    spectrum = np.fft.rfft(signal - signal.mean()) / len(signal) * 2
    amplitude = [abs(spectrum[n_cycles * k]) for k in range(1, HARMONICS + 1)]
    # τ₁'s work from row i0 to i1: each step's τ₁ on its trapezoid of ω₁.
    work = float(np.sum(tau_1[i0 + 1:i1 + 1] * 0.5 * (w_1[i0 + 1:i1 + 1] + w_1[i0:i1]) * h))
    efficiency = 1.0 - (loss[i1] - loss[i0]) / work if work > 0 else float("nan")
    return {"harmonics_um": [a * 1e6 for a in amplitude], "mean_um": float(signal.mean() * 1e6),
            "efficiency": efficiency, "cycles": n_cycles,
            "mesh_hz": float(z1 * w_1[i0:i1 + 1].mean() / (2 * math.pi))}


def harmonics_with_and_without_friction(fmu: Path, spec: Path, mesh_hz: float, mu: float) -> dict:
    """{(run, μ): analyse(…)} for one FMU, μ = 0 and `mu`."""
    md = read_model_description(str(fmu))
    if not any(v.name == "friction_coefficient" for v in md.modelVariables):
        raise SystemExit(f"{fmu} has no friction_coefficient: rebuild it")
    unzipped = extract(str(fmu))
    # The pair's teeth and operating torque from its spec (the geometry alone: no FE), the
    # inertias from the FMU's own start values (the PMOR-Hertz FMU's are its FE gears').
    with tempfile.TemporaryDirectory() as tmp:
        dump = Path(tmp) / "pair.json"
        subprocess.run(["target/release/fmu-build", "inspect", str(spec), "--mesh-law", "analytic", "--json",
                        str(dump)], check=True, capture_output=True)
        mesh = json.loads(dump.read_text())
    for v in md.modelVariables:
        if v.name in ("inertia_1", "inertia_2"):
            mesh[f"{v.name}_kgm2"] = float(v.start)
    z1, z2 = mesh["teeth_1"], mesh["teeth_2"]
    ratio = z2 / z1
    results = {}
    for friction in (0.0, mu):
        # Example 3.
        slave, vr = open_slave(fmu, unzipped, f"ex3-{friction}", {"friction_coefficient": friction}, False,
                               (0.0, 0.0))

        def example3(t, w_2):
            return (185.0 * (0.5 * (1 - math.cos(math.pi * t / 5e-3)) if t < 5e-3 else 1.0), -20.0 * w_2)

        rows = run(slave, vr, 1250, 2e-5, example3)
        results[("example 3", friction)] = analyse(rows, z1, 0.0)
        # At speed, brake-held.
        torque = mesh["operating_torque_nm"]
        w2_target = 2 * math.pi * mesh_hz / z2
        gain = (mesh["inertia_2_kgm2"] + mesh["inertia_1_kgm2"] * ratio**2) / 0.01
        slave, vr = open_slave(fmu, unzipped, f"speed-{friction}",
                               {"friction_coefficient": friction, "w_1_start": w2_target * ratio,
                                "w_2_start": w2_target},
                               True, (torque, -torque * ratio))
        h = 1e-5
        steps = round(61 / mesh_hz / h)
        rows = run(slave, vr, steps, h, lambda t, w_2: (torque, -torque * ratio - gain * (w_2 - w2_target)))
        results[("at speed", friction)] = analyse(rows, z1, 40.0)
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("spec", type=Path, help="the pair's spec (its teeth and operating torque)")
    parser.add_argument("fmus", type=Path, nargs="+", help="gear-pair FMUs of that spec (lumped or PMOR-Hertz)")
    parser.add_argument("--mesh-hz", type=float, default=1500.0, help="the at-speed run's mesh frequency")
    parser.add_argument("--mu", type=float, default=0.05)
    parser.add_argument("--png", type=Path)
    args = parser.parse_args()
    results = {fmu: harmonics_with_and_without_friction(fmu, args.spec, args.mesh_hz, args.mu) for fmu in args.fmus}
    for fmu, by_run in results.items():
        for (case, mu), r in by_run.items():
            print(f"{fmu.stem}: {case:9s} μ = {mu:4.2f}: mesh {r['mesh_hz']:7.1f} Hz over {r['cycles']:2d} cycles, "
                  f"DTE mean {r['mean_um']:.3f} µm, harmonics 1–{HARMONICS} "
                  + " / ".join(f"{a:.4f}" for a in r["harmonics_um"]) + f" µm, mean efficiency {r['efficiency']:.5f}")
    if args.png:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(len(args.fmus), 2, figsize=(10, 3.4 * len(args.fmus)), squeeze=False)
        for row, fmu in zip(axes, args.fmus):
            for ax, case in zip(row, ("example 3", "at speed")):
                k = np.arange(1, HARMONICS + 1)
                for offset, mu in ((-0.18, 0.0), (0.18, args.mu)):
                    r = results[fmu][(case, mu)]
                    ax.bar(k + offset, r["harmonics_um"], width=0.36,
                           label=f"μ = {mu:g}" + (f", η = {100 * r['efficiency']:.2f} %" if mu else ""))
                r = results[fmu][(case, 0.0)]
                ax.set_title(f"{fmu.stem}, {case}: {r['mesh_hz']:.0f} Hz mesh frequency", fontsize=10)
                ax.set_xlabel("harmonic of the mesh frequency")
                ax.set_ylabel("DTE amplitude (µm)")
                ax.set_xticks(k)
                ax.legend()
        fig.suptitle("Tooth friction and the DTE's mesh harmonics")
        fig.tight_layout()
        fig.savefig(args.png, dpi=110)
        print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
