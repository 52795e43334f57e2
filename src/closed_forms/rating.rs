//! The loads a pair is built for: its rated torque (the default operating point of a spec
//! without `[operating] torque_nm`) and its yield torque (where the linear-elastic model ends).
//!
//! Both come from the nominal tooth-root stress σ_F0 of `root_stress` (Lewis on the real
//! profile) with the whole normal force on one tooth pair at the tip of the weaker gear — the
//! worst place a single pair can carry it, and independent of how the pairs share the load:
//! - the **yield torque** puts σ_F0 at the yield strength: the guard of the statics refuses any
//!   case beyond it;
//! - the **rated torque** is a third of it. ISO 6336-3's root stress is σ_F0 times a notch
//!   factor Y_S ≈ 2 (`root_stress`: 1.5–2), and a safety factor S_F = 1.5 against the
//!   permissible stress leaves σ_F0 ≤ yield / (Y_S·S_F) = yield / 3. A design load, not a
//!   fatigue rating: a spec that knows its load says so in `[operating] torque_nm`.
//!
//! The Kurokawa spur pair (m 6 mm, b 15 mm, 1000 MPa) rates at 652 N·m (yield 1956 N·m), above
//! the paper's largest static load, 370 N·m; the small spur example (m 2.5 mm, b 18 mm,
//! 850 MPa) at 142 N·m.

use super::root_stress::nominal_root_stress;
use crate::gear::GearPair;

/// σ_F0 at the rated torque as a share of the yield strength: 1/(Y_S·S_F) with Y_S = 2, S_F = 1.5.
pub const RATED_ROOT_STRESS_OVER_YIELD: f64 = 1.0 / 3.0;

/// The torque on gear 1 (N·m) at which σ_F0 of the weaker gear, the whole load on one pair at its
/// tip, reaches `share` × the yield strength.
fn torque_at_root_stress(pair: &GearPair, share: f64) -> f64 {
    // σ_F0 is linear in the force: its value for a unit normal force scales.
    let unit_normal_force = 1.0;
    let transverse = unit_normal_force * pair.base_helix_angle_rad.cos();
    let stress_per_newton = [&pair.gear1, &pair.gear2]
        .iter()
        .map(|gear| {
            nominal_root_stress(
                gear,
                pair.transverse_pressure_angle_rad,
                pair.face_width_m,
                transverse,
                gear.tip_radius_m,
            )
            .0
        })
        .fold(0.0, f64::max);
    let normal_force_n = share * pair.yield_strength_pa / stress_per_newton;
    // The normal force's transverse part acts along the line of action, at gear 1's base radius.
    normal_force_n * pair.base_helix_angle_rad.cos() * pair.gear1.base_radius_m
}

/// The rated torque on gear 1 (N·m): σ_F0 at [`RATED_ROOT_STRESS_OVER_YIELD`] of the yield.
pub fn rated_torque_nm(pair: &GearPair) -> f64 {
    torque_at_root_stress(pair, RATED_ROOT_STRESS_OVER_YIELD)
}

/// The yield torque on gear 1 (N·m): σ_F0 at the yield strength, one pair at the tip.
pub fn yield_torque_nm(pair: &GearPair) -> f64 {
    torque_at_root_stress(pair, 1.0)
}

/// The mesh force along the transverse line of action (N, the FMUs' `mesh_force`) at which one
/// pair carrying it at the tip reaches the yield strength: the run-time guard of both FMUs (a
/// mesh force beyond it is logged once).
pub fn yield_mesh_force_n(pair: &GearPair) -> f64 {
    yield_torque_nm(pair) / pair.gear1.base_radius_m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::closed_forms::root_stress::check_root_stress;
    use crate::gear::PairSpec;

    fn kurokawa_spur() -> GearPair {
        let spec = PairSpec::from_toml(include_str!("../../examples/kurokawa_spur.toml")).unwrap();
        GearPair::from_spec(&spec).unwrap()
    }

    /// The yield torque is where the statics' own guard (`check_root_stress`, one pair at the tip)
    /// starts refusing: 0.5 % below it passes, 0.5 % above it is refused.
    #[test]
    fn the_yield_torque_is_where_the_root_stress_guard_refuses() {
        let pair = kurokawa_spur();
        let force_at = |torque: f64| torque / (pair.gear1.base_radius_m * pair.base_helix_angle_rad.cos());
        let tips = [pair.gear1.tip_radius_m, pair.gear2.tip_radius_m];
        let t = yield_torque_nm(&pair);
        // The guard loads one gear's tip and the mate at the matching radius; load each tip in turn.
        let radii_at_tip =
            |i: usize| if i == 0 { [tips[0], pair.gear2.base_radius_m] } else { [pair.gear1.base_radius_m, tips[1]] };
        let passes = |torque: f64| (0..2).all(|i| check_root_stress(&pair, force_at(torque), radii_at_tip(i)).is_ok());
        assert!(passes(0.995 * t), "refused below the yield torque {t} N·m");
        assert!(!passes(1.005 * t), "accepted above the yield torque {t} N·m");
        assert!((rated_torque_nm(&pair) * 3.0 / t - 1.0).abs() < 1e-12);
    }

    /// Closed form (Lewis): σ = 6·F·h/(b·s²) for the nominal stress at the critical section, so the
    /// rated torque scales as b·m² on geometrically similar pairs. Doubling the face width doubles
    /// it; doubling the module (and the bores) multiplies it by 8 (b·m² times r_b ∝ m).
    #[test]
    fn the_rated_torque_scales_as_lewis_says() {
        let text = include_str!("../../examples/kurokawa_spur.toml");
        let pair_of = |t: &str| GearPair::from_spec(&PairSpec::from_toml(t).unwrap()).unwrap();
        let base = rated_torque_nm(&pair_of(text));
        let wide = rated_torque_nm(&pair_of(&text.replace("face_width_mm = 15.0", "face_width_mm = 30.0")));
        assert!((wide / base - 2.0).abs() < 1e-9, "{wide} / {base}");
        let big = text
            .replace("module_mm = 6.0", "module_mm = 12.0")
            .replace("face_width_mm = 15.0", "face_width_mm = 30.0")
            .replace("bore_radius_mm = 20.0", "bore_radius_mm = 40.0")
            .replace("bore_radius_mm = 25.0", "bore_radius_mm = 50.0")
            .replace("backlash_mm = 0.1", "backlash_mm = 0.2");
        let big = rated_torque_nm(&pair_of(&big));
        // The fillet and the tip edge scale with m too; the section search samples 200 radii.
        assert!((big / base / 8.0 - 1.0).abs() < 1e-3, "{big} / {base} = {}", big / base);
    }
}
