#!/usr/bin/env python3
"""The drivetrain as an SSP system, run by two masters: libcosim (DNV's Open Simulation
Platform) and fmpy, against examples/drivetrain.py's element co-simulation.

    motor ──shaft_1──► gear pair ──shaft_2──► load        (out/drivetrain.ssp, by fmu-build ssp)

Every component is an FMU: the element FMUs built by ``fmu-build element`` (inertia, shaft,
motor, load; MSL Rotational signs) and the gear-pair FMU. Both masters couple them explicitly
(Jacobi: every FMU steps from the outputs the others had at the start of the step) at the
communication step the file declares, 2.5e-5 s: a massless shaft's torque reaches a body two
steps after the angles it is made of, and this explicit loop diverges between 6e-5 and 7e-5 s. The third run, ``drivetrain.element_cosimulation``, is the same
system with the elements written out in Python and only the gear pair as an FMU: the check that
the element FMUs and the file's connections and parameters are what the demo means.

Usage
-----

    python examples/drivetrain_ssp.py out/drivetrain.ssp [--t-end 0.5] [--png out/drivetrain_ssp.png]
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
COMM_STEP_S = 2.5e-5

# What the runs record: (component, variable).
PROBES = (("motor", "w"), ("gear_pair", "w_1"), ("gear_pair", "w_2"), ("load", "w"), ("gear_pair", "dte"))


def _drivetrain_module():
    spec = importlib.util.spec_from_file_location("drivetrain", HERE / "drivetrain.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("drivetrain", module)
    spec.loader.exec_module(module)
    return module


def run_libcosim(ssp_path: Path, t_end: float, comm_step: float) -> dict:
    """The .ssp in libcosim (its SSP loader, its fixed-step algorithm); the probes after every step."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    step_ns = int(round(comm_step * 1e9))
    execution = CosimExecution.from_ssp_file(str(ssp_path), step_size=step_ns)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    refs = []
    for component, variable in PROBES:
        index = execution.slave_index_from_instance_name(component)
        names = {v.name.decode(): v.reference for v in execution.slave_variables(slave_index=index)}
        refs.append((index, names[variable]))
    steps = int(round(t_end / comm_step))
    rows = np.empty((steps, len(PROBES)))
    for k in range(steps):
        if not execution.step():
            raise RuntimeError(f"libcosim step {k} failed")
        rows[k] = [observer.last_real_values(slave_index=i, variable_references=[r])[0] for i, r in refs]
    return {"t": comm_step * np.arange(1, steps + 1), **{f"{c}.{v}": rows[:, j] for j, (c, v) in enumerate(PROBES)}}


def _own_parameter_set(ssp_path: Path):
    """The file's component parameter sets as one set named component.variable (fmpy.ssp applies
    only the set it is given, not the bindings in the file)."""
    from fmpy.ssp.ssd import Parameter, ParameterSet, read_ssd

    ssd = read_ssd(str(ssp_path))
    merged = ParameterSet(name="drivetrain")
    for component in ssd.system.elements:
        for binding in component.parameterBindings:
            for values in binding.parameterValues:
                for p in values.parameters:
                    merged.parameters.append(Parameter(name=f"{component.name}.{p.name}", type=p.type, value=p.value))
    return merged


def run_fmpy(ssp_path: Path, t_end: float, comm_step: float) -> dict:
    """The .ssp in fmpy.ssp (Jacobi at a fixed step), with the file's own parameter sets."""
    from fmpy.ssp.simulation import simulate_ssp

    result = simulate_ssp(str(ssp_path), stop_time=t_end, step_size=comm_step, parameter_set=_own_parameter_set(ssp_path))
    steps = int(round(t_end / comm_step))
    return {"t": comm_step * np.arange(1, steps + 1), **{f"{c}.{v}": result[f"{c}.{v}"][:steps] for c, v in PROBES}}


def run_reference(ssp_path: Path, t_end: float, comm_step: float) -> dict:
    """examples/drivetrain.py's element co-simulation of the same system, on the gear FMU in the file."""
    drivetrain = _drivetrain_module()
    with tempfile.TemporaryDirectory() as tmp:
        with zipfile.ZipFile(ssp_path) as archive:
            gear_fmu = Path(archive.extract("resources/gear_pair.fmu", tmp))
        result = drivetrain.element_cosimulation(gear_fmu, drivetrain.DrivetrainParams(), t_end, comm_step)
    steps = int(round(t_end / comm_step))
    return {"t": result["t"][:steps], **{f"{c}.{v}": result[f"{c}.{v}"][:steps] for c, v in PROBES}}


def compare(a: dict, b: dict) -> dict:
    """Per probe: the largest difference relative to the reference b's largest |value| (speeds)
    or its range (the DTE)."""
    out = {}
    for c, v in PROBES:
        key = f"{c}.{v}"
        x, y = np.asarray(a[key]), np.asarray(b[key])
        scale = (y.max() - y.min()) if v == "dte" else np.abs(y).max()
        out[key] = float(np.abs(x - y).max() / scale)
    return out


def plot(runs: dict, png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (speeds, dte) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for (name, run), style in zip(runs.items(), ("-", "--", ":")):
        for c, v in PROBES[:-1]:
            speeds.plot(run["t"], run[f"{c}.{v}"], style, label=f"{c}.{v} ({name})")
        dte.plot(run["t"], 1e6 * run["gear_pair.dte"], style, label=name)
    speeds.set_ylabel("speed (rad/s, each in its gear's mesh sense)")
    speeds.legend(fontsize=7, ncol=3)
    dte.set_ylabel("DTE (µm)")
    dte.set_xlabel("t (s)")
    dte.legend(fontsize=8)
    fig.suptitle("SSP drivetrain: motor → shaft → gear pair → shaft → load")
    fig.tight_layout()
    fig.savefig(png, dpi=120)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("ssp", type=Path)
    parser.add_argument("--t-end", type=float, default=0.5)
    parser.add_argument("--comm-step", type=float, default=COMM_STEP_S)
    parser.add_argument("--png", type=Path, default=None)
    args = parser.parse_args(argv)
    runs = {
        "libcosim": run_libcosim(args.ssp, args.t_end, args.comm_step),
        "fmpy": run_fmpy(args.ssp, args.t_end, args.comm_step),
        "drivetrain.py": run_reference(args.ssp, args.t_end, args.comm_step),
    }
    for name in ("libcosim", "fmpy"):
        worst = compare(runs[name], runs["drivetrain.py"])
        print(f"{name} against drivetrain.py: " + ", ".join(f"{k} {e:.1e}" for k, e in worst.items()))
    last = runs["libcosim"]
    print(
        f"at t = {last['t'][-1]:.3f} s: motor {last['motor.w'][-1]:.4f} rad/s, gear 2 {last['gear_pair.w_2'][-1]:.4f} rad/s, "
        f"load {last['load.w'][-1]:.4f} rad/s, DTE {1e6 * last['gear_pair.dte'][-1]:.3f} µm"
    )
    if args.png:
        plot(runs, args.png)
        print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
