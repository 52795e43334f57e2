//! The tooth friction coefficient of a lubricated pair as ISO/TR 14179-2 gives it (issue 42):
//! the mean coefficient of friction along the path of contact, μ_mz, from the load, the speed,
//! the oil and the flanks' roughness. It is Schlenk's fit to FZG gear tests, the one ISO/TR
//! 14179-2 (and, with other constants, ISO/TS 6336-20's integral temperature method) uses:
//!
//!   μ_mz = 0.048 · (F_bt/b / (v_ΣC·ρ_redC))^0.2 · η_oil^−0.05 · Ra^0.25 · X_L
//!
//! in the standard's units, which the fit's constant carries: F_bt the transverse force along the
//! line of action (N), b the face width (mm), v_ΣC = 2·v_t·sin α_wt the sum of the flanks'
//! rolling speeds at the pitch point (m/s), ρ_redC the relative radius of curvature there in the
//! normal section (mm), η_oil the oil's dynamic viscosity at its running temperature (mPa·s), Ra
//! the mean arithmetic roughness of the two flanks (µm) and X_L the lubricant factor (1.0 for
//! mineral oil; ISO/TR 14179-2 tabulates it per oil type).
//!
//! Why this law: a drivetrain engineer's loss figure comes from it (it is also what the FVA and
//! Niemann/Winter loss methods use), and it carries the three dependences a constant μ lacks —
//! μ falls with speed (a thicker film), rises with load and roughness. It is a mean over the
//! path: the models apply it at every contact, as they apply a constant μ.
//!
//! Where it stops: the fit describes running gears in mixed and elasto-hydrodynamic
//! lubrication, and grows without bound as the speed falls (v^−0.2). Below
//! `MIN_SUM_VELOCITY_M_PER_S` the models hold μ_mz at its value there and say so once (a run-up
//! from rest, a reversal): that is boundary lubrication, which the fit does not describe.

use serde::{Deserialize, Serialize};

/// The sum velocity at the pitch point below which μ_mz is held (m/s): 1 m/s, a pitch-line speed
/// of about 1.5 m/s on a 20° pair. Our choice, not the standard's: the fit's own data are from
/// running gears; below it μ_mz would rise as v^−0.2 without a physical bound.
pub const MIN_SUM_VELOCITY_M_PER_S: f64 = 1.0;

pub use crate::gear::lubrication::LubricatedFlanks;

/// The pair's pitch-point geometry the law reads.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PitchPointGeometry {
    pub face_width_m: f64,
    /// r_w1 = r_b1 / cos α_wt: gear 1's operating pitch radius (m).
    pub pitch_radius_1_m: f64,
    pub operating_pressure_angle_rad: f64,
    /// ρ_redC: the relative radius of curvature at the pitch point, normal section (m).
    pub relative_curvature_radius_m: f64,
}

impl PitchPointGeometry {
    pub fn of_pair(pair: &crate::gear::GearPair) -> Self {
        let alpha = pair.operating_pressure_angle_rad;
        // The involutes' radii of curvature at C are the tangent lengths T₁C and T₂C; in the
        // normal section each is divided by cos β_b.
        let (rho_1, rho_2) = pair.radii_of_curvature(pair.pitch_point_m());
        PitchPointGeometry {
            face_width_m: pair.face_width_m,
            pitch_radius_1_m: pair.gear1.base_radius_m / alpha.cos(),
            operating_pressure_angle_rad: alpha,
            relative_curvature_radius_m: rho_1 * rho_2 / (rho_1 + rho_2) / pair.base_helix_angle_rad.cos(),
        }
    }

    /// v_ΣC = 2·|ω₁|·r_w1·sin α_wt (m/s).
    pub fn sum_velocity_m_per_s(&self, omega_1_rad_s: f64) -> f64 {
        2.0 * omega_1_rad_s.abs() * self.pitch_radius_1_m * self.operating_pressure_angle_rad.sin()
    }
}

/// μ_mz at one operating point, and whether the speed was below the law's floor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeanFriction {
    pub coefficient: f64,
    /// v_ΣC was below `MIN_SUM_VELOCITY_M_PER_S`: μ_mz is the floor's.
    pub held_at_low_speed: bool,
}

impl LubricatedFlanks {
    /// μ_mz under a transverse mesh force `transverse_force_n` (N, along the line of action; its
    /// size is taken) with gear 1 at ω₁ (rad/s).
    pub fn mean_coefficient(
        &self,
        g: &PitchPointGeometry,
        transverse_force_n: f64,
        omega_1_rad_s: f64,
    ) -> MeanFriction {
        let v = g.sum_velocity_m_per_s(omega_1_rad_s);
        let held_at_low_speed = v < MIN_SUM_VELOCITY_M_PER_S;
        let v = v.max(MIN_SUM_VELOCITY_M_PER_S);
        // The standard's units: N/mm over (m/s · mm); mPa·s; µm.
        let load_n_per_mm = transverse_force_n.abs() / (g.face_width_m * 1e3);
        let rho_mm = g.relative_curvature_radius_m * 1e3;
        let coefficient = 0.048
            * (load_n_per_mm / (v * rho_mm)).powf(0.2)
            * self.oil_viscosity_mpa_s.powf(-0.05)
            * self.roughness_ra_um.powf(0.25)
            * self.lubricant_factor;
        MeanFriction { coefficient, held_at_low_speed }
    }

    /// The largest μ_mz the models answer for: at the speed floor under `max_force_n`. What the
    /// friction's regularization is sized on.
    pub fn largest_coefficient(&self, g: &PitchPointGeometry, max_force_n: f64) -> f64 {
        self.mean_coefficient(g, max_force_n, 0.0).coefficient
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry() -> PitchPointGeometry {
        // A 20° pair, r_w1 = 40 mm, ρ_redC = 8 mm, b = 20 mm.
        PitchPointGeometry {
            face_width_m: 0.02,
            pitch_radius_1_m: 0.04,
            operating_pressure_angle_rad: 20f64.to_radians(),
            relative_curvature_radius_m: 0.008,
        }
    }

    const OIL: LubricatedFlanks =
        LubricatedFlanks { oil_viscosity_mpa_s: 30.0, roughness_ra_um: 0.5, lubricant_factor: 1.0 };

    /// Closed form: the fit evaluated by hand at 2000 N (100 N/mm), ω₁ = 100 rad/s:
    /// v_ΣC = 2·4·sin 20° = 2.736 m/s, so μ = 0.048·(100/(2.736·8))^0.2·30^−0.05·0.5^0.25.
    #[test]
    fn mean_coefficient_is_the_fit_in_the_standards_units() {
        let v = 2.0 * 4.0 * 20f64.to_radians().sin();
        let by_hand = 0.048 * (100.0 / (v * 8.0)).powf(0.2) * 30f64.powf(-0.05) * 0.5f64.powf(0.25);
        let mu = OIL.mean_coefficient(&geometry(), -2000.0, 100.0);
        assert!((mu.coefficient - by_hand).abs() < 1e-15, "{} vs {by_hand}", mu.coefficient);
        assert!(!mu.held_at_low_speed);
        assert!((0.03..0.07).contains(&mu.coefficient), "a lubricated steel pair's μ: {}", mu.coefficient);
    }

    /// Its dependences: μ ∝ F^0.2 and v^−0.2 above the floor; held (and flagged) below it.
    #[test]
    fn mean_coefficient_falls_with_speed_rises_with_load_and_is_held_below_the_floor() {
        let g = geometry();
        let mu = |f: f64, w: f64| OIL.mean_coefficient(&g, f, w).coefficient;
        assert!((mu(2000.0, 200.0) / mu(2000.0, 100.0) - 0.5f64.powf(0.2)).abs() < 1e-12);
        assert!((mu(4000.0, 100.0) / mu(2000.0, 100.0) - 2f64.powf(0.2)).abs() < 1e-12);
        let floor_omega = MIN_SUM_VELOCITY_M_PER_S / g.sum_velocity_m_per_s(1.0);
        let slow = OIL.mean_coefficient(&g, 2000.0, 0.1 * floor_omega);
        assert!(slow.held_at_low_speed);
        assert_eq!(slow.coefficient, mu(2000.0, floor_omega));
        assert_eq!(OIL.largest_coefficient(&g, 2000.0), slow.coefficient);
    }
}
