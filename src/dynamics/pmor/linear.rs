//! The reduced pair linearized about a static equilibrium: what an engineer asks of a gear mesh
//! before any time run — where it sits under a preload, its natural frequencies there (the mesh
//! mode among them), and how long an explicit step may be.
//!
//! - [`static_equilibrium`]: gear 2 held at θ₂, gear 1 loaded with τ₁; Newton's method finds θ₁,
//!   η₁, η₂ and the reaction τ₂ at which every generalized acceleration vanishes.
//! - [`linearize`]: the Jacobian of the first-order flow ẏ = f(y) there, by central differences of
//!   the right-hand side (the same code the integrator runs, so the linear model is the one the
//!   time runs see), with its blocks ∂q̈/∂q (stiffness) and ∂q̈/∂q̇ (damping, gyroscopic).
//! - [`LinearizedPair::natural_frequencies_hz`]: √(eigenvalues of −∂q̈/∂q), the undamped spectrum;
//!   [`LinearizedPair::stability_limit_s`]: the largest step an integrator keeps stable for
//!   every eigenvalue λ of the flow.

use super::integrator::Integrator;
use super::{PmorDynamics, PmorState};
use nalgebra::{Complex, DMatrix, DVector};

/// The load of the step-limit linearization as a multiple of the largest ROM torque
/// (`stability_limit_under_load`): the stiffest mode is the Hertz contact's, which stiffens (slowly,
/// logarithmically) with load; at 4× the limit is 11 % shorter than at the ROM load on the
/// default spur pair.
pub const STEP_LOAD_FACTOR: f64 = 4.0;

/// Relative size of the differences (of the coordinate's scale, below).
const DIFFERENCE: f64 = 1e-6;

/// The Jacobian of the flow at a state, in the layout of `PmorDynamics::pack` (without the two
/// work integrals).
pub struct LinearizedPair {
    /// ∂ẏ/∂y over (q, q̇), 2n × 2n.
    pub flow: DMatrix<f64>,
    /// n = dim q.
    pub coordinates: usize,
}

/// Scale of each coordinate of q for the differences (a step is `DIFFERENCE` of it): the
/// coordinate's own size, at least 10⁻³ in its unit (rad for angles; for η, modal amplitudes of
/// unit modal mass, 10⁻³ is far above a loaded gear's, so the step stays a small perturbation
/// above round-off).
fn scales(q: &[f64]) -> Vec<f64> {
    q.iter().map(|v| v.abs().max(1e-3)).collect()
}

/// The static equilibrium with gear 2 at θ₂ and τ₁ on gear 1: (state at rest, τ₂). Starts from
/// θ₁ at the rigid contact plus `te_guess_m` along the line of action.
pub fn static_equilibrium(
    dynamics: &PmorDynamics,
    theta2: f64,
    torque1_nm: f64,
    te_guess_m: f64,
) -> Result<(PmorState, f64), String> {
    let model = dynamics.model;
    let rb = [model.pair.gear1.base_radius_m, model.pair.gear2.base_radius_m];
    let mut s = model.initial_state([(rb[1] * theta2 + te_guess_m) / rb[0], theta2], [0.0; 2]);
    let mut y = dynamics.pack(&s);
    let n = y.len() / 2 - 1;
    let i_theta2 = 1 + model.gears[0].elastic_size();
    // Unknowns: q without θ₂, then τ₂. Residuals: all n accelerations.
    let unknowns: Vec<usize> = (0..n).filter(|&k| k != i_theta2).collect();
    let mut torque2 = -torque1_nm * rb[1] / rb[0];
    let residual = |y: &[f64], torque2: f64| -> Result<DVector<f64>, String> {
        let (dy, _) = dynamics.rhs(y, s.anchor, [torque1_nm, torque2])?;
        Ok(DVector::from_column_slice(&dy[n..2 * n]))
    };
    let scale = scales(&y[..n]);
    for _ in 0..40 {
        let r = residual(&y, torque2)?;
        let mut jac = DMatrix::zeros(n, n);
        for (col, &k) in unknowns.iter().enumerate() {
            let h = DIFFERENCE * scale[k];
            let (mut up, mut down) = (y.clone(), y.clone());
            up[k] += h;
            down[k] -= h;
            jac.set_column(col, &((residual(&up, torque2)? - residual(&down, torque2)?) / (2.0 * h)));
        }
        let h = 1e-3 * torque1_nm.abs().max(1.0);
        jac.set_column(n - 1, &((residual(&y, torque2 + h)? - residual(&y, torque2 - h)?) / (2.0 * h)));
        let step = jac.lu().solve(&(-&r)).ok_or("the static equilibrium's Jacobian is singular")?;
        for (col, &k) in unknowns.iter().enumerate() {
            y[k] += step[col];
        }
        torque2 += step[n - 1];
        let size = unknowns.iter().enumerate().map(|(c, &k)| (step[c] / scale[k]).abs()).fold(0.0, f64::max);
        if size < 1e-10 {
            dynamics.unpack(&y, &mut s);
            return Ok((s, torque2));
        }
    }
    Err(format!("the static equilibrium at θ₂ = {theta2} rad, τ₁ = {torque1_nm} N·m did not converge"))
}

/// The Jacobian of the flow at state `s` under constant torques.
pub fn linearize(dynamics: &PmorDynamics, s: &PmorState, torques: [f64; 2]) -> Result<LinearizedPair, String> {
    let y = dynamics.pack(s);
    let n = y.len() / 2 - 1;
    let mut flow = DMatrix::zeros(2 * n, 2 * n);
    let q_scale = scales(&y[..n]);
    for k in 0..2 * n {
        // Velocities by the speed a micro-scale displacement reaches at 10 kHz.
        let h = DIFFERENCE * if k < n { q_scale[k] } else { 6e4 * q_scale[k - n] };
        let (mut up, mut down) = (y.clone(), y.clone());
        up[k] += h;
        down[k] -= h;
        let (f_up, _) = dynamics.rhs(&up, s.anchor, torques)?;
        let (f_down, _) = dynamics.rhs(&down, s.anchor, torques)?;
        for r in 0..2 * n {
            flow[(r, k)] = (f_up[r] - f_down[r]) / (2.0 * h);
        }
    }
    Ok(LinearizedPair { flow, coordinates: n })
}

impl LinearizedPair {
    /// −∂q̈/∂q, the mass-normalized stiffness.
    pub fn stiffness_block(&self) -> DMatrix<f64> {
        let n = self.coordinates;
        -self.flow.view((n, 0), (n, n)).into_owned()
    }

    /// Undamped natural frequencies (Hz), ascending: √λ/2π of −∂q̈/∂q (the rigid rotation near 0).
    pub fn natural_frequencies_hz(&self) -> Vec<f64> {
        let mut f: Vec<f64> = self
            .stiffness_block()
            .complex_eigenvalues()
            .iter()
            .map(|l| l.re.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
            .collect();
        f.sort_by(f64::total_cmp);
        f
    }

    /// Eigenvalues of the whole flow (damping and gyroscopic terms included).
    pub fn flow_eigenvalues(&self) -> Vec<Complex<f64>> {
        self.flow.complex_eigenvalues().iter().copied().collect()
    }

    /// The largest step `integrator` keeps stable for every eigenvalue λ of the flow
    /// (`Integrator::largest_stable_step`).
    pub fn stability_limit_s(&self, integrator: Integrator) -> f64 {
        // The rigid rotation's near-zero eigenvalues never limit the step; the differences leave
        // the undamped pairs a real part of round-off size, either sign: a step is judged on
        // the oscillation, Re λ clamped to ≤ 0.
        let lambdas: Vec<Complex<f64>> = self
            .flow_eigenvalues()
            .into_iter()
            .filter(|l| l.norm() > 1e2)
            .map(|l| Complex::new(l.re.min(0.0), l.im))
            .collect();
        integrator.largest_stable_step(&lambdas, 1e-3)
    }
}

/// The stability limit (s) of `dynamics.integrator` on the pair as `dynamics` has it (inertias,
/// damping), linearized at its static equilibrium under `torque_nm` on gear 1 at four angles
/// over gear 2's pitch (single and double contact), the shortest; with the undamped natural frequencies (Hz) there. The
/// Newton starts at a tenth of the STE a mesh stiffness of 10 N/(mm·µm) would give: with η = 0
/// the whole approach sits in the Hertz contact, so the iterates come from the light side and
/// stay inside the contact law's range (b ≤ h/4).
pub fn stability_limit_under_load(dynamics: &PmorDynamics, torque_nm: f64) -> Result<(f64, Vec<f64>), String> {
    let model = dynamics.model;
    let guess = torque_nm / model.pair.gear1.base_radius_m / (1e11 * model.pair.face_width_m);
    let mut shortest: Option<(f64, Vec<f64>)> = None;
    for quarter in 0..4 {
        let theta2 = (quarter as f64 + 0.5) / 4.0 * model.gears[1].pitch_rad();
        let (state, torque2) = static_equilibrium(dynamics, theta2, torque_nm, guess)?;
        let lin = linearize(dynamics, &state, [torque_nm, torque2])?;
        let limit = lin.stability_limit_s(dynamics.integrator);
        if shortest.as_ref().map_or(true, |s| limit < s.0) {
            shortest = Some((limit, lin.natural_frequencies_hz()));
        }
    }
    Ok(shortest.expect("four angles"))
}
