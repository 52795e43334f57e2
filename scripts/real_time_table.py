#!/usr/bin/env python3
"""Issue 39's real-time table: the cost of a gear-pair FMU at operating speed, through a plain
fmpy master loop (`gearfmu.at_speed.brake_case`: synchronous start, constant T₁, a viscous brake
on gear 2 fed back from w_2 each step).

One row per FMU × mesh frequency × communication step × inertia: µs per doStep, internal
sub-steps per doStep (the FMU's rule: max_step and the speed bound, `PmorDynamics::
angular_step_bound_s`; 1 µs-spaced for the lumped FMU's max_step) and the real-time factor
(wall time inside doStep over simulated time; ≤ 1 is real time). "inertia ×2" runs with each
gear's `inertia_i` at twice its start value: a gear on a shaft, where the PMOR-Hertz FMU's
fast/slow split differs from the build's.

T₁ is each FMU's operating torque (its vendor annotation) unless `--torque-nm` is given, so one
run covers pairs with different ratings:

    .venv/bin/python scripts/real_time_table.py out/KurokawaSpur.fmu out/KurokawaSpurLumped.fmu \\
        out/SmallHelical.fmu out/SmallHelicalLumped.fmu
"""

import argparse
import math
import sys

sys.path.insert(0, __file__.rsplit("/scripts/", 1)[0] + "/python")
from gearfmu.at_speed import Fmu, brake_case  # noqa: E402
from gearfmu.sweep import operating_torque_nm  # noqa: E402


def floats(text: str) -> list[float]:
    return [float(x) for x in text.split(",") if x]


def substeps(fmu: Fmu, mesh_hz: float, step_s: float, max_step: float) -> int:
    """The FMU's internal steps per doStep at this speed: ⌈h / min(max_step, Δϑ/(2ω))⌉ with
    Δϑ = pitch / n_θ (PMOR-Hertz; the lumped FMU has no speed bound) and max_step the instance's
    own after initialization (inertias above the FE values may shorten it)."""
    bound = max_step
    if not fmu.lumped and fmu.samples_per_pitch:
        z1, _ = fmu.teeth
        omega_1 = 2.0 * math.pi * mesh_hz / z1
        # Δϑ/(2ω) on either gear is the same time: a pitch passes both in one mesh period.
        bound = min(max_step, 1.0 / (mesh_hz * fmu.samples_per_pitch * 2.0)) if omega_1 > 0 else max_step
    return math.ceil(step_s / bound - 1e-9)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("fmus", nargs="+")
    p.add_argument("--mesh-hz", type=floats, default=floats("500,1500,3000,5000,8000"))
    p.add_argument("--steps-us", type=floats, default=floats("20,100"))
    p.add_argument("--torque-nm", type=float, help="T₁ (N·m; default: each FMU's operating torque)")
    p.add_argument("--samples-per-pitch", type=int, default=20,
                   help="the PMOR-Hertz build's angular samples per pitch n_θ (the default build's)")
    p.add_argument("--t-end", type=float, default=0.02, help="simulated time per case (s)")
    args = p.parse_args()

    print(f"{'FMU':<28} {'f_m Hz':>7} {'h µs':>5} {'inertia':>8} {'ok':>3} {'µs/doStep':>9} {'steps/doStep':>12} "
          f"{'× real':>7}", flush=True)
    failed = 0
    for path in args.fmus:
        fmu = Fmu(path)
        fmu.samples_per_pitch = args.samples_per_pitch
        torque_nm = args.torque_nm if args.torque_nm is not None else operating_torque_nm(path)
        for mesh_hz in args.mesh_hz:
            for step_us in args.steps_us:
                for doubled in (False, True):
                    params = {name: 2.0 * fmu.start[name] for name in ("inertia_1", "inertia_2")} if doubled else {}
                    r = brake_case(fmu, mesh_hz, step_us * 1e-6, torque_nm, t_end_s=args.t_end,
                                   parameters=params)
                    failed += not r["completed"]
                    max_step = r.get("max_step_s") or fmu.start.get("max_step") or fmu.get("max_step")[0]
                    n = substeps(fmu, mesh_hz, step_us * 1e-6, max_step)
                    print(f"{path.rsplit('/', 1)[-1]:<28} {mesh_hz:7.0f} {step_us:5.0f} {'×2' if doubled else 'FE':>8} "
                          f"{'yes' if r['completed'] else 'NO':>3} {r['us_per_doStep']:9.0f} {n:12d} "
                          f"{r['real_time_factor']:7.2f}" + (f"  {r['error'][:120]}" if r["error"] else ""),
                          flush=True)
        fmu.close()
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
