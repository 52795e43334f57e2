//! The lubricated flanks a pair's spec may give (`[friction] law = "iso-tr-14179-2"`): the inputs
//! of ISO/TR 14179-2's friction law besides the geometry, and the range each may take. The law
//! itself is `dynamics::lubricated_friction`.

use serde::{Deserialize, Serialize};

/// The lubricated flanks: what ISO/TR 14179-2's μ_mz needs beside the geometry and the state.
/// Its default is the law unset: no oil, no roughness, X_L at mineral oil's 1.0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LubricatedFlanks {
    /// η_oil: the oil's dynamic viscosity at its running temperature (mPa·s).
    pub oil_viscosity_mpa_s: f64,
    /// Ra = (Ra₁ + Ra₂)/2: the flanks' mean arithmetic roughness (µm).
    pub roughness_ra_um: f64,
    /// X_L: the lubricant factor (1.0 mineral oil).
    pub lubricant_factor: f64,
}

impl Default for LubricatedFlanks {
    fn default() -> Self {
        LubricatedFlanks { oil_viscosity_mpa_s: 0.0, roughness_ra_um: 0.0, lubricant_factor: 1.0 }
    }
}

/// The range each input may take: what the fit was made for, widely (gear oils from ISO VG 2 hot
/// to VG 1500 cold; ground to rough-milled flanks; ISO/TR 14179-2's X_L runs 0.6–1.5).
pub const FIELD_RANGES: [(&str, (f64, f64)); 3] =
    [("oil_viscosity_mpa_s", (0.1, 1e5)), ("roughness_ra_um", (0.01, 10.0)), ("lubricant_factor", (0.1, 2.0))];

/// The rule of one input, `field` one of `FIELD_RANGES`' names.
pub fn field_rule(field: &str, value: f64) -> Result<(), String> {
    let (_, (low, high)) =
        FIELD_RANGES.iter().find(|(name, _)| *name == field).ok_or_else(|| format!("no input {field}"))?;
    if value.is_finite() && (*low..=*high).contains(&value) {
        Ok(())
    } else {
        Err(format!(
            "must be in [{low}, {high}] for ISO/TR 14179-2's friction law, got {}",
            super::spec_error::sig(value)
        ))
    }
}

impl LubricatedFlanks {
    /// The rule every field obeys: `Err((field, rule))` for the first it breaks.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        let values = [self.oil_viscosity_mpa_s, self.roughness_ra_um, self.lubricant_factor];
        for ((name, _), value) in FIELD_RANGES.iter().zip(values) {
            field_rule(name, value).map_err(|rule| (*name, rule))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const OIL: LubricatedFlanks =
        LubricatedFlanks { oil_viscosity_mpa_s: 30.0, roughness_ra_um: 0.5, lubricant_factor: 1.0 };

    #[test]
    fn check_names_the_field_and_the_rule() {
        let bad = LubricatedFlanks { roughness_ra_um: 0.0, ..OIL };
        let (field, rule) = bad.check().unwrap_err();
        assert_eq!(field, "roughness_ra_um");
        assert!(rule.contains("[0.01, 10]"), "{rule}");
        assert!(OIL.check().is_ok());
    }
}
