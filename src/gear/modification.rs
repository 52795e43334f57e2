//! Flank modifications (ISO 21771-1 names) and shaft misalignment: what a gear engineer grinds
//! into the flanks or gets from the mounting, as a deviation δ normal to the flank, in metres of
//! material removed (δ > 0 opens the gap). The contact reads δ where it reads the rigid gap, so
//! the flank grid, the FE model and the reduction stay those of the unmodified gear.
//!
//! Per gear, on its own flank: δ(ρ, z) = profile(ρ) + lead(z), ρ the roll length (distance from
//! the base circle's tangent point along the involute's generating line) and z the gear's own
//! axial coordinate, zero mid-face.
//! - tip relief C_a over the roll length L_Ca below the tip: C_a·s (linear) or C_a·s²
//!   (parabolic), s = (ρ − (ρ_a − L_Ca))/L_Ca ∈ [0, 1];
//! - root relief C_f over L_Cf above the start of the active profile (SAP), the same shapes;
//! - profile crowning C_α over the active profile: C_α·(2(ρ − ρ_mid)/L_α)²;
//! - lead crowning C_β: C_β·(2z/b)²;
//! - helix slope deviation f_Hβ: −f_Hβ·z/b (the flank at +z stands proud of the −z end by f_Hβ);
//! - end relief C_e at both face ends over L_Ce: C_e·(|z| − (b/2 − L_Ce))/L_Ce where positive.
//!
//! The pair: a misalignment f_ma in the plane of action closes the +z end: −f_ma·z/b in gear 1's
//! (the world's) z.

use super::spec_error::{invalid, SpecError};
use serde::{Deserialize, Serialize};

/// The shape of a relief over its length.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ReliefShape {
    #[default]
    Linear,
    Parabolic,
}

impl ReliefShape {
    fn at(self, s: f64) -> f64 {
        match self {
            ReliefShape::Linear => s,
            ReliefShape::Parabolic => s * s,
        }
    }
}

/// `[gearN.modification]` as written (µm and mm in the keys).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModificationSpec {
    #[serde(default)]
    pub tip_relief_um: f64,
    /// L_Ca: the roll length below the tip over which the tip relief acts.
    #[serde(default)]
    pub tip_relief_length_mm: f64,
    #[serde(default)]
    pub tip_relief_shape: ReliefShape,
    #[serde(default)]
    pub root_relief_um: f64,
    /// L_Cf: the roll length above the start of the active profile.
    #[serde(default)]
    pub root_relief_length_mm: f64,
    #[serde(default)]
    pub root_relief_shape: ReliefShape,
    #[serde(default)]
    pub profile_crowning_um: f64,
    #[serde(default)]
    pub lead_crowning_um: f64,
    #[serde(default)]
    pub helix_slope_um: f64,
    #[serde(default)]
    pub end_relief_um: f64,
    /// L_Ce: the axial length from each face end over which the end relief acts.
    #[serde(default)]
    pub end_relief_length_mm: f64,
}

/// One gear's modification in SI, with the active profile it was checked against.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct FlankModification {
    pub tip_relief_m: f64,
    pub tip_relief_length_m: f64,
    pub tip_relief_shape: ReliefShape,
    pub root_relief_m: f64,
    pub root_relief_length_m: f64,
    pub root_relief_shape: ReliefShape,
    pub profile_crowning_m: f64,
    pub lead_crowning_m: f64,
    pub helix_slope_m: f64,
    pub end_relief_m: f64,
    pub end_relief_length_m: f64,
    /// The active profile's roll lengths: the start (SAP, where the mate's tip reaches) and the tip.
    pub active_roll_m: [f64; 2],
    pub face_width_m: f64,
}

impl FlankModification {
    /// Whether any deviation is nonzero.
    pub fn is_some(&self) -> bool {
        [
            self.tip_relief_m,
            self.root_relief_m,
            self.profile_crowning_m,
            self.lead_crowning_m,
            self.helix_slope_m,
            self.end_relief_m,
        ]
        .iter()
        .any(|&x| x != 0.0)
    }

    /// δ (m, material removed, normal to the flank) at roll length ρ and own axial z.
    pub fn deviation_m(&self, roll_m: f64, z_m: f64) -> f64 {
        let [sap, tip] = self.active_roll_m;
        let mut d = 0.0;
        if self.tip_relief_m > 0.0 {
            let s = ((roll_m - (tip - self.tip_relief_length_m)) / self.tip_relief_length_m).clamp(0.0, 1.0);
            d += self.tip_relief_m * self.tip_relief_shape.at(s);
        }
        if self.root_relief_m > 0.0 {
            let s = (((sap + self.root_relief_length_m) - roll_m) / self.root_relief_length_m).clamp(0.0, 1.0);
            d += self.root_relief_m * self.root_relief_shape.at(s);
        }
        if self.profile_crowning_m > 0.0 {
            let x = (2.0 * roll_m - (sap + tip)) / (tip - sap);
            d += self.profile_crowning_m * x * x;
        }
        let b = self.face_width_m;
        d += self.lead_crowning_m * (2.0 * z_m / b).powi(2) - self.helix_slope_m * z_m / b;
        if self.end_relief_m > 0.0 {
            let s = ((z_m.abs() - (0.5 * b - self.end_relief_length_m)) / self.end_relief_length_m).clamp(0.0, 1.0);
            d += self.end_relief_m * s;
        }
        d
    }

    /// dδ/dρ (the profile part: the contact's angle derivatives need it).
    pub fn slope_per_roll(&self, roll_m: f64) -> f64 {
        let h = 1e-7;
        (self.deviation_m(roll_m + h, 0.0) - self.deviation_m(roll_m - h, 0.0)) / (2.0 * h)
    }
}

/// The largest amount accepted, as a share of the normal module: a deeper one removes the
/// involute it is meant to modify (ISO 21771-1's reliefs are tens of µm on modules of mm).
pub const MAX_AMOUNT_OVER_MODULE: f64 = 0.1;

/// Checks a gear's `[modification]` against its active profile and face width and converts it.
pub fn build(
    which: &str,
    spec: &ModificationSpec,
    active_roll_m: [f64; 2],
    face_width_m: f64,
    normal_module_m: f64,
) -> Result<FlankModification, SpecError> {
    let field = |name: &str| format!("{which}.modification.{name}");
    let amount = |name: &str, um: f64| -> Result<f64, SpecError> {
        let limit_um = MAX_AMOUNT_OVER_MODULE * normal_module_m * 1e6;
        if !(um.is_finite() && um >= 0.0) {
            return Err(invalid(&field(name), format!("must be a finite amount ≥ 0 µm, got {um}")));
        }
        if um > limit_um {
            return Err(invalid(
                &field(name),
                format!("{um} µm is deeper than {MAX_AMOUNT_OVER_MODULE} × the normal module ({limit_um:.0} µm): it would remove the flank it modifies"),
            ));
        }
        Ok(um * 1e-6)
    };
    let helix_slope = spec.helix_slope_um;
    if !helix_slope.is_finite() || helix_slope.abs() > MAX_AMOUNT_OVER_MODULE * normal_module_m * 1e6 {
        return Err(invalid(
            &field("helix_slope_um"),
            format!(
                "must be finite and within ±{:.0} µm, got {helix_slope}",
                MAX_AMOUNT_OVER_MODULE * normal_module_m * 1e6
            ),
        ));
    }
    let active = active_roll_m[1] - active_roll_m[0];
    let length = |name: &str, mm: f64, amount_m: f64, span_m: f64, span: &str| -> Result<f64, SpecError> {
        if amount_m == 0.0 && mm == 0.0 {
            return Ok(0.0);
        }
        if !(mm.is_finite() && mm > 0.0) {
            return Err(invalid(&field(name), format!("a relief needs its length > 0 mm, got {mm}")));
        }
        if mm * 1e-3 > span_m + 1e-12 {
            return Err(invalid(
                &field(name),
                format!("{mm} mm starts outside the {span} ({:.3} mm): the relief must start on it", span_m * 1e3),
            ));
        }
        Ok(mm * 1e-3)
    };
    let tip = amount("tip_relief_um", spec.tip_relief_um)?;
    let root = amount("root_relief_um", spec.root_relief_um)?;
    let end = amount("end_relief_um", spec.end_relief_um)?;
    let m = FlankModification {
        tip_relief_m: tip,
        tip_relief_length_m: length("tip_relief_length_mm", spec.tip_relief_length_mm, tip, active, "active profile")?,
        tip_relief_shape: spec.tip_relief_shape,
        root_relief_m: root,
        root_relief_length_m: length(
            "root_relief_length_mm",
            spec.root_relief_length_mm,
            root,
            active,
            "active profile",
        )?,
        root_relief_shape: spec.root_relief_shape,
        profile_crowning_m: amount("profile_crowning_um", spec.profile_crowning_um)?,
        lead_crowning_m: amount("lead_crowning_um", spec.lead_crowning_um)?,
        helix_slope_m: helix_slope * 1e-6,
        end_relief_m: end,
        end_relief_length_m: length(
            "end_relief_length_mm",
            spec.end_relief_length_mm,
            end,
            0.5 * face_width_m,
            "half face width",
        )?,
        active_roll_m,
        face_width_m,
    };
    if m.tip_relief_length_m + m.root_relief_length_m > active + 1e-12 {
        return Err(invalid(
            &field("root_relief_length_mm"),
            format!(
                "tip and root relief lengths ({:.3} + {:.3} mm) overlap on the active profile ({:.3} mm)",
                m.tip_relief_length_m * 1e3,
                m.root_relief_length_m * 1e3,
                active * 1e3
            ),
        ));
    }
    Ok(m)
}

/// The pair's misalignment in the plane of action (m): −f_ma·z/b at world z.
pub fn misalignment_deviation_m(misalignment_m: f64, face_width_m: f64, z_m: f64) -> f64 {
    -misalignment_m * z_m / face_width_m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gear(spec: ModificationSpec) -> Result<FlankModification, SpecError> {
        build("gear1", &spec, [5e-3, 20e-3], 20e-3, 4e-3)
    }

    /// Closed forms: a linear tip relief is C_a at the tip, half of it mid-way, zero below its
    /// start; a parabolic one a quarter mid-way; lead crowning C_β at the face ends.
    #[test]
    fn deviations_follow_their_iso_21771_shapes() {
        let linear =
            gear(ModificationSpec { tip_relief_um: 20.0, tip_relief_length_mm: 4.0, ..Default::default() }).unwrap();
        assert!((linear.deviation_m(20e-3, 0.0) - 20e-6).abs() < 1e-15);
        assert!((linear.deviation_m(18e-3, 0.0) - 10e-6).abs() < 1e-15);
        assert_eq!(linear.deviation_m(15e-3, 0.0), 0.0);
        let parabolic = gear(ModificationSpec {
            tip_relief_um: 20.0,
            tip_relief_length_mm: 4.0,
            tip_relief_shape: ReliefShape::Parabolic,
            ..Default::default()
        })
        .unwrap();
        assert!((parabolic.deviation_m(18e-3, 0.0) - 5e-6).abs() < 1e-15);
        let crowned = gear(ModificationSpec { lead_crowning_um: 8.0, ..Default::default() }).unwrap();
        assert!((crowned.deviation_m(10e-3, 10e-3) - 8e-6).abs() < 1e-15);
        assert_eq!(crowned.deviation_m(10e-3, 0.0), 0.0);
    }

    /// A bad value names the field and the rule.
    #[test]
    fn bad_modifications_name_the_field_and_the_rule() {
        let e = gear(ModificationSpec { tip_relief_um: 20.0, tip_relief_length_mm: 16.0, ..Default::default() })
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("gear1.modification.tip_relief_length_mm") && e.contains("starts outside the active profile"),
            "{e}"
        );
        let e = gear(ModificationSpec { tip_relief_um: 500.0, tip_relief_length_mm: 2.0, ..Default::default() })
            .unwrap_err()
            .to_string();
        assert!(e.contains("gear1.modification.tip_relief_um") && e.contains("deeper than"), "{e}");
        let e = gear(ModificationSpec { root_relief_um: 5.0, ..Default::default() }).unwrap_err().to_string();
        assert!(e.contains("root_relief_length_mm") && e.contains("needs its length"), "{e}");
    }
}
