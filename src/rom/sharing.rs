//! Load-sharing shapes: the directions in which the tooth pairs in mesh share the load
//! differently from the static solution.
//!
//! One static shape per angular sample fixes how the load splits between the pairs in mesh: in
//! the floating frame the shape's amplitude scales, its split does not. Under a steady load that
//! split is right. Where a pair enters early under load or leaves late, the split depends on
//! the load: the entering pair's share grows with the deflection of the loaded one. A dynamic
//! mesh force changes the split, and a single shape cannot follow it. It holds the split and
//! overstates the stiffness at each pair's entry, exactly where the mesh mode is excited. The
//! DTE's peak-to-peak then depends on the ROM torque.
//!
//! A second static shape at another torque level adds no direction: PMOR-Hertz's global shapes
//! are nearly proportional to the load (the nonlinear part is the analytic Hertz law). Two
//! levels coincide to 1e-10 wherever the contact pattern does not change.
//!
//! A sharing shape is the gear's response to unit normal loads on every tooth pair near the
//! line of action, weighted by a smooth function of each section's position u along it:
//!
//!   w_m(ξ) = P_m(ξ)·(1 − ξ²)²,   ξ = (u − u_mid) / L,   |ξ| < 1,
//!
//! with P_m the Legendre polynomial of order m ≥ 1, u_mid the middle of the path of contact, and
//! L half the path plus half a base pitch. The window takes in the pairs just outside the path,
//! which premature contact under load reaches.
//!
//! - **Periodic by construction.** The weight depends only on u, and one pitch on every pair
//!   stands where the next stood. So the shape one pitch on is the tooth rotation of the first,
//!   column by column, as the closure S_{s+n_θ} = P·S_s needs.
//! - **Continuous in the angle.** The weights vanish with one continuous derivative at the
//!   window's ends. The load points follow each gear's crossing of the line of action and rest
//!   at the flank's ends beyond them (`FlankGrid::point_shares` clamps).
//! - **Never parallel to the static shape.** With two pairs in mesh, m = 1 loads them with
//!   opposite signs, where the static split has equal signs. With one pair at mid-path, its
//!   weight vanishes and the two neighbours carry the shape.

use super::reductor::ReducedGear;
use crate::contact::mesh_kinematics::PairPlacement;

/// The Legendre polynomial P_m(ξ).
fn legendre(m: usize, xi: f64) -> f64 {
    let (mut previous, mut current) = (1.0, xi);
    if m == 0 {
        return previous;
    }
    for k in 1..m {
        let next = ((2 * k + 1) as f64 * xi * current - k as f64 * previous) / (k + 1) as f64;
        previous = current;
        current = next;
    }
    current
}

/// The weight of the sharing shape of order m at position u along the line of action (m).
pub fn sharing_weight(placement: &PairPlacement, order: usize, u_m: f64) -> f64 {
    let p = &placement.pair;
    let middle = 0.5 * (p.path_start_m + p.path_end_m);
    let half_window = 0.5 * p.path_length_m() + 0.5 * p.base_pitch_m;
    let xi = (u_m - middle) / half_window;
    if xi.abs() >= 1.0 {
        return 0.0;
    }
    legendre(order, xi) * (1.0 - xi * xi).powi(2)
}

/// Gear i's reduced coordinates under the sharing load of order m, gear 2 at θ₂ within its
/// reference pitch and the gears rigid (TE = 0). Each axial section of each tooth pair in reach
/// carries a unit force along its flank's inward normals, times the weight at its crossing u of
/// the line of action. It acts at gear i's own crossing (gear 1: radius √(r_b1² + u²); gear 2:
/// √(r_b2² + (T₁T₂ − u)²)), clamped to the flank's extent.
pub fn sharing_load(placement: &PairPlacement, gear: &ReducedGear, i: usize, theta2: f64, order: usize) -> Vec<f64> {
    let p = &placement.pair;
    let (g1, g2) = (&p.gear1, &p.gear2);
    let own = if i == 0 { g1 } else { g2 };
    let z = &gear.flank.layer_z_m;
    let tan_bb = p.base_helix_angle_rad.tan();
    let hand = g1.helix_hand.sign();
    let loa = p.loa_length_m();
    let mut q = vec![0.0; gear.size()];
    for j in placement.pairs_in_reach() {
        let tooth = j.rem_euclid(own.teeth as i64) as usize;
        for s in 0..z.len() - 1 {
            let z_mid = 0.5 * (z[s] + z[s + 1]);
            let u = p.pitch_point_m() + g2.base_radius_m * theta2 + j as f64 * p.base_pitch_m + hand * z_mid * tan_bb;
            let w = sharing_weight(placement, order, u);
            if w == 0.0 {
                continue;
            }
            let r = if i == 0 { g1.base_radius_m.hypot(u) } else { g2.base_radius_m.hypot(loa - u) };
            let Some(shares) = gear.flank.point_shares(tooth, r, s) else { continue };
            let row = gear.inward_load_row(&shares);
            q.iter_mut().zip(&row).for_each(|(a, b)| *a += w * b);
        }
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the closed forms P₁ = ξ, P₂ = (3ξ² − 1)/2, P₃ = (5ξ³ − 3ξ)/2.
    #[test]
    fn legendre_polynomials_match_their_closed_forms() {
        for xi in [-0.9, -0.3, 0.0, 0.4, 1.0] {
            assert_eq!(legendre(0, xi), 1.0);
            assert!((legendre(1, xi) - xi).abs() < 1e-15);
            assert!((legendre(2, xi) - 0.5 * (3.0 * xi * xi - 1.0)).abs() < 1e-15);
            assert!((legendre(3, xi) - 0.5 * (5.0 * xi.powi(3) - 3.0 * xi)).abs() < 1e-15);
        }
    }
}
