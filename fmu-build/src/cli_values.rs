//! Value parsers for the command line: each refuses a value with the rule it breaks.

use anyhow::Result;

/// A count in [LO, HI] (a value outside is refused with the range, before any work).
pub(crate) fn count<const LO: usize, const HI: usize>(text: &str) -> Result<usize, String> {
    let n: usize = text.trim().parse().map_err(|_| format!("`{text}` is not a whole number"))?;
    if (LO..=HI).contains(&n) {
        Ok(n)
    } else {
        Err(format!("must be in {LO}..={HI}, got {n}"))
    }
}

/// A number, or the message clap prints for a value that is none.
pub(crate) fn number(text: &str) -> Result<f64, String> {
    text.trim().parse().map_err(|_| format!("`{text}` is not a number"))
}

/// A positive, finite number (a torque, a length, a time).
pub(crate) fn positive_number(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a positive finite number, got {}", gearfmu::gear::sig(v)))
    }
}

/// A share of energy in (0, 1].
pub(crate) fn energy_share(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if v > 0.0 && v <= 1.0 {
        Ok(v)
    } else {
        Err(format!("must be in (0, 1] (a share of the deformation energy), got {}", gearfmu::gear::sig(v)))
    }
}

/// A Coulomb friction coefficient in [0, 1).
pub(crate) fn friction_coefficient(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if (0.0..1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("must be in [0, 1) (a Coulomb coefficient of tooth friction), got {}", gearfmu::gear::sig(v)))
    }
}

/// A damping ratio in [0, 1).
pub(crate) fn damping_ratio(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if (0.0..1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("must be in [0, 1) (a fraction of critical damping), got {}", gearfmu::gear::sig(v)))
    }
}
