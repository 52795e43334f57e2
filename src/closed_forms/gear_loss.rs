//! Mesh friction's kinematics and ISO/TR 14179-2's gear loss factor H_V (issue 42): the closed
//! forms the tooth friction of the dynamics is to be checked against.
//!
//! A contact at u (from T₁ along the transverse line of action) lies on two involutes whose radii
//! of curvature are ρ₁ = u and ρ₂ = T₁T₂ − u. Each flank's surface moves along the common tangent
//! at its gear's speed times its ρ, so the flanks slide at v_g = ω₁ρ₁ − ω₂ρ₂ (the speeds in each
//! gear's own sense of mesh rotation, design §3): zero at the pitch point C, where ω₁·r_b1 =
//! ω₂·r_b2, and of opposite sign on either side of it. The friction force μF acts along that
//! tangent, which is parallel to OᵢTᵢ (both are perpendicular to the line of action), so its
//! distance from the axis Oᵢ is TᵢP = ρᵢ: the friction torque on each gear is μF·ρᵢ, and it changes
//! sign at C with the sliding.
//!
//! Averaged over a mesh cycle with ISO's load sharing (the whole transverse load on a pair alone,
//! half of it on each of two pairs), the loss is P_V = μ·H_V·P_A with
//! H_V = π(u + 1)/(z₁·u·cos β_b) · (1 − ε_α + ε₁² + ε₂²), u = z₂/z₁, ε₁ and ε₂ the addendum
//! contact ratios of gear 1 (the recess, C to E) and of gear 2 (the approach, A to C)
//! (ISO/TR 14179-2:2001, after Ohlendorf; valid for 1 ≤ ε_α < 2 with ε₁, ε₂ < 1, which
//! `gear_loss_factor` checks).

use crate::gear::GearPair;

/// The flanks' sliding speed at a contact u (m from T₁ on the transverse line of action), m/s:
/// ω₁ρ₁ − ω₂ρ₂, positive where gear 1's flank runs ahead of gear 2's (beyond the pitch point
/// when the pair rolls forward: gear 1's addendum, the recess).
pub fn sliding_velocity_m_per_s(pair: &GearPair, u_m: f64, omega_1_rad_s: f64, omega_2_rad_s: f64) -> f64 {
    let (rho_1, rho_2) = pair.radii_of_curvature(u_m);
    omega_1_rad_s * rho_1 - omega_2_rad_s * rho_2
}

/// The arms (m) of a friction force along the common tangent at u about gear 1's and gear 2's
/// axes: the radii of curvature ρ₁ = u and ρ₂ = T₁T₂ − u.
pub fn friction_arms_m(pair: &GearPair, u_m: f64) -> [f64; 2] {
    let (rho_1, rho_2) = pair.radii_of_curvature(u_m);
    [rho_1, rho_2]
}

/// The addendum contact ratios [ε₁, ε₂]: gear 1's (pitch point C to the path's end E, the recess
/// when gear 1 drives) and gear 2's (the path's start A to C), each over the transverse base
/// pitch; ε₁ + ε₂ = ε_α.
pub fn addendum_contact_ratios(pair: &GearPair) -> [f64; 2] {
    let c = pair.pitch_point_m();
    [(pair.path_end_m - c) / pair.base_pitch_m, (c - pair.path_start_m) / pair.base_pitch_m]
}

/// ISO/TR 14179-2's gear loss factor H_V (module doc): P_V = μ·H_V·P_A, the mesh efficiency
/// 1 − μ·H_V. An error names the rule where the pair is outside the formula's range (ε_α < 1 or
/// ≥ 2, an addendum contact ratio ≥ 1, or the pitch point off the path).
pub fn gear_loss_factor(pair: &GearPair) -> Result<f64, String> {
    let [e1, e2] = addendum_contact_ratios(pair);
    let e_alpha = e1 + e2;
    if !(1.0..2.0).contains(&e_alpha) || !(0.0..1.0).contains(&e1) || !(0.0..1.0).contains(&e2) {
        return Err(format!(
            "ISO/TR 14179-2's H_V holds for 1 ≤ ε_α < 2 with each addendum contact ratio in [0, 1); this pair has \
             ε_α = {e_alpha:.4} (ε₁ = {e1:.4}, ε₂ = {e2:.4})"
        ));
    }
    let u = pair.gear2.teeth as f64 / pair.gear1.teeth as f64;
    Ok(std::f64::consts::PI * (u + 1.0) / (pair.gear1.teeth as f64 * u * pair.base_helix_angle_rad.cos())
        * (1.0 - e_alpha + e1 * e1 + e2 * e2))
}

/// The gear loss factor for a load spread evenly over the path of contact (per unit length of
/// the line of action), the limit a helical pair with ε_β ≥ 1 approaches as its inclined contact
/// lines sweep the plane of action: the same ISO normalization, with the mean of |u − C| over
/// A…E, (AC² + CE²)/(2·AE), in place of H_V's spur sharing. H_V,uniform = π(u + 1)/(z₁·u·cos β_b)
/// · (ε₁² + ε₂²)/ε_α: equal to H_V at ε_α = 1 (one pair carries it all), above it otherwise
/// (H_V's pairs share the double-contact zones' load by halves, which puts less of it at the
/// path's ends, where the arm is longest). Derived here, not ISO's.
pub fn gear_loss_factor_uniform_load(pair: &GearPair) -> f64 {
    let [e1, e2] = addendum_contact_ratios(pair);
    let u = pair.gear2.teeth as f64 / pair.gear1.teeth as f64;
    std::f64::consts::PI * (u + 1.0) / (pair.gear1.teeth as f64 * u * pair.base_helix_angle_rad.cos())
        * (e1 * e1 + e2 * e2)
        / (e1 + e2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gear::PairSpec;

    fn pair(toml: &str) -> GearPair {
        GearPair::from_spec(&PairSpec::from_toml(toml).unwrap()).unwrap()
    }

    fn examples() -> Vec<GearPair> {
        vec![
            pair(include_str!("../../examples/kurokawa_spur.toml")),
            pair(include_str!("../../examples/kurokawa_helical.toml")),
            pair(include_str!("../../examples/small_spur.toml")),
            pair(include_str!("../../examples/small_helical.toml")),
        ]
    }

    /// A contact at u in coordinates, the rigid-body evidence of the tests below. The frame: O₁
    /// at the origin, O₂ on +x at the centre distance; the line of action from T₁ (on gear 1's
    /// base circle) towards T₂, direction `loa`; `tangent` the flanks' common tangent. Gear 1
    /// turns counter-clockwise at ω₁, gear 2 clockwise at ω₂ (each its own sense of mesh
    /// rotation); each surface point moves at ω × r about its centre.
    struct RigidContact {
        loa: [f64; 2],
        tangent: [f64; 2],
        point: [f64; 2],
        from_2: [f64; 2],
        v1: [f64; 2],
        v2: [f64; 2],
    }

    fn rigid_contact(p: &GearPair, u: f64, w1: f64, w2: f64) -> RigidContact {
        let alpha = p.operating_pressure_angle_rad;
        let loa = [alpha.sin(), alpha.cos()];
        let t1 = [p.gear1.base_radius_m * alpha.cos(), -p.gear1.base_radius_m * alpha.sin()];
        let point = [t1[0] + u * loa[0], t1[1] + u * loa[1]];
        let from_2 = [point[0] - p.center_distance_m, point[1]];
        RigidContact {
            loa,
            tangent: [loa[1], -loa[0]],
            point,
            from_2,
            v1: [-w1 * point[1], w1 * point[0]],
            v2: [w2 * from_2[1], -w2 * from_2[0]],
        }
    }

    fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
        a[0] * b[0] + a[1] * b[1]
    }

    /// The sliding speed from the flanks' own surface speeds (evidence: rigid-body kinematics, no
    /// involute formula): each point of gear i moves at ωᵢ × r; the contact's two surface speeds
    /// along the common tangent (perpendicular to the line of action) differ by v_g, which is
    /// zero at the pitch point and (ω₁ + ω₂)·(u − C) along the path.
    #[test]
    fn the_sliding_speed_is_the_difference_of_the_flanks_surface_speeds() {
        for p in examples() {
            let (w1, w2) = (100.0, 100.0 * p.gear1.teeth as f64 / p.gear2.teeth as f64);
            for k in 0..=10 {
                let u = p.path_start_m + p.path_length_m() * k as f64 / 10.0;
                let RigidContact { loa, tangent, v1, v2, .. } = rigid_contact(&p, u, w1, w2);
                let along = |v: [f64; 2]| dot(v, tangent);
                assert!((dot(v1, loa) - dot(v2, loa)).abs() < 1e-9 * w1, "the flanks do not part along the normal");
                // Both surfaces move along −tangent when the pair rolls forward: gear 1's runs
                // ahead of gear 2's by along(v2) − along(v1).
                assert!(along(v1) <= 0.0 && along(v2) <= 0.0);
                let kinematic = along(v2) - along(v1);
                let closed = sliding_velocity_m_per_s(&p, u, w1, w2);
                assert!((kinematic - closed).abs() < 1e-9 * w1, "{}: u {u}: {kinematic} against {closed}", p.name);
                let linear = (w1 + w2) * (u - p.pitch_point_m());
                assert!((closed - linear).abs() < 1e-9 * w1, "{}: {closed} against (ω₁ + ω₂)(u − C) {linear}", p.name);
            }
            assert!(sliding_velocity_m_per_s(&p, p.pitch_point_m(), w1, w2).abs() < 1e-9 * w1);
        }
    }

    /// The friction torques (evidence: the moment of the friction force about each axis, from the
    /// coordinates and the flanks' rigid-body surface speeds): a unit force along the common
    /// tangent against gear 1's sliding relative to gear 2 (and its reaction on gear 2) has the
    /// moment −sgn(v_g)·ρ₁ about O₁ in gear 1's sense and +sgn(v_g)·ρ₂ about O₂ in gear 2's, the
    /// closed form's arms: friction drives gear 1 before the pitch point (its flank the slower)
    /// and brakes it after.
    #[test]
    fn the_friction_torques_have_the_radii_of_curvature_as_arms_and_turn_at_the_pitch_point() {
        for p in examples() {
            let (w1, w2) = (1.0, p.gear1.teeth as f64 / p.gear2.teeth as f64);
            let cross = |r: [f64; 2], f: [f64; 2]| r[0] * f[1] - r[1] * f[0];
            let mut sides = [false, false];
            for k in 0..=20 {
                let u = p.path_start_m + p.path_length_m() * (k as f64 + 0.25) / 20.5;
                let RigidContact { tangent, point, from_2, v1, v2, .. } = rigid_contact(&p, u, w1, w2);
                // Gear 1's surface against gear 2's, along the tangent; the friction on gear 1 opposes it.
                let slip = dot([v1[0] - v2[0], v1[1] - v2[1]], tangent);
                let on_1 = [-slip.signum() * tangent[0], -slip.signum() * tangent[1]];
                // Moments in each gear's own sense: counter-clockwise for gear 1, clockwise for gear 2.
                let torque_1 = cross(point, on_1);
                let torque_2 = -cross(from_2, [-on_1[0], -on_1[1]]);
                let v_g = sliding_velocity_m_per_s(&p, u, w1, w2);
                let arms = friction_arms_m(&p, u);
                assert!((torque_1 + v_g.signum() * arms[0]).abs() < 1e-12, "{}: u {u}: {torque_1}", p.name);
                assert!((torque_2 - v_g.signum() * arms[1]).abs() < 1e-12, "{}: u {u}: {torque_2}", p.name);
                let approach = u < p.pitch_point_m();
                assert_eq!(torque_1 > 0.0, approach, "{}: u {u}: friction drives gear 1 in the approach only", p.name);
                sides[approach as usize] = true;
            }
            assert_eq!(sides, [true, true], "{}: both sides of the pitch point sampled", p.name);
        }
    }

    /// The addendum contact ratios from the tip circles (evidence: the involute's roll length
    /// √(r_a² − r_b²) to each tip): ε₁ is gear 1's, from C to its tip, ε₂ gear 2's.
    #[test]
    fn the_addendum_contact_ratios_are_each_gears_tip_over_the_base_pitch() {
        for p in examples() {
            let [e1, e2] = addendum_contact_ratios(&p);
            let roll = |g: &crate::gear::Gear| (g.tip_radius_m.powi(2) - g.base_radius_m.powi(2)).sqrt();
            let c = p.pitch_point_m();
            let c_from_t2 = p.loa_length_m() - c;
            assert!((e1 * p.base_pitch_m - (roll(&p.gear1) - c)).abs() < 1e-12, "{}", p.name);
            assert!((e2 * p.base_pitch_m - (roll(&p.gear2) - c_from_t2)).abs() < 1e-12, "{}", p.name);
            assert!((e1 + e2 - p.transverse_contact_ratio).abs() < 1e-9, "{}", p.name);
        }
    }

    /// H_V against the mesh cycle it averages (evidence: the loss summed over roll positions):
    /// pairs one base pitch apart along the path, ISO's sharing (the load on one pair, half on
    /// each of two), the instantaneous loss μ·Σ F_j·|v_g(u_j)|/cos β_b over the input power
    /// F_bt·ω₁·r_b1, averaged over 20 000 positions.
    #[test]
    fn the_gear_loss_factor_is_the_mesh_cycle_mean_of_the_sliding_loss() {
        for p in examples() {
            let h_v = gear_loss_factor(&p).unwrap();
            let (w1, w2) = (1.0, p.gear1.teeth as f64 / p.gear2.teeth as f64);
            let positions = 20_000;
            let mut sum = 0.0;
            for k in 0..positions {
                let lead = p.path_start_m + p.base_pitch_m * (k as f64 + 0.5) / positions as f64;
                let in_contact: Vec<f64> = (0..3)
                    .map(|j| lead + j as f64 * p.base_pitch_m)
                    .filter(|u| (p.path_start_m..=p.path_end_m).contains(u))
                    .collect();
                let share = 1.0 / in_contact.len() as f64; // F_bt = 1 N
                sum += in_contact.iter().map(|&u| share * sliding_velocity_m_per_s(&p, u, w1, w2).abs()).sum::<f64>()
                    / p.base_helix_angle_rad.cos();
            }
            let mean = sum / positions as f64 / (w1 * p.gear1.base_radius_m);
            assert!((mean / h_v - 1.0).abs() < 1e-4, "{}: mean {mean} against H_V {h_v}", p.name);
        }
    }

    /// The uniform-load factor against the loss it averages (evidence: the loss integrated over
    /// the path with an even load per unit length, 20 000 points), and against H_V where they
    /// must agree (a path one base pitch long: one pair carries all).
    #[test]
    fn the_uniform_load_factor_is_the_path_mean_of_the_sliding_loss() {
        for p in examples() {
            let (w1, w2) = (1.0, p.gear1.teeth as f64 / p.gear2.teeth as f64);
            let points = 20_000;
            let length = p.path_end_m - p.path_start_m;
            let mean_sliding = (0..points)
                .map(|k| {
                    let u = p.path_start_m + length * (k as f64 + 0.5) / points as f64;
                    sliding_velocity_m_per_s(&p, u, w1, w2).abs()
                })
                .sum::<f64>()
                / points as f64;
            let mean = mean_sliding / p.base_helix_angle_rad.cos() / (w1 * p.gear1.base_radius_m);
            let uniform = gear_loss_factor_uniform_load(&p);
            assert!((mean / uniform - 1.0).abs() < 1e-4, "{}: mean {mean} against {uniform}", p.name);
            let c = p.pitch_point_m();
            // ε_α = 1 + 1e-9 (H_V's range starts at 1, which rounding could miss).
            let one_pitch =
                GearPair { path_start_m: c - 0.4 * p.base_pitch_m, path_end_m: c + (0.6 + 1e-9) * p.base_pitch_m, ..p };
            let (a, b) = (gear_loss_factor_uniform_load(&one_pitch), gear_loss_factor(&one_pitch).unwrap());
            assert!((a / b - 1.0).abs() < 1e-8, "{a} vs {b}");
        }
    }

    /// Outside its range the formula is refused with the rule, each bound on its own: ε_α below 1,
    /// an addendum contact ratio of 1 or more with ε_α below 2, and ε_α of 2 (the path moved
    /// along the line of action about the pitch point).
    #[test]
    fn the_gear_loss_factor_refuses_a_pair_outside_its_range() {
        let p = examples().remove(0);
        let c = p.pitch_point_m();
        let with_path = |e2: f64, e1: f64| GearPair {
            path_start_m: c - e2 * p.base_pitch_m,
            path_end_m: c + e1 * p.base_pitch_m,
            ..p.clone()
        };
        assert!(gear_loss_factor(&with_path(0.8, 0.7)).is_ok());
        for (e2, e1) in [(0.5, 0.4), (0.3, 1.2), (1.1, 0.5), (1.0, 1.0)] {
            let message = gear_loss_factor(&with_path(e2, e1)).unwrap_err();
            assert!(message.contains("1 ≤ ε_α < 2"), "{message}");
            assert!(message.contains(&format!("ε₁ = {e1:.4}, ε₂ = {e2:.4}")), "{message}");
        }
    }
}
