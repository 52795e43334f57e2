"""Tooth friction through the FMI interface (issue 42), with fmpy as the master.

The lumped FMUs whose mesh law and friction contacts come from the FE statics (`--model lumped`,
the default FE law) run slow, speed-held brake runs: the mesh loss over whole mesh cycles
against ISO/TR 14179-2's gear loss factor H_V (evidence: the closed form, ``fmu-build inspect
--json``), and the shaft-force outputs against F_t = T₁/r_w1, F_r = F_t·tan α_wt,
F_a = F_t·tan β_w. The PMOR-Hertz spur FMU is checked the same way, frictionless and at
μ = 0.05. A slow torque reversal through zero speed runs without an
error, its friction dissipation never decreasing.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from conftest import REPO_ROOT, GearCase, _fmu_build

# The pairs of issue 42's efficiency check: spec -> FE-fed lumped FMU.
FRICTION_SPECS = {
    "kurokawa_spur": "examples/kurokawa_spur.toml",
    "small_spur": "examples/small_spur.toml",
    "small_helical": "examples/small_helical.toml",
}


@pytest.fixture(scope="module")
def friction_fmus(tmp_path_factory) -> dict[str, GearCase]:
    from fmpy import extract

    out = tmp_path_factory.mktemp("friction")
    cases = {}
    for name, spec in FRICTION_SPECS.items():
        fmu = REPO_ROOT / "target" / "fmu" / f"friction_{name}.fmu"
        fmu.parent.mkdir(parents=True, exist_ok=True)
        _fmu_build("build", spec, "-o", str(fmu), "--model", "lumped")
        dump = out / f"{name}.json"
        _fmu_build("inspect", spec, "--json", str(dump), "--from-fmu", str(fmu))
        mesh = json.loads(dump.read_text())
        unzip = Path(extract(str(fmu), unzipdir=out / f"{name}_unzipped"))
        cases[name] = GearCase(name, REPO_ROOT / spec, fmu, dump, mesh, unzip, "lumped")
    return cases


def brake_held_run(slave, mesh: dict, torque: float, mesh_hz: float, cycles: int, comm_step: float = 1e-4):
    """τ₁ held, gear 2 braked to hold its speed: τ₂ = −T₁·z₂/z₁ − k·(ω₂ − ω₂*) − k_i·∫(ω₂ − ω₂*),
    critically damped at 50 rad/s on the pair's inertia. The integral takes up the friction
    loss: with the proportional part alone the speed settled T₁·(z₂/z₁)·loss/k below its target
    (a third of it on the small pairs). After 40 mesh cycles, `cycles` whole ones are measured.
    Returns the loss over the window's input work, and the window's mean shaft forces, each
    output sampled per step."""
    z1, z2 = mesh["teeth_1"], mesh["teeth_2"]
    ratio = z2 / z1
    w2_target = 2 * math.pi * mesh_hz / z2
    j_total = mesh["inertia_2_kgm2"] + mesh["inertia_1_kgm2"] * ratio**2
    gain, integral_gain, integral = 100.0 * j_total, 2500.0 * j_total, 0.0
    period = 1.0 / mesh_hz
    settle = round(40 * period / comm_step)
    window = round(cycles * period / comm_step)
    vr = slave.vr
    outputs = [vr[n] for n in ("w_1", "w_2", "mesh_energy_loss", "force_tangential", "force_radial", "force_axial",
                               "mesh_efficiency")]
    t, work, start_loss, sums = 0.0, 0.0, None, [0.0, 0.0, 0.0, 0.0]
    w1, w2 = slave.fmu.getReal(outputs[:2])
    for k in range(settle + window):
        integral += integral_gain * (w2 - w2_target) * comm_step
        slave.set_inputs(torque, -torque * ratio - gain * (w2 - w2_target) - integral)
        slave.step(t, comm_step)
        t += comm_step
        w1_next, w2, loss, f_t, f_r, f_a, eta = slave.fmu.getReal(outputs)
        assert 0.0 < eta <= 1.0, f"instantaneous efficiency {eta} at t = {t}"
        if k == settle - 1:
            start_loss = loss
        elif k >= settle:
            work += torque * 0.5 * (w1 + w1_next) * comm_step
            for i, v in enumerate((f_t, f_r, f_a, eta)):
                sums[i] += v / window
        w1 = w1_next
    assert w2 == pytest.approx(w2_target, rel=0.01), "the brake holds the mesh frequency"
    return (loss - start_loss) / work, sums


def synchronous_slave(make_slave, case: GearCase, instance: str, mesh: dict, torque: float, mu: float,
                      mesh_hz: float = 200.0):
    """An instance at rest in its static equilibrium under T₁ against the balancing brake,
    turning at the rigid speeds of `mesh_hz` mesh frequency, with friction μ."""
    z1, z2 = mesh["teeth_1"], mesh["teeth_2"]
    w1 = 2 * math.pi * mesh_hz / z1
    return make_slave(case, instance, parameters={"friction_coefficient": mu, "w_1_start": w1,
                                                  "w_2_start": w1 * z1 / z2},
                      booleans={"start_at_equilibrium": True}, inputs=(torque, -torque * z2 / z1))


def operating(mesh: dict) -> tuple[float, float, float]:
    """The operating torque, r_w1 and the operating pressure angle."""
    alpha = mesh["operating_pressure_angle_rad"]
    return mesh["operating_torque_nm"], mesh["base_radius_1_m"] / math.cos(alpha), alpha


@pytest.mark.parametrize("name", sorted(FRICTION_SPECS))
def test_quasi_static_efficiency_against_iso_tr_14179_2(friction_fmus, make_slave, name):
    """Evidence: ISO/TR 14179-2's H_V, P_loss = μ·H_V·P_in, for spur pairs; for the helical pair
    (ε_β ≈ 1, load on inclined contact lines spread over the plane of action, which H_V's spur
    sharing does not describe) the uniform-load closed form, ISO's printed beside it. At 200 Hz
    mesh frequency (a tenth of the resonance and below) the mesh is quasi-static; μ = 0.05."""
    case = friction_fmus[name]
    mesh = case.mesh
    torque, _, _ = operating(mesh)
    mu = 0.05
    slave = synchronous_slave(make_slave, case, f"eff-{name}", mesh, torque, mu)
    loss_share, (_, _, _, eta_mean) = brake_held_run(slave, mesh, torque, 200.0, 20)
    h_v, h_u = mesh["gear_loss_factor_iso"], mesh["gear_loss_factor_uniform_load"]
    helical = mesh["overlap_ratio"] > 0.5
    reference = mu * (h_u if helical else h_v)
    print(f"{name}: loss {loss_share:.5f} of the input (efficiency {1 - loss_share:.5f}, mean instantaneous "
          f"{eta_mean:.5f}); μH_V = {mu * h_v:.5f} (ISO/TR 14179-2), μH_V,u = {mu * h_u:.5f} (uniform load); "
          f"loss / ISO's {loss_share / (mu * h_v):.4f}")
    assert loss_share == pytest.approx(reference, rel=0.10)
    # The instantaneous efficiency's mean tells the same loss to within the load's ripple.
    assert 1 - eta_mean == pytest.approx(loss_share, rel=0.05)


@pytest.mark.parametrize("name", sorted(FRICTION_SPECS))
def test_shaft_forces_against_the_closed_forms(friction_fmus, make_slave, name):
    """Evidence: F_t = T₁/r_w1, F_r = F_t·tan α_wt, F_a = F_t·tan β_w (tan β_w = tan β_b/cos α_wt),
    mean over 20 mesh cycles of a slow brake-held run, frictionless: within 1 %. With μ = 0.05 the
    forces move by friction's own force along the flanks' common tangent (printed; the Rust test
    `shaft_forces_match_the_closed_forms_and_friction_moves_them_along_the_flank_tangent` checks
    the decomposition)."""
    case = friction_fmus[name]
    mesh = case.mesh
    torque, r_w1, alpha = operating(mesh)
    f_t = torque / r_w1
    tan_beta_w = math.tan(mesh["base_helix_angle_rad"]) / math.cos(alpha)
    means = {}
    for mu in (0.0, 0.05):
        slave = synchronous_slave(make_slave, case, f"forces-{name}-{mu}", mesh, torque, mu)
        _, means[mu] = brake_held_run(slave, mesh, torque, 200.0, 20)
    t0, r0, a0, _ = means[0.0]
    t1, r1, a1, _ = means[0.05]
    print(f"{name}: F_t {t0:.2f} N (T₁/r_w1 {f_t:.2f}), F_r {r0:.2f} N ({f_t * math.tan(alpha):.2f}), "
          f"F_a {a0:.2f} N ({f_t * tan_beta_w:.2f}); μ = 0.05: F_t {100 * (t1 / t0 - 1):+.3f} %, "
          f"F_r {100 * (r1 / r0 - 1):+.3f} %, F_a {a1:.2f} N")
    assert t0 == pytest.approx(f_t, rel=0.01)
    assert r0 == pytest.approx(f_t * math.tan(alpha), rel=0.01)
    assert a0 == pytest.approx(f_t * tan_beta_w, rel=0.01, abs=1e-6 * f_t)


@pytest.mark.parametrize("name", ["spur-pmor", "helical-pmor"])
def test_the_pmor_hertz_fmu_carries_friction_as_the_lumped_one(gear_fmus, make_slave, name):
    """The PMOR-Hertz FMUs of the Kurokawa pairs, brake-held at 200 Hz mesh frequency under their
    operating torque: frictionless, their shaft forces meet F_t = T₁/r_w1, F_r = F_t·tan α_wt and
    F_a = F_t·tan β_w within 1 % and they lose nothing; with μ = 0.05 the spur pair's mesh loss is
    within 10 % of ISO/TR 14179-2's μ·H_V, the helical pair's (ε_β 0.73: load on inclined contact
    lines, not H_V's spur sharing) of the uniform-load form μ·H_V,u (evidence: the closed forms),
    as the lumped FMUs' are."""
    case = gear_fmus[name]
    mesh = case.mesh
    torque, r_w1, alpha = operating(mesh)
    tan_beta_w = math.tan(mesh["base_helix_angle_rad"]) / math.cos(alpha)
    runs = {}
    for mu in (0.0, 0.05):
        slave = synchronous_slave(make_slave, case, f"{name}-friction-{mu}", mesh, torque, mu)
        runs[mu] = brake_held_run(slave, mesh, torque, 200.0, 10)
    loss_0, (f_t, f_r, f_a, eta_0) = runs[0.0]
    loss, (f_t1, f_r1, _, eta) = runs[0.05]
    h_v, h_u = mesh["gear_loss_factor_iso"], mesh["gear_loss_factor_uniform_load"]
    helical = mesh["overlap_ratio"] > 0.5
    print(f"{name}: frictionless F_t {f_t:.2f} N (T₁/r_w1 {torque / r_w1:.2f}), F_r {f_r:.2f} N "
          f"({torque / r_w1 * math.tan(alpha):.2f}), F_a {f_a:.2f} N ({torque / r_w1 * tan_beta_w:.2f}); μ = 0.05: "
          f"loss {loss:.5f} of the input (efficiency {1 - loss:.5f}, mean instantaneous {eta:.5f}), μH_V {0.05 * h_v:.5f}, "
          f"μH_V,u {0.05 * h_u:.5f}; loss / ISO's {loss / (0.05 * h_v):.4f}; F_t {100 * (f_t1 / f_t - 1):+.3f} %, "
          f"F_r {100 * (f_r1 / f_r - 1):+.3f} %")
    assert f_t == pytest.approx(torque / r_w1, rel=0.01)
    assert f_r == pytest.approx(torque / r_w1 * math.tan(alpha), rel=0.01)
    assert f_a == pytest.approx(torque / r_w1 * tan_beta_w, rel=0.01, abs=1e-6 * f_t)
    assert loss_0 == 0.0 and eta_0 == pytest.approx(1.0, abs=1e-12)
    assert loss == pytest.approx(0.05 * (h_u if helical else h_v), rel=0.10)


def test_a_friction_coefficient_out_of_range_is_refused(gear_fmus, make_slave):
    """Outside [0, 0.3] friction_coefficient is an fmi2Error, on either FMU (not a silently
    clipped value); 0.3 is taken."""
    from fmpy.fmi1 import FMICallException

    for name in ("spur", "spur-pmor"):
        # Set in Initialization Mode, where a parameter may be set; an fmi2Error ends the
        # instance (FMI 2.0): a fresh one per value.
        for k, bad in enumerate((-0.01, 0.31, float("nan"))):
            with pytest.raises(FMICallException):
                make_slave(gear_fmus[name], f"refuse-{name}-{k}", parameters={"friction_coefficient": bad})
        slave = make_slave(gear_fmus[name], f"accept-{name}", parameters={"friction_coefficient": 0.3})
        assert slave.fmu.getReal([slave.vr["friction_coefficient"]]) == [0.3]


@pytest.mark.parametrize("kind", ["lumped", "pmor-hertz"])
def test_the_friction_force_changes_sign_at_the_pitch_point(friction_fmus, gear_fmus, make_slave, kind):
    """Evidence: a single tooth pair's sliding (closed form). Where one pair carries the load (the
    FMU's `contact_pairs`) the friction force is μF_n·v/√(v² + v_ε²), v = ω₁u − ω₂(T₁T₂ − u), zero
    at the pitch point C at the rigid speed ratio: negative in the approach, positive in the
    recess, Coulomb's ±μF_n beyond the regularization (v_ε the FMU's `friction_regularization`;
    the mesh's own vibration, δ̇ = r_b1ω₁ − r_b2ω₂, slides the flanks at mm/s near C). u is the contact point: the reference mesh
    position puts a pair at C, and the contact point is read on gear 1's involute, u = C + r_b1·φ₁
    modulo the base pitch. Read off the outputs of a
    quasi-static brake-held run (200 Hz mesh frequency, μ = 0.05): friction is the part of the
    tangential shaft force the normal force does not make, Σf = (F_t − F_bt·cos α_wt)/sin α_wt.
    Within 0.05 of μF_n.

    On the PMOR-Hertz FMU the sliding is the deformed flanks': the teeth's own elastic rates
    along the flank add to the ports' (the mesh mode rings in this run, and both teeth deflecting
    with it slide the flanks the same way: measured ±2.4 mm/s near C, in phase on both gears),
    which the outputs do not show. Within 2·v_ε of zero sliding a sliding off by that much moves
    μF_n·v/√(v² + v_ε²) by up to 0.2 of μF_n (v_ε = 15 mm/s); beyond it by at most 0.02. There the
    closed form is asked within 0.05; within the band the difference is reported."""
    mesh = friction_fmus["kurokawa_spur"].mesh
    case = friction_fmus["kurokawa_spur"] if kind == "lumped" else gear_fmus["spur-pmor"]
    torque, _, alpha = operating(mesh)
    z1, z2 = mesh["teeth_1"], mesh["teeth_2"]
    rb1, rb2, pb, c = mesh["base_radius_1_m"], mesh["base_radius_2_m"], mesh["base_pitch_m"], mesh["pitch_point_m"]
    single = (mesh["path_end_m"] - pb, mesh["path_start_m"] + pb)
    loa = (rb1 + rb2) * math.tan(alpha)
    w1 = 2 * math.pi * 200.0 / z1
    slave = synchronous_slave(make_slave, case, f"sign-{kind}", mesh, torque, 0.05)
    vr = slave.vr
    eps = slave.fmu.getReal([vr["friction_regularization"]])[0]
    refs = [vr[n] for n in ("phi_1", "w_1", "w_2", "mesh_force", "force_tangential")]
    gain = (mesh["inertia_2_kgm2"] + mesh["inertia_1_kgm2"] * (z2 / z1) ** 2) / 0.01
    h, t, samples = 2e-5, 0.0, []
    for _ in range(round(0.25 / h)):
        phi_1, w_1, w_2, force, f_t = slave.fmu.getReal(refs)
        pairs = slave.fmu.getInteger([vr["contact_pairs"]])[0]
        slave.set_inputs(torque, -torque * z2 / z1 - gain * (w_2 - w1 * z1 / z2))
        slave.step(t, h)
        t += h
        if t < 0.05:
            continue
        u = c + ((rb1 * phi_1 + 0.5 * pb) % pb - 0.5 * pb)
        v = w_1 * u - w_2 * (loa - u)
        ratio = (f_t - force * math.cos(alpha)) / math.sin(alpha) / (0.05 * force)
        samples.append((u, pairs, ratio, v / math.hypot(v, eps)))
    # Where one pair is under load (the FMU's own count: under load the next pair touches before
    # the rigid geometry's zone ends, by about 1 mm on the Kurokawa spur pair), less two of the
    # lumped law's rows at each end (its count is the nearest row's, its friction a blend of two).
    lo = min(u for u, pairs, *_ in samples if pairs == 1) + 2 * pb / 128
    hi = max(u for u, pairs, *_ in samples if pairs == 1) - 2 * pb / 128
    assert single[0] < lo < c < hi < single[1], "one loaded pair only inside the rigid single-contact zone"
    core = [(u, ratio, closed) for u, _, ratio, closed in samples if lo < u < hi]
    # The PMOR-Hertz flanks' elastic sliding is not in the ports' closed form: asked beyond 2·v_ε.
    band = 2.0 / math.sqrt(5.0) if kind == "pmor-hertz" else 0.0  # |v| = 2·v_ε
    compared = [(u, ratio, closed) for u, ratio, closed in core if abs(closed) >= band]
    worst = max(abs(ratio - closed) for _, ratio, closed in compared)
    inside = max((abs(ratio - closed) for _, ratio, closed in core if abs(closed) < band), default=0.0)

    signs = {math.copysign(1.0, ratio) for _, ratio, _ in core}
    print(f"{kind}: {len(core)} samples with one loaded pair, {(lo - c) * 1e3:+.2f} … {(hi - c) * 1e3:+.2f} mm from C "
          f"(the rigid zone {(single[0] - c) * 1e3:+.2f} … {(single[1] - c) * 1e3:+.2f}), v_ε {eps * 1e3:.2f} mm/s: "
          f"Σf/(μF_n) within {worst:.4f} of the single pair's over {len(compared)} of them"
          + (f", within {inside:.4f} inside 2·v_ε" if band else ""))
    assert signs == {-1.0, 1.0} and len(core) > 100 and len(compared) > 100
    assert worst < 0.05


@pytest.mark.parametrize("kind", ["lumped", "pmor-hertz"])
def test_a_slow_reversal_through_zero_speed_runs_and_friction_only_dissipates(friction_fmus, gear_fmus, make_slave,
                                                                                kind):
    """Gear 1's torque reverses slowly (cosine over 0.4 s, ±T₁) against a viscous brake, from rest:
    the pair stops, turns back, and the flanks part and meet the coast side. No fmi2Error, the
    friction dissipation never decreases, the instantaneous efficiency stays ≤ 1 (in the
    transient it can fall below 0: the mesh pays friction from its stored energy). Both FMUs of
    the Kurokawa spur pair."""
    mesh = friction_fmus["kurokawa_spur"].mesh
    case = friction_fmus["kurokawa_spur"] if kind == "lumped" else gear_fmus["spur-pmor"]
    torque = mesh["operating_torque_nm"]
    slave = make_slave(case, f"reversal-{kind}", parameters={"friction_coefficient": 0.05},
                       booleans={"start_at_equilibrium": True}, inputs=(torque, 0.0))
    vr = slave.vr
    refs = [vr[n] for n in ("w_1", "w_2", "mesh_energy_loss", "mesh_efficiency", "mesh_force")]
    h, t, last_loss, speeds, forces, lowest_eta = 1e-4, 0.0, 0.0, [], [], 1.0
    for _ in range(6000):
        w1, w2, loss, eta, force = slave.fmu.getReal(refs)
        slave.set_inputs(torque * math.cos(math.pi * min(t / 0.4, 1.0)), -2.0 * torque * w2 / 50.0)
        slave.step(t, h)
        t += h
        assert loss >= last_loss and eta <= 1.0
        lowest_eta = min(lowest_eta, eta)
        last_loss = loss
        speeds.append(w1)
        forces.append(force)
    print(f"reversal, {kind}: ω₁ from {max(speeds):.2f} to {min(speeds):.2f} rad/s, mesh force {max(forces):.0f} … "
          f"{min(forces):.0f} N, friction dissipated {last_loss:.3f} J, lowest instantaneous efficiency {lowest_eta:.3f}")
    assert max(speeds) > 0.0 > min(speeds), "the pair turned back"
    assert min(forces) < 0.0 < max(forces), "both flanks carried the load"


# ISO/TR 14179-2's inputs of the law tests: an ISO VG 100 mineral oil near 70 °C, ground flanks.
ISO_LAW = {"friction_coefficient": 0.0, "oil_viscosity": 30.0, "flank_roughness_ra": 0.5, "lubricant_factor": 1.0}


def iso_tr_14179_2_mu(mesh: dict, transverse_force_n: float, w1: float) -> float:
    """ISO/TR 14179-2's μ_mz = 0.048·(F_bt/b / (v_ΣC·ρ_redC))^0.2·η^−0.05·Ra^0.25·X_L, written
    here from the standard's formula in its units (N/mm, m/s, mm, mPa·s, µm), apart from the
    Rust code; v_ΣC held at 1 m/s below it, as the FMU documents."""
    alpha = mesh["operating_pressure_angle_rad"]
    rb1, rb2 = mesh["base_radius_1_m"], mesh["base_radius_2_m"]
    v_sum = max(2.0 * abs(w1) * rb1 / math.cos(alpha) * math.sin(alpha), 1.0)
    rho_1 = rb1 * math.tan(alpha)  # T₁C
    rho_2 = rb2 * math.tan(alpha)  # T₂C
    rho_red_mm = 1e3 * rho_1 * rho_2 / (rho_1 + rho_2) / math.cos(mesh["base_helix_angle_rad"])
    load_n_per_mm = abs(transverse_force_n) / (1e3 * mesh["face_width_m"])
    return (0.048 * (load_n_per_mm / (v_sum * rho_red_mm)) ** 0.2 * ISO_LAW["oil_viscosity"] ** -0.05
            * ISO_LAW["flank_roughness_ra"] ** 0.25 * ISO_LAW["lubricant_factor"])


@pytest.mark.parametrize("kind", ["lumped", "pmor-hertz"])
def test_iso_tr_14179_2_law_gives_its_mu_and_the_loss_follows(friction_fmus, gear_fmus, make_slave, log_capture,
                                                               kind):
    """Evidence: ISO/TR 14179-2's μ_mz (its formula, written in this test) and H_V. The Kurokawa
    spur pair brake-held under its operating torque at 200 Hz mesh frequency with the law switched
    on by the FMU parameters: the μ it applies (`friction_coefficient_applied`) is μ_mz at the
    mesh force and speed a step starts from (to 1e-9), and the mesh loss is μ_mz·H_V within 10 %
    at the mean load T₁/r_b1, as with a constant μ. At rest (v_ΣC = 0) the law is held at v_ΣC =
    1 m/s, and the FMU says so: one warning, however many steps stay below."""
    mesh = friction_fmus["kurokawa_spur"].mesh
    case = friction_fmus["kurokawa_spur"] if kind == "lumped" else gear_fmus["spur-pmor"]
    torque = mesh["operating_torque_nm"]
    z1, z2 = mesh["teeth_1"], mesh["teeth_2"]
    w1 = 2 * math.pi * 200.0 / z1
    load = torque / mesh["base_radius_1_m"]
    slave = make_slave(case, f"iso-law-{kind}", parameters={**ISO_LAW, "w_1_start": w1, "w_2_start": w1 * z1 / z2},
                       booleans={"start_at_equilibrium": True}, inputs=(torque, -torque * z2 / z1))
    loss, _ = brake_held_run(slave, mesh, torque, 200.0, 10)
    # One more step: the μ it applies is the law's at the mesh force and speed it starts from
    # (the mesh force output is the normal force on the PMOR-Hertz FMU: F_bt = F_n·cos β_b).
    vr = slave.vr
    force, w1_now = slave.fmu.getReal([vr["mesh_force"], vr["w_1"]])
    t = 0.0
    for _ in range(round(40 / 200.0 / 1e-4) + round(10 / 200.0 / 1e-4)):  # brake_held_run's time, summed as it sums
        t += 1e-4
    slave.step(t, 1e-4)
    mu_applied = slave.fmu.getReal([vr["friction_coefficient_applied"]])[0]
    cos_bb = 1.0 if kind == "lumped" else math.cos(mesh["base_helix_angle_rad"])
    assert mu_applied == pytest.approx(iso_tr_14179_2_mu(mesh, force * cos_bb, w1_now), rel=1e-9)
    mu_iso = iso_tr_14179_2_mu(mesh, load, w1_now)
    h_v = mesh["gear_loss_factor_iso"]
    print(f"{kind}: μ applied {mu_applied:.5f} (mesh force {force / load:.4f} × T₁/r_b1), ISO/TR 14179-2's μ_mz at "
          f"T₁/r_b1 {mu_iso:.5f}; loss {loss:.5f} of the input, μ_mz·H_V {mu_iso * h_v:.5f} (ratio "
          f"{loss / (mu_iso * h_v):.4f})")
    assert loss == pytest.approx(mu_iso * h_v, rel=0.10)
    # At rest under load: held at the speed floor.
    name = f"iso-law-rest-{kind}"
    rest = make_slave(case, name, parameters=ISO_LAW, booleans={"start_at_equilibrium": True},
                      inputs=(torque, -torque * z2 / z1), callbacks=log_capture.callbacks, logging_on=True)
    held = rest.fmu.getReal([rest.vr["friction_coefficient_applied"]])[0]
    floor = iso_tr_14179_2_mu(mesh, load, 0.0)
    assert held == pytest.approx(floor, rel=1e-3)
    t = 0.0
    for _ in range(3):
        rest.step(t, 1e-4)
        t += 1e-4
    held_logs = [m for status, _, m in log_capture.for_instance(name) if "ISO/TR 14179-2's friction law is held" in m]
    assert len(held_logs) == 1, held_logs


def test_iso_tr_14179_2_law_inputs_are_checked(gear_fmus, make_slave):
    """The law's inputs out of range are an fmi2Error at the call that sets them; a law without
    its roughness, or beside a constant friction_coefficient, at the end of initialization, each
    naming the parameter (logged)."""
    from fmpy.fmi1 import FMICallException

    case = gear_fmus["spur"]
    bad = [
        {"oil_viscosity": -1.0},
        {"flank_roughness_ra": 20.0},
        {"lubricant_factor": float("nan")},
        {**ISO_LAW, "flank_roughness_ra": 0.0},
        {**ISO_LAW, "friction_coefficient": 0.05},
    ]
    for k, parameters in enumerate(bad):
        with pytest.raises(FMICallException):
            make_slave(case, f"iso-refuse-{k}", parameters=parameters)
    slave = make_slave(case, "iso-accept", parameters=ISO_LAW)
    assert slave.fmu.getReal([slave.vr["oil_viscosity"]]) == [30.0]
