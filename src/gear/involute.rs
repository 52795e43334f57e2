//! The involute function and its inverse.

/// inv(α) = tan α − α.
pub fn inv(alpha: f64) -> f64 {
    alpha.tan() - alpha
}

/// The pressure angle α in (0, π/2) with inv(α) = value (Newton on a monotone function).
pub fn inv_inverse(value: f64) -> f64 {
    // Starting guess from inv(α) ≈ α³/3 for small α.
    let mut alpha = (3.0 * value).cbrt().min(1.4);
    for _ in 0..60 {
        let f = inv(alpha) - value;
        let df = alpha.tan().powi(2); // d/dα (tan α − α) = tan²α
        let step = f / df;
        alpha = (alpha - step).clamp(1e-9, 1.55);
        if step.abs() < 1e-15 {
            break;
        }
    }
    alpha
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn inverse_round_trips() {
        for deg in [5.0_f64, 14.5, 20.0, 25.0, 35.0, 60.0] {
            let a = deg.to_radians();
            assert!((inv_inverse(inv(a)) - a).abs() < 1e-12);
        }
    }
}
