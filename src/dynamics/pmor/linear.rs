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
use super::model::FlankContact;
use super::{PmorDynamics, PmorState};
use crate::contact::mesh_kinematics::Flank;
use nalgebra::{Complex, DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Fraction of the stability limit taken as the default step: room for the transient loads of
/// impacts and re-engagement and for a user's larger damping ratios. On example 3 the DTE at
/// 1 µs and at 6 µs agree within 0.2 % (BENCHMARKS), so the step is set by stability, not accuracy.
pub const STEP_SAFETY: f64 = 0.6;

/// How a reduced pair's default step is chosen (`default_step`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct IntegratorStep {
    /// The load of the linearization (N·m on gear 1).
    pub torque_nm: f64,
    /// Undamped natural frequencies of the linearized pair (Hz), ascending, the rigid rotation
    /// first, at the angle with the shortest limit.
    pub natural_frequencies_hz: Vec<f64>,
    pub integrator: Integrator,
    /// The integrator's largest stable step at that load with the dynamics' damping (s).
    pub stability_limit_s: f64,
    /// The FMU's default step: `STEP_SAFETY` × the limit, rounded down to 0.1 µs.
    pub max_step_s: f64,
}

/// Each retry of the build's linearization lowers the load by this factor.
const STEP_LOAD_BACKOFF: f64 = 0.8;

/// The default step of `dynamics` (its integrator, inertias and damping): the stability limit on
/// the pair linearized under [`PmorModel::linearization_torque_nm`](super::model::PmorModel::linearization_torque_nm) (`stability_limit_under_load`), and
/// `STEP_SAFETY` of it. In the build (no load found yet) a load at which the contact law leaves
/// its range (the Hertz band wider than h/4 on a pair whose teeth are short against their
/// load, e.g. a small helical pair near its yield torque) is lowered by `STEP_LOAD_BACKOFF`
/// down to the ROM torque, and the load reached is the model's range (`IntegratorStep::torque_nm`).
///
/// The discrete gradient keeps the body modes up to `IMPLICIT_BODY_CUTOFF_PER_MESH_MODE` dynamic,
/// which cost it no stability; at that cut-off its step rule stays velocity Verlet's on the pair
/// condensed at the explicit one (`BODY_CUTOFF_PER_MESH_MODE`), the accuracy its DTE was measured
/// at.
pub fn default_step(dynamics: &PmorDynamics) -> Result<IntegratorStep, String> {
    use crate::dynamics::pmor::integrator::Integrator;
    use crate::dynamics::pmor::quasi_static::{mesh_mode_estimate_hz, BODY_CUTOFF_PER_MESH_MODE};
    let model = dynamics.model;
    let explicit_cutoff;
    // Only at the discrete gradient's own cut-off: a study that sets another (every body mode
    // dynamic, say) gets the limit of what it integrates.
    let at_implicit_cutoff = dynamics
        .condensed()
        .is_some_and(|q| q.splits[0].cutoff_hz == crate::dynamics::pmor::quasi_static::body_cutoff_hz(model));
    let dynamics = if dynamics.integrator == Integrator::DiscreteGradient && at_implicit_cutoff {
        let mut d = dynamics.with_mesh_damper(dynamics.mesh_damping_n_s_per_m);
        d.set_quasi_static_cutoff(BODY_CUTOFF_PER_MESH_MODE * mesh_mode_estimate_hz(model));
        explicit_cutoff = d;
        &explicit_cutoff
    } else {
        dynamics
    };
    let rom = model.info.rom_torques_nm.iter().cloned().fold(0.0, f64::max);
    let mut torque_nm = model.linearization_torque_nm();
    let retry = model.step_checked_torque_nm <= 0.0;
    let (stability_limit_s, natural_frequencies_hz) = loop {
        match stability_limit_under_load(dynamics, torque_nm) {
            Ok(found) => break found,
            Err(_) if retry && torque_nm > rom * (1.0 + 1e-9) => {
                torque_nm = (STEP_LOAD_BACKOFF * torque_nm).max(rom);
            }
            Err(e) => return Err(format!("linearized at T₁ = {torque_nm:.4} N·m: {e}")),
        }
    };
    Ok(IntegratorStep {
        torque_nm,
        natural_frequencies_hz,
        integrator: dynamics.integrator,
        stability_limit_s,
        max_step_s: (STEP_SAFETY * stability_limit_s * 1e7).floor() / 1e7,
    })
}

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
    let torque2_start = -torque1_nm * rb[1] / rb[0];
    // Where the flank modifications leave the rigid flanks apart at the guess (a relief, a
    // crowning open the gap: no contact, a singular Jacobian), the guess moves by their opening
    // at this angle (`PairPlacement::modification_opening_m`) onto the flank the torque loads.
    let mut opening = 0.0;
    if dynamics.place.is_modified() {
        let s = model.initial_state([(rb[1] * theta2 + te_guess_m) / rb[0], theta2], [0.0; 2]);
        if dynamics.outputs(&s).map_or(false, |o| o.contact.normal_force_n == 0.0) {
            let flank = if torque1_nm < 0.0 { Flank::Coast } else { Flank::Drive };
            let layers = &model.gears[0].flank(flank).grid.layer_z_m;
            let z_mid: Vec<f64> = layers.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
            opening = dynamics.place.modification_opening_m(flank, theta2, &z_mid).unwrap_or(0.0);
        }
    }
    // The start: the rigid pair at the guessed TE. Where that guess, all of it taken by the Hertz
    // law at undeformed teeth, is beyond the law's range (a small pair: the half-width rule), the
    // guess is halved until the start evaluates; Newton's steps do the rest.
    let mut guess = te_guess_m;
    let (mut s, mut y) = loop {
        let s = model.initial_state([(rb[1] * theta2 + opening + guess) / rb[0], theta2], [0.0; 2]);
        let y = dynamics.pack(&s);
        match dynamics.rhs(&y, s.anchor, [torque1_nm, torque2_start]) {
            // Node-to-surface penalty contact (the reference model) on a coarse flank grid can
            // leave every node clear at a guess the Hertz sections would close: a singular
            // Jacobian. The guess grows until a node touches (the local deformation that the
            // CMS shapes carry then takes the load).
            Ok((_, o))
                if o.contact.normal_force_n == 0.0
                    && torque1_nm != 0.0
                    && matches!(model.info.contact, FlankContact::Penalty { .. })
                    && guess.abs() < 1e-3 =>
            {
                guess = if guess == 0.0 { 1e-6 * torque1_nm.signum() } else { 1.5 * guess }
            }
            Ok(_) => break (s, y),
            Err(e) if guess.abs() < 1e-3 * te_guess_m.abs() => return Err(e),
            Err(_) => guess *= 0.5,
        }
    };
    let anchor = s.anchor;
    let n = y.len() / 2 - 1;
    // Gear 2's angle coordinate (its mean axis where the model is condensed).
    let i_theta2 = dynamics.layout().q(1);
    // Unknowns: q without θ₂, then τ₂. Residuals: all n accelerations.
    let unknowns: Vec<usize> = (0..n).filter(|&k| k != i_theta2).collect();
    let mut torque2 = torque2_start;
    let residual = |y: &[f64], torque2: f64| -> Result<DVector<f64>, String> {
        let (dy, _) = dynamics.rhs(y, anchor, [torque1_nm, torque2])?;
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
        let mut step = jac.lu().solve(&(-&r)).ok_or("the static equilibrium's Jacobian is singular")?;
        // A full step can overshoot into a contact beyond the Hertz law's range (b > h/4) where
        // the quasi-static shapes have not yet relieved it: halve it until the pair evaluates.
        let mut trial = y.clone();
        for halving in 0.. {
            for (col, &k) in unknowns.iter().enumerate() {
                trial[k] = y[k] + step[col];
            }
            match residual(&trial, torque2 + step[n - 1]) {
                Ok(_) => break,
                Err(e) if halving >= 6 => return Err(e),
                Err(_) => step *= 0.5,
            }
        }
        y = trial;
        torque2 += step[n - 1];
        let size = unknowns.iter().enumerate().map(|(c, &k)| (step[c] / scale[k]).abs()).fold(0.0, f64::max);
        if size < 1e-10 {
            dynamics.unpack(&y, &mut s);
            return Ok((s, torque2));
        }
    }
    Err(format!("the static equilibrium at θ₂ = {theta2} rad, τ₁ = {torque1_nm} N·m did not converge"))
}

/// The mesh force at which the mesh damper's stiffness is taken: 200 N/mm of face width, the
/// lumped model's reference (`LumpedMesh::reference_force_n`), so both model kinds define the
/// mesh damping ratio alike.
pub fn reference_mesh_force_n(pair: &crate::gear::GearPair) -> f64 {
    200.0e3 * pair.face_width_m
}

/// Positions over a pitch at which the mean mesh stiffness is sampled.
const STIFFNESS_POSITIONS: usize = 8;

/// The mean tangent mesh stiffness (N/m) of the reduced pair at the mesh force `force_n`: at
/// positions spread over a pitch of gear 2, the static transmission error r_b1θ₁ − r_b2θ₂ at
/// 0.95 and 1.05 × the force (static equilibria of the whole reduced pair: teeth, bodies and
/// Hertz contact), the force step over the TE step, averaged over the positions — the quantity
/// the lumped model's mean of ∂F/∂δ is (`MeshLaw::mean_tangent_stiffness`).
pub fn mean_mesh_stiffness(dynamics: &PmorDynamics, force_n: f64) -> Result<f64, String> {
    let model = dynamics.model;
    let rb = [model.pair.gear1.base_radius_m, model.pair.gear2.base_radius_m];
    let guess = force_n / (1e11 * model.pair.face_width_m);
    let mut sum = 0.0;
    for j in 0..STIFFNESS_POSITIONS {
        let theta2 = (j as f64 + 0.5) / STIFFNESS_POSITIONS as f64 * model.gears[1].pitch_rad();
        let te = |force: f64| -> Result<f64, String> {
            let (s, _) = static_equilibrium(dynamics, theta2, force * rb[0], guess)?;
            Ok(rb[0] * s.theta[0] - rb[1] * s.theta[1])
        };
        let (low, high) = (te(0.95 * force_n)?, te(1.05 * force_n)?);
        if high <= low {
            return Err(format!(
                "the static transmission error does not grow with the load at θ₂ = {theta2} rad ({low:e} → {high:e} m)"
            ));
        }
        sum += 0.1 * force_n / (high - low);
    }
    Ok(sum / STIFFNESS_POSITIONS as f64)
}

/// The damping ratio the calibration asks of the mesh mode (`mesh_damper_gain`).
const GAIN_REFERENCE_RATIO: f64 = 0.05;

/// The calibration g of the mesh damper (`PmorModel::mesh_damper_gain`). With the damper at
/// g = 1 sized for ζ = 0.05 (c = 2ζ√(k̄·m_e)), the ratio it adds to the mesh mode, Δζ, is
/// measured at the mesh positions of [`mean_mesh_stiffness`] under the reference mesh force k̄
/// is measured at ([`reference_mesh_force_n`]); g = ζ / mean Δζ, so that the mesh mode gets the
/// ratio asked on the average over a mesh cycle, as k̄ is the cycle's mean stiffness. Like any
/// viscous mesh damper's (the lumped model's too, by √(k/k̄)), the ratio then varies with the
/// contact zone: on the default spur pair Δζ/ζ at g = 1 is 0.65 in single and 0.41 in double
/// contact. Where fewer than half the positions give a mesh mode under that force (on the small
/// helical example a tip-edge section leaves the Hertz law's range b < h/4 in the
/// linearization), half and then a quarter of it is tried. The ratio added is linear in c over
/// the range a user sets (measured on the default spur pair from ζ = 0.02 to 0.75), so one
/// ratio calibrates all; `pmor_dynamics` checks the result at other ratios and loads.
/// Returns (g, the load on gear 1 it was found at).
pub fn mesh_damper_gain(dynamics: &PmorDynamics) -> Result<(f64, f64), String> {
    let model = dynamics.model;
    let inertia = [model.gears[0].polar_inertia_kgm2, model.gears[1].polar_inertia_kgm2];
    let c = 2.0 * GAIN_REFERENCE_RATIO * (model.mesh_stiffness_n_per_m * model.mesh_mass_kg(inertia)).sqrt();
    let mut failures = Vec::new();
    for share in [1.0, 0.5, 0.25] {
        let torque1_nm = share * reference_mesh_force_n(&model.pair) * model.pair.gear1.base_radius_m;
        let mut added = Vec::new();
        for j in 0..STIFFNESS_POSITIONS {
            let theta2 = (j as f64 + 0.5) / STIFFNESS_POSITIONS as f64 * model.gears[1].pitch_rad();
            let with = |c: f64| -> Result<f64, String> {
                Ok(mesh_mode(&dynamics.with_mesh_damper(c), theta2, torque1_nm)?.damping_ratio)
            };
            match (with(c), with(0.0)) {
                (Ok(damped), Ok(undamped)) => added.push(damped - undamped),
                (Err(e), _) | (_, Err(e)) => {
                    failures.push(format!("T₁ = {torque1_nm:.4} N·m, θ₂ = {theta2:.4e} rad: {e}"))
                }
            }
        }
        if 2 * added.len() >= STIFFNESS_POSITIONS {
            let mean = added.iter().sum::<f64>() / added.len() as f64;
            if !(mean > 0.0) {
                return Err(format!("the mesh damper adds no damping to the mesh mode (mean Δζ = {mean})"));
            }
            return Ok((GAIN_REFERENCE_RATIO / mean, torque1_nm));
        }
    }
    Err(format!("the mesh damper could not be calibrated: {}", failures.join("; ")))
}

/// The mesh mode of the reduced pair at one mesh position.
#[derive(Debug, Clone, Copy)]
pub struct MeshMode {
    /// Undamped natural frequency (Hz), √λ of −∂q̈/∂q.
    pub frequency_hz: f64,
    /// −Re μ/|μ| of the damped flow's eigenvalue μ nearest it.
    pub damping_ratio: f64,
    /// Its share of the DTE's modal response to a load step (the mode "is" the mesh mode when
    /// one mode carries most of it).
    pub dte_share: f64,
}

/// The mesh mode with gear 2 at θ₂ under T₁: the mode that carries most of the DTE's response
/// to a small load step (T₁ → 1.02·T₁, both static equilibria). Linear theory splits that
/// response into modes, a_k = d·φ_k·(ψ_kᵀΔq)/(ψ_kᵀφ_k), φ, ψ the right and left eigenvectors of
/// −∂q̈/∂q (inverse iteration on each eigenvalue), d the TE row r_b1θ₁ − r_b2θ₂ and Δq the static
/// change (`pmor_dynamics::torque_step_rings_at_the_linearized_mesh_mode` checks it against the
/// spectrum of a nonlinear run).
pub fn mesh_mode(dynamics: &PmorDynamics, theta2: f64, torque1_nm: f64) -> Result<MeshMode, String> {
    let model = dynamics.model;
    let rb = [model.pair.gear1.base_radius_m, model.pair.gear2.base_radius_m];
    let guess = torque1_nm / rb[0] / (1e11 * model.pair.face_width_m);
    let (s0, t2) = static_equilibrium(dynamics, theta2, torque1_nm, guess)?;
    let te0 = rb[0] * s0.theta[0] - rb[1] * s0.theta[1];
    let (s1, _) = static_equilibrium(dynamics, theta2, 1.02 * torque1_nm, te0)?;
    let lin = linearize(dynamics, &s0, [torque1_nm, t2])?;
    let a = lin.stiffness_block();
    let n = lin.coordinates;
    let (y0, y1) = (dynamics.pack(&s0), dynamics.pack(&s1));
    let dq = DVector::from_iterator(n, (0..n).map(|k| y1[k] - y0[k]));
    let mut d = DVector::zeros(n);
    d[0] = rb[0];
    d[dynamics.layout().q(1)] = -rb[1];
    let mut modes: Vec<(f64, f64)> = Vec::new();
    for lambda in a.complex_eigenvalues().iter() {
        if lambda.re < 1.0 {
            continue; // the rigid rotation
        }
        let shift = lambda.re * (1.0 + 1e-9);
        let vector = |m: &DMatrix<f64>| -> Result<DVector<f64>, String> {
            let lu = (m - DMatrix::identity(n, n) * shift).lu();
            let mut x = DVector::from_element(n, 1.0);
            for _ in 0..3 {
                x = lu.solve(&x).ok_or("inverse iteration: singular shift")?;
                x /= x.norm();
            }
            Ok(x)
        };
        let (phi, psi) = (vector(&a)?, vector(&a.transpose())?);
        let amplitude = d.dot(&phi) * psi.dot(&dq) / psi.dot(&phi);
        modes.push((lambda.re.sqrt() / (2.0 * std::f64::consts::PI), amplitude.abs()));
    }
    let total: f64 = modes.iter().map(|m| m.1).sum();
    let (frequency_hz, amplitude) =
        modes.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1)).ok_or("the pair has no oscillating mode")?;
    let damping_ratio = mesh_mode_damping_ratio(dynamics, &s0, [torque1_nm, t2], &lin, frequency_hz)?;
    Ok(MeshMode { frequency_hz, damping_ratio, dte_share: amplitude / total })
}

/// Steps of the continuation in the mesh damper (`mesh_mode_damping_ratio`).
const DAMPER_CONTINUATION_STEPS: usize = 10;

/// The damping ratio −Re μ/|μ| of the mesh mode's eigenvalue μ of the damped flow. Without the
/// mesh damper (damping modal, light) μ is the oscillating eigenvalue whose |μ| is nearest the
/// undamped mesh frequency. The mesh damper is not proportional: at high ratios it couples the
/// mesh mode with the body modes, and the nearest |μ| can be another mode's (found at ζ = 0.3 in
/// single contact). So μ is followed from the damper-free flow as the damper grows to its
/// value in `DAMPER_CONTINUATION_STEPS` steps, each step taking the eigenvalue nearest the last.
fn mesh_mode_damping_ratio(
    dynamics: &PmorDynamics,
    s0: &PmorState,
    torques: [f64; 2],
    lin: &LinearizedPair,
    frequency_hz: f64,
) -> Result<f64, String> {
    let oscillating = |lin: &LinearizedPair| -> Vec<Complex<f64>> {
        lin.flow_eigenvalues().into_iter().filter(|l| l.im > 0.0).collect()
    };
    let nearest_frequency = |eigenvalues: Vec<Complex<f64>>| {
        eigenvalues
            .into_iter()
            .min_by(|a, b| {
                let f = |l: &Complex<f64>| (l.norm() / (2.0 * std::f64::consts::PI) - frequency_hz).abs();
                f(a).total_cmp(&f(b))
            })
            .ok_or("the flow has no oscillating eigenvalue")
    };
    let damper = dynamics.mesh_damping_n_s_per_m;
    if damper <= 0.0 {
        let mu = nearest_frequency(oscillating(lin))?;
        return Ok(-mu.re / mu.norm());
    }
    let mut d = dynamics.with_mesh_damper(0.0);
    let mut mu = nearest_frequency(oscillating(&linearize(&d, s0, torques)?))?;
    for k in 1..=DAMPER_CONTINUATION_STEPS {
        d.mesh_damping_n_s_per_m = damper * k as f64 / DAMPER_CONTINUATION_STEPS as f64;
        let eigenvalues =
            if k == DAMPER_CONTINUATION_STEPS { oscillating(lin) } else { oscillating(&linearize(&d, s0, torques)?) };
        mu = eigenvalues
            .into_iter()
            .min_by(|a, b| (*a - mu).norm().total_cmp(&(*b - mu).norm()))
            .ok_or("the flow has no oscillating eigenvalue")?;
    }
    Ok(-mu.re / mu.norm())
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

    /// The largest step `integrator` keeps stable on the linearized flow: RK4 per eigenvalue λ
    /// of the flow (its one-step map is a polynomial in hJ, so that is exact); velocity Verlet
    /// on its own one-step map of the whole flow (`verlet_stability_limit_s`).
    pub fn stability_limit_s(&self, integrator: Integrator) -> f64 {
        // The discrete gradient is unconditionally stable; its step rule is Verlet's limit.
        if integrator == Integrator::Verlet || integrator == Integrator::DiscreteGradient {
            return self.verlet_stability_limit_s();
        }
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

    /// Velocity Verlet's one-step map of the linearized flow q̈ = A q + B q̇, as `verlet_advance`
    /// runs it: the acceleration a step starts with is the one the previous step ended with,
    /// taken at that step's predicted velocity v*, so the map acts on (q, v, v*). In the scaled
    /// coordinates z = (q, u, w) = (q, h·v, h·v*), so that its entries are O(1), with P = h²A,
    /// Q = hB and h²a = P q + Q w:
    ///   q′ = q + u + ½(P q + Q w),   w′ = u + (P q + Q w),
    ///   u′ = u + ½(P q + Q w) + ½(P q′ + Q w′).
    pub fn verlet_map(&self, h: f64) -> DMatrix<f64> {
        let n = self.coordinates;
        let p = self.flow.view((n, 0), (n, n)) * (h * h);
        let q = self.flow.view((n, n), (n, n)) * h;
        let mut s = DMatrix::zeros(n, 3 * n); // z ↦ h²a
        s.view_mut((0, 0), (n, n)).copy_from(&p);
        s.view_mut((0, 2 * n), (n, n)).copy_from(&q);
        let (mut x_next, mut w_next) = (s.clone() * 0.5, s.clone()); // q′, w′
        for k in 0..n {
            x_next[(k, k)] += 1.0;
            x_next[(k, n + k)] += 1.0;
            w_next[(k, n + k)] += 1.0;
        }
        let a_next = &p * &x_next + &q * &w_next; // h²a′
        let mut u_next = (&s + &a_next) * 0.5;
        for k in 0..n {
            u_next[(k, n + k)] += 1.0;
        }
        let mut g = DMatrix::zeros(3 * n, 3 * n);
        g.view_mut((0, 0), (n, 3 * n)).copy_from(&x_next);
        g.view_mut((n, 0), (n, 3 * n)).copy_from(&u_next);
        g.view_mut((2 * n, 0), (n, 3 * n)).copy_from(&w_next);
        g
    }

    /// The largest step whose velocity Verlet map has spectral radius ≤ 1 (bisection). The map
    /// is built from the whole flow, not mode by mode: the shapes' damping is diagonal in η, not
    /// in the coupled modes, and at a heavy damping ratio the per-eigenvalue estimate (exact for
    /// RK4, whose map is a polynomial in hJ) overstates Verlet's limit. Eigenvalues μ within
    /// 1e3·h of 1 are the rigid rotation and slow modes (|λ| ≤ 1e3/s), resolved by any step:
    /// the differences leave the rigid rotation a real pair ±170/s on the default spur pair,
    /// whose μ ≈ 1 + 170h is no instability of the integrator; the lowest elastic mode has
    /// |λ| = 1.5e4/s. Undamped pairs sit on |μ| = 1 up to the differences' round-off, so the
    /// test is |μ| ≤ 1 + 1e-5 (an instability past the limit grows far faster).
    pub fn verlet_stability_limit_s(&self) -> f64 {
        let stable = |h: f64| {
            self.verlet_map(h)
                .complex_eigenvalues()
                .iter()
                .filter(|mu| (*mu - Complex::new(1.0, 0.0)).norm() > 1e3 * h)
                .all(|mu| mu.norm() <= 1.0 + 1e-5)
        };
        crate::dynamics::rk4_stability::bisect_stable_step(stable, 1e-3)
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
