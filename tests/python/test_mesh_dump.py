"""Plausibility of the mesh-law dump (``fmu-build inspect --json``).

Independent evidence: textbook involute geometry computed here from the TOML
spec alone (base radii, transverse base pitch, bounds on the gear inertias
from solid annuli at root and tip radius), the ISO 6336 range of mesh
stiffness per face width, and the known fact that a helical mesh (overlap)
has a smoother stiffness than a spur mesh.  Everything the FMU integrates
comes from these numbers, so they are checked before the dynamics.
"""

import math
import tomllib

import numpy as np
import pytest


def _geometry(spec_path):
    spec = tomllib.loads(spec_path.read_text())
    rack, mount, mat = spec["rack"], spec["mounting"], spec["material"]
    m_n = rack["module_mm"] * 1e-3
    alpha_n = math.radians(rack["pressure_angle_deg"])
    beta = math.radians(rack.get("helix_angle_deg", 0.0))
    m_t = m_n / math.cos(beta)
    alpha_t = math.atan(math.tan(alpha_n) / math.cos(beta))
    return dict(
        m_n=m_n, m_t=m_t, alpha_t=alpha_t, beta=beta,
        ha=rack["addendum_coefficient"], hf=rack["dedendum_coefficient"],
        width=mount["face_width_mm"] * 1e-3, density=mat["density_kg_m3"],
        teeth=(spec["gear1"]["teeth"], spec["gear2"]["teeth"]),
        bores=(spec["gear1"]["bore_radius_mm"] * 1e-3, spec["gear2"]["bore_radius_mm"] * 1e-3),
        backlash=mount["backlash_mm"] * 1e-3,
    )


def _annulus_inertia(density, width, r_out, r_in):
    return 0.5 * density * math.pi * width * (r_out**4 - r_in**4)


def test_involute_geometry(gear_case):
    g, mesh = _geometry(gear_case.spec_path), gear_case.mesh
    z1, z2 = g["teeth"]
    assert (mesh["teeth_1"], mesh["teeth_2"]) == (z1, z2)
    for key, z in (("base_radius_1_m", z1), ("base_radius_2_m", z2)):
        r_base = 0.5 * g["m_t"] * z * math.cos(g["alpha_t"])
        assert mesh[key] == pytest.approx(r_base, rel=1e-9), key
    # The mesh law is periodic in one transverse base pitch: p_b = 2π r_b / z for both gears.
    assert mesh["base_pitch_m"] == pytest.approx(2 * math.pi * mesh["base_radius_1_m"] / z1, rel=1e-12)
    assert mesh["base_pitch_m"] == pytest.approx(2 * math.pi * mesh["base_radius_2_m"] / z2, rel=1e-12)
    # The spec's backlash is the normal backlash j_bn along the line of action
    # (spur: the dump has exactly 0.1 mm, not 0.1 mm·cos α as a circumferential
    # value would give); the law works in the transverse plane, where
    # j_bt = j_bn / cos β_b with sin β_b = sin β · cos α_n (ISO 21771).
    alpha_n = math.atan(math.tan(g["alpha_t"]) * math.cos(g["beta"]))
    cos_beta_b = math.sqrt(1.0 - (math.sin(g["beta"]) * math.cos(alpha_n)) ** 2)
    assert mesh["backlash_m"] == pytest.approx(g["backlash"] / cos_beta_b, rel=1e-9)


def test_inertias_between_root_and_tip_annuli(gear_case):
    g, mesh = _geometry(gear_case.spec_path), gear_case.mesh
    for i, key in enumerate(("inertia_1_kgm2", "inertia_2_kgm2")):
        r_pitch = 0.5 * g["m_t"] * g["teeth"][i]
        r_root, r_tip = r_pitch - g["hf"] * g["m_n"], r_pitch + g["ha"] * g["m_n"]
        lower = _annulus_inertia(g["density"], g["width"], r_root, g["bores"][i])
        upper = _annulus_inertia(g["density"], g["width"], r_tip, g["bores"][i])
        assert lower < mesh[key] < upper, (key, lower, mesh[key], upper)


def test_stiffness_tables(gear_case, gear_fmus):
    mesh = gear_case.mesh
    roll = np.asarray(mesh["roll_m"])
    drive = np.asarray(mesh["drive_stiffness_n_per_m"])
    coast = np.asarray(mesh["coast_stiffness_n_per_m"])
    n = len(roll)
    assert n >= 8 and len(drive) == n and len(coast) == n
    np.testing.assert_allclose(roll, np.arange(n) * mesh["base_pitch_m"] / n, rtol=0, atol=1e-15)
    assert np.all(np.isfinite(drive)) and np.all(drive > 0)
    assert np.all(np.isfinite(coast)) and np.all(coast > 0)
    # The mean of a periodic piecewise-linear function on a uniform grid is the mean of its nodes.
    assert mesh["mean_drive_stiffness_n_per_m"] == pytest.approx(drive.mean(), rel=1e-2)
    # ISO 6336 mesh stiffness of steel gears is about 10-20 N/(mm·µm) per face width;
    # accept a factor of two either way.
    width_mm = _geometry(gear_case.spec_path)["width"] * 1e3
    per_width = mesh["mean_drive_stiffness_n_per_m"] / width_mm / 1e6
    assert 5.0 < per_width < 40.0, per_width


def test_helical_mesh_stiffness_is_smoother_than_spur(gear_fmus):
    def fluctuation(mesh):
        k = np.asarray(mesh["drive_stiffness_n_per_m"])
        return (k.max() - k.min()) / k.mean()

    spur, helical = fluctuation(gear_fmus["spur"].mesh), fluctuation(gear_fmus["helical"].mesh)
    assert spur > 0.1, "a spur pair with contact ratio ~1.6 alternates single/double contact"
    assert helical < spur
