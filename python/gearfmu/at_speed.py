"""The gear-pair FMU at operating speed, driven as a drivetrain engineer drives it.

Two master loops, each written the plain way an FMI master runs (inputs held over a communication
step, outputs read at its end):

* :func:`brake_case` — both gears start at synchronous speed (``w_1_start``, ``w_2_start``), gear 1
  carries a constant torque T₁, gear 2 a viscous brake fed back from ``w_2`` each step,
  c = T₁·z₂/(z₁·ω₂*), so the speeds are balanced from t = 0. The grid of issue 38 runs it over mesh
  frequencies × communication steps × torques.
* :func:`run_up` — a motor inertia under PI speed control drives gear 1 through a torsional shaft
  that the master integrates; gear 2 carries a constant load. The speed target ramps through the
  mesh resonance; the DTE peak-to-peak is recorded per mesh-frequency bin.

Each returns a plain dict (never raises for an FMU failure: ``error`` holds the FMU's message), with
the wall time spent inside ``doStep`` and the real-time factor (wall / simulated).
"""

from __future__ import annotations

import math
import time

import numpy as np

from .operating_point import FmuLog, teeth_from_description


class Fmu:
    """One instance of a gear-pair FMU with its value references (reset between cases)."""

    def __init__(self, fmu_path: str, instance_name: str = "at_speed"):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        md = read_model_description(fmu_path)
        self.path = fmu_path
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.start = {v.name: float(v.start) for v in md.modelVariables
                      if v.type == "Real" and v.start is not None and v.causality == "parameter"}
        self.teeth = teeth_from_description(md.description)
        self.lumped = "lumped model" in (md.description or "")
        self.log = FmuLog()
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu_path),
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName=instance_name)
        self.fmu.instantiate(callbacks=self.log.callbacks)

    def initialize(self, parameters: dict) -> None:
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in parameters.items():
            self.fmu.setReal([self.vr[name]], [float(value)])
        self.fmu.exitInitializationMode()

    def get(self, *names: str) -> list[float]:
        return self.fmu.getReal([self.vr[n] for n in names])

    def close(self) -> None:
        self.fmu.freeInstance()


def _failure(fmu: Fmu, exc: Exception) -> str:
    log = fmu.log.take()
    return f"{type(exc).__name__}: {exc}" + (f" — FMU log: {log}" if log else "")


SHAFT_MODE_HZ = 423.0   # the run-up shaft's mode on the pinion alone: √(k_s/J₁)/2π


def brake_case(fmu: Fmu, mesh_frequency_hz: float, step_s: float, torque_1_nm: float, t_end_s: float = 0.02,
               parameters: dict | None = None) -> dict:
    """Issue 38's speed × step case: synchronous start, constant T₁, a viscous brake on gear 2
    fed back explicitly from w_2. Returns completion, the mean ω₂ over the last 5 ms against its
    target, the DTE there and the cost."""
    z1, z2 = fmu.teeth
    omega_2 = 2.0 * math.pi * mesh_frequency_hz / z2
    omega_1 = omega_2 * z2 / z1
    c = torque_1_nm * z2 / (z1 * omega_2)
    result = dict(mesh_frequency_hz=mesh_frequency_hz, step_s=step_s, torque_1_nm=torque_1_nm, t_end_s=t_end_s,
                  error="")
    n_steps = int(round(t_end_s / step_s))
    tail = max(1, int(round(0.005 / step_s)))
    w2, dte = np.full(n_steps, np.nan), np.full(n_steps, np.nan)
    wall = 0.0
    try:
        fmu.initialize({**(parameters or {}), "w_1_start": omega_1, "w_2_start": omega_2})
        # The instance's own default step (its parameters may shorten the build's).
        result["max_step_s"] = float(fmu.fmu.getReal([fmu.vr["max_step"]])[0])
        w_2 = omega_2
        refs_in = [fmu.vr["tau_1"], fmu.vr["tau_2"]]
        refs_out = [fmu.vr["w_2"], fmu.vr["dte"]]
        for n in range(n_steps):
            fmu.fmu.setReal(refs_in, [torque_1_nm, -c * w_2])
            tick = time.perf_counter()
            fmu.fmu.doStep(currentCommunicationPoint=n * step_s, communicationStepSize=step_s)
            wall += time.perf_counter() - tick
            w_2, dte[n] = fmu.fmu.getReal(refs_out)
            w2[n] = w_2
    except Exception as exc:   # an fmi2Error from doStep: recorded with the FMU's own message
        result["error"] = _failure(fmu, exc)
        result["failed_at_s"] = float(np.count_nonzero(~np.isnan(w2)) * step_s)
    fmu.fmu.reset()
    fmu.log.take()
    done = int(np.count_nonzero(~np.isnan(w2)))
    result["completed"] = not result["error"]
    result["doStep_wall_s"] = wall
    result["real_time_factor"] = wall / max(done * step_s, 1e-300)
    result["us_per_doStep"] = 1e6 * wall / max(done, 1)
    if result["completed"]:
        last = w2[-tail:]
        result["omega_2_error"] = float(last.mean() / omega_2 - 1.0)
        result["dte_rms_m"] = float(dte[-tail:].std())
        result["dte_pp_m"] = float(np.ptp(dte[-tail:]))
    return result


def run_up(fmu: Fmu, step_s: float, f_end_hz: float = 4000.0, ramp_s: float = 0.5, load_nm: float = 185.0,
           f_start_hz: float | None = None,
           motor_inertia_kgm2: float = 0.01, shaft_stiffness_nm_per_rad: float | None = None, bin_hz: float = 50.0,
           settle_s: float = 0.02, parameters: dict | None = None) -> dict:
    """Issue 38's run-up: a motor inertia J_m under PI speed control (its target ramps from the mesh
    frequency ``f_start_hz``, default a tenth of the end's, to ``f_end_hz`` over ``ramp_s``; an end
    below the start runs it down) drives gear 1 through a torsional shaft k_s
    (with a little damping) integrated by the master with symplectic Euler at the communication
    step; gear 2 carries the constant load (−``load_nm``). The shaft's default stiffness puts the
    pinion's mode on it at ``SHAFT_MODE_HZ`` (2·10⁴ N·m/rad on the Kurokawa pinion, issue 38's), so
    an explicit master is as stable on any pair as on that one. The DTE peak-to-peak is taken per
    bin of the mesh frequency z₁·ω₁/2π after ``settle_s`` (the start's loading transient); the
    peak bin is the result."""
    z1, z2 = fmu.teeth
    w_end = 2.0 * math.pi * f_end_hz / z1
    w_start = 2.0 * math.pi * (f_start_hz if f_start_hz is not None else 0.1 * f_end_hz) / z1
    j_m = motor_inertia_kgm2
    k_s = shaft_stiffness_nm_per_rad or (2.0 * math.pi * SHAFT_MODE_HZ) ** 2 * fmu.start["inertia_1"]
    # Shaft damping: 2 % of critical on the motor against a fixed end.
    c_s = 2.0 * 0.02 * math.sqrt(k_s * j_m)
    # PI on the motor speed: bandwidth ~20 Hz on the whole drivetrain's inertia seen at the motor.
    j_total = j_m + fmu.start.get("inertia_1", 0.0) + fmu.start.get("inertia_2", 0.0) * (z1 / z2) ** 2
    wc = 2.0 * math.pi * 20.0
    kp, ki = 2.0 * wc * j_total, wc * wc * j_total
    result = dict(step_s=step_s, f_start_hz=z1 * w_start / (2.0 * math.pi), f_end_hz=f_end_hz, ramp_s=ramp_s,
                  error="")
    n_steps = int(round(ramp_s / step_s))
    rows = []
    wall, n_done = 0.0, 0
    try:
        fmu.initialize({**(parameters or {}), "w_1_start": w_start, "w_2_start": w_start * z1 / z2})
        phi_m, w_m = 0.0, w_start
        integral = load_nm * z1 / z2     # the PI's integral starts at the steady drive torque
        phi_1, w_1 = fmu.get("phi_1", "w_1")
        phi_m = phi_1 + integral / k_s   # the shaft pre-twisted to carry it
        refs_in = [fmu.vr["tau_1"], fmu.vr["tau_2"]]
        refs_out = [fmu.vr["phi_1"], fmu.vr["w_1"], fmu.vr["dte"]]
        for n in range(n_steps):
            t = n * step_s
            target = w_start + (w_end - w_start) * min(t / ramp_s, 1.0)
            shaft = k_s * (phi_m - phi_1) + c_s * (w_m - w_1)
            error = target - w_m
            integral += ki * error * step_s
            motor = kp * error + integral
            w_m += step_s * (motor - shaft) / j_m
            phi_m += step_s * w_m
            fmu.fmu.setReal(refs_in, [shaft, -load_nm])
            tick = time.perf_counter()
            fmu.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=step_s)
            wall += time.perf_counter() - tick
            n_done += 1
            phi_1, w_1, dte = fmu.fmu.getReal(refs_out)
            if t >= settle_s:
                rows.append((z1 * w_1 / (2.0 * math.pi), dte))
    except Exception as exc:
        result["error"] = _failure(fmu, exc)
    fmu.fmu.reset()
    fmu.log.take()
    result["completed"] = not result["error"]
    result["doStep_wall_s"] = wall
    result["real_time_factor"] = wall / max(n_done * step_s, 1e-300)
    if rows:
        data = np.array(rows)
        result["reached_hz"] = float(data[-1, 0])
        bins = np.floor(data[:, 0] / bin_hz).astype(int)
        pp = {}
        for b in np.unique(bins):
            d = data[bins == b, 1]
            if len(d) >= 8:
                pp[b] = float(np.ptp(d))
        if pp:
            peak = max(pp, key=pp.get)
            result["peak_dte_pp_m"] = pp[peak]
            result["peak_frequency_hz"] = (peak + 0.5) * bin_hz
            result["dte_pp_by_bin"] = {float((b + 0.5) * bin_hz): v for b, v in sorted(pp.items())}
    return result
