"""A pair that is not the Kurokawa example, built on its defaults and run through fmpy (issue 25).

* The shipped small examples (``examples/small_spur.toml``, ``small_helical.toml``: m_n 2.5 mm,
  z 23/41, b 18 mm, x +0.2/−0.1; the helical at β 25°) and a pair of a size no example covers
  (m 1.75 mm, z 19/57, b 12 mm, written here) build with both models on their defaults: no
  ``--rom-torques-nm``, no ``[mesh]``, no ``[operating]`` — the ROM torque, the contact depth, the
  helical pair's axial slices and the step's load follow from the spec.
* Each FMU is driven by fmpy at the pair's operating torque (``fmu-build inspect``) against an
  explicit viscous brake fed back from ``w_2``. Evidence: the steady state's closed form — the
  speed ratio is z₂/z₁ and the brake's torque balances T₁·z₂/z₁, so ω₂ = T₁z₂/(z₁c).
* Run-time validity, the same rule in both models: a mesh force past the yield of a tooth root
  (one pair loaded at its tip, ``closed_forms::rating``) is logged once as fmi2Warning, never silently.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]

UNCOVERED_SIZE = """\
# A spur pair of a size no example covers: m 1.75 mm, ratio 3.
name = "RatioThree"

[rack]
module_mm = 1.75
pressure_angle_deg = 20.0

[material]
youngs_modulus_gpa = 206.0
poisson_ratio = 0.3
density_kg_m3 = 7850.0
yield_strength_mpa = 900.0

[mounting]
face_width_mm = 12.0
backlash_mm = 0.04
mesh_damping_ratio = 0.05

[gear1]
teeth = 19
profile_shift = 0.3
bore_radius_mm = 8.0

[gear2]
teeth = 57
bore_radius_mm = 20.0
"""

PAIRS = ("small_spur", "small_helical", "ratio_three")
MODELS = ("pmor-hertz", "lumped")


def _spec(name: str, tmp: Path) -> Path:
    if name == "ratio_three":
        path = tmp / "ratio_three.toml"
        path.write_text(UNCOVERED_SIZE)
        return path
    return REPO_ROOT / "examples" / f"{name}.toml"


def _run(*args: str) -> str:
    """`fmu-build args…` through the session's build cache (conftest); fails the test on an error."""
    from conftest import _fmu_build

    return _fmu_build(*args).stdout


@pytest.fixture(scope="module")
def own_fmus(gear_fmus, tmp_path_factory):
    """(pair, model) -> (fmu path, unzip dir, operating torque N·m, teeth (z1, z2)).

    ``gear_fmus`` first: it builds the workspace (the fmu-build binary and the FMU library)."""
    from fmpy import extract

    tmp = tmp_path_factory.mktemp("own_pairs")
    built = {}
    for pair in PAIRS:
        spec = _spec(pair, tmp)
        # The geometry and the operating torque: no FE needed.
        inspect = _run("inspect", str(spec), "--mesh-law", "analytic")
        torque = float(re.search(r"operating ([0-9.e+]+) N·m", inspect).group(1))
        teeth = tuple(int(z) for z in re.search(r"z (\d+)/(\d+)", inspect).groups())
        # On its defaults: the spec, nothing else. The lumped FMU comes from the same build
        # (`--lumped-fmu`: its FE-fed law from the build's own statics, the file
        # `--model lumped` writes, `pmor_dynamics::the_builds_lumped_mesh_law_is_the_one_a_separate_reduction_gives`).
        fmus = {model: tmp / f"{pair}-{model}.fmu" for model in MODELS}
        _run("build", str(spec), "-o", str(fmus["pmor-hertz"]), "--lumped-fmu", str(fmus["lumped"]))
        for model in MODELS:
            unzip = Path(extract(str(fmus[model]), unzipdir=tmp / f"{pair}-{model}"))
            built[(pair, model)] = (fmus[model], unzip, torque, teeth)
    return built


def _slave(fmu: Path, unzip: Path, name: str, callbacks=None):
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=str(unzip),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    slave.instantiate(callbacks=callbacks)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave, vr


def _brake_run(slave, vr, torque_nm, brake, t_end, h=1e-4, ramp_s=2e-3):
    """examples/brake_run.py's loop: the tour's own script is what the test runs."""
    return _brake_run_module().brake_loop(slave, vr, torque_nm, brake, t_end, h, ramp_s)


def _brake_run_module():
    import importlib.util
    import sys

    if "brake_run" not in sys.modules:
        spec = importlib.util.spec_from_file_location("brake_run", REPO_ROOT / "examples" / "brake_run.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        sys.modules["brake_run"] = module
    return sys.modules["brake_run"]


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("pair", PAIRS)
def test_own_pair_on_defaults_reaches_the_closed_form_steady_state(own_fmus, pair, model):
    fmu, unzip, torque, (z1, z2) = own_fmus[(pair, model)]
    target_w2 = 40.0  # rad/s: the brake is sized for it
    brake = torque * z2 / z1 / target_w2
    slave, vr = _slave(fmu, unzip, f"own_{pair}_{model}")
    try:
        rows = _brake_run(slave, vr, torque, brake, t_end=12e-3)
    finally:
        slave.terminate()
        slave.freeInstance()
    tail = [r for r in rows if r[0] > rows[-1][0] - 4e-3]
    w1 = sum(r[1] for r in tail) / len(tail)
    w2 = sum(r[2] for r in tail) / len(tail)
    dte = sum(r[3] for r in tail) / len(tail)
    print(f"{pair} {model}: T1 {torque:.1f} N·m, w2 {w2:.4f} rad/s (closed form {target_w2}), "
          f"w1/w2 {w1 / w2:.5f} (z2/z1 {z2 / z1:.5f}), mean DTE {dte * 1e6:.3f} µm")
    assert w1 / w2 == pytest.approx(z2 / z1, rel=5e-3)
    # The brake's time constant is well under a millisecond here: 4 ms in, ω₂ sits at the closed form.
    assert w2 == pytest.approx(target_w2, rel=1e-2)
    # Driven, the teeth deflect forward: a positive transmission error of a few to tens of µm.
    assert 0.0 < dte < 100e-6


@pytest.mark.parametrize("model", MODELS)
def test_a_mesh_force_past_the_root_yield_is_logged_once_in_both_models(own_fmus, model, log_capture):
    from fmpy.fmi2 import fmi2Warning

    fmu, unzip, torque, (z1, z2) = own_fmus[("small_spur", model)]
    name = f"yield_warning_{model}"
    # The spec's rated torque is a third of the yield torque (closed_forms::rating): 4.5 × it is 1.5 × past
    # yield. The lumped law carries it; the PMOR-Hertz model also says it is past its checked range.
    overload = 4.5 * torque
    slave, vr = _slave(fmu, unzip, name, callbacks=log_capture.callbacks)
    try:
        rows = _brake_run(slave, vr, overload, overload * z2 / z1 / 40.0, t_end=4e-3, h=1e-4, ramp_s=1e-3)
    except Exception as error:  # a run-away past the model's range must say so, not crash
        lines = log_capture.for_instance(name)
        assert any("ran away" in m or "beyond" in m for (_, _, m) in lines), (error, lines)
        rows = None
    finally:
        slave.terminate()
        slave.freeInstance()
    lines = log_capture.for_instance(name)
    warnings = [m for (s, _, m) in lines if s == fmi2Warning and "yield strength" in m]
    assert len(warnings) == 1, lines
    assert "mesh force" in warnings[0] and " N " in warnings[0]
    if model == "pmor-hertz":
        # Past yield as well as past the model's range: no rebuild can help, and the message says so.
        assert any(s == fmi2Warning and "the largest load this model was built" in m and "lower the load" in m
                   for (s, _, m) in lines), lines
    if rows is not None:
        assert all(math.isfinite(r[2]) for r in rows)


def test_no_warning_at_the_operating_torque(own_fmus, log_capture):
    from fmpy.fmi2 import fmi2Warning

    fmu, unzip, torque, (z1, z2) = own_fmus[("small_spur", "lumped")]
    name = "no_warning_lumped"
    slave, vr = _slave(fmu, unzip, name, callbacks=log_capture.callbacks)
    try:
        _brake_run(slave, vr, torque, torque * z2 / z1 / 40.0, t_end=4e-3)
    finally:
        slave.terminate()
        slave.freeInstance()
    assert not [m for (s, _, m) in log_capture.for_instance(name) if s == fmi2Warning]


@pytest.mark.parametrize("model", MODELS)
def test_the_fmu_carries_its_operating_point_for_the_sweeps(own_fmus, model):
    """gearfmu.sweep's default torque is the one fmu-build inspect prints for the spec."""
    from gearfmu.sweep import operating_torque_nm

    fmu, _, torque, _ = own_fmus[("small_spur", model)]
    assert operating_torque_nm(fmu) == pytest.approx(torque, rel=1e-5)


@pytest.mark.parametrize("pair", PAIRS)
def test_own_pair_steps_at_its_physics_and_starts_at_its_static_equilibrium(own_fmus, pair):
    """The step set by the physics on pairs that are not the example (issue 24): the PMOR-Hertz
    FMU's default ``max_step`` is at least 5 µs — bounded by the mesh mode and the body modes
    below the cut-off (3 × the mesh mode's 2-DOF estimate), not by the hub or the stiff body
    modes above it (the small spur pair's default was 2.0 µs with every body mode dynamic).
    Evidence, a fixed point: started at its static equilibrium under balanced operating
    torques, the pair stays there (DTE within 1e-3 of its start over 1 ms at 10 µs steps; the
    time stepping's Newton ends at |Δz|/|z| ≈ 1e-6 on the fast coordinates, and the swing
    measured is 1.0e-4 on the ratio-three pair, against the 50–100 % of a cold start); and
    ``fmu-build linearize`` finds the mesh mode on the FMU (it failed on the small spur pair:
    the rigid start guess alone overloaded the Hertz law)."""
    from fmpy import read_model_description

    fmu, unzip, torque, (z1, z2) = own_fmus[(pair, "pmor-hertz")]
    md = read_model_description(str(fmu))
    max_step = float(next(v.start for v in md.modelVariables if v.name == "max_step"))
    print(f"{pair}: default max_step {max_step * 1e6:.1f} µs")
    assert max_step >= 5e-6
    linearized = _run("linearize", str(fmu), "--positions", "2", "--count", "2")
    assert "mesh mode on the mean mesh stiffness" in linearized, linearized

    from fmpy.fmi2 import FMU2Slave

    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=str(unzip),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName=f"{pair}_equilibrium")
    slave.instantiate()
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setBoolean([vr["start_at_equilibrium"]], [True])
        slave.setReal([vr["tau_1"], vr["tau_2"]], [torque, -torque * z2 / z1])
        slave.exitInitializationMode()
        dte = [slave.getReal([vr["dte"]])[0]]
        for k in range(100):
            slave.doStep(currentCommunicationPoint=k * 1e-5, communicationStepSize=1e-5)
            dte.append(slave.getReal([vr["dte"]])[0])
    finally:
        slave.terminate()
        slave.freeInstance()
    swing = max(dte) - min(dte)
    print(f"{pair}: static DTE {dte[0] * 1e6:.3f} µm, swing over 1 ms {swing * 1e6:.2e} µm")
    assert dte[0] > 0.0
    assert swing < 1e-3 * dte[0]
