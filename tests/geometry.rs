//! Gear geometry against closed forms: the involute, tooth thickness, the fillet's tangency at
//! the form circle, base pitch and contact ratios.

use gearfmu::fe::gear_mesh::{mesh_gear, MeshSpec};
use gearfmu::gear::{GearPair, PairSpec};
use std::f64::consts::PI;

const SPUR: &str = include_str!("../examples/kurokawa_spur.toml");
const HELICAL: &str = include_str!("../examples/kurokawa_helical.toml");

fn pair(text: &str) -> GearPair {
    GearPair::from_spec(&PairSpec::from_toml(text).unwrap()).unwrap()
}

/// With profile shift +0.3 on the pinion and −0.3 on the wheel (a V-zero pair).
fn shifted(text: &str) -> GearPair {
    let t = text.replacen("teeth = 21", "teeth = 21\nprofile_shift = 0.3", 1).replacen(
        "teeth = 31",
        "teeth = 31\nprofile_shift = -0.3",
        1,
    );
    pair(&t)
}

/// Every flank node of the mesh lies on one involute: with t = √(r²/r_b² − 1), the point is
/// r_b·(cos(θ₀ ∓ t) ± t·sin(θ₀ ∓ t), …) for a single θ₀ per flank (the unwound string).
#[test]
fn flank_points_lie_on_the_involute_to_1e_9_m() {
    for p in [pair(SPUR), shifted(SPUR)] {
        let gm = mesh_gear(&p, &p.gear1, &MeshSpec::default());
        let rb = p.gear1.base_radius_m;
        for side in [-1i8, 1] {
            let flank: Vec<_> =
                gm.flank_nodes.iter().filter(|f| f.tooth == 0 && f.side == side && f.slice == 0).collect();
            assert!(flank.len() >= 3);
            // θ₀ from the first point; the polar angle of an involute point is θ₀ ∓ inv(α) … so
            // reconstruct θ₀ from one point and regenerate every other point from the formula.
            let polar = |n: usize| gm.mesh.nodes[n][1].atan2(gm.mesh.nodes[n][0]);
            let radius = |n: usize| gm.mesh.nodes[n][0].hypot(gm.mesh.nodes[n][1]);
            let s = -(side as f64); // the right flank (+) unwinds clockwise
            let t0 = ((radius(flank[0].node) / rb).powi(2) - 1.0).sqrt();
            let theta0 = polar(flank[0].node) - s * (t0 - t0.atan());
            let mut worst: f64 = 0.0;
            for f in &flank {
                let t = ((radius(f.node) / rb).powi(2) - 1.0).sqrt();
                let a = theta0 + s * t;
                let point = [rb * (a.cos() + s * t * a.sin()), rb * (a.sin() - s * t * a.cos())];
                let node = gm.mesh.nodes[f.node];
                worst = worst.max((point[0] - node[0]).hypot(point[1] - node[1]));
            }
            println!("side {side}: largest distance from the involute {worst:.2e} m over {} points", flank.len());
            assert!(worst < 1e-9, "{worst}");
        }
    }
}

/// Arc tooth thickness at the reference circle s_t = m_t·π/2 + 2x·m_n·tan α_t (= m_t(π/2 + 2x_t tan α_t)
/// with the transverse shift x_t = x·m_n/m_t; the same as the form for spur gears).
#[test]
fn tooth_thickness_at_the_pitch_circle() {
    for p in [pair(SPUR), pair(HELICAL), shifted(SPUR), shifted(HELICAL)] {
        for g in [&p.gear1, &p.gear2] {
            let mt = p.normal_module_m / p.helix_angle_rad.cos();
            let expected =
                mt * PI / 2.0 + 2.0 * g.profile_shift * p.normal_module_m * p.transverse_pressure_angle_rad.tan();
            let measured = 2.0
                * g.pitch_radius_m
                * g.profile_half_thickness_angle(g.pitch_radius_m, p.transverse_pressure_angle_rad);
            assert!((measured - expected).abs() < 1e-12, "{measured} vs {expected}");
        }
    }
}

/// The generated fillet meets the involute at the form circle with the same position and
/// direction (dψ/dr), as a rack-generated fillet must.
#[test]
fn fillet_is_tangent_to_the_flank_at_the_form_circle() {
    for p in [pair(SPUR), pair(HELICAL), shifted(SPUR)] {
        let alpha = p.transverse_pressure_angle_rad;
        for g in [&p.gear1, &p.gear2] {
            let r = g.form_radius_m;
            // The fillet's own curve just below the form point (the table's interpolation) and the
            // involute just above it.
            let fillet = |rr: f64| {
                let i = g.fillet.partition_point(|&(x, _)| x < rr).clamp(1, g.fillet.len() - 1);
                let ((r0, a0), (r1, a1)) = (g.fillet[i - 1], g.fillet[i]);
                a0 + (a1 - a0) * (rr - r0) / (r1 - r0)
            };
            let h = 2e-5;
            let gap = (fillet(r) - g.half_thickness_angle(r, alpha)).abs() * r;
            let slope_fillet = (fillet(r) - fillet(r - h)) / h;
            let slope_involute = (g.half_thickness_angle(r + h, alpha) - g.half_thickness_angle(r, alpha)) / h;
            println!(
                "z = {}: form circle {:.4} mm, gap {:.2e} m, dψ/dr fillet {slope_fillet:.3} vs involute {slope_involute:.3} rad/m",
                g.teeth,
                r * 1e3,
                gap
            );
            assert!(gap < 2e-6, "position gap {gap} m");
            assert!((slope_fillet - slope_involute).abs() < 0.1 * slope_involute.abs() + 0.5, "direction differs");
        }
    }
}

/// Base pitch p_bt = π·m_t·cos α_t; ε_α from the textbook formula written out for standard
/// gears at standard center distance; ε_β = b·sin β/(π m_n) = b·tan β_b/p_bt.
#[test]
fn base_pitch_and_contact_ratios_match_closed_forms() {
    let p = pair(SPUR);
    let (m, alpha, z1, z2) = (6e-3, 20f64.to_radians(), 21.0, 31.0);
    let (ra1, ra2) = (m * (z1 / 2.0 + 1.0), m * (z2 / 2.0 + 1.0));
    let (rb1, rb2) = (m * z1 / 2.0 * alpha.cos(), m * z2 / 2.0 * alpha.cos());
    let a = m * (z1 + z2) / 2.0;
    let pb = PI * m * alpha.cos();
    let eps = ((ra1 * ra1 - rb1 * rb1).sqrt() + (ra2 * ra2 - rb2 * rb2).sqrt() - a * alpha.sin()) / pb;
    assert!((p.base_pitch_m - pb).abs() < 1e-15);
    assert!((p.transverse_contact_ratio - eps).abs() < 1e-12, "{} vs {eps}", p.transverse_contact_ratio);
    println!("spur: p_b = {:.6} mm, ε_α = {eps:.6}", pb * 1e3);

    let h = pair(HELICAL);
    let eps_beta = h.face_width_m * h.helix_angle_rad.sin() / (PI * h.normal_module_m);
    let via_base = h.face_width_m * h.base_helix_angle_rad.tan() / h.base_pitch_m;
    assert!((h.overlap_ratio - eps_beta).abs() < 1e-12 && (via_base - eps_beta).abs() < 1e-12);
    let mt = 6e-3 / 20f64.to_radians().cos();
    let alpha_t = (alpha.tan() / 20f64.to_radians().cos()).atan();
    assert!((h.base_pitch_m - PI * mt * alpha_t.cos()).abs() < 1e-15);
    println!("helical: ε_α = {:.6}, ε_β = {eps_beta:.6}", h.transverse_contact_ratio);
}
