//! RK4's stability limit on a linear(ized) flow: the largest step h for which every eigenvalue λ
//! of the flow has |R(hλ)| ≤ 1, R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 the method's amplification.
//! Both models check their sub-step against it at ExitInitializationMode (issue 13's stability
//! contract); PMOR-Hertz also chooses its default max_step from it.

use nalgebra::Complex;

/// Whether RK4's amplification |R(hλ)| stays ≤ 1.
pub fn rk4_is_stable(lambda: Complex<f64>, h: f64) -> bool {
    let z = lambda * h;
    let r = Complex::new(1.0, 0.0) + z + z * z / 2.0 + z * z * z / 6.0 + z * z * z * z / 24.0;
    r.norm() <= 1.0 + 1e-12
}

/// The largest stable step (s) for the eigenvalues `lambdas` (1/s), by bisection below `upper_s`
/// (returned if even that is stable). Eigenvalues with a positive real part are not the
/// integrator's to damp: the caller passes Re λ ≤ 0.
pub fn largest_stable_step(lambdas: &[Complex<f64>], upper_s: f64) -> f64 {
    bisect_stable_step(|h| lambdas.iter().all(|&l| rk4_is_stable(l, h)), upper_s)
}

/// The largest h ≤ `upper_s` with `stable(h)`, by bisection (the stable steps of a method on a
/// set of modes form an interval from 0 for the regions and rays met here).
pub fn bisect_stable_step(stable: impl Fn(f64) -> bool, upper_s: f64) -> f64 {
    if stable(upper_s) {
        return upper_s;
    }
    let (mut lo, mut hi) = (0.0, upper_s);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if stable(mid) {
            lo = mid
        } else {
            hi = mid
        }
        if hi - lo <= 1e-12 * hi {
            break;
        }
    }
    lo
}

/// The eigenvalues of the oscillator m·ẍ + c·ẋ + k·x = 0.
pub fn oscillator_eigenvalues(mass: f64, damping: f64, stiffness: f64) -> [Complex<f64>; 2] {
    let disc = damping * damping - 4.0 * mass * stiffness;
    let re = -damping / (2.0 * mass);
    if disc < 0.0 {
        let im = (-disc).sqrt() / (2.0 * mass);
        [Complex::new(re, im), Complex::new(re, -im)]
    } else {
        let d = disc.sqrt() / (2.0 * mass);
        [Complex::new(re + d, 0.0), Complex::new(re - d, 0.0)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed forms of RK4's stability region: on the imaginary axis it reaches 2√2, on the
    /// negative real axis 2.7853 (the real root of R(z) = −1).
    #[test]
    fn limits_on_the_axes_match_the_closed_forms() {
        let w = 1e4;
        let h = largest_stable_step(&[Complex::new(0.0, w), Complex::new(0.0, -w)], 1.0);
        assert!((h * w / 8f64.sqrt() - 1.0).abs() < 1e-9, "{}", h * w);
        let h = largest_stable_step(&[Complex::new(-w, 0.0)], 1.0);
        assert!((h * w - 2.785293563405282).abs() < 1e-8, "{}", h * w);
    }
}
