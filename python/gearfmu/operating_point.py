"""One operating point of the gear-pair FMU, driven to its dynamic steady state and measured.

The set-up is the seed's example 3 with the load sized for the target speed:

* gear 1 carries a constant driving torque T₁;
* gear 2 carries a viscous load τ₂ = −c·ω₂ with c = T₁·(z₂/z₁)/ω₂*, so that at the target speeds
  ω₁* and ω₂* = ω₁*·z₁/z₂ the load balances the drive exactly (T₁/r_b1 = c·ω₂*/r_b2);
* both gears *start* at the target speeds (parameters ``w_1_start``, ``w_2_start``).

Why this start: the rigid-body mode of the pair sees only the external torques, and those are
balanced from t = 0, so the mean speed is right from the first step and only the mesh transient
(the loading of the teeth from zero deflection) has to decay — with time constant 1/(ζ·ω_n), about
1 ms at the default 5 % mesh damping. Example 3 as published starts from rest; its speed then
approaches the target with the rigid-body time constant J_eq/c (tens of ms at 9000 rpm, seconds at
low speed), and a sweep would spend almost all its time there. BENCHMARKS.md ("Sweeps") has the
measurement. The viscous load (rather than a constant load torque) keeps the rigid-body mode
stable: a speed error decays instead of persisting.

The load is coupled explicitly, as a 1-D master would: τ₂ for a communication step uses ω₂ at
the step's start. An explicit damper is stable for c·h/J₂ < 2; the step is kept below J₂/c.

The record: after the transient, consecutive windows of a whole number of mesh cycles are
sampled at a fixed number of samples per mesh period (mesh frequency f_m = z₁·n₁/60). The point
is steady when two consecutive windows agree (DTE RMS and peak-to-peak, maximum mesh force) to a
relative tolerance; the last window is measured. A point that does not settle within the time
limit (a sub-harmonic or chaotic response beyond contact loss) is measured all the same and says
so (``settled`` = 0, ``steady_change`` = the last relative change).
"""

from __future__ import annotations

import ctypes
import math
import re
import time
from dataclasses import dataclass, field

import numpy as np

MESH_ORDERS = (1, 2, 3)


@dataclass(frozen=True)
class Recording:
    """How each point is driven and sampled."""

    samples_per_mesh_period: int = 64   # ≥ 20 per period of mesh order 3
    cycles_per_window: int = 10         # mesh cycles per window; the DFT runs over one window
    settle_s: float = 0.01              # simulated before the first window: ≈ 10/(ζ·ω_n) at ζ = 5 %
    steady_tolerance: float = 1e-3      # relative change between consecutive windows
    max_record_s: float = 0.05          # simulated time after which a point is measured regardless
    max_communication_step_s: float = 2e-5   # ≤ 1/16 of the mesh-mode period (3.2 kHz here): the
                                             # load torque held over a step lags by h/2

    def as_attrs(self) -> dict:
        return dict(self.__dict__)


@dataclass(frozen=True)
class PairFacts:
    """What the sweep needs to know about the FMU's gear pair, read from the FMU itself."""

    teeth_1: int
    teeth_2: int
    base_radius_1_m: float
    base_radius_2_m: float
    start_values: dict = field(default_factory=dict)   # parameter start values (inertias, damping, …)
    description: str = ""                               # the modelDescription's, which names the model kind

    @property
    def mesh_stiffness_is_whole_mesh(self) -> bool:
        """The lumped model's ``mesh_stiffness`` is the whole mesh's tangent stiffness; PMOR-Hertz's is
        only its Hertz contacts' (the teeth's bending lives in the elastic coordinates, README)."""
        return "lumped model" in self.description

    @property
    def ratio(self) -> float:
        """ω₂/ω₁ for rigid teeth (= z₁/z₂)."""
        return self.teeth_1 / self.teeth_2


def mesh_frequency_hz(speed_1_rpm: float, teeth_1: int) -> float:
    """f_m = z₁·n₁/60: tooth pairs entering the mesh per second."""
    return teeth_1 * speed_1_rpm / 60.0


def mesh_natural_frequency_hz(mesh_stiffness_n_per_m: float, base_radius_1_m: float, base_radius_2_m: float,
                              inertia_1_kgm2: float, inertia_2_kgm2: float) -> float:
    """The mesh mode of two rigid gears joined by a spring k along the line of action.

    With the DTE δ = r_b1·φ₁ − r_b2·φ₂ as coordinate, J₁φ₁'' = −r_b1·kδ and J₂φ₂'' = +r_b2·kδ give
    δ'' = −k·(r_b1²/J₁ + r_b2²/J₂)·δ, so ω_n² = k·(r_b1²/J₁ + r_b2²/J₂), i.e. k over the
    equivalent mass m_eq = 1/(r_b1²/J₁ + r_b2²/J₂) on the line of action.
    """
    omega_squared = mesh_stiffness_n_per_m * (base_radius_1_m**2 / inertia_1_kgm2
                                              + base_radius_2_m**2 / inertia_2_kgm2)
    return math.sqrt(omega_squared) / (2.0 * math.pi)


def teeth_from_description(description: str) -> tuple[int, int]:
    """fmu-build writes "Gear pair NAME (z Z1/Z2), …" into the modelDescription."""
    match = re.search(r"\(z (\d+)/(\d+)\)", description or "")
    if match is None:
        raise ValueError(f"no '(z Z1/Z2)' in the FMU's description {description!r}; pass the teeth explicitly")
    return int(match.group(1)), int(match.group(2))


class FmuLog:
    """Collects what the FMU logs (fmi2Error messages name the cause of a failed step).

    The FMU logs through a C-variadic callback with format "%s"; ctypes cannot receive varargs,
    so fmpy's ``addLoggerProxy`` puts a C function in front that formats the text first.
    """

    def __init__(self):
        from fmpy import calloc, free
        from fmpy.fmi2 import (addLoggerProxy, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

        self.messages: list[str] = []
        self._logger = fmi2CallbackLoggerTYPE(self._log)   # kept alive as long as the callbacks
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = self._logger
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(ctypes.byref(self.callbacks))

    def _log(self, env, instance_name, status, category, message):
        self.messages.append(message.decode("utf-8", "replace") if message else "")

    def take(self) -> str:
        text = " | ".join(self.messages)
        self.messages.clear()
        return text


class GearPairRunner:
    """One FMU instance, reused point after point through fmi2Reset (fmpy's parameter-variation pattern)."""

    SIGNALS = ("dte", "mesh_force", "mesh_stiffness", "w_1", "w_2")

    def __init__(self, fmu_path: str, unzip_dir: str, instance_name: str = "sweep"):
        from fmpy import read_model_description
        from fmpy.fmi2 import FMU2Slave

        model = read_model_description(fmu_path)
        self.vr = {v.name: v.valueReference for v in model.modelVariables}
        self.parameter_names = [v.name for v in model.modelVariables if v.causality == "parameter"]
        # The Real parameters (inertias, damping, …): what a sweep sets; a Boolean's start is
        # "true"/"false".
        start_values = {v.name: float(v.start) for v in model.modelVariables
                        if v.causality == "parameter" and v.type == "Real" and v.start is not None}
        self.log = FmuLog()
        self.fmu = FMU2Slave(guid=model.guid, unzipDirectory=unzip_dir,
                             modelIdentifier=model.coSimulation.modelIdentifier, instanceName=instance_name)
        self.fmu.instantiate(callbacks=self.log.callbacks)
        self._signal_refs = [self.vr[name] for name in self.SIGNALS]
        self._contact_ref = [self.vr["contact_pairs"]]
        self._torque_refs = [self.vr["tau_1"], self.vr["tau_2"]]
        self.pair = self._probe_pair(model.description, start_values)

    def _probe_pair(self, description: str, start_values: dict) -> PairFacts:
        """Teeth from the description; r_b2 = dte/dte_angle (the outputs' definition) at a turned start.

        Gear 1 is turned back (into the backlash, no tooth touching), not forward: forward would press
        the flanks together by r_b1·φ without deformation, which PMOR-Hertz refuses as beyond Hertz.
        """
        z1, z2 = teeth_from_description(description)
        self._initialize({"phi_1_start": -1e-4})
        dte, dte_angle = self.fmu.getReal([self.vr["dte"], self.vr["dte_angle"]])
        self.fmu.reset()
        r_b2 = dte / dte_angle
        # Base radii of a gear pair are in the ratio of the teeth (r_b = m_t·z·cos α_t / 2).
        return PairFacts(z1, z2, r_b2 * z1 / z2, r_b2, start_values, description)

    def _initialize(self, parameters: dict) -> None:
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in parameters.items():
            self.fmu.setReal([self.vr[name]], [float(value)])
        self.fmu.exitInitializationMode()

    def close(self) -> None:
        # After fmi2Reset the instance is back in "instantiated", where fmi2Terminate is not allowed.
        self.fmu.freeInstance()

    def run(self, speed_1_rpm: float, torque_1_nm: float, parameters: dict, recording: Recording) -> dict:
        """Drive one point to steady state and measure it. Never raises for a failed FMU call: the
        result then carries ``error`` (the exception and the FMU's log) and the instance is reset."""
        started = time.perf_counter()
        try:
            result = self._run(speed_1_rpm, torque_1_nm, parameters, recording)
            result["error"] = ""
        except Exception as exc:   # an fmi2Error from doStep, a refused parameter, …: stored, not lost
            log = self.log.take()
            result = {"error": f"{type(exc).__name__}: {exc}" + (f" — FMU log: {log}" if log else "")}
        self.fmu.reset()
        self.log.take()
        result["wall_s"] = time.perf_counter() - started
        return result

    def _run(self, speed_1_rpm: float, torque_1_nm: float, parameters: dict, rec: Recording) -> dict:
        pair = self.pair
        values = {**pair.start_values, **parameters}
        omega_1 = speed_1_rpm * 2.0 * math.pi / 60.0
        omega_2 = omega_1 * pair.ratio
        load_damping = torque_1_nm / pair.ratio / omega_2           # c = T₁·(z₂/z₁)/ω₂*
        self._initialize({**parameters, "w_1_start": omega_1, "w_2_start": omega_2})

        # Communication step: a whole fraction of the mesh period, below J₂/c (explicit damper) and
        # small against the mesh-mode period (the held load torque lags by h/2).
        mesh_period = 1.0 / mesh_frequency_hz(speed_1_rpm, pair.teeth_1)
        per_period = rec.samples_per_mesh_period
        step_bound = rec.max_communication_step_s
        if load_damping > 0.0:
            step_bound = min(step_bound, values["inertia_2"] / load_damping)
        per_period *= max(1, math.ceil(mesh_period / per_period / step_bound))
        step = mesh_period / per_period
        window_steps = per_period * rec.cycles_per_window
        settle_steps = per_period * math.ceil(rec.settle_s / mesh_period)     # whole mesh cycles
        max_windows = max(3, math.ceil(rec.max_record_s / (window_steps * step)))

        signals = np.empty((window_steps, len(self.SIGNALS)))
        contact_pairs = np.empty(window_steps, dtype=np.int64)
        n, w_2, fmu_seconds = 0, omega_2, 0.0

        def advance(steps: int) -> None:
            nonlocal n, w_2, fmu_seconds
            for k in range(steps):
                self.fmu.setReal(self._torque_refs, [torque_1_nm, -load_damping * w_2])
                tick = time.perf_counter()
                # t = n·h exactly, so the FMU's time check never sees accumulated rounding.
                self.fmu.doStep(currentCommunicationPoint=n * step, communicationStepSize=step)
                fmu_seconds += time.perf_counter() - tick
                n += 1
                signals[k % window_steps] = self.fmu.getReal(self._signal_refs)
                contact_pairs[k % window_steps] = self.fmu.getInteger(self._contact_ref)[0]
                w_2 = signals[k % window_steps, 4]

        advance(settle_steps)
        previous, change = None, math.inf
        for window in range(1, max_windows + 1):
            advance(window_steps)
            measures = measure_window(signals, contact_pairs, rec.cycles_per_window)
            if previous is not None:
                change = max(abs(measures[key] - previous[key]) / max(abs(previous[key]), 1e-300)
                             for key in ("dte_rms_m", "dte_pp_m", "mesh_force_max_n"))
            previous = measures
            if change <= rec.steady_tolerance:
                break
        static_force = torque_1_nm / pair.base_radius_1_m            # T₁ on the line of action
        return {
            **measures,
            "dynamic_factor": measures["mesh_force_max_n"] / static_force if static_force else math.nan,
            "static_mesh_force_n": static_force,
            "mesh_frequency_hz": 1.0 / mesh_period,
            "load_damping_nms": load_damping,
            "communication_step_s": step,
            "simulated_s": n * step,
            "windows": window,
            "settled": int(change <= rec.steady_tolerance),
            "steady_change": change,
            "fmu_s": fmu_seconds,
        }


def mesh_order_amplitudes(signal: np.ndarray, cycles: int, orders=MESH_ORDERS) -> np.ndarray:
    """Single-sided amplitudes of mesh orders 1…3 by the DFT over a window of whole mesh cycles.

    Over `cycles` whole periods sampled evenly, mesh order k falls exactly on DFT bin k·cycles
    (no leakage), and a cosine of amplitude A there has |X| = A·N/2.
    """
    spectrum = np.fft.rfft(signal)
    return np.array([2.0 * abs(spectrum[k * cycles]) / len(signal) for k in orders])


def measure_window(signals: np.ndarray, contact_pairs: np.ndarray, cycles: int) -> dict:
    dte, force, stiffness, w_1 = signals[:, 0], signals[:, 1], signals[:, 2], signals[:, 3]
    return {
        "dte_mean_m": float(dte.mean()),
        "dte_rms_m": float(dte.std()),                     # RMS about the mean: the dynamic part
        "dte_pp_m": float(np.ptp(dte)),
        "dte_order_amplitude_m": mesh_order_amplitudes(dte, cycles),
        "mesh_force_mean_n": float(force.mean()),
        "mesh_force_max_n": float(force.max()),
        "mesh_stiffness_mean_n_per_m": float(stiffness.mean()),
        "contact_loss_share": float(np.mean(contact_pairs == 0)),
        "back_flank_share": float(np.mean(force < 0.0)),   # mesh_force < 0: the coast flank carries
        "speed_1_mean_rpm": float(w_1.mean() * 60.0 / (2.0 * math.pi)),
    }
