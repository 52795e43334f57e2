//! Gear-pair geometry and kinematics in SI units, built (and validated) from a [`PairSpec`].
//!
//! Conventions (design §3): gear 1 drives, gear 2 is driven; angles are positive in each gear's
//! own sense of mesh rotation (z₁θ₁ = z₂θ₂). Positions on the line of action (LOA) are lengths
//! `u` measured from T₁, the point where the LOA touches gear 1's base circle, towards T₂.

pub mod fillet;
mod from_spec;
pub mod involute;
pub mod lubrication;
pub mod mesh_spec;
pub mod modification;
pub mod spec;
pub mod spec_error;
pub use spec_error::sig;

use involute::inv;
use serde::{Deserialize, Serialize};
pub use spec::{HertzContact, PairSpec};
pub use spec_error::SpecError;
use std::f64::consts::PI;

/// The normal modules a spec may give (mm): below, the tooth is finer than a 3 mm-class FE mesh
/// and the Hertz band resolve together; above, no gear is made.
pub const MODULE_RANGE_MM: (f64, f64) = (0.1, 100.0);
/// The most teeth a gear may have: every tooth is meshed, so the FE model grows with z.
pub const MAX_TEETH: i64 = 500;
/// The largest tooth friction coefficient a spec or an FMU instance may set: dry steel on steel
/// (lubricated gear teeth run at 0.02–0.1).
pub const MAX_FRICTION_COEFFICIENT: f64 = 0.3;
/// Yield strengths a spec may give (MPa): from gear plastics to through-hardened steel.
pub const YIELD_RANGE_MPA: (f64, f64) = (20.0, 5000.0);

/// The default tip edge radius over the normal module (`GearSpec::tip_edge_radius_mm`).
pub const DEFAULT_TIP_EDGE_RADIUS_OVER_MODULE: f64 = 0.1;

/// One gear's radii and mass properties (SI).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Gear {
    pub teeth: u32,
    pub profile_shift: f64,
    pub pitch_radius_m: f64,
    pub base_radius_m: f64,
    pub tip_radius_m: f64,
    pub root_radius_m: f64,
    pub bore_radius_m: f64,
    /// Radius at which the generated involute ends and the trochoidal fillet begins.
    pub form_radius_m: f64,
    /// Half tooth-thickness angle at the reference (pitch) circle, transverse section.
    pub half_thickness_angle_pitch_rad: f64,
    /// The trochoidal root fillet as (radius, half tooth-thickness angle), root circle upwards.
    pub fillet: Vec<(f64, f64)>,
    pub inertia_kgm2: f64,
    /// Whether the spec gave the inertia (`inertia_kgm2`) instead of the profile's integral.
    #[serde(default)]
    pub inertia_overridden: bool,
    /// Radius of the rounded tip edge (the tip-corner body of the contact).
    pub tip_edge_radius_m: f64,
    /// Hand of the helix (gear 1's from the spec, gear 2's the opposite one).
    pub helix_hand: spec::HelixHand,
    /// Flank modifications (`[gearN.modification]`; none by default).
    #[serde(default)]
    pub modification: modification::FlankModification,
}

impl Gear {
    /// The roll length ρ = √(r² − r_b²) of the involute point at radius r (0 inside the base circle).
    pub fn roll_length_m(&self, radius_m: f64) -> f64 {
        (radius_m * radius_m - self.base_radius_m * self.base_radius_m).max(0.0).sqrt()
    }
}

impl Gear {
    /// Half tooth-thickness angle at radius r on the involute (transverse section).
    pub fn half_thickness_angle(&self, radius_m: f64, transverse_pressure_angle: f64) -> f64 {
        let alpha_r = (self.base_radius_m / radius_m).min(1.0).acos();
        self.half_thickness_angle_pitch_rad + inv(transverse_pressure_angle) - inv(alpha_r)
    }

    /// Area (m²) and polar moment of area about the axis (m⁴) of the transverse section, bore
    /// excluded, by quadrature of the real profile: z·∫2ψ(r)·rⁿ dr over the teeth plus the
    /// annulus bore → root circle.
    pub fn section_moments(&self, transverse_pressure_angle: f64) -> (f64, f64) {
        let (r_root, psi_root) = self.fillet.first().copied().unwrap_or((self.root_radius_m, PI / self.teeth as f64));
        let n = 20_000;
        let dr = (self.tip_radius_m - r_root) / n as f64;
        let (mut area, mut polar) = (0.0, 0.0);
        for i in 0..n {
            let r = r_root + (i as f64 + 0.5) * dr;
            let psi = self.profile_half_thickness_angle(r, transverse_pressure_angle).min(psi_root);
            area += 2.0 * psi * r * dr;
            polar += 2.0 * psi * r.powi(3) * dr;
        }
        let z = self.teeth as f64;
        let (rb4, rr4) = (self.bore_radius_m.powi(4), r_root.powi(4));
        (z * area + PI * (r_root * r_root - self.bore_radius_m.powi(2)), z * polar + PI / 2.0 * (rr4 - rb4))
    }

    /// Half tooth-thickness angle of the real profile at radius r: the generated fillet from the
    /// root circle up to where it meets the involute, the involute above.
    pub fn profile_half_thickness_angle(&self, radius_m: f64, transverse_pressure_angle: f64) -> f64 {
        // The involute holds from the form circle up (the rack's straight flank generates it);
        // the fillet table, whose discrete end lies near that point, is used only below it.
        match self.fillet.last() {
            Some(&(r_join, _)) if self.fillet.len() >= 2 && radius_m < r_join.min(self.form_radius_m) => {
                let i = self.fillet.partition_point(|&(r, _)| r < radius_m).clamp(1, self.fillet.len() - 1);
                let ((r0, a0), (r1, a1)) = (self.fillet[i - 1], self.fillet[i]);
                a0 + (a1 - a0) * (radius_m - r0) / (r1 - r0)
            }
            _ => self.half_thickness_angle(radius_m, transverse_pressure_angle),
        }
    }
}

/// A meshing pair, everything downstream needs about geometry and kinematics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GearPair {
    pub name: String,
    pub gear1: Gear,
    pub gear2: Gear,
    pub normal_module_m: f64,
    pub normal_pressure_angle_rad: f64,
    pub helix_angle_rad: f64,
    pub base_helix_angle_rad: f64,
    pub transverse_pressure_angle_rad: f64,
    pub face_width_m: f64,
    pub center_distance_m: f64,
    /// Operating transverse pressure angle, from the center distance.
    pub operating_pressure_angle_rad: f64,
    /// Transverse base pitch p_bt: distance between successive tooth pairs along the LOA.
    pub base_pitch_m: f64,
    /// Start (A, mating tip circle of gear 2) and end (E, tip circle of gear 1) of the path of
    /// contact, as distances from T₁ along the LOA.
    pub path_start_m: f64,
    pub path_end_m: f64,
    /// Transverse contact ratio ε_α and overlap ratio ε_β.
    pub transverse_contact_ratio: f64,
    pub overlap_ratio: f64,
    /// Total backlash measured along the transverse LOA.
    pub backlash_loa_m: f64,
    pub youngs_modulus_pa: f64,
    pub poisson_ratio: f64,
    pub density_kg_m3: f64,
    /// Yield strength: the bound of the tooth-root stress guard (`root_stress`).
    pub yield_strength_pa: f64,
    pub mesh_damping_ratio: f64,
    /// The tooth friction coefficient μ (`[friction]`, issue 42; 0: frictionless).
    #[serde(default)]
    pub friction_coefficient: f64,
    /// ISO/TR 14179-2's law for μ (`[friction] law = "iso-tr-14179-2"`): where given, the
    /// models take μ_mz from the load and speed instead of `friction_coefficient` (then 0).
    #[serde(default)]
    pub lubricated_flanks: Option<lubrication::LubricatedFlanks>,
    /// The design torque on gear 1 (N·m): the spec's `operating.torque_nm`, or the pair's rated
    /// torque (`rating::rated_torque_nm`). What the offline builds size their models on.
    pub operating_torque_nm: f64,
    /// Dedendum of the basic rack over the module, h_fP/m_n (ISO 6336-1's C_B needs it).
    pub rack_dedendum_coefficient: f64,
    /// Contact law of the lumped model.
    pub hertz_contact: HertzContact,
    /// Shaft misalignment in the plane of action across the face width (m; closes the +z end).
    #[serde(default)]
    pub misalignment_m: f64,
}

impl GearPair {
    /// Length T₁T₂ of the line of action between the base-circle tangent points.
    pub fn loa_length_m(&self) -> f64 {
        self.center_distance_m * self.operating_pressure_angle_rad.sin()
    }

    /// Pitch point C, distance from T₁.
    pub fn pitch_point_m(&self) -> f64 {
        self.gear1.base_radius_m * self.operating_pressure_angle_rad.tan()
    }

    /// Length of the path of contact AE.
    pub fn path_length_m(&self) -> f64 {
        self.path_end_m - self.path_start_m
    }

    /// Radii of curvature of the two involutes at a contact point u (from T₁) on the LOA,
    /// in the transverse plane: each is the distance to its own base-circle tangent point.
    pub fn radii_of_curvature(&self, u_m: f64) -> (f64, f64) {
        (u_m, self.loa_length_m() - u_m)
    }

    /// Radius on gear 1 and on gear 2 of the contact point at u (from T₁).
    pub fn contact_radii(&self, u_m: f64) -> (f64, f64) {
        let (rho1, rho2) = self.radii_of_curvature(u_m);
        (self.gear1.base_radius_m.hypot(rho1), self.gear2.base_radius_m.hypot(rho2))
    }
}
