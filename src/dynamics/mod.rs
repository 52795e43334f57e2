//! The gear-pair models the FMU runs, each a `model_file::ModelKind`: the lumped pair
//! (`lumped`, its tabulated mesh law in `mesh_law`), the FE-based PMOR-Hertz reduced pair and
//! the standard PMOR penalty reference (`pmor`); and the sub-stepping of a communication step
//! they share. The FMU glue that drives them is `crate::fmu`.

pub mod lubricated_friction;
pub mod lumped;
pub mod mesh_friction;
pub mod mesh_law;
pub mod pmor;
pub mod rk4_stability;

/// The number of equal sub-steps no longer than `max_step` that cover `duration`: ⌈duration /
/// max_step⌉, except that a quotient within a relative 1e-9 of a whole number is that number.
/// A master computes its communication step as a difference of times (libcosim does), so h
/// arrives an ulp or two off the value the user chose; without the rounding 1e-4 / 1e-5 can
/// come out 10.000000000000002 and take 11 sub-steps, and two masters then disagree by the
/// integrator's error (measured 2.5e-4 relative on the lumped FMU, issue 29).
pub fn substep_count(duration: f64, max_step: f64) -> usize {
    let quotient = duration / max_step;
    let nearest = quotient.round();
    let n = if (quotient - nearest).abs() <= 1e-9 * nearest { nearest } else { quotient.ceil() };
    n.max(1.0) as usize
}

/// Refuses a communication step h that needs more than `bound` sub-steps of `max_step` (a call
/// must end in bounded time); the message says how to get under it.
pub fn check_substep_bound(h: f64, max_step: f64, bound: f64) -> Result<(), String> {
    let n = (h / max_step).ceil();
    if n <= bound {
        Ok(())
    } else {
        Err(format!(
            "communicationStepSize h = {h:e} s with max_step = {max_step:e} s needs {n:e} sub-steps, more than the bound of {bound:e} per call; take shorter communication steps or a larger max_step"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::substep_count;

    /// A communication step that is a difference of times, an ulp off the step the user chose,
    /// takes the same sub-steps as the step itself; a real remainder still takes one more.
    #[test]
    fn the_substep_count_is_robust_to_the_last_bits_of_the_step() {
        let h: f64 = 7e-4 - 6e-4; // 1.0000000000000005e-4
        assert_ne!(h, 1e-4, "the test needs a step an ulp off");
        assert!((h / 1e-5).ceil() == 11.0, "the plain ceiling flips");
        assert_eq!(substep_count(h, 1e-5), 10);
        assert_eq!(substep_count(1e-4, 1e-5), 10);
        assert_eq!(substep_count(1e-4 * (1.0 - 2e-16), 1e-5), 10);
        assert_eq!(substep_count(1.05e-4, 1e-5), 11);
        assert_eq!(substep_count(1e-4 * (1.0 + 1e-6), 1e-5), 11);
        assert_eq!(substep_count(1e-7, 1e-5), 1);
    }
}
