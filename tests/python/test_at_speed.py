"""Issue 38: the spur FMUs at operating speed, driven by plain master loops (`gearfmu.at_speed`).

Evidence:
- the viscous brake balances T₁ exactly at the target speed (closed form c·ω₂* = T₁·z₂/z₁), so a
  case that completes must hold ω₂ within 1 % of its target over its last 5 ms;
- the cases that failed before the step followed the speed (2.9–5 kHz mesh frequency at 10–50 µs,
  the resonance with contact loss) are in the reduced grid, at the operating torque and a tenth
  of it, with steps from 20 µs to 1 ms;
- the run-up through the mesh resonance (PI-controlled motor, torsional shaft the master
  integrates, 20 and 100 µs coupling) completes on both FMUs, and both see the resonance (a DTE
  peak-to-peak above the quasi-static one) between 2.5 and 3.6 kHz, the lumped FMU's and the
  PMOR-Hertz FMU's linearized mesh modes' range;
- the run-up's peak against the full-dynamics build of the same spec (every reduced coordinate
  with its inertia, RK4, converged in its own step): the issue's 5 % and 2 %.
"""

import math
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "python"))
from gearfmu.at_speed import Fmu, brake_case, run_up  # noqa: E402

GRID_MESH_HZ = (1000.0, 2900.0, 3000.0, 5000.0)
GRID_STEPS_S = (20e-6, 50e-6, 1e-3)
GRID_TORQUES_NM = (185.0, 18.5)


@pytest.fixture(scope="module")
def spur_fmus(gear_fmus):
    fmus = {"pmor": Fmu(str(gear_fmus["spur-pmor"].fmu_path), "grid_pmor"),
            "lumped": Fmu(str(gear_fmus["spur"].fmu_path), "grid_lumped")}
    yield fmus
    for f in fmus.values():
        f.close()


@pytest.mark.parametrize("kind", ["pmor", "lumped"])
def test_the_at_speed_grid_completes_and_holds_the_brakes_balance_speed(spur_fmus, kind):
    fmu = spur_fmus[kind]
    failures = []
    for torque in GRID_TORQUES_NM:
        for f in GRID_MESH_HZ:
            for h in GRID_STEPS_S:
                r = brake_case(fmu, f, h, torque, t_end_s=0.02)
                if not r["completed"] or abs(r["omega_2_error"]) >= 0.01:
                    failures.append((torque, f, h, r.get("omega_2_error"), r["error"][:200]))
    assert not failures, failures


@pytest.mark.parametrize("kind", ["pmor", "lumped"])
@pytest.mark.parametrize("step_s", [20e-6, 100e-6])
def test_a_run_up_through_the_mesh_resonance_completes_and_sees_it(spur_fmus, kind, step_s):
    fmu = spur_fmus[kind]
    # 2.0 → 3.6 kHz in 0.22 s: the rate of issue 38's 0.4 → 4 kHz in 0.5 s, over the resonance.
    r = run_up(fmu, step_s, f_start_hz=2000.0, f_end_hz=3600.0, ramp_s=0.22, load_nm=185.0)
    assert r["completed"], r["error"]
    assert abs(r["reached_hz"] / 3600.0 - 1.0) < 0.02, r["reached_hz"]
    bins = r["dte_pp_by_bin"]
    low = min(v for f, v in bins.items() if f < 2300.0)
    assert 2500.0 < r["peak_frequency_hz"] < 3600.0, r["peak_frequency_hz"]
    assert r["peak_dte_pp_m"] > 2.0 * low, (r["peak_dte_pp_m"], low)
    assert math.isfinite(r["real_time_factor"])


def test_fmpys_own_master_runs_the_pmor_fmu_through_the_resonance_at_odd_steps(gear_fmus):
    """A master loop not written here (fmpy.simulate_fmu) at communication steps that divide
    neither the mesh period nor the default sub-step (37 and 73 µs), at 2.9 and 3.0 kHz with
    contact loss: completes, and with balanced torques (T₂ = −T₁z₂/z₁, no brake) ω₂ stays within
    1 % of its start (only the damping's losses slow the pair)."""
    import numpy as np
    from fmpy import simulate_fmu

    z1, z2 = 21, 31
    for f_mesh, h in [(2900.0, 3.7e-5), (3000.0, 7.3e-5)]:
        w2 = 2.0 * math.pi * f_mesh / z2
        inputs = np.array([(0.0, 185.0, -185.0 * z2 / z1), (1.0, 185.0, -185.0 * z2 / z1)],
                          dtype=[("time", float), ("tau_1", float), ("tau_2", float)])
        r = simulate_fmu(str(gear_fmus["spur-pmor"].fmu_path), stop_time=0.02, step_size=h, output_interval=h,
                         start_values={"w_1_start": w2 * z2 / z1, "w_2_start": w2}, input=inputs,
                         output=["w_2", "dte", "contact_pairs"])
        assert abs(r["w_2"][-1] / w2 - 1.0) < 0.01, (f_mesh, r["w_2"][-1] / w2)
        assert np.any(r["contact_pairs"] == 0), "the resonance should lose contact"


@pytest.fixture(scope="module")
def small_helical_pmor(tmp_path_factory):
    """The shipped automotive-size helical pair (examples/small_helical.toml), PMOR-Hertz on its
    defaults: built here since issue 40 brought its build to about a minute and a half."""
    from conftest import _fmu_build

    folder = tmp_path_factory.mktemp("small_helical")
    path = folder / "SmallHelical.fmu"
    # The call test_own_pair makes (the lumped FMU beside it): one build for both (the cache).
    _fmu_build("build", "examples/small_helical.toml", "-o", str(path), "--lumped-fmu", str(folder / "lumped.fmu"))
    fmu = Fmu(str(path), "small_helical")
    yield fmu
    fmu.close()


def test_the_small_helical_pair_at_speed_completes_and_holds_the_brakes_balance_speed(small_helical_pmor):
    """Issue 40, Build 4 (issue 38's helical grid, reduced): at its rated 142 N·m, at the mesh
    resonance (2.7 kHz, where the run-up's DTE peaks) and far above it (8 kHz), at 20 µs and
    1 ms coupling, every case completes and holds ω₂ within 1 % of the brake's balance speed
    (closed form c·ω₂* = T₁z₂/z₁)."""
    failures = []
    for f in (2700.0, 8000.0):
        for h in (20e-6, 1e-3):
            r = brake_case(small_helical_pmor, f, h, 142.0, t_end_s=0.02)
            print(f"small helical {f:.0f} Hz, {h * 1e6:.0f} µs: ω₂ error {r.get('omega_2_error')}, {r['error'][:100]}")
            if not r["completed"] or abs(r["omega_2_error"]) >= 0.01:
                failures.append((f, h, r.get("omega_2_error"), r["error"][:200]))
    assert not failures, failures


@pytest.fixture(scope="module")
def spur_full_reference(tmp_path_factory):
    """Issue 38's reference: the same spec built with every reduced coordinate carrying its
    inertia (`--dynamics full`, the paper's model) and integrated by RK4."""
    from conftest import _fmu_build

    path = tmp_path_factory.mktemp("spur_full") / "KurokawaSpurFull.fmu"
    _fmu_build("build", "examples/kurokawa_spur.toml", "-o", str(path), "--dynamics", "full", "--integrator", "rk4")
    fmu = Fmu(str(path), "spur_full")
    yield fmu
    fmu.close()


# The reference's max_step: halved until the run-up's peak moved < 0.5 % (BENCHMARKS §12, at
# 20 µs coupling: 41.67 / 41.88 / 41.90 µm at 2.7 / 1.35 / 0.675 µs); the test checks it again.
REFERENCE_MAX_STEP_S = 1.35e-6


def test_the_run_up_peak_is_the_full_models(spur_fmus, spur_full_reference):
    """Issue 38's must-show, on the spur example at 20 µs coupling: the run-up through the mesh
    resonance, the PMOR-Hertz FMU against the full-dynamics reference through the same loop — its
    peak DTE peak-to-peak within 5 %, the mesh frequency of the peak within 2 % (independent
    evidence: a model that keeps the inertia the default condenses, converged in its own step).

    Not at 100 µs: there the peak of either model moves by ±5 % with the window of the ramp
    alone (BENCHMARKS §12: −3.2 %, +5.6 %, +2.1 % against the reference for three windows), so a
    5 % assertion would test the window, not the model."""
    # 2.6 → 3.4 kHz in 0.111 s: issue 38's rate (0.4 → 4 kHz in 0.5 s) over the jump and the
    # peak (3075–3125 Hz), the reference's cost kept to the window that decides.
    common = dict(f_start_hz=2600.0, f_end_hz=3400.0, ramp_s=0.111, load_nm=185.0)
    step_s = 20e-6
    ref = run_up(spur_full_reference, step_s, parameters={"max_step": REFERENCE_MAX_STEP_S}, **common)
    assert ref["completed"], ref["error"]
    finer = run_up(spur_full_reference, step_s, parameters={"max_step": REFERENCE_MAX_STEP_S / 2}, **common)
    assert finer["completed"], finer["error"]
    assert abs(finer["peak_dte_pp_m"] / ref["peak_dte_pp_m"] - 1.0) < 0.005, (finer["peak_dte_pp_m"], ref["peak_dte_pp_m"])
    r = run_up(spur_fmus["pmor"], step_s, **common)
    assert r["completed"], r["error"]
    print(f"\nrun-up at 20 µs: PMOR-Hertz {r['peak_dte_pp_m'] * 1e6:.2f} µm at {r['peak_frequency_hz']:.0f} Hz, "
          f"reference {ref['peak_dte_pp_m'] * 1e6:.2f} µm at {ref['peak_frequency_hz']:.0f} Hz")
    assert abs(r["peak_dte_pp_m"] / ref["peak_dte_pp_m"] - 1.0) < 0.05, (r["peak_dte_pp_m"], ref["peak_dte_pp_m"])
    assert abs(r["peak_frequency_hz"] / ref["peak_frequency_hz"] - 1.0) < 0.02, (r["peak_frequency_hz"], ref["peak_frequency_hz"])
