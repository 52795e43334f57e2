#!/usr/bin/env python3
"""A 1-D torsional drivetrain co-simulated with the gearfmu gear-pair FMU.

Topology
--------

    motor ──shaft 1──► gear 1 ═╡mesh╞═ gear 2 ──shaft 2──► load
    (J_m, τ_m(t))  (k1, d1)    └──── gear-pair FMU ────┘  (k2, d2)  (J_L, τ_load(ω_L))

The gear pair (both gear inertias and the nonlinear, time-varying mesh) lives
inside the FMU.  This script is the co-simulation *master*: it owns the motor
and the load inertias and the two shafts, and exchanges torques and angles
with the FMU once per communication step.

Sign conventions (the same in the FMU, the master and the monolithic reference)
-------------------------------------------------------------------------------

* Every angle and speed is positive in its own *mesh sense*: gear 1 and gear 2
  both turn "forwards" when the pair rolls in the driving direction, so the
  rigid kinematics is ``z1·phi_1 = z2·phi_2`` and ``w_2 = w_1·z1/z2`` (no minus
  sign, the physical counter-rotation is folded into the sign convention).
  Motor angle ``theta_m`` is measured in the gear-1 sense, load angle
  ``theta_L`` in the gear-2 sense.
* ``tau_1`` (FMU input) is the torque the shaft 1 applies to gear 1, positive
  when it drives gear 1 forwards:
      tau_1 = k1·(theta_m − phi_1) + d1·(w_m − w_1)
  The motor feels the reaction ``−tau_1``.
* ``tau_2`` (FMU input) is the torque the shaft 2 applies to gear 2, positive
  forwards.  A load that brakes makes it negative:
      shaft_2_torque = k2·(phi_2 − theta_L) + d2·(w_2 − w_L)    (twist of shaft 2)
      tau_2          = −shaft_2_torque
  The load inertia is driven by ``+shaft_2_torque``.
* The load torque opposes the load speed: viscous ``c·w_L`` or quadratic
  ``a·w_L·|w_L|``.
* ``dte`` = r_b1·phi_1 − r_b2·phi_2 (m), the dynamic transmission error along
  the line of action; it is positive when the driven gear lags (drive-flank
  contact).  ``mesh_force`` is positive on the drive flank, negative on the
  coast (back) flank.

Coupling scheme
---------------

Explicit (Jacobi) coupling at a fixed communication step H.  At t_n the master
reads the gear angles and speeds, computes both shaft torques, sends them to
the FMU, and both sides advance over [t_n, t_n + H] in parallel:

* the FMU integrates the gears with the shaft torques held constant;
* the master integrates motor and load with one classical RK4 step, seeing the
  gear angles extrapolated with their held speeds
  (phi(t) = phi_n + w_n·(t − t_n)) and the gear speeds held.

This zero-order-hold coupling is first-order accurate in H.
:func:`monolithic_reference` solves the same drivetrain and the same mesh law
in one stiff-accurate ODE, which is what the co-simulation converges to.

Usage
-----

    python examples/drivetrain.py --fmu target/fmu/KurokawaSpur.fmu --png out.png
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

REPO_ROOT = Path(__file__).resolve().parents[1]
DEFAULT_FMU = REPO_ROOT / "target" / "fmu" / "KurokawaSpur.fmu"


# ---------------------------------------------------------------------------
# Parameters
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class MotorParams:
    """Motor rotor with a haversine torque ramp to a final torque."""

    inertia_kgm2: float = 0.05
    final_torque_nm: float = 200.0
    ramp_time_s: float = 0.02

    def torque_nm(self, t_s: float) -> float:
        """Haversine ramp: τ_final·sin²(π/2 · t/t_ramp), then constant."""
        if t_s <= 0.0:
            return 0.0
        if t_s >= self.ramp_time_s:
            return self.final_torque_nm
        return self.final_torque_nm * math.sin(0.5 * math.pi * t_s / self.ramp_time_s) ** 2


@dataclass(frozen=True)
class ShaftParams:
    """Massless torsional spring + damper."""

    stiffness_nm_per_rad: float
    damping_nms_per_rad: float

    def torque_nm(self, twist_rad: float, twist_rate_rad_s: float) -> float:
        return self.stiffness_nm_per_rad * twist_rad + self.damping_nms_per_rad * twist_rate_rad_s


@dataclass(frozen=True)
class LoadParams:
    """Load inertia with a speed-dependent resisting torque.

    kind = "viscous":   τ_load = viscous_nms_per_rad · w_L
    kind = "quadratic": τ_load = quadratic_nms2_per_rad2 · w_L·|w_L|   (fan / propeller)
    """

    inertia_kgm2: float = 0.2
    kind: str = "viscous"
    viscous_nms_per_rad: float = 2.0
    quadratic_nms2_per_rad2: float = 0.02

    def torque_nm(self, speed_rad_s: float) -> float:
        if self.kind == "viscous":
            return self.viscous_nms_per_rad * speed_rad_s
        if self.kind == "quadratic":
            return self.quadratic_nms2_per_rad2 * speed_rad_s * abs(speed_rad_s)
        raise ValueError(f"unknown load kind {self.kind!r}")


@dataclass(frozen=True)
class DrivetrainParams:
    """Everything outside the gear pair.  The drivetrain starts at rest, unstrained."""

    motor: MotorParams = field(default_factory=MotorParams)
    shaft_1: ShaftParams = field(default_factory=lambda: ShaftParams(2.0e4, 2.0))
    shaft_2: ShaftParams = field(default_factory=lambda: ShaftParams(4.0e4, 4.0))
    load: LoadParams = field(default_factory=LoadParams)


# ---------------------------------------------------------------------------
# The mesh law (a Python transcription of what the FMU integrates)
# ---------------------------------------------------------------------------


class MeshLaw:
    """Gear-mesh force law, built from the ``fmu-build inspect --json`` dump.

    K(s), Kc(s): drive / coast flank stiffness, periodic piecewise-linear in
    the roll distance s = (r_b1·θ1 + roll_offset) mod p_b.  The contact force
    acts along the line of action; the gradient term G = ½·K'(s)·δ² makes the
    force derive from the potential V = ½·K(s)·δ².
    """

    def __init__(self, mesh: dict):
        self.base_radius_1_m = float(mesh["base_radius_1_m"])
        self.base_radius_2_m = float(mesh["base_radius_2_m"])
        self.teeth_1 = int(mesh["teeth_1"])
        self.teeth_2 = int(mesh["teeth_2"])
        self.inertia_1_kgm2 = float(mesh["inertia_1_kgm2"])
        self.inertia_2_kgm2 = float(mesh["inertia_2_kgm2"])
        self.base_pitch_m = float(mesh["base_pitch_m"])
        self.backlash_m = float(mesh["backlash_m"])
        self.damping_n_s_per_m = float(mesh["mesh_damping_n_s_per_m"])
        self.roll_offset_m = float(mesh["roll_offset_m"])
        self.natural_frequency_hz = float(mesh["mesh_natural_frequency_hz"])
        roll = [float(x) for x in mesh["roll_m"]]
        drive = [float(x) for x in mesh["drive_stiffness_n_per_m"]]
        coast = [float(x) for x in mesh["coast_stiffness_n_per_m"]]
        if not (len(roll) == len(drive) == len(coast) and len(roll) >= 2):
            raise ValueError("mesh tables must have equal length >= 2")
        n = len(roll)
        # Segment i runs from roll[i] to roll[i+1]; the last one wraps to roll[0] + p_b.
        ends = roll[1:] + [roll[0] + self.base_pitch_m]
        self.roll_m = roll
        self.drive_stiffness_n_per_m = drive
        self.coast_stiffness_n_per_m = coast
        self._drive_slope = [(drive[(i + 1) % n] - drive[i]) / (ends[i] - roll[i]) for i in range(n)]
        self._coast_slope = [(coast[(i + 1) % n] - coast[i]) / (ends[i] - roll[i]) for i in range(n)]
        self._segment_length_m = self.base_pitch_m / n

    @classmethod
    def from_json(cls, mesh_json: str | Path | dict) -> "MeshLaw":
        if isinstance(mesh_json, dict):
            return cls(mesh_json)
        return cls(json.loads(Path(mesh_json).read_text()))

    @property
    def ratio_z1_over_z2(self) -> float:
        return self.teeth_1 / self.teeth_2

    def roll_position_m(self, phi_1_rad: float) -> float:
        return (self.base_radius_1_m * phi_1_rad + self.roll_offset_m) % self.base_pitch_m

    def _segment(self, s_m: float) -> int:
        n = len(self.roll_m)
        i = min(int(s_m / self._segment_length_m), n - 1)
        # Guard against rounding at the segment boundaries.
        while i > 0 and s_m < self.roll_m[i]:
            i -= 1
        while i < n - 1 and s_m >= self.roll_m[i + 1]:
            i += 1
        return i

    def stiffness(self, phi_1_rad: float) -> tuple[float, float, float, float]:
        """(K, K', Kc, Kc') at the roll position of gear 1."""
        s = self.roll_position_m(phi_1_rad)
        i = self._segment(s)
        ds = s - self.roll_m[i]
        k_drive = self.drive_stiffness_n_per_m[i] + self._drive_slope[i] * ds
        k_coast = self.coast_stiffness_n_per_m[i] + self._coast_slope[i] * ds
        return k_drive, self._drive_slope[i], k_coast, self._coast_slope[i]

    def force_n(self, phi_1, w_1, phi_2, w_2) -> tuple[float, float]:
        """(F, G): normal mesh force and potential-gradient term, both in N."""
        dte_m = self.base_radius_1_m * phi_1 - self.base_radius_2_m * phi_2
        dte_rate_m_s = self.base_radius_1_m * w_1 - self.base_radius_2_m * w_2
        c = self.damping_n_s_per_m
        j = self.backlash_m
        if dte_m > 0.0:
            k, dk, _, _ = self.stiffness(phi_1)
            return max(k * dte_m + c * dte_rate_m_s, 0.0), 0.5 * dk * dte_m * dte_m
        if dte_m < -j:
            _, _, kc, dkc = self.stiffness(phi_1)
            pen = dte_m + j
            return min(kc * pen + c * dte_rate_m_s, 0.0), 0.5 * dkc * pen * pen
        return 0.0, 0.0

    def gear_accelerations(self, phi_1, w_1, phi_2, w_2, tau_1_nm, tau_2_nm,
                           inertia_1_kgm2=None, inertia_2_kgm2=None) -> tuple[float, float, float]:
        """(dw_1/dt, dw_2/dt, F) of the two gears under shaft torques tau_1, tau_2."""
        j1 = self.inertia_1_kgm2 if inertia_1_kgm2 is None else inertia_1_kgm2
        j2 = self.inertia_2_kgm2 if inertia_2_kgm2 is None else inertia_2_kgm2
        force, gradient = self.force_n(phi_1, w_1, phi_2, w_2)
        dw_1 = (tau_1_nm - self.base_radius_1_m * (force + gradient)) / j1
        dw_2 = (tau_2_nm + self.base_radius_2_m * force) / j2
        return dw_1, dw_2, force


# ---------------------------------------------------------------------------
# Master-side dynamics (motor and load), shared by both solvers
# ---------------------------------------------------------------------------


def shaft_torques_nm(params: DrivetrainParams, theta_m, w_m, phi_1, w_1, phi_2, w_2, theta_L, w_L):
    """(shaft 1 torque on gear 1 = tau_1, shaft 2 twist torque; tau_2 = −that)."""
    shaft_1 = params.shaft_1.torque_nm(theta_m - phi_1, w_m - w_1)
    shaft_2 = params.shaft_2.torque_nm(phi_2 - theta_L, w_2 - w_L)
    return shaft_1, shaft_2


def motor_and_load_accelerations(params: DrivetrainParams, t_s, shaft_1_nm, shaft_2_nm, w_L):
    dw_m = (params.motor.torque_nm(t_s) - shaft_1_nm) / params.motor.inertia_kgm2
    dw_L = (shaft_2_nm - params.load.torque_nm(w_L)) / params.load.inertia_kgm2
    return dw_m, dw_L


# ---------------------------------------------------------------------------
# Co-simulation master
# ---------------------------------------------------------------------------

GEAR_OUTPUTS = ("phi_1", "w_1", "phi_2", "w_2", "dte", "mesh_force", "mesh_stiffness")


class FmuGearPair:
    """The gear-pair FMU seen through ``fmpy.fmi2.FMU2Slave``: torques in, gear states out."""

    def __init__(self, fmu_path, t_end: float, fmu_parameters: dict | None = None,
                 instance_name: str = "gear_pair"):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        model = read_model_description(str(fmu_path))
        self.value_refs = {v.name: v.valueReference for v in model.modelVariables}
        self._unzip_dir = extract(str(fmu_path))
        self.fmu = FMU2Slave(guid=model.guid, unzipDirectory=str(self._unzip_dir),
                             modelIdentifier=model.coSimulation.modelIdentifier,
                             instanceName=instance_name)
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0, stopTime=t_end)
        self.fmu.enterInitializationMode()
        for name, value in (fmu_parameters or {}).items():
            self.fmu.setReal([self.value_refs[name]], [float(value)])
        self.fmu.exitInitializationMode()
        self._output_refs = [self.value_refs[name] for name in GEAR_OUTPUTS]
        self._input_refs = [self.value_refs["tau_1"], self.value_refs["tau_2"]]

    def outputs(self) -> dict:
        return dict(zip(GEAR_OUTPUTS, self.fmu.getReal(self._output_refs)))

    def do_step(self, t_s: float, step_s: float, tau_1_nm: float, tau_2_nm: float) -> None:
        self.fmu.setReal(self._input_refs, [tau_1_nm, tau_2_nm])
        self.fmu.doStep(currentCommunicationPoint=t_s, communicationStepSize=step_s)

    def close(self) -> None:
        try:
            self.fmu.terminate()
        finally:
            self.fmu.freeInstance()
            shutil.rmtree(self._unzip_dir, ignore_errors=True)


def run_master(gear_pair, params: DrivetrainParams, t_end: float, comm_step: float) -> dict:
    """Explicit Jacobi co-simulation loop around any object with
    ``outputs() -> dict`` and ``do_step(t, H, tau_1, tau_2)`` (see :class:`FmuGearPair`)."""
    n_steps = int(round(t_end / comm_step))
    if n_steps < 1 or abs(n_steps * comm_step - t_end) > 1e-9 * max(1.0, t_end):
        raise ValueError("t_end must be a whole number of communication steps")

    keys = ("time_s", "motor_angle_rad", "motor_speed_rad_s", "load_angle_rad", "load_speed_rad_s",
            "phi_1_rad", "w_1_rad_s", "phi_2_rad", "w_2_rad_s", "shaft_1_torque_nm",
            "shaft_2_torque_nm", "dte_m", "mesh_force_n", "mesh_stiffness_n_per_m")
    record = {key: np.empty(n_steps + 1) for key in keys}

    # Master states: motor and load angle/speed.  The drivetrain starts at rest, unstrained.
    theta_m = w_m = theta_L = w_L = 0.0
    h = comm_step
    for n in range(n_steps + 1):
        t = n * h  # not accumulated, so communication points stay exact multiples of H
        gear = gear_pair.outputs()
        phi_1, w_1, phi_2, w_2 = gear["phi_1"], gear["w_1"], gear["phi_2"], gear["w_2"]
        shaft_1, shaft_2 = shaft_torques_nm(params, theta_m, w_m, phi_1, w_1, phi_2, w_2, theta_L, w_L)

        row = (t, theta_m, w_m, theta_L, w_L, phi_1, w_1, phi_2, w_2, shaft_1, shaft_2,
               gear["dte"], gear["mesh_force"], gear["mesh_stiffness"])
        for key, value in zip(keys, row):
            record[key][n] = value
        if n == n_steps:
            break

        # The FMU advances the gears with the shaft torques held over the step ...
        gear_pair.do_step(t, h, shaft_1, -shaft_2)

        # ... while the master advances motor and load (one classical RK4 step),
        # seeing the gears at their held speeds.
        def rhs(tau, state):
            th_m, om_m, th_L, om_L = state
            s1, s2 = shaft_torques_nm(params, th_m, om_m, phi_1 + w_1 * tau, w_1,
                                      phi_2 + w_2 * tau, w_2, th_L, om_L)
            dw_m, dw_L = motor_and_load_accelerations(params, t + tau, s1, s2, om_L)
            return (om_m, dw_m, om_L, dw_L)

        y0 = (theta_m, w_m, theta_L, w_L)
        k1 = rhs(0.0, y0)
        k2 = rhs(0.5 * h, tuple(y + 0.5 * h * k for y, k in zip(y0, k1)))
        k3 = rhs(0.5 * h, tuple(y + 0.5 * h * k for y, k in zip(y0, k2)))
        k4 = rhs(h, tuple(y + h * k for y, k in zip(y0, k3)))
        theta_m, w_m, theta_L, w_L = (y + h / 6.0 * (a + 2.0 * b + 2.0 * c + d)
                                      for y, a, b, c, d in zip(y0, k1, k2, k3, k4))
    return record


def cosimulate(fmu_path, params: DrivetrainParams, t_end: float, comm_step: float,
               fmu_parameters: dict | None = None) -> dict:
    """Co-simulate the drivetrain with the gear-pair FMU at a fixed communication step.

    Returns a dict of numpy arrays sampled at the communication points
    t_n = n·comm_step, n = 0..N (N = t_end/comm_step, which must be whole).
    ``fmu_parameters`` optionally sets FMU parameters (e.g. ``{"max_step": 5e-6}``).
    """
    gear_pair = FmuGearPair(fmu_path, t_end, fmu_parameters)
    try:
        return run_master(gear_pair, params, t_end, comm_step)
    finally:
        gear_pair.close()


# ---------------------------------------------------------------------------
# Monolithic reference
# ---------------------------------------------------------------------------


def monolithic_reference(mesh_json, params: DrivetrainParams, t_end: float,
                         sample_times=None, rtol: float = 1e-10, atol: float = 1e-13) -> dict:
    """Solve drivetrain + mesh law as one ODE with scipy's DOP853.

    ``mesh_json``: path to (or dict of) the ``fmu-build inspect --json`` dump.
    ``sample_times``: where to sample the dense solution (default: 2001 points).
    The step is bounded by 1/40 of the mesh natural period; the kinks of the
    stiffness tables and the contact on/off switching are left to the
    (tight) error control.
    """
    from scipy.integrate import solve_ivp

    mesh = MeshLaw.from_json(mesh_json)
    if sample_times is None:
        sample_times = np.linspace(0.0, t_end, 2001)
    sample_times = np.asarray(sample_times, dtype=float)

    def rhs(t, y):
        theta_m, w_m, phi_1, w_1, phi_2, w_2, theta_L, w_L = y
        shaft_1, shaft_2 = shaft_torques_nm(params, theta_m, w_m, phi_1, w_1, phi_2, w_2, theta_L, w_L)
        dw_1, dw_2, _ = mesh.gear_accelerations(phi_1, w_1, phi_2, w_2, shaft_1, -shaft_2)
        dw_m, dw_L = motor_and_load_accelerations(params, t, shaft_1, shaft_2, w_L)
        return [w_m, dw_m, w_1, dw_1, w_2, dw_2, w_L, dw_L]

    max_step_s = 1.0 / (40.0 * mesh.natural_frequency_hz)
    sol = solve_ivp(rhs, (0.0, t_end), np.zeros(8), method="DOP853", t_eval=sample_times,
                    rtol=rtol, atol=atol, max_step=max_step_s)
    if not sol.success:
        raise RuntimeError(f"monolithic reference failed: {sol.message}")
    theta_m, w_m, phi_1, w_1, phi_2, w_2, theta_L, w_L = sol.y

    shaft_1 = params.shaft_1.stiffness_nm_per_rad * (theta_m - phi_1) + params.shaft_1.damping_nms_per_rad * (w_m - w_1)
    shaft_2 = params.shaft_2.stiffness_nm_per_rad * (phi_2 - theta_L) + params.shaft_2.damping_nms_per_rad * (w_2 - w_L)
    mesh_force = np.array([mesh.force_n(*x)[0] for x in zip(phi_1, w_1, phi_2, w_2)])
    return {
        "time_s": sol.t, "motor_angle_rad": theta_m, "motor_speed_rad_s": w_m,
        "load_angle_rad": theta_L, "load_speed_rad_s": w_L,
        "phi_1_rad": phi_1, "w_1_rad_s": w_1, "phi_2_rad": phi_2, "w_2_rad_s": w_2,
        "shaft_1_torque_nm": shaft_1, "shaft_2_torque_nm": shaft_2,
        "dte_m": mesh.base_radius_1_m * phi_1 - mesh.base_radius_2_m * phi_2,
        "mesh_force_n": mesh_force, "n_rhs_evaluations": sol.nfev,
    }


# ---------------------------------------------------------------------------
# Demo
# ---------------------------------------------------------------------------


def plot(result: dict, png_path, reference: dict | None = None, title: str = "") -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t_ms = result["time_s"] * 1e3
    fig, (ax_speed, ax_torque, ax_dte) = plt.subplots(3, 1, sharex=True, figsize=(9, 9))
    ax_speed.plot(t_ms, result["motor_speed_rad_s"], label="motor")
    ax_speed.plot(t_ms, result["w_1_rad_s"], label="gear 1")
    ax_speed.plot(t_ms, result["w_2_rad_s"], label="gear 2")
    ax_speed.plot(t_ms, result["load_speed_rad_s"], label="load")
    ax_speed.set_ylabel("speed (rad/s)")
    ax_torque.plot(t_ms, result["shaft_1_torque_nm"], label="shaft 1 (= tau_1)")
    ax_torque.plot(t_ms, result["shaft_2_torque_nm"], label="shaft 2 (= −tau_2)")
    ax_torque.set_ylabel("shaft torque (N·m)")
    ax_dte.plot(t_ms, result["dte_m"] * 1e6, label="co-simulation", lw=0.8)
    if reference is not None:
        ref_ms = reference["time_s"] * 1e3
        ax_speed.plot(ref_ms, reference["w_2_rad_s"], "k--", lw=0.8, label="gear 2, monolithic")
        ax_dte.plot(ref_ms, reference["dte_m"] * 1e6, "k--", lw=0.8, label="monolithic")
    ax_dte.set_ylabel("DTE (µm)")
    ax_dte.set_xlabel("time (ms)")
    for ax in (ax_speed, ax_torque, ax_dte):
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize="small")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(png_path, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--fmu", type=Path, default=DEFAULT_FMU, help="gear-pair FMU (default: %(default)s)")
    parser.add_argument("--t-end", type=float, default=0.05, help="end time in s (default: %(default)s)")
    parser.add_argument("--comm-step", type=float, default=5e-5, help="communication step in s (default: %(default)s)")
    parser.add_argument("--load", choices=("viscous", "quadratic"), default="viscous")
    parser.add_argument("--mesh-json", type=Path, default=None,
                        help="fmu-build inspect --json dump; if given, overlay the monolithic reference")
    parser.add_argument("--png", type=Path, default=Path("drivetrain.png"), help="output plot (default: %(default)s)")
    args = parser.parse_args(argv)

    params = DrivetrainParams(load=LoadParams(kind=args.load))
    result = cosimulate(args.fmu, params, args.t_end, args.comm_step)
    reference = None
    if args.mesh_json is not None:
        reference = monolithic_reference(args.mesh_json, params, args.t_end, sample_times=result["time_s"])
        err = np.max(np.abs(result["w_2_rad_s"] - reference["w_2_rad_s"]))
        print(f"max |w_2 co-sim − w_2 monolithic| = {err:.3e} rad/s")
    plot(result, args.png, reference, title=f"{args.fmu.name}, H = {args.comm_step:g} s")
    print(f"final speeds: motor {result['motor_speed_rad_s'][-1]:.3f}, gear 1 {result['w_1_rad_s'][-1]:.3f}, "
          f"gear 2 {result['w_2_rad_s'][-1]:.3f}, load {result['load_speed_rad_s'][-1]:.3f} rad/s")
    print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
