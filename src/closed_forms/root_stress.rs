//! Nominal tooth-root bending stress of a loaded tooth (Lewis on the real profile): the guard
//! that tells a load the model can carry from one past the material's yield, where the
//! linear-elastic FE model and its reduction no longer hold.
//!
//! The normal force F acts on the flank at radius r along the line of action, tangent to the
//! base circle. In the tooth's frame (centreline = y axis) that line makes the angle
//! φ = α_r − ψ(r) with the x axis (α_r = arccos(r_b/r), ψ the half tooth-thickness angle), so it
//! crosses the centreline at y_L = r_b / cos φ. The section through the profile at radius ρ — the
//! chord s = 2ρ·sin ψ(ρ) at height y = ρ·cos ψ(ρ) — carries the moment F·cos φ·(y_L − y), so
//!   σ(ρ) = 6·F·cos φ·(y_L − y) / (b·s²).
//! Its maximum between the root circle and the load is the nominal root stress σ_F0. ISO 6336-3
//! takes the 30°-tangent section and multiplies by form and notch factors; the notch raises the
//! peak by 1.5–2 over this nominal value, so σ_F0 beyond the yield strength means a root far
//! past yield.

use crate::gear::{Gear, GearPair};

/// Sections sampled between the root circle and the load.
const SECTIONS: usize = 200;

/// σ_F0 (Pa) and the radius of its section, for a transverse force `force_n` (N) on `gear`'s
/// flank at `radius_m`, spread over `face_width_m`.
pub fn nominal_root_stress(
    gear: &Gear,
    transverse_pressure_angle: f64,
    face_width_m: f64,
    force_n: f64,
    radius_m: f64,
) -> (f64, f64) {
    let r = radius_m.clamp(gear.base_radius_m, gear.tip_radius_m);
    let psi_load = gear.profile_half_thickness_angle(r, transverse_pressure_angle);
    let phi = (gear.base_radius_m / r).min(1.0).acos() - psi_load;
    let y_load = gear.base_radius_m / phi.cos();
    let r_root = gear.fillet.first().map_or(gear.root_radius_m, |f| f.0);
    let mut worst = (0.0, r_root);
    for k in 0..=SECTIONS {
        let rho = r_root + (r - r_root) * k as f64 / SECTIONS as f64;
        let psi = gear.profile_half_thickness_angle(rho, transverse_pressure_angle);
        let (chord, height) = (2.0 * rho * psi.sin(), rho * psi.cos());
        let sigma = 6.0 * force_n * phi.cos() * (y_load - height) / (face_width_m * chord * chord);
        if sigma > worst.0 {
            worst = (sigma, rho);
        }
    }
    worst
}

/// `Err` naming the rule and the values when a tooth pair carrying the normal force `force_n` at
/// radii `radius_m` (on gear 1, gear 2) bends either root beyond `GearPair::yield_strength_pa`.
pub fn check_root_stress(pair: &GearPair, force_n: f64, radius_m: [f64; 2]) -> Result<(), String> {
    let transverse = force_n * pair.base_helix_angle_rad.cos();
    for (i, gear) in [&pair.gear1, &pair.gear2].into_iter().enumerate() {
        let (sigma, at) =
            nominal_root_stress(gear, pair.transverse_pressure_angle_rad, pair.face_width_m, transverse, radius_m[i]);
        if sigma > pair.yield_strength_pa {
            return Err(format!(
                "the nominal tooth-root bending stress of gear {} is σ_F0 = {:.0} MPa (Lewis, section at r = {:.2} mm, \
                 normal force {force_n:.4e} N at r = {:.2} mm), beyond material.yield_strength_mpa = {:.0} MPa: \
                 the root yields and the linear-elastic model does not hold; lower the load",
                i + 1,
                sigma * 1e-6,
                at * 1e3,
                radius_m[i] * 1e3,
                pair.yield_strength_pa * 1e-6
            ));
        }
    }
    Ok(())
}
