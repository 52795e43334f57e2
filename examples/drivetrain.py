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
import bisect
import json
import math
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

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


class MeshForce(NamedTuple):
    """The force law of one flank evaluated at one (δ, ξ) (zeros when the flank is open)."""

    force_n: float             # elastic mesh force F (N), ≥ 0
    stiffness_n_per_m: float   # tangent stiffness ∂F/∂δ (N/m)
    potential_j: float         # elastic energy V(δ, ξ) = ∫₀^δ F dδ′ (J)
    roll_force_n: float        # generalized force on the roll coordinate, −∂V/∂ξ (N)


class MeshState(NamedTuple):
    """The mesh at one state of the two gears."""

    force_n: float             # contact force along the line of action incl. damping (N); > 0 drive, < 0 coast
    roll_force_n: float        # −∂V/∂ξ of the flank in contact (N); 0 when no flank touches
    stiffness_n_per_m: float   # tangent stiffness of the flank in contact (N/m); 0 when none
    potential_j: float         # elastic energy of the flank in contact (J)
    elastic_force_n: float     # the undamped part of force_n (N)


class FlankLaw:
    """Load-dependent force law F(δ, ξ) of one flank, from a table of static deflections.

    Row i holds, at roll ξ_i = i·p_b/N, the static deflection δ_k(ξ_i) under the mesh force
    F_k (k = 0…K, F_0 = 0, δ_0 = 0).  Rows are interpolated linearly in ξ; along a row F(δ)
    is piecewise linear and its last segment extends beyond δ_K.  The potential is
    V = F·δ − W*(F, ξ) with the complementary energy W* = ∫₀^F δ dF′, exact (trapezoids) for
    the piecewise-linear rows, and the roll force −∂V/∂ξ = ∂W*/∂ξ at fixed F.  A line-by-line
    transcription of ``MeshLaw::evaluate`` in src/dynamics/mesh_law.rs (same operation order).
    """

    def __init__(self, base_pitch_m: float, force_levels_n, deflection_rows_m):
        self.base_pitch_m = float(base_pitch_m)
        self.force_levels_n = [float(f) for f in force_levels_n]
        self.rows = [[float(d) for d in row] for row in deflection_rows_m]
        f = self.force_levels_n
        levels = len(f)
        if levels < 2 or f[0] != 0.0 or any(b <= a for a, b in zip(f, f[1:])):
            raise ValueError("force levels must start at 0 and increase strictly")
        if len(self.rows) < 2 or any(len(row) != levels for row in self.rows):
            raise ValueError("need >= 2 deflection rows of one value per force level")
        self.energy_rows = []
        for row in self.rows:
            w = [0.0] * levels
            for k in range(1, levels):
                w[k] = w[k - 1] + 0.5 * (row[k - 1] + row[k]) * (f[k] - f[k - 1])
            self.energy_rows.append(w)

    def _interval(self, roll_m: float) -> tuple[int, int, float, float]:
        n = len(self.rows)
        dx = self.base_pitch_m / n
        pos = (roll_m % self.base_pitch_m) / dx      # Python's float % is Rust's rem_euclid here
        i = min(math.floor(pos), n - 1)
        return i, (i + 1) % n, pos - i, dx

    def evaluate(self, delta_m: float, roll_m: float) -> MeshForce:
        if delta_m <= 0.0:
            return MeshForce(0.0, 0.0, 0.0, 0.0)
        i, j, t, dx = self._interval(roll_m)
        a, b = self.rows[i], self.rows[j]
        f = self.force_levels_n
        last = len(f) - 1
        lo, hi = 0, last
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if (1.0 - t) * a[mid] + t * b[mid] <= delta_m:
                lo = mid
            else:
                hi = mid
        m = min(lo, last - 1)
        d0 = (1.0 - t) * a[m] + t * b[m]
        d1 = (1.0 - t) * a[m + 1] + t * b[m + 1]
        s = (delta_m - d0) / (d1 - d0)
        force = f[m] + s * (f[m + 1] - f[m])

        def w_row(row, w):
            d_at_force = row[m] + s * (row[m + 1] - row[m])
            return w[m] + 0.5 * (row[m] + d_at_force) * (force - f[m])

        wa, wb = w_row(a, self.energy_rows[i]), w_row(b, self.energy_rows[j])
        w_star = (1.0 - t) * wa + t * wb
        return MeshForce(force, (f[m + 1] - f[m]) / (d1 - d0), force * delta_m - w_star, (wb - wa) / dx)

    def static_deflection_m(self, force_n: float, roll_m: float) -> float:
        """δ(F, ξ): the static mesh deflection under the force F (extrapolated beyond F_K)."""
        i, j, t, _ = self._interval(roll_m)
        f = self.force_levels_n
        m = min(max(bisect.bisect_right(f, force_n), 1), len(f) - 1) - 1
        s = (force_n - f[m]) / (f[m + 1] - f[m])
        a, b = self.rows[i], self.rows[j]
        return (1.0 - t) * (a[m] + s * (a[m + 1] - a[m])) + t * (b[m] + s * (b[m + 1] - b[m]))

    def mean_static_deflection_m(self, force_n: float) -> float:
        """Mean over one base pitch of δ(F, ξ) (the rows are a uniform periodic grid)."""
        n = len(self.rows)
        return sum(self.static_deflection_m(force_n, i * self.base_pitch_m / n) for i in range(n)) / n

    def mean_tangent_stiffness_n_per_m(self, force_n: float) -> float:
        """Mean over ξ (mid-interval samples) of ∂F/∂δ at the static deflection under F."""
        n = len(self.rows)
        dx = self.base_pitch_m / n
        return sum(self.evaluate(self.static_deflection_m(force_n, (i + 0.5) * dx), (i + 0.5) * dx)
                   .stiffness_n_per_m for i in range(n)) / n


class MeshLaw:
    """Gear-mesh force law, built from the ``fmu-build inspect --json`` dump.

    Drive flank (δ > 0) and coast flank (δ < −j) each follow a load-dependent law
    F(δ, ξ) (:class:`FlankLaw`), ξ = r_b1·θ1 + roll_offset the roll position, periodic
    in p_b.  The coast law is written for the positive closure −(δ + j) and pushes back.
    Damping c·δ̇ acts only while a flank touches, and a flank never pulls.  Besides the
    mesh force F = ∂V/∂δ the mesh exerts the roll force R = −∂V/∂ξ on gear 1, so the
    undamped law conserves E = kinetic + V − work of the torques:

        J1·dw_1/dt = τ1 − r_b1·F + r_b1·R,      J2·dw_2/dt = τ2 + r_b2·F.

    For a linear table δ_k = F_k/K(ξ) this is the old law F = K·δ, R = −½K′δ².
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
        self.reference_force_n = float(mesh["reference_force_n"])
        self.reference_stiffness_n_per_m = float(mesh["reference_stiffness_n_per_m"])
        self.roll_m = [float(x) for x in mesh["roll_m"]]
        self.force_levels_n = [float(x) for x in mesh["force_levels_n"]]
        self.drive = FlankLaw(self.base_pitch_m, self.force_levels_n, mesh["drive_deflection_m"])
        self.coast = FlankLaw(self.base_pitch_m, self.force_levels_n, mesh["coast_deflection_m"])
        n = len(self.roll_m)
        if not (len(self.drive.rows) == len(self.coast.rows) == n):
            raise ValueError("roll_m and the deflection tables must have the same number of rows")
        for i, s in enumerate(self.roll_m):
            if abs(s - i * self.base_pitch_m / n) > 1e-12 * self.base_pitch_m:
                raise ValueError("roll_m must be the uniform grid i·p_b/N")

    @classmethod
    def from_json(cls, mesh_json: str | Path | dict) -> "MeshLaw":
        if isinstance(mesh_json, dict):
            return cls(mesh_json)
        return cls(json.loads(Path(mesh_json).read_text()))

    @property
    def ratio_z1_over_z2(self) -> float:
        return self.teeth_1 / self.teeth_2

    def roll_position_m(self, phi_1_rad: float) -> float:
        """Roll position ξ = (r_b1·φ1 + roll_offset) mod p_b."""
        return (self.base_radius_1_m * phi_1_rad + self.roll_offset_m) % self.base_pitch_m

    def mesh_state(self, phi_1, w_1, phi_2, w_2, damping_n_s_per_m=None) -> MeshState:
        """The mesh (force, roll force, stiffness, potential) at a state of the gears."""
        delta = self.base_radius_1_m * phi_1 - self.base_radius_2_m * phi_2
        delta_dot = self.base_radius_1_m * w_1 - self.base_radius_2_m * w_2
        xi = self.base_radius_1_m * phi_1 + self.roll_offset_m
        c = self.damping_n_s_per_m if damping_n_s_per_m is None else damping_n_s_per_m
        if delta > 0.0:
            law = self.drive.evaluate(delta, xi)
            return MeshState(max(law.force_n + c * delta_dot, 0.0), law.roll_force_n,
                             law.stiffness_n_per_m, law.potential_j, law.force_n)
        if delta < -self.backlash_m:
            law = self.coast.evaluate(-(delta + self.backlash_m), xi)
            return MeshState(min(-law.force_n + c * delta_dot, 0.0), law.roll_force_n,
                             law.stiffness_n_per_m, law.potential_j, -law.force_n)
        return MeshState(0.0, 0.0, 0.0, 0.0, 0.0)

    def force_n(self, phi_1, w_1, phi_2, w_2) -> float:
        """Normal mesh force F (N) including damping; > 0 on the drive flank, < 0 on the coast flank."""
        return self.mesh_state(phi_1, w_1, phi_2, w_2).force_n

    def potential_j(self, phi_1, phi_2) -> float:
        """Elastic energy V of the mesh (J) at the gear angles."""
        return self.mesh_state(phi_1, 0.0, phi_2, 0.0, damping_n_s_per_m=0.0).potential_j

    def gear_accelerations(self, phi_1, w_1, phi_2, w_2, tau_1_nm, tau_2_nm,
                           inertia_1_kgm2=None, inertia_2_kgm2=None,
                           include_roll_force=True) -> tuple[float, float, float]:
        """(dw_1/dt, dw_2/dt, F) of the two gears under shaft torques tau_1, tau_2.

        ``include_roll_force=False`` drops R (a negative control for energy checks only).
        """
        j1 = self.inertia_1_kgm2 if inertia_1_kgm2 is None else inertia_1_kgm2
        j2 = self.inertia_2_kgm2 if inertia_2_kgm2 is None else inertia_2_kgm2
        mesh = self.mesh_state(phi_1, w_1, phi_2, w_2)
        roll = mesh.roll_force_n if include_roll_force else 0.0
        # Same operation order as LumpedModel::derivative.
        dw_1 = (tau_1_nm - self.base_radius_1_m * mesh.force_n + self.base_radius_1_m * roll) / j1
        dw_2 = (tau_2_nm + self.base_radius_2_m * mesh.force_n) / j2
        return dw_1, dw_2, mesh.force_n


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
# The SSP system's coupling, its elements written out here
# ---------------------------------------------------------------------------


def substep_count(duration_s: float, max_step_s: float) -> int:
    """⌈duration / max_step⌉, a quotient within 1e-9 of a whole number taken as that number
    (the FMUs' rule, src/dynamics/mod.rs)."""
    quotient = duration_s / max_step_s
    nearest = round(quotient)
    n = nearest if abs(quotient - nearest) <= 1e-9 * nearest else math.ceil(quotient)
    return max(int(n), 1)


def _rk4_body(phi, w, t0, h, max_step, accel):
    """Classical RK4 on (φ, ω), ω̇ = accel(t, ω), over h in equal sub-steps ≤ max_step."""
    n = substep_count(h, max_step)
    dt = h / n
    for k in range(n):
        t = t0 + k * dt
        k1p, k1w = w, accel(t, w)
        k2p, k2w = w + 0.5 * dt * k1w, accel(t + 0.5 * dt, w + 0.5 * dt * k1w)
        k3p, k3w = w + 0.5 * dt * k2w, accel(t + 0.5 * dt, w + 0.5 * dt * k2w)
        k4p, k4w = w + dt * k3w, accel(t + dt, w + dt * k3w)
        phi, w = phi + dt / 6.0 * (k1p + 2.0 * k2p + 2.0 * k3p + k4p), w + dt / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w)
    return phi, w


def element_cosimulation(fmu_path, params: DrivetrainParams, t_end: float, comm_step: float,
                         max_step: float = 5e-5) -> dict:
    """The drivetrain as the SSP system couples it (``fmu-build ssp``), with the motor, the load
    and the two shafts written out here and only the gear pair an FMU.

    Jacobi coupling, as libcosim and fmpy.ssp run the file: every component steps over
    [t_n, t_n + H] from the values its inputs got at the end of the last step (all zero at the
    start), then every output is passed on. A shaft is massless (MSL SpringDamper): its torques
    are read from its inputs, so a torque reaches a body one step after the angles it is made
    of. The bodies integrate J·ω̇ = Σ τ in RK4 sub-steps ≤ ``max_step``, the motor's ramp on the
    time since the start. Speeds are returned after every step, keyed component.variable.
    """
    motor, load = params.motor, params.load
    steps = int(round(t_end / comm_step))
    gear_pair = FmuGearPair(fmu_path, t_end)
    # The connectors (component.variable → value), all zero at the start.
    c = {k: 0.0 for k in ("motor.phi", "motor.w", "load.phi", "load.w", "shaft_1.tau_a", "shaft_1.tau_b",
                          "shaft_2.tau_a", "shaft_2.tau_b", "gear_pair.phi_1", "gear_pair.w_1",
                          "gear_pair.phi_2", "gear_pair.w_2", "gear_pair.dte")}
    keys = ("motor.w", "gear_pair.w_1", "gear_pair.w_2", "load.w", "gear_pair.dte")
    record = {k: np.empty(steps) for k in keys}
    m_phi = m_w = l_phi = l_w = 0.0
    try:
        for n in range(steps):
            t = n * comm_step
            # Each component from its inputs (the connections' values at t_n).
            tau_motor, tau_load = c["shaft_1.tau_a"], c["shaft_2.tau_b"]
            m_phi, m_w = _rk4_body(m_phi, m_w, t, comm_step, max_step,
                                   lambda tt, w: (tau_motor + motor.torque_nm(tt)) / motor.inertia_kgm2)
            l_phi, l_w = _rk4_body(l_phi, l_w, t, comm_step, max_step,
                                   lambda tt, w: (tau_load - load.torque_nm(w)) / load.inertia_kgm2)
            s1 = params.shaft_1.torque_nm(c["gear_pair.phi_1"] - c["motor.phi"], c["gear_pair.w_1"] - c["motor.w"])
            s2 = params.shaft_2.torque_nm(c["load.phi"] - c["gear_pair.phi_2"], c["load.w"] - c["gear_pair.w_2"])
            gear_pair.do_step(t, comm_step, c["shaft_1.tau_b"], c["shaft_2.tau_a"])
            gear = gear_pair.outputs()
            # Every output passed on.
            c.update({"motor.phi": m_phi, "motor.w": m_w, "load.phi": l_phi, "load.w": l_w,
                      "shaft_1.tau_a": s1, "shaft_1.tau_b": -s1, "shaft_2.tau_a": s2, "shaft_2.tau_b": -s2,
                      **{f"gear_pair.{k}": gear[k] for k in ("phi_1", "w_1", "phi_2", "w_2", "dte")}})
            for k in keys:
                record[k][n] = c[k]
    finally:
        gear_pair.close()
    return {"t": comm_step * np.arange(1, steps + 1), **record}


# ---------------------------------------------------------------------------
# Monolithic reference
# ---------------------------------------------------------------------------


def monolithic_reference(mesh_json, params: DrivetrainParams, t_end: float,
                         sample_times=None, rtol: float = 1e-10, atol: float = 1e-13) -> dict:
    """Solve drivetrain + mesh law as one ODE with scipy's DOP853.

    ``mesh_json``: path to (or dict of) the ``fmu-build inspect --json`` dump.
    ``sample_times``: where to sample the dense solution (default: 2001 points).
    The step is bounded by 1/40 of the mesh natural period (at the dump's
    reference force; the load-dependent stiffness varies by a few % over the
    tabulated loads); the kinks of the deflection tables and the contact
    on/off switching are left to the (tight) error control.
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
    mesh_force = np.array([mesh.force_n(*x) for x in zip(phi_1, w_1, phi_2, w_2)])
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
