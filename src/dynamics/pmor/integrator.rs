//! The time integrators of the reduced pair, and the stability limit of each.
//!
//! - [`Integrator::Rk4`]: the paper's classical Runge–Kutta, four right-hand sides per step,
//!   fourth order; stable for hλ inside R(z) = 1 + z + z²/2 + z³/6 + z⁴/24, |R| ≤ 1 (reaches
//!   hω = 2√2 on the imaginary axis).
//! - [`Integrator::Verlet`]: velocity Verlet (kick–drift–kick), one right-hand side per step,
//!   second order. The forces that depend on the velocity (damping, the quadratic velocity
//!   vector) are taken at the predicted end velocity v* = vₙ + h·aₙ, which keeps the order at
//!   two. Stable to hω = 2 on an undamped mode, so per unit of simulated time it needs
//!   4 × 2/(2√2) ≈ 2.8 times fewer right-hand sides than RK4 at the same share of its limit.
//!
//! Why a second-order method is enough here: the step is set by stability, not accuracy. The
//! stiffest retained dynamics (the load-sharing shapes against the Hertz contact, ≈ 100 kHz)
//! are 25 times faster than the mesh mode (≈ 3.8 kHz) the DTE rings at, and at a step near the
//! stability limit the mesh mode sees ωh ≈ 0.05: a phase error of (ωh)²/24 ≈ 1e-4 per period.
//! BENCHMARKS ("Integrators") measures the DTE of both against RK4 at a quarter of its step.
//!
//! Velocity Verlet needs the acceleration at the start of a step. It is recomputed at the start
//! of every `advance` (one right-hand side per call, so the state stays plain data and a torque
//! set between calls is seen at once) and after every pitch re-anchoring.

use super::{PmorDynamics, PmorState};
use nalgebra::Complex;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Integrator {
    Rk4,
    Verlet,
}

impl Integrator {
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Rk4 => "RK4",
            Integrator::Verlet => "velocity Verlet",
        }
    }

    /// Whether a step h keeps the mode(s) of eigenvalue λ bounded (|amplification| ≤ 1).
    pub fn is_stable(self, lambda: Complex<f64>, h: f64) -> bool {
        match self {
            Integrator::Rk4 => crate::dynamics::rk4_stability::rk4_is_stable(lambda, h),
            // Past the limit |μ| leaves 1 like √(h − h_limit), so a tolerance above the
            // eigenvalues' round-off near a double root (√ε) moves the limit by ~ε only.
            Integrator::Verlet => verlet_spectral_radius(lambda, h) <= 1.0 + 1e-7,
        }
    }

    /// The largest step (s) below `upper_s` that is stable for every eigenvalue in `lambdas`
    /// (bisection; the regions are star-shaped along the rays that matter here).
    pub fn largest_stable_step(self, lambdas: &[Complex<f64>], upper_s: f64) -> f64 {
        crate::dynamics::rk4_stability::bisect_stable_step(|h| lambdas.iter().all(|&l| self.is_stable(l, h)), upper_s)
    }
}

/// Spectral radius of velocity Verlet's one-step map on the mode of flow eigenvalue λ.
///
/// A complex pair λ, λ̄ is the mode ẍ = αx + βẋ with α = −|λ|², β = 2 Re λ (the roots of
/// λ² = α + βλ). As `verlet_advance` runs it, a step starts from the acceleration the previous
/// one ended with, taken at that step's predicted velocity v*, so the map acts on (x, v, v*). A
/// real eigenvalue is taken as a pure decay
/// v̇ = λv. The map is `LinearizedPair::verlet_map` of that one mode (the whole flow's limit,
/// `verlet_stability_limit_s`, uses it on all modes at once); exact where the damping is modal.
fn verlet_spectral_radius(lambda: Complex<f64>, h: f64) -> f64 {
    let (alpha, beta) = if lambda.im == 0.0 { (0.0, lambda.re) } else { (-lambda.norm_sqr(), 2.0 * lambda.re) };
    let mode = super::linear::LinearizedPair {
        flow: nalgebra::DMatrix::from_row_slice(2, 2, &[0.0, 1.0, alpha, beta]),
        coordinates: 1,
    };
    mode.verlet_map(h).complex_eigenvalues().iter().map(|mu| mu.norm()).fold(0.0, f64::max)
}

impl<'a> PmorDynamics<'a> {
    /// Advances by `duration` in velocity Verlet steps no longer than `max_step`.
    pub fn verlet_advance(
        &self,
        s: &mut PmorState,
        torques: [f64; 2],
        duration: f64,
        max_step: f64,
    ) -> Result<(), String> {
        self.verlet_advance_from(s, torques, duration, max_step, None)
    }

    /// `verlet_advance` from the right-hand side at `s` where the caller has it already (the
    /// quasi-static coordinates' settling under new torques evaluates it).
    pub(super) fn verlet_advance_from(
        &self,
        s: &mut PmorState,
        torques: [f64; 2],
        duration: f64,
        max_step: f64,
        first: Option<(Vec<f64>, super::PmorOutputs)>,
    ) -> Result<(), String> {
        let (n, h) = super::substeps(duration, max_step);
        let mut y = self.pack(s);
        let (mut dy, mut start) = match first {
            Some(f) => f,
            None => self.rhs(&y, s.anchor, torques)?,
        };
        let len = y.len();
        let l = self.layout();
        let n_q = l.n_q[0] + l.n_q[1];
        let mut predicted = vec![0.0; len];
        for _ in 0..n {
            // Kick and drift; the velocity-dependent forces at the predicted end velocity.
            for k in 0..n_q {
                let (a, v) = (dy[n_q + k], y[n_q + k]);
                let v_half = v + 0.5 * h * a;
                predicted[k] = y[k] + h * v_half;
                predicted[n_q + k] = v + h * a;
                y[n_q + k] = v_half;
            }
            let (next, end) = self.rhs(&predicted, s.anchor, torques)?;
            // The second kick. The work integrals are the work the scheme's own forces do on its
            // own displacement Δq, by the trapezoid rule: with those, the kinetic energy's change
            // over a step is the work done up to a term that telescopes (h²/8·Δ|a|² where M is
            // constant), so the balance cannot drift. The dissipation power at the predicted
            // velocity would not do: for a shape mode at ωh ≈ 1, v* is far from the velocity
            // the step moves with.
            let mut dissipated = 0.0;
            for k in 0..n_q {
                dissipated += 0.5 * (start.damping_force[k] + end.damping_force[k]) * (predicted[k] - y[k]);
            }
            let input = torques[0] * (end.bore_theta[0] - start.bore_theta[0])
                + torques[1] * (end.bore_theta[1] - start.bore_theta[1]);
            for k in 0..n_q {
                y[k] = predicted[k];
                y[n_q + k] += 0.5 * h * next[n_q + k];
            }
            y[len - 2] += input;
            y[len - 1] += dissipated;
            if y.iter().any(|x| !x.is_finite()) {
                return Err(format!("the PMOR-Hertz state became non-finite at step {h} s: the step is too large"));
            }
            (dy, start) = (next, end);
            self.unpack(&y, s);
            let anchor = s.anchor;
            self.reanchor(s);
            if s.anchor != anchor {
                y = self.pack(s);
                let before = start.bore_theta;
                (dy, start) = self.rhs(&y, s.anchor, torques)?;
                // A condensed pair's new solve may move the bore by a Newton step: its work.
                y[len - 2] +=
                    torques[0] * (start.bore_theta[0] - before[0]) + torques[1] * (start.bore_theta[1] - before[1]);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed forms: on an undamped mode velocity Verlet is stable to hω = 2, RK4 to 2√2; on a
    /// pure decay v̇ = λv, with the lagged predicted velocity, Verlet's map has the characteristic
    /// polynomial μ² − (1 + 3z/2)μ + z/2 (z = hλ), which reaches μ = −1 at z = −1.
    #[test]
    fn limits_on_the_axes_match_the_closed_forms() {
        let w = 1e4;
        let pair = [Complex::new(0.0, w), Complex::new(0.0, -w)];
        let h = Integrator::Verlet.largest_stable_step(&pair, 1.0);
        assert!((h * w - 2.0).abs() < 1e-9, "{}", h * w);
        let h = Integrator::Rk4.largest_stable_step(&pair, 1.0);
        assert!((h * w - 8f64.sqrt()).abs() < 1e-9, "{}", h * w);
        // A simple root crosses |μ| = 1 linearly: the 1e-7 tolerance of `is_stable` moves it by 1e-7.
        let h = Integrator::Verlet.largest_stable_step(&[Complex::new(-w, 0.0)], 1.0);
        assert!((h * w - 1.0).abs() < 2e-7, "{}", h * w);
    }

    /// The whole-flow map (`LinearizedPair::verlet_stability_limit_s`) agrees with the mode-wise
    /// closed form where the damping is modal: two uncoupled modes, 10 and 40 kHz, 5 % damping.
    #[test]
    fn the_whole_flow_map_agrees_with_the_modes_where_damping_is_modal() {
        use crate::dynamics::pmor::linear::LinearizedPair;
        let w = [2.0 * std::f64::consts::PI * 1e4, 2.0 * std::f64::consts::PI * 4e4];
        let zeta = 0.05;
        let mut flow = nalgebra::DMatrix::zeros(4, 4);
        for i in 0..2 {
            flow[(i, 2 + i)] = 1.0;
            flow[(2 + i, i)] = -w[i] * w[i];
            flow[(2 + i, 2 + i)] = -2.0 * zeta * w[i];
        }
        let whole = LinearizedPair { flow, coordinates: 2 }.verlet_stability_limit_s();
        let l = Complex::new(-zeta * w[1], w[1] * (1.0 - zeta * zeta).sqrt());
        let modes = Integrator::Verlet.largest_stable_step(&[l, l.conj()], 1e-3);
        assert!((whole / modes - 1.0).abs() < 1e-6, "whole flow {whole:e} s, modes {modes:e} s");
    }

    /// A lightly damped mode stays stable a little beyond hω = 2's neighbourhood only if the
    /// scheme damps it: at ζ = 5 % the map's spectral radius below the limit is < 1 (the
    /// physical decay, not an amplification).
    #[test]
    fn a_damped_mode_decays_below_the_limit() {
        let (w, zeta) = (1e4f64, 0.05);
        let l = Complex::new(-zeta * w, w * (1.0 - zeta * zeta).sqrt());
        let r = verlet_spectral_radius(l, 1.0 / w);
        let exact = (-zeta * w * (1.0 / w)).exp();
        assert!(r < 1.0 && (r - exact).abs() < 0.05, "radius {r}, exact decay {exact}");
    }
}
