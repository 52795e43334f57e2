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

pub use super::model::Integrator;
use super::{PmorDynamics, PmorState};
use nalgebra::Complex;

/// The choice of integrator is the model's data (`model::Integrator`); its numerics are here.
impl Integrator {
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Rk4 => "RK4",
            Integrator::Verlet => "velocity Verlet",
            Integrator::DiscreteGradient => "discrete gradient",
        }
    }

    /// Whether a step h keeps the mode(s) of eigenvalue λ bounded (|amplification| ≤ 1).
    pub fn is_stable(self, lambda: Complex<f64>, h: f64) -> bool {
        match self {
            Integrator::Rk4 => crate::dynamics::rk4_stability::rk4_is_stable(lambda, h),
            // Past the limit |μ| leaves 1 like √(h − h_limit), so a tolerance above the
            // eigenvalues' round-off near a double root (√ε) moves the limit by ~ε only.
            // The discrete gradient's trapezoid, (1 + z/2)/(1 − z/2), is within the unit circle
            // wherever Re z ≤ 0; its step rule is Verlet's, so it is judged as Verlet.
            Integrator::Verlet | Integrator::DiscreteGradient => verlet_spectral_radius(lambda, h) <= 1.0 + 1e-7,
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

/// Newton iterations of a discrete-gradient step before the step is halved.
const DISCRETE_GRADIENT_ITERATIONS: usize = 12;

/// How often a step that does not converge is halved before the advance is refused.
const DISCRETE_GRADIENT_HALVINGS: usize = 4;

/// A discrete-gradient step has converged when Newton's next move would change the energy by
/// less than this share of the elastic energy (the energy in play in the teeth and bodies; not
/// the kinetic energy of the rotation, which a relative displacement test would be dominated by).
/// Measured (undamped energy test over ten pitches; example 3 through fmpy at 0.1 ms): 1e-9
/// keeps the energy to 7.2e-7 of the vibration energy in 0.085 s, 1e-7 to 1.0e-5 in 0.061 s.
const DISCRETE_GRADIENT_ENERGY: f64 = 1e-7;

/// The share of `DISCRETE_GRADIENT_ENERGY` that the error estimated to remain after a Newton
/// move may reach for the move to be taken without a new solve (Hairer & Wanner's κ, 0.03–0.1).
/// Measured on the step-path bench's cases (both pairs, 20 and 100 µs): where the estimate was
/// within 0.1 of the tolerance and the loaded sections had not changed, the next correction
/// exceeded the tolerance in 40 of 43 800 steps, by at most 7.8 × (a tolerance of 1e-7 of
/// the elastic energy).
const DISCRETE_GRADIENT_FOLLOW_SHARE: f64 = 0.1;

/// The noise of the potential V relative to the elastic energy: the time stepper's quasi-static
/// solve stops at a Newton decrement of `quasi_static::STEP_RELATIVE_DECREMENT` (1e-6) of it.
const DISCRETE_GRADIENT_NOISE: f64 = 1e-6;

/// The bodies' (I + h/2·D + h²/4·A)⁻¹ on the slow coordinates: the identity on the angles (no
/// body stiffness acts on them) and each gear's ξ block, kept with its split
/// (`GearSplit::iteration_block`).
struct BodyIteration {
    blocks: [std::sync::Arc<nalgebra::DMatrix<f64>>; 2],
    /// Where each gear's ξ block starts in the slow coordinates.
    starts: [usize; 2],
}

impl BodyIteration {
    fn apply(&self, x: &nalgebra::DVector<f64>) -> nalgebra::DVector<f64> {
        let mut out = x.clone();
        for (block, &start) in self.blocks.iter().zip(&self.starts) {
            let n = block.nrows();
            out.rows_mut(start, n).gemv(1.0, block, &x.rows(start, n), 0.0);
        }
        out
    }
}

/// Newton's matrix of a discrete-gradient step: the bodies' alone, or the step's own factor
/// with the mesh.
enum NewtonMatrix {
    Bodies(BodyIteration),
    WithMesh(std::rc::Rc<MeshNewton>),
}

impl NewtonMatrix {
    fn solve(&self, residual: &nalgebra::DVector<f64>) -> nalgebra::DVector<f64> {
        match self {
            NewtonMatrix::Bodies(p) => p.apply(residual),
            // Invertible by construction (`discrete_gradient_matrix_with_mesh`).
            NewtonMatrix::WithMesh(m) => m.factor.solve(residual).unwrap_or_else(|| residual.clone()),
        }
    }
}

/// Newton's matrix with the mesh, LU-factored, and what it is made of, as a step's predictor
/// made it: kept for the next steps of the call while they converge as fast (at most two
/// solves) with the same step and as many loaded sections — the mesh's stiffness changes little
/// from one step to the next, and the matrix only sets how fast Newton converges, not where.
struct MeshNewton {
    factor: nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>,
    parts: StepJacobian<'static>,
    step_s: f64,
    sections: usize,
}

/// −∂a/∂q and −∂a/∂q̇ of the slow accelerations at a step's predictor (the bodies', and the
/// mesh's where the teeth touch): what Newton's matrix is made of.
struct StepJacobian<'q> {
    stiffness: std::borrow::Cow<'q, nalgebra::DMatrix<f64>>,
    damping: std::borrow::Cow<'q, nalgebra::DMatrix<f64>>,
}

impl StepJacobian<'_> {
    /// The accelerations after a move Δq of the positions and Δq̇ of the velocities, to first
    /// order: a −= A·Δq + D·Δq̇. Returns D·Δq̇ (the damping's part of the change).
    fn follow(&self, acceleration: &mut [f64], dq: &[f64], dv: &[f64]) -> Vec<f64> {
        let n = dq.len();
        let dq = nalgebra::DVectorView::from_slice(dq, n);
        let dv = nalgebra::DVectorView::from_slice(dv, n);
        let elastic = &*self.stiffness * dq;
        let damping = &*self.damping * dv;
        for k in 0..n {
            acceleration[k] -= elastic[k] + damping[k];
        }
        damping.as_slice().to_vec()
    }
}

/// One step's start: the slow state y, its ẏ and outputs, and the accelerations of the steps
/// before (the predictor's).
struct StepStart {
    dy: Vec<f64>,
    outputs: super::PmorOutputs,
    history: AccelerationHistory,
    /// The last step's Newton matrix with the mesh, where the next may take it (`MeshNewton`).
    newton: Option<std::rc::Rc<MeshNewton>>,
}

/// The slow accelerations at the starts of the last two steps of a call, most recent first,
/// each with the length of the step that followed it.
#[derive(Default)]
struct AccelerationHistory(Vec<(Vec<f64>, f64)>);

impl AccelerationHistory {
    fn push(&mut self, acceleration: Vec<f64>, step_s: f64) {
        self.0.insert(0, (acceleration, step_s));
        self.0.truncate(2);
    }

    /// The acceleration at the end of a step of length h from a₀, extrapolated: the polynomial
    /// through a₀ and the (up to two) accelerations before it, at their times (Lagrange, the
    /// steps need not be equal: a halved step follows a whole one).
    fn extrapolate(&self, a0: f64, k: usize, h: f64) -> f64 {
        match self.0.as_slice() {
            [] => a0,
            [(a1, d1)] => a0 + (a0 - a1[k]) * h / d1,
            [(a1, d1), (a2, d2), ..] => {
                let (t1, t2) = (-d1, -d1 - d2);
                let l0 = (h - t1) * (h - t2) / (t1 * t2);
                let l1 = h * (h - t2) / (t1 * (t1 - t2));
                let l2 = h * (h - t1) / (t2 * (t2 - t1));
                l0 * a0 + l1 * a1[k] + l2 * a2[k]
            }
        }
    }
}

impl<'a> PmorDynamics<'a> {
    /// Advances the quasi-statically condensed pair by `duration` in energy-conserving
    /// discrete-gradient steps no longer than `max_step` (Gonzalez's discrete gradient on the
    /// trapezoid; the slow coordinates' mass is constant):
    ///
    ///   q₁ = q₀ + h·(v₀ + v₁)/2,   M(v₁ − v₀) = h·[f̄ + c·MΔq/(ΔqᵀMΔq)] − h·½(d₀ + d₁),
    ///   f̄ = ½(f₀ + f₁),   c = −(V₁ − V₀) − f̄·Δq,
    ///
    /// with f the conservative forces (elastic, contact, and the external torques at the bore,
    /// whose potential −τ·θ_bore V includes) and d the damping forces. Then
    /// ΔT = ½(v₀ + v₁)ᵀM(v₁ − v₀) = −ΔV − ½(d₀ + d₁)·Δq exactly, whatever kinks the forces
    /// have: a contact's onset, a flank-grid node, a rattle impact do not move the energy, where
    /// velocity Verlet's shadow energy jumps by (ωh)² of the energy in play at each.
    ///
    /// The step is implicit. Newton's method solves it, with the Jacobian I + h/2·D + h²/4·A made
    /// at the predictor (A and D the bodies' and the mesh's stiffness and damping,
    /// `discrete_gradient_matrix_with_mesh`), from the trapezoid with the acceleration
    /// extrapolated; one quasi-static solve per iteration, the predictor's to a looser
    /// tolerance (`quasi_static::PREDICTOR_RELATIVE_DECREMENT`), two to three per step. The
    /// trapezoid is unconditionally stable; its step is Verlet's default, for the same
    /// accuracy (the DTE of example 3 within 0.3 % of Verlet's). Where Newton does not
    /// converge (a hard impact), the step is halved, up to `DISCRETE_GRADIENT_HALVINGS` times.
    /// Returns the quasi-static solves made.
    pub fn discrete_gradient_advance(
        &self,
        s: &mut PmorState,
        torques: [f64; 2],
        duration: f64,
        max_step: f64,
    ) -> Result<usize, String> {
        self.discrete_gradient_advance_from(s, torques, duration, max_step, None).map(|(solves, _)| solves)
    }

    /// `discrete_gradient_advance` from the right-hand side at `s` where the caller has it
    /// already (the settling to new torques evaluates it). Returns the solves and the outputs of
    /// the last evaluation: those of the end state, the potential the step booked (evaluated at
    /// the last Newton iterate's velocity, which the accepted one matches to the step's
    /// convergence).
    pub(super) fn discrete_gradient_advance_from(
        &self,
        s: &mut PmorState,
        torques: [f64; 2],
        duration: f64,
        max_step: f64,
        first: Option<(Vec<f64>, super::PmorOutputs)>,
    ) -> Result<(usize, super::PmorOutputs), String> {
        let qs = self.condensed().ok_or("the discrete-gradient step needs the quasi-static condensation")?;
        let (n, h) = super::substeps(duration, max_step);
        let solves_before = qs.counts.get().1;
        let mut y = self.pack(s);
        let (dy, outputs) = match first {
            Some(f) => f,
            None => self.rhs(&y, s.anchor, torques)?,
        };
        let mut start = StepStart { dy, outputs, history: AccelerationHistory::default(), newton: None };
        for _ in 0..n {
            self.discrete_gradient_step(qs, s, &mut y, &mut start, torques, h, 0)?;
            self.end_discrete_gradient_step(s, &mut y, &mut start, torques)?;
        }
        Ok((qs.counts.get().1 - solves_before, start.outputs))
    }

    /// After an accepted step: the state at y, each anchor moved to the pitch that holds its
    /// angle and, where one moved, the step's start evaluated again in the new pitch (a
    /// condensed pair's new solve may move the bore by a Newton step: its work is booked).
    fn end_discrete_gradient_step(
        &self,
        s: &mut PmorState,
        y: &mut Vec<f64>,
        start: &mut StepStart,
        torques: [f64; 2],
    ) -> Result<(), String> {
        self.unpack(y, s);
        let anchor = s.anchor;
        self.reanchor(s);
        if s.anchor != anchor {
            *y = self.pack(s);
            let before = start.outputs.bore_theta;
            let (dy, outputs) = self.rhs(y, s.anchor, torques)?;
            let len = y.len();
            y[len - 2] +=
                torques[0] * (outputs.bore_theta[0] - before[0]) + torques[1] * (outputs.bore_theta[1] - before[1]);
            *start =
                StepStart { dy, outputs, history: std::mem::take(&mut start.history), newton: start.newton.take() };
        }
        Ok(())
    }

    /// One step of length h from (y, start), or two of h/2 where Newton does not converge (the
    /// anchors moved between them as between any two steps: the halves of a step that crosses
    /// a pitch end must each stay within the stored samples).
    #[allow(clippy::too_many_arguments)]
    fn discrete_gradient_step(
        &self,
        qs: &super::quasi_static::QuasiStatic,
        s: &mut PmorState,
        y: &mut Vec<f64>,
        start: &mut StepStart,
        torques: [f64; 2],
        h: f64,
        halvings: usize,
    ) -> Result<(), String> {
        let anchor = s.anchor;
        let l = self.layout();
        let n_q = l.n_q[0] + l.n_q[1];
        let len = y.len();
        let potential = |o: &super::PmorOutputs| {
            o.elastic_j + o.contact_j - torques[0] * o.bore_theta[0] - torques[1] * o.bore_theta[1]
        };
        let mass = |x: &[f64]| {
            let mut out = vec![0.0; n_q];
            self.slow_mass_times(qs, x, &mut out);
            out
        };
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
        let (q0, v0, a0) = (&y[..n_q], &y[n_q..2 * n_q], &start.dy[n_q..2 * n_q]);
        let m_a0 = mass(a0);
        let v_0 = potential(&start.outputs);
        // The start: the trapezoid with the end acceleration extrapolated from the last three
        // (velocity Verlet's prediction on a call's first step) — but for the bodies' own
        // linear part, −Aq − Dq̇, which is taken at the end (the trapezoid on it, solved with
        // the bodies' matrix): extrapolated, a body mode with ωh > 2 makes the start an
        // unstable explicit step, and Newton's last unconverged remainder, below the energy
        // test, grew from one step to the next (issue 38: a 17 kHz mode on example 3 at 6 ×).
        let body_stiffness = self.slow_body_acceleration_stiffness(qs);
        let body_damping = self.slow_body_acceleration_damping(qs);
        let q0_v = nalgebra::DVector::from_column_slice(q0);
        let v0_v = nalgebra::DVector::from_column_slice(v0);
        let g0 = nalgebra::DVector::from_column_slice(a0) + body_stiffness * &q0_v + body_damping * &v0_v;
        let d_q0 = body_damping * &q0_v;
        let d_v0 = body_damping * &v0_v;
        let mut trial = y.clone();
        let mut predictor_rhs = nalgebra::DVector::zeros(n_q);
        for k in 0..n_q {
            let g1 = start.history.extrapolate(g0[k], k, h);
            predictor_rhs[k] =
                q0[k] + h * v0[k] + 0.25 * h * h * (a0[k] + g1) + 0.5 * h * d_q0[k] + 0.25 * h * h * d_v0[k];
        }
        let q1 = match self.discrete_gradient_matrix(qs, h) {
            Some(p) => p.apply(&predictor_rhs),
            None => predictor_rhs,
        };
        for k in 0..n_q {
            trial[k] = q1[k];
            trial[n_q + k] = 2.0 * (q1[k] - q0[k]) / h - v0[k];
        }
        // Newton's matrix, made at the first iterate (the mesh's stiffness at the predictor),
        // and what it is made of.
        let mut newton = None;
        let mut bodies_jacobian: Option<StepJacobian> = None;
        let mut residual = nalgebra::DVector::zeros(n_q);
        let mut converged = None;
        // The last iterate's energy change |f̄·Δq| and its loaded sections (the stopping rule).
        let mut previous: Option<(f64, usize)> = None;
        let mut iterations = 0;
        for iteration in 0..DISCRETE_GRADIENT_ITERATIONS {
            iterations = iteration + 1;
            // The predictor's solve may end looser: the iterations after it solve again.
            qs.at_predictor.set(iteration == 0);
            qs.last_solve_tight.set(true);
            let rhs = self.rhs(&trial, anchor, torques);
            qs.at_predictor.set(false);
            let Ok((next, end)) = rhs else { break };
            if iteration == 0 {
                // The mesh's stiffness and damper at the predictor join the bodies' for this
                // step (or the last step's, `MeshNewton`); out of contact the bodies' alone,
                // kept per step length.
                let sections = end.contact.sections.len();
                let kept = start.newton.take().filter(|m| m.step_s == h && m.sections == sections && sections > 0);
                let with_mesh = kept.or_else(|| {
                    self.discrete_gradient_matrix_with_mesh(qs, h)
                        .map(|(factor, parts)| std::rc::Rc::new(MeshNewton { factor, parts, step_s: h, sections }))
                });
                newton = match with_mesh {
                    Some(m) => {
                        start.newton = Some(m.clone());
                        Some(NewtonMatrix::WithMesh(m))
                    }
                    None => {
                        bodies_jacobian = Some(StepJacobian {
                            stiffness: std::borrow::Cow::Borrowed(body_stiffness),
                            damping: std::borrow::Cow::Borrowed(body_damping),
                        });
                        self.discrete_gradient_matrix(qs, h).map(NewtonMatrix::Bodies)
                    }
                };
            }
            let jacobian = match &newton {
                Some(NewtonMatrix::WithMesh(m)) => Some(&m.parts),
                _ => bodies_jacobian.as_ref(),
            };
            let m_a1 = mass(&next[n_q..2 * n_q]);
            let dq: Vec<f64> = (0..n_q).map(|k| trial[k] - q0[k]).collect();
            let norm2 = dot(&dq, &mass(&dq));
            // The conservative forces' mean f̄ = ½(Ma₀ + d₀ + Ma₁ + d₁), and its work on Δq.
            let f_bar: Vec<f64> = (0..n_q)
                .map(|k| 0.5 * (m_a0[k] + start.outputs.damping_force[k] + m_a1[k] + end.damping_force[k]))
                .collect();
            // The correction closes the balance where the mean force misses ΔV; below the noise
            // of V it would only amplify that noise (c/|Δq|² at a pair near rest): V comes from
            // a quasi-static solve to `STEP_RELATIVE_DECREMENT` of the elastic energy.
            let elastic = 0.5 * (start.outputs.elastic_j + start.outputs.contact_j + end.elastic_j + end.contact_j);
            let c = -(potential(&end) - v_0) - dot(&f_bar, &dq);
            let gonzalez = if norm2 > 0.0 && c.abs() > DISCRETE_GRADIENT_NOISE * elastic { c / norm2 } else { 0.0 };
            // The step's equations at this iterate: q₁ = q₀ + h·v₀ + h²/2·ā, v₁ = v₀ + h·ā.
            for k in 0..n_q {
                let a_bar = 0.5 * (a0[k] + next[n_q + k]) + gonzalez * dq[k];
                trial[n_q + k] = v0[k] + h * a_bar;
                residual[k] = trial[k] - (q0[k] + h * v0[k] + 0.5 * h * h * a_bar);
            }
            let correction = newton.as_ref().map_or_else(|| residual.clone(), |p| p.solve(&residual));
            let shift: Vec<f64> = correction.iter().map(|c| -c).collect();
            let change = dot(&f_bar, &shift).abs();
            let tolerance = DISCRETE_GRADIENT_ENERGY * elastic.abs() + 1e-20;
            let tight = qs.last_solve_tight.get();
            if tight && change <= tolerance {
                converged = Some((next, end, dq));
                break;
            }
            // The stopping rule of simplified Newton (Hairer & Wanner, Solving ODEs II, §IV.8):
            // at a contraction rate ρ = |Δₖ|/|Δₖ₋₁| the error left after this move is about
            // ρ/(1 − ρ)·|Δₖ|. Where that is a small share of the tolerance, the move is taken
            // without a new solve: the forces follow it to first order (`follow_newton_move`).
            // Not across a change of the loaded sections, where the forces have a kink.
            let sections = end.contact.sections.len();
            let rate =
                previous.and_then(|(before, n)| (n == sections && change < 0.5 * before).then(|| change / before));
            if let (true, Some(rate), Some(parts)) = (tight, rate, jacobian) {
                if rate / (1.0 - rate) * change <= DISCRETE_GRADIENT_FOLLOW_SHARE * tolerance {
                    let (next, end) =
                        self.follow_newton_move(qs, parts, y, &mut trial, &shift, next, end, torques, h)?;
                    let dq = (0..n_q).map(|k| trial[k] - q0[k]).collect();
                    converged = Some((next, end, dq));
                    break;
                }
            }
            previous = Some((change, sections));
            // The velocity that goes with the shifted positions (q̇₁ = 2(q₁ − q₀)/h − q̇₀): the
            // damping forces of the next evaluation see it, as Newton's matrix assumes.
            for k in 0..n_q {
                trial[k] += shift[k];
                trial[n_q + k] = 2.0 * (trial[k] - q0[k]) / h - v0[k];
            }
        }
        // A step that needed more than two solves makes the next one build its own matrix.
        if converged.is_none() || iterations > 2 {
            start.newton = None;
        }
        let Some((mut next, end, dq)) = converged else {
            if halvings >= DISCRETE_GRADIENT_HALVINGS {
                return Err(format!(
                    "the discrete-gradient step found no solution down to {h:e} s (Newton did not converge in {DISCRETE_GRADIENT_ITERATIONS} iterations)"
                ));
            }
            // The quasi-static solver restarts from the step's start, then two half steps.
            let y0 = y.clone();
            let _ = self.rhs(&y0, anchor, torques)?;
            self.discrete_gradient_step(qs, s, y, start, torques, 0.5 * h, halvings + 1)?;
            self.end_discrete_gradient_step(s, y, start, torques)?;
            return self.discrete_gradient_step(qs, s, y, start, torques, 0.5 * h, halvings + 1);
        };
        // The accepted state is the last one evaluated (its potential is the one booked), with
        // the velocity of the last update.
        let dissipated: f64 =
            (0..n_q).map(|k| 0.5 * (start.outputs.damping_force[k] + end.damping_force[k]) * dq[k]).sum();
        let input = torques[0] * (end.bore_theta[0] - start.outputs.bore_theta[0])
            + torques[1] * (end.bore_theta[1] - start.outputs.bore_theta[1]);
        y[..2 * n_q].copy_from_slice(&trial[..2 * n_q]);
        y[len - 2] += input;
        y[len - 1] += dissipated;
        // Tooth friction's share, by the trapezoid of its power (each end ≥ 0: never decreasing).
        s.friction_dissipated_j += 0.5 * h * (start.outputs.contact.friction_power_w + end.contact.friction_power_w);
        if y.iter().any(|x| !x.is_finite()) {
            return Err(format!("the PMOR-Hertz state became non-finite at step {h} s"));
        }
        // ẏ's positions part is the velocity: the accepted one.
        next[..n_q].copy_from_slice(&y[n_q..2 * n_q]);
        start.dy = next;
        start.history.push(g0.as_slice().to_vec(), h);
        start.outputs = end;
        Ok(())
    }

    /// The step's last Newton move Δq taken without a new solve, from the step's `start` (q₀, q̇₀):
    /// positions and velocities moved (Δq̇ = 2Δq/h), the slow accelerations and damping forces to first order
    /// (`StepJacobian::follow`), the fast coordinates with them (`follow_slow_move`), and the
    /// potential by the work of the trapezoid's mean conservative force, ΔV = −½(f + f′)·Δq, so
    /// that the step's energy balance closes on the booked V as it does at a solved iterate.
    #[allow(clippy::too_many_arguments)]
    fn follow_newton_move(
        &self,
        qs: &super::quasi_static::QuasiStatic,
        jacobian: &StepJacobian,
        start: &[f64],
        trial: &mut [f64],
        shift: &[f64],
        mut next: Vec<f64>,
        mut end: super::PmorOutputs,
        torques: [f64; 2],
        h: f64,
    ) -> Result<(Vec<f64>, super::PmorOutputs), String> {
        let n_q = shift.len();
        let mass = |x: &[f64]| {
            let mut out = vec![0.0; n_q];
            self.slow_mass_times(qs, x, &mut out);
            out
        };
        let conservative = |next: &[f64], end: &super::PmorOutputs| -> Vec<f64> {
            mass(&next[n_q..2 * n_q]).iter().zip(&end.damping_force).map(|(m, d)| m + d).collect()
        };
        let before = conservative(&next, &end);
        // The velocity of the trapezoid, q̇₁ = 2(q₁ − q₀)/h − q̇₀, as at every iterate: the
        // evaluation saw it at the unmoved positions.
        let dv: Vec<f64> = shift.iter().map(|s| 2.0 * s / h).collect();
        for k in 0..n_q {
            trial[k] += shift[k];
            trial[n_q + k] = 2.0 * (trial[k] - start[k]) / h - start[n_q + k];
        }
        let damping_change = jacobian.follow(&mut next[n_q..2 * n_q], shift, &dv);
        for (d, m) in end.damping_force.iter_mut().zip(mass(&damping_change)) {
            *d += m;
        }
        let after = conservative(&next, &end);
        let potential_change: f64 = -(0..n_q).map(|k| 0.5 * (before[k] + after[k]) * shift[k]).sum::<f64>();
        let (turn, approach) = self.follow_slow_move(qs, shift)?;
        for (section, a) in end.contact.sections.iter().zip(&approach) {
            end.contact.normal_force_n += section.flank_sign * section.stiffness_n_per_m * a;
        }
        end.bore_theta[0] += turn[0];
        end.bore_theta[1] += turn[1];
        // V = U − τ·θ_bore: U takes the rest.
        end.elastic_j += potential_change + torques[0] * turn[0] + torques[1] * turn[1];
        let v = &trial[n_q..2 * n_q];
        end.kinetic_j = 0.5 * v.iter().zip(mass(v)).map(|(v, m)| v * m).sum::<f64>();
        Ok((next, end))
    }

    /// I + h/2·(D + D_c) + h²/4·(A + A_c), LU-factored, with the mesh's stiffness A_c and damper
    /// D_c at the last solve (`slow_contact_accelerations`)
    /// beside the bodies' A and D: Newton's matrix for one step, made at its predictor and used
    /// for a few solves only, so factored rather than inverted (the inverse took a fifth of a
    /// step with the body modes to 6 × the mesh mode dynamic). Returned with A + A_c and
    /// D + D_c, which carry the step's last Newton move onto the forces
    /// (`StepJacobian::follow`). `None` where there is no contact (the bodies' alone then serve).
    fn discrete_gradient_matrix_with_mesh(
        &self,
        qs: &super::quasi_static::QuasiStatic,
        h: f64,
    ) -> Option<(nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>, StepJacobian<'static>)> {
        let (contact, mesh_damper) = self.slow_contact_accelerations(qs)?;
        let stiffness = contact + self.slow_body_acceleration_stiffness(qs);
        let mut damping = self.slow_body_acceleration_damping(qs).clone();
        if let Some(mesh) = mesh_damper {
            damping += mesh;
        }
        let mut a = &stiffness * (0.25 * h * h);
        a += &damping * (0.5 * h);
        for k in 0..a.nrows() {
            a[(k, k)] += 1.0;
        }
        let factor = a.lu();
        factor.is_invertible().then_some((
            factor,
            StepJacobian { stiffness: std::borrow::Cow::Owned(stiffness), damping: std::borrow::Cow::Owned(damping) },
        ))
    }

    /// A = −∂a/∂q of the slow coordinates' bodies (`GearSplit::slow_body_stiffness`; zero on the
    /// angles), made once per condensation.
    fn slow_body_acceleration_stiffness<'q>(
        &self,
        qs: &'q super::quasi_static::QuasiStatic,
    ) -> &'q nalgebra::DMatrix<f64> {
        self.slow_body_block(&qs.body_acceleration_stiffness, |i| qs.splits[i].slow_body_stiffness().clone())
    }

    /// D = −∂a/∂q̇ of the slow coordinates' bodies' modal damping (`GearSplit::slow_body_damping`;
    /// zero on the angles), made once per condensation.
    fn slow_body_acceleration_damping<'q>(
        &self,
        qs: &'q super::quasi_static::QuasiStatic,
    ) -> &'q nalgebra::DMatrix<f64> {
        self.slow_body_block(&qs.body_acceleration_damping, |i| {
            qs.splits[i].slow_body_damping(self.damping[i].modes_ratio)
        })
    }

    /// The n_q × n_q matrix with each gear's ξ block from `block`, kept in `cell`.
    fn slow_body_block<'q>(
        &self,
        cell: &'q std::cell::OnceCell<nalgebra::DMatrix<f64>>,
        block: impl Fn(usize) -> nalgebra::DMatrix<f64>,
    ) -> &'q nalgebra::DMatrix<f64> {
        cell.get_or_init(|| {
            let l = self.layout();
            let n = l.n_q[0] + l.n_q[1];
            let mut a = nalgebra::DMatrix::zeros(n, n);
            for i in 0..2 {
                let k = block(i);
                let q = l.q(i) + 1;
                a.view_mut((q, q), (k.nrows(), k.ncols())).copy_from(&k);
            }
            a
        })
    }

    /// (I + h/2·D + h²/4·A)⁻¹ with A = −∂a/∂q and D = −∂a/∂q̇ of the slow coordinates' bodies
    /// (`slow_body_acceleration_stiffness`, `slow_body_acceleration_damping`): the Jacobian of the
    /// trapezoid's positions, with q̇₁ = 2(q₁ − q₀)/h − q̇₀, frozen. Exact for the body modes,
    /// which are linear; where the teeth touch, each step replaces it with
    /// `discrete_gradient_matrix_with_mesh` at its predictor. Block-diagonal, each gear's block
    /// inverted once per step length and kept with its split (`GearSplit::iteration_block`).
    fn discrete_gradient_matrix(&self, qs: &super::quasi_static::QuasiStatic, h: f64) -> Option<BodyIteration> {
        let l = self.layout();
        let block = |i: usize| qs.splits[i].iteration_block(h, self.damping[i].modes_ratio);
        Some(BodyIteration { blocks: [block(0)?, block(1)?], starts: [l.q(0) + 1, l.q(1) + 1] })
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
