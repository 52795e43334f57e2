//! Mesh stiffness after ISO 6336-1:2019, method B (Sect. 9): the independent reference the
//! analytic and FE mesh stiffness are checked against.

use crate::gear::GearPair;

/// Theoretical single stiffness c′_th = 1/q′ in N/(mm·µm), from the q′ series (ISO 6336-1, Eq. 42,
/// Table 9) with ISO's virtual tooth numbers z_n = z / (cos²β_b·cos β) (not the cruder z / cos³β,
/// which is 0.9 % larger at β = 15.8°).
pub fn theoretical_single_stiffness(pair: &GearPair) -> f64 {
    let virtual_factor = pair.base_helix_angle_rad.cos().powi(2) * pair.helix_angle_rad.cos();
    let zn1 = pair.gear1.teeth as f64 / virtual_factor;
    let zn2 = pair.gear2.teeth as f64 / virtual_factor;
    let (x1, x2) = (pair.gear1.profile_shift, pair.gear2.profile_shift);
    let q =
        0.04723 + 0.15551 / zn1 + 0.25791 / zn2 - 0.00635 * x1 - 0.11654 * x1 / zn1 - 0.00193 * x2 - 0.24188 * x2 / zn2
            + 0.00529 * x1 * x1
            + 0.00182 * x2 * x2;
    1.0 / q
}

/// Young's modulus the q′ series was fitted for: steel/steel pairs, E_st = 206 000 N/mm².
pub const STEEL_REFERENCE_MODULUS_PA: f64 = 206.0e9;

/// Material factor E/E_st by which ISO 6336-1 scales c′ and c_γ for pairs other than the steel
/// the q′ series was fitted on (E = 2E₁E₂/(E₁+E₂); both gears share one material here). The
/// Kurokawa pairs have E = 200 GPa (paper Table 3): 0.971.
pub fn material_factor(pair: &GearPair) -> f64 {
    pair.youngs_modulus_pa / STEEL_REFERENCE_MODULUS_PA
}

/// Single stiffness c′ = c′_th·C_M·C_R·C_B·cos β·E/E_st in N/(mm·µm): solid gear blanks
/// (C_R = 1), C_M = 0.8, the basic-rack factor C_B from the dedendum of the rack (h_fP/m_n), and
/// the material factor.
pub fn single_stiffness(pair: &GearPair) -> f64 {
    let dedendum_coefficient = pair.rack_dedendum_coefficient;
    let c_m = 0.8;
    let c_r = 1.0;
    let c_b = (1.0 + 0.5 * (1.2 - dedendum_coefficient))
        * (1.0 - 0.02 * (20.0 - pair.normal_pressure_angle_rad.to_degrees()));
    theoretical_single_stiffness(pair) * c_m * c_r * c_b * pair.helix_angle_rad.cos() * material_factor(pair)
}

/// Mean mesh stiffness c_γα = c′·(0.75 ε_α + 0.25) in N/(mm·µm) (ISO 6336-1 Eq. 43), valid for
/// specific loads F_t·K_A/b ≥ 100 N/mm.
pub fn mesh_stiffness_c_gamma_alpha(pair: &GearPair) -> f64 {
    single_stiffness(pair) * (0.75 * pair.transverse_contact_ratio + 0.25)
}

/// c_γα at a specific load w = F_t·K_A/b (N/mm): below 100 N/mm ISO 6336-1 (Sect. 9.1, the
/// note to Eq. 41) scales c′ by (w/100)^0.25 — the contact softens at light load.
pub fn mesh_stiffness_c_gamma_alpha_at(pair: &GearPair, specific_load_n_per_mm: f64) -> f64 {
    mesh_stiffness_c_gamma_alpha(pair) * light_load_factor(specific_load_n_per_mm)
}

/// ISO's (w/100)^0.25 below 100 N/mm, 1 above.
fn light_load_factor(specific_load_n_per_mm: f64) -> f64 {
    (specific_load_n_per_mm / 100.0).min(1.0).powf(0.25)
}

/// Converts a stiffness per face width in N/(mm·µm) to a total stiffness in N/m.
pub fn to_newton_per_metre(c_n_per_mm_um: f64, face_width_m: f64) -> f64 {
    c_n_per_mm_um * 1e6 * face_width_m * 1e3
}

/// c′ at a specific load w (N/mm), with the same (w/100)^0.25 light-load factor as
/// [`mesh_stiffness_c_gamma_alpha_at`].
pub fn single_stiffness_at(pair: &GearPair, specific_load_n_per_mm: f64) -> f64 {
    single_stiffness(pair) * light_load_factor(specific_load_n_per_mm)
}

/// The face load factor K_Hβ of ISO 6336-1 (method C, §7.6) from the effective equivalent
/// misalignment F_βy (µm) at a specific load F_m/b (N/mm): with c_γβ = 0.85·c_γα,
/// K_Hβ = 1 + F_βy·c_γβ/(2·F_m/b) where that is ≤ 2 (the contact covers the whole face), else
/// √(2·F_βy·c_γβ/(F_m/b)) (part of the face unloaded).
pub fn face_load_factor_k_h_beta(pair: &GearPair, f_beta_y_um: f64, specific_load_n_per_mm: f64) -> f64 {
    let c_gamma_beta = 0.85 * mesh_stiffness_c_gamma_alpha_at(pair, specific_load_n_per_mm);
    let x = f_beta_y_um * c_gamma_beta / specific_load_n_per_mm;
    if 1.0 + 0.5 * x <= 2.0 {
        1.0 + 0.5 * x
    } else {
        (2.0 * x).sqrt()
    }
}

/// Double-contact stiffness over c′ that c_γα implies for a spur pair whose stiffness is c′ over
/// the single-contact share 2 − ε_α of a pitch and c_d over the double-contact share ε_α − 1:
/// c′(2 − ε_α) + c_d(ε_α − 1) = c′(0.75 ε_α + 0.25) gives c_d = 1.75 c′ for every ε_α.
pub const IMPLIED_DOUBLE_OVER_SINGLE: f64 = 1.75;

/// The spur STE sorted by contact zone and set beside ISO 6336-1.
///
/// Every compliance in series with all tooth pairs (the torsion of the gear bodies between the
/// clamped bores and the teeth, which the bore radii set) adds the same amount to the STE in
/// single and in double contact. The single-zone stiffness and the double/single ratio move with
/// it; the zone contrast (STE₁ − STE₂)/(F/b) does not. ISO's c_γα = c′(0.75 ε_α + 0.25) read zone
/// by zone (see [`IMPLIED_DOUBLE_OVER_SINGLE`]) gives that contrast as (1 − 1/1.75)/c′.
#[derive(Debug, Clone, Copy)]
pub struct ZoneComparison {
    /// Mean STE (m) over the positions with one pair in contact, and their number.
    pub single_ste_m: f64,
    pub single_positions: usize,
    /// Mean STE (m) over the positions with two pairs in contact, and their number.
    pub double_ste_m: f64,
    pub double_positions: usize,
    /// Force along the line of action per face width over the single-zone mean STE, N/(mm·µm).
    pub single_stiffness: f64,
    /// ISO's c′ at this load, N/(mm·µm).
    pub iso_single_stiffness: f64,
    /// Double-zone stiffness over single-zone stiffness (STE₁ / STE₂); ISO: 1.75.
    pub double_over_single: f64,
    /// (STE₁ − STE₂)/(F/b) in mm·µm/N: the bore-independent figure.
    pub zone_contrast: f64,
    /// ISO's (1 − 1/1.75)/c′ in mm·µm/N.
    pub iso_zone_contrast: f64,
}

impl ZoneComparison {
    /// From one torque's sweep: (STE in m, pairs in contact) per position. `None` unless the pair
    /// is spur and both zones occur.
    pub fn from_sweep(pair: &GearPair, torque_nm: f64, positions: &[(f64, usize)]) -> Option<Self> {
        if pair.helix_angle_rad.abs() > 1e-12 {
            return None;
        }
        let zone = |n: usize| {
            let ste: Vec<f64> = positions.iter().filter(|p| p.1 == n).map(|p| p.0).collect();
            (!ste.is_empty()).then(|| (ste.iter().sum::<f64>() / ste.len() as f64, ste.len()))
        };
        let ((single, n1), (double, n2)) = (zone(1)?, zone(2)?);
        let b_mm = pair.face_width_m * 1e3;
        let line_load = torque_nm / pair.gear1.base_radius_m / b_mm; // N/mm along the line of action
        let iso_c = single_stiffness_at(pair, torque_nm / pair.gear1.pitch_radius_m / b_mm);
        Some(ZoneComparison {
            single_ste_m: single,
            single_positions: n1,
            double_ste_m: double,
            double_positions: n2,
            single_stiffness: line_load / (single * 1e6),
            iso_single_stiffness: iso_c,
            double_over_single: single / double,
            zone_contrast: (single - double) * 1e6 / line_load,
            iso_zone_contrast: (1.0 - 1.0 / IMPLIED_DOUBLE_OVER_SINGLE) / iso_c,
        })
    }
}
