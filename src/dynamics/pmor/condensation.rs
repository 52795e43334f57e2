//! The quasi-static condensation's data (`quasi_static`): per gear the split of the coordinates
//! into the slow ones that are integrated and the fast ones solved at every right-hand side
//! (`GearSplit`), the cut-offs that decide it, and the Newton solver's state and matrices
//! (`QuasiStatic`, `FastTangent`, `Prediction`). Set up once per instance; what is done with it
//! at every right-hand side is in `quasi_static`.

use nalgebra::{DMatrix, DVector};
use std::cell::RefCell;

/// Without a mesh-mode estimate (a model whose mean mesh stiffness is not yet known), the hub
/// direction is condensed when its free frequency exceeds this multiple of the highest body mode.
pub const HUB_CUTOFF: f64 = 1.5;

/// The body modes above this multiple of the mesh mode's 2-DOF estimate √(k̄/m_e)/2π (FE
/// inertias) are condensed with the fast coordinates under an explicit integrator (velocity
/// Verlet, RK4): they bound its step, yet at the mesh mode and below — everything a drivetrain
/// resolves — a mode at ≥ 3× the excitation responds within 1/(1 − 1/9) = 1.125 of its static
/// response, which is what the condensation keeps. Measured on example 3 (Kurokawa spur pair,
/// 20 µs sampling, against no cut-off): factors 6, 4, 3 and 2 leave the DTE mean within 0.002 %
/// and its RMS and peak-to-peak within 0.14 %. It is also the step rule of the discrete
/// gradient (`linear::default_step`), which keeps more modes dynamic
/// (`IMPLICIT_BODY_CUTOFF_PER_MESH_MODE`).
pub const BODY_CUTOFF_PER_MESH_MODE: f64 = 3.0;

/// The discrete gradient's cut-off. It is unconditionally stable, so a dynamic body mode costs it
/// no step, and at 6× the mesh mode comes within 0.3–0.5 % of the full pair's (+0.9–1.9 % at 3×,
/// which left the response above the resonance up to 14 % high; issue 38,
/// `examples/mesh_mode_condensation.rs`). It was held at 3× while two masters feeding the same
/// inputs (libcosim, whose h is a difference of times, and fmpy) drew apart by 4e-5 of ω₂'s
/// range on example 3 at 6×: the step's start extrapolated the bodies' stiff modes explicitly,
/// so a mode with ωh > 2 (17 kHz at 20 µs) grew from Newton's remainder below its energy test
/// (`examples/step_map_sensitivity.rs`; fixed in `discrete_gradient_step`).
pub const IMPLICIT_BODY_CUTOFF_PER_MESH_MODE: f64 = 6.0;

/// The cut-off frequency (Hz) above which a body mode is quasi-static under the model's
/// integrator: `IMPLICIT_BODY_CUTOFF_PER_MESH_MODE` for the discrete gradient,
/// `BODY_CUTOFF_PER_MESH_MODE` for an explicit one, times the mesh mode's estimate; none
/// (infinite) before the build has measured k̄.
pub fn body_cutoff_hz(model: &super::model::PmorModel) -> f64 {
    let factor = match model.integrator {
        super::integrator::Integrator::DiscreteGradient => IMPLICIT_BODY_CUTOFF_PER_MESH_MODE,
        _ => BODY_CUTOFF_PER_MESH_MODE,
    };
    factor * mesh_mode_estimate_hz(model)
}

/// The mesh mode's 2-DOF estimate √(k̄/m_e)/2π at the FE inertias (Hz), infinite before the build
/// has measured k̄.
pub fn mesh_mode_estimate_hz(model: &super::model::PmorModel) -> f64 {
    let inertia = [model.gears[0].polar_inertia_kgm2, model.gears[1].polar_inertia_kgm2];
    let k = model.mesh_stiffness_n_per_m;
    if k > 0.0 {
        (k / model.mesh_mass_kg(inertia)).sqrt() / (2.0 * std::f64::consts::PI)
    } else {
        f64::INFINITY
    }
}

/// Newton's iterations on the fast coordinates before giving up.
pub(super) const NEWTON_ITERATIONS: usize = 40;

/// Newton stops when the decrement ΔzᵀKΔz falls below this fraction of the potential energy
/// (plus an absolute floor far below any loaded pair's, J): |Δz|/|z| ≈ 1e-8, far inside the
/// linearization's central differences (relative 1e-6). The decrement's round-off floor is
/// about 2e-20 of the potential (measured on the default spur pair in example 3), so this is
/// the tightest test that round-off cannot defeat; quadratic convergence usually lands far
/// below it.
pub(super) const NEWTON_RELATIVE_DECREMENT: f64 = 1e-16;
pub(super) const NEWTON_FLOOR_J: f64 = 1e-24;

/// In time stepping, a solve ends at the first evaluation whose decrement is below this
/// fraction of the potential (|Δz|/|z| ≲ 1e-3): the last Newton step Δz is then taken without
/// evaluating the contact again, the slow forces moved along with it to first order
/// (`shift_slow_forces`). What is left is Newton's own error after that step: the Jacobian's
/// inexactness (the band rows, the angle terms left out; measured, each step shrinks |Δz| about
/// a thousandfold) times |Δz|, ≈ 1e-6 of z. No start can do better than O(h) where the contact
/// point crosses a node of the flank grid (the bilinear shares have kinks there): on example 3
/// the first decrement spreads from 1e-4 to 1e-9 of the potential. Measured on example 3
/// (default spur pair, every body mode dynamic, 7.3 µs, secant start): 1.23 evaluations per
/// solve at 1e-6 against 1.54 at 1e-8 and 1.80 at 1e-10, the DTE's mean and peak-to-peak the
/// same to 1e-5; with the cut-off at 20 µs, 1e-5 and 1e-4 save 4 and 7 % of the evaluations
/// only. The energy tests of `pmor_dynamics` hold at it. The settling to new torques at the
/// start of each `advance` uses it too (`Prediction` starts it from the last solve's tangent).
pub(super) const STEP_RELATIVE_DECREMENT: f64 = 1e-6;

/// A discrete-gradient step's first solve, at its predictor, ends at this decrement: the step's
/// Newton iterations solve again from it (each at `STEP_RELATIVE_DECREMENT`), and the step is
/// never accepted on a solve this loose (`PmorDynamics::discrete_gradient_step`). The predictor
/// moves the slow state by a whole step from the last solve, and at the step's tolerance its solve
/// took 2.2 contact evaluations on average against one at each later iteration. Measured on the
/// Kurokawa spur pair (`cargo bench --bench step_path`, contact evaluations per doStep at 0.5 kHz
/// 20 µs / 1.5 kHz 20 µs / 1.5 kHz 100 µs / 3 kHz 20 µs): 5.37 / 8.63 / 27.77 / 9.26 at 1e-6,
/// 4.74 / 7.16 / 23.01 / 8.37 at 1e-3, 4.49 / 7.06 / 22.43 / 8.17 at 1e-2 (the solves rise by
/// 3–9 %: a later iteration is needed more often).
pub(super) const PREDICTOR_RELATIVE_DECREMENT: f64 = 1e-2;

/// A time step's solve that has not lowered its decrement for this many iterations has
/// stalled: Newton's matrix leaves out the contact's angle terms and is one side's where the
/// contact point sits on a node of the flank grid, so there it can cycle above the step's
/// tolerance (measured in the PMOR-Hertz soak of `tests/fmi_c_api.rs`, a steady drive: the
/// decrement cycled between 1.2e-6 and 3.2e-6 of the potential for 40 iterations and the doStep
/// failed). A stalled solve is taken where it stands within twice its lowest decrement and below
/// `STALL_RELATIVE_DECREMENT`: the spread a flank-grid node leaves the first decrement with in
/// any case (1e-4 to 1e-9 of the potential on example 3).
pub(super) const STALL_ITERATIONS: usize = 6;
pub(super) const STALL_RELATIVE_DECREMENT: f64 = 1e-4;

/// How many (h, ζ) a split keeps its bodies' iteration block for: a run at constant speed uses
/// one step length; a ramp moves through the few that its calls split into.
const ITERATION_BLOCKS_KEPT: usize = 4;

/// A kept iteration block: its key (h, ζ as bits) and the inverse.
#[derive(Debug)]
struct IterationBlock {
    key: [u64; 2],
    inverse: std::sync::Arc<DMatrix<f64>>,
}

/// One gear's split of η_Φ into the slow part Q·ξ and the fast part F·z_Φ: the hub direction b̂
/// (where the bore is light) and the body modes above the cut-off.
#[derive(Debug, Clone)]
pub struct GearSplit {
    /// Whether the hub direction is condensed.
    pub hub: bool,
    /// b = (Gx)ᵀMΦ (n_k).
    pub b: DVector<f64>,
    /// J (kg·m²): the FE body's polar inertia plus the added.
    pub inertia_kgm2: f64,
    /// F (n_k × n_f): orthonormal columns, b̂ restricted to the retained modes (where the hub is
    /// condensed) and the unit vectors of the condensed body modes.
    pub fast_basis: DMatrix<f64>,
    /// F's nonzero entries (row, value) per column: b̂ has the few of the hub's modes, the others
    /// one each, so the step path reads F in O(n_f).
    pub(super) fast_columns: Vec<Vec<(usize, f64)>>,
    /// Fᵀb/J: the bore's turn per unit of the fast coordinates (θ = φ − bᵀ(Qξ + Fz)/J).
    pub bore_turn: DVector<f64>,
    /// FᵀΛF: the fast body coordinates' stiffness, diagonal (b̂ lies on the retained modes,
    /// the condensed modes are unit vectors).
    pub(super) fast_stiffness: DVector<f64>,
    /// Q (n_k × n_ξ): orthonormal columns, the complement of F.
    pub basis: DMatrix<f64>,
    /// Q in the form the step path applies: on the retained modes (their indices in η_Φ), the
    /// last n_l − 1 columns of the Householder reflection H = I − s·vvᵀ that takes e₁ to b̂
    /// (`complement`), or the identity where the hub stays. b̂ has an entry on every retained
    /// mode that turns the bore, so Q is dense there; in this form Q·ξ and Qᵀf cost O(n_l).
    slow_map: SlowMap,
    /// Qᵀ(M_ΦΦ − bbᵀ/J)Q, the slow mass on ξ, and its Cholesky factor.
    pub xi_mass: DMatrix<f64>,
    /// M_ξ⁻¹, made once per split from its Cholesky factor: the step path applies it as a dense
    /// product (issue 39: nalgebra's triangular solves, column by column, took a third of a doStep
    /// with `inertia_i` at twice the FE value, where M_ξ is not the identity).
    pub(super) xi_mass_inverse: DMatrix<f64>,
    /// Whether that mass is the identity to round-off (Φ mass-normalized: measured ≤ 1e-14 on
    /// the example pairs), so the accelerations are the forces themselves.
    pub(super) xi_mass_is_unit: bool,
    /// The slow body coordinates' stiffness and modal-damping root as accelerations
    /// (`slow_body_stiffness`, `slow_body_damping`), made with the split: the discrete
    /// gradient's Newton matrix reads them at every doStep.
    pub(super) slow_body_acceleration_stiffness: DMatrix<f64>,
    pub(super) slow_body_acceleration_damping_root: DMatrix<f64>,
    /// (I + h/2·D_ξ + h²/4·A_ξ)⁻¹ for the last few (h, ζ) (`iteration_block`): shared by the
    /// dynamics every doStep makes, so an FMU inverts it once per step length, not per call (it
    /// was half of a doStep's overhead; issue 39). A pure function of its key: kept or made
    /// again, the same matrix.
    iteration_blocks: std::sync::Arc<std::sync::Mutex<Vec<IterationBlock>>>,
    /// The hub mode's free frequency (Hz) among the retained modes, the choice was made on.
    pub hub_frequency_hz: f64,
    /// The cut-off (Hz) and the body modes above it.
    pub cutoff_hz: f64,
    pub condensed_modes: usize,
}

impl GearSplit {
    /// The gear's port, condensed (`PmorDynamics::port`): the slow angle φ = θ + bᵀη_Φ/J and its
    /// rate, from the bore's θ, ω and the elastic state η, η̇ (η_Φ first); the shapes carry no
    /// inertia here.
    pub fn mean_axis_port(&self, eta: &[f64], eta_dot: &[f64], theta: f64, omega: f64) -> (f64, f64) {
        let n_k = self.b.len();
        let dot = |a: &[f64]| self.b.as_slice().iter().zip(&a[..n_k]).map(|(x, y)| x * y).sum::<f64>();
        (theta + dot(eta) / self.inertia_kgm2, omega + dot(eta_dot) / self.inertia_kgm2)
    }

    pub fn new(gear: &super::model::PmorGear, added_inertia_kgm2: f64, cutoff_hz: f64) -> Result<Self, String> {
        let n_k = gear.modes();
        let inertia = gear.polar_inertia_kgm2 + added_inertia_kgm2;
        let b = gear.gx_phi.clone();
        let hz = |lambda: f64| lambda.max(0.0).sqrt() / (2.0 * std::f64::consts::PI);
        let (low, high): (Vec<usize>, Vec<usize>) = (0..n_k).partition(|&j| hz(gear.eigenvalues[j]) <= cutoff_hz);
        let embed = |cols: &DMatrix<f64>| {
            let mut m = DMatrix::zeros(n_k, cols.ncols());
            for (r, &j) in low.iter().enumerate() {
                m.row_mut(j).copy_from(&cols.row(r));
            }
            m
        };
        // The mean-axis mass M_ΦΦ − bbᵀ/J and, on the retained modes, the pencil (Λ_L, its block):
        // its highest frequency is the hub mode where the bore is light.
        let mass = &gear.phi_phi - &b * b.transpose() / inertia;
        let n_l = low.len();
        let mass_low = DMatrix::from_fn(n_l, n_l, |r, c| mass[(low[r], low[c])]);
        let (hub_frequency_hz, body_top_hz) = if n_l == 0 {
            (0.0, 0.0)
        } else {
            let l = mass_low.clone().cholesky().ok_or("the mean-axis mass M_ΦΦ − bbᵀ/J is not positive definite")?.l();
            let l_inv = l.try_inverse().ok_or("singular mean-axis mass")?;
            let lambda = DMatrix::from_diagonal(&DVector::from_iterator(n_l, low.iter().map(|&j| gear.eigenvalues[j])));
            let a = &l_inv * lambda * l_inv.transpose();
            let top = nalgebra::SymmetricEigen::new((&a + a.transpose()) * 0.5).eigenvalues.max();
            (hz(top), low.iter().map(|&j| hz(gear.eigenvalues[j])).fold(0.0, f64::max))
        };
        let hub_threshold_hz = if cutoff_hz.is_finite() { cutoff_hz } else { HUB_CUTOFF * body_top_hz };
        let b_low = DVector::from_iterator(n_l, low.iter().map(|&j| b[j]));
        let hub = n_l > 1 && b_low.norm() > 0.0 && hub_frequency_hz > hub_threshold_hz;
        let (basis, mut fast_basis) = if hub {
            let b_hat = b_low.normalize();
            (embed(&complement(&b_hat)), embed(&DMatrix::from_column_slice(n_l, 1, b_hat.as_slice())))
        } else {
            (embed(&DMatrix::identity(n_l, n_l)), DMatrix::zeros(n_k, 0))
        };
        for &j in &high {
            let n_f = fast_basis.ncols();
            fast_basis = fast_basis.insert_column(n_f, 0.0);
            fast_basis[(j, n_f)] = 1.0;
        }
        let lambda = DMatrix::from_diagonal(&DVector::from_column_slice(&gear.eigenvalues));
        let fast_stiffness = (fast_basis.transpose() * &lambda * &fast_basis).diagonal();
        let bore_turn = fast_basis.transpose() * &b / inertia;
        let fast_columns = nonzero_columns(&fast_basis);
        let slow_map = SlowMap {
            retained: low.clone(),
            reflector: hub.then(|| {
                let v = householder_vector(&b_low.normalize());
                let scale = 2.0 / v.norm_squared();
                (v, scale)
            }),
        };
        let xi_mass = basis.transpose() * &mass * &basis;
        let xi_mass_factor = xi_mass.clone().cholesky().ok_or("the slow mass on ξ is not positive definite")?;
        let n_x = xi_mass.nrows();
        let xi_mass_is_unit = (&xi_mass - DMatrix::identity(n_x, n_x)).amax() < 1e-12;
        let slow_body_acceleration_stiffness = {
            let mut k = basis.transpose() * &lambda * &basis;
            if fast_basis.ncols() > 0 {
                let kqf = basis.transpose() * &lambda * &fast_basis;
                let kff = fast_basis.transpose() * &lambda * &fast_basis;
                if let Some(inverse) = kff.try_inverse() {
                    k -= &kqf * inverse * kqf.transpose();
                }
            }
            xi_mass_factor.solve(&k)
        };
        let root = DMatrix::from_diagonal(&DVector::from_iterator(n_k, gear.eigenvalues.iter().map(|l| l.sqrt())));
        let slow_body_acceleration_damping_root = xi_mass_factor.solve(&(basis.transpose() * root * &basis));
        let xi_mass_inverse = xi_mass_factor.inverse();
        let split = GearSplit {
            slow_body_acceleration_stiffness,
            slow_body_acceleration_damping_root,
            iteration_blocks: Default::default(),
            hub,
            b,
            inertia_kgm2: inertia,
            fast_basis,
            fast_columns,
            bore_turn,
            fast_stiffness,
            basis,
            slow_map,
            xi_mass,
            xi_mass_inverse,
            xi_mass_is_unit,
            hub_frequency_hz,
            cutoff_hz,
            condensed_modes: high.len(),
        };
        split.check_slow_map()?;
        Ok(split)
    }

    /// The step path's Q (`slow_map`) against the matrix it stands for, column by column.
    fn check_slow_map(&self) -> Result<(), String> {
        let (n_k, n_x) = (self.basis.nrows(), self.basis.ncols());
        let mut worst: f64 = 0.0;
        let mut xi = vec![0.0; n_x];
        let mut eta = vec![0.0; n_k];
        let mut back = vec![0.0; n_x];
        for c in 0..n_x {
            xi.fill(0.0);
            xi[c] = 1.0;
            eta.fill(0.0);
            self.add_slow(&xi, &mut eta);
            self.force_on_slow_into(0.0, &eta, &mut back);
            for r in 0..n_k {
                worst = worst.max((eta[r] - self.basis[(r, c)]).abs());
            }
            // QᵀQ = I.
            for (r, b) in back.iter().enumerate() {
                worst = worst.max((b - if r == c { 1.0 } else { 0.0 }).abs());
            }
        }
        if worst > 1e-12 {
            return Err(format!("the slow map differs from its basis Q by {worst:e}"));
        }
        Ok(())
    }

    /// (Fᵀv)_c.
    pub(super) fn fast_dot(&self, c: usize, v: &[f64]) -> f64 {
        self.fast_columns[c].iter().map(|&(j, f)| f * v[j]).sum()
    }

    /// The slow body coordinates' condensed stiffness, mass-normalized: (Qᵀ(M_ΦΦ − bbᵀ/J)Q)⁻¹
    /// times QᵀΛQ − QᵀΛF(FᵀΛF)⁻¹FᵀΛQ (the fast body coordinates at their equilibrium; the
    /// contact and the torque left out). The discrete-gradient step's Newton matrix is made of
    /// it: exact for the bodies, which are linear.
    pub fn slow_body_stiffness(&self) -> &DMatrix<f64> {
        &self.slow_body_acceleration_stiffness
    }

    /// The slow body coordinates' modal damping at ratio ζ, mass-normalized:
    /// M_ξ⁻¹·Qᵀ·diag(2ζ√λ)·Q (the damping force of η̇_Φ = Q·ξ̇, as `PmorDynamics::evaluate`
    /// applies it). With the stiffness, what the discrete gradient's Newton matrix needs of the
    /// bodies.
    pub fn slow_body_damping(&self, ratio: f64) -> DMatrix<f64> {
        &self.slow_body_acceleration_damping_root * (2.0 * ratio)
    }

    /// (I + h/2·D_ξ + h²/4·A_ξ)⁻¹ at step h and modal damping ratio ζ: this gear's block of the
    /// discrete gradient's Newton matrix for the bodies; `None` where it is singular.
    pub(super) fn iteration_block(&self, h: f64, modal_ratio: f64) -> Option<std::sync::Arc<DMatrix<f64>>> {
        let key = [h.to_bits(), modal_ratio.to_bits()];
        let mut kept = self.iteration_blocks.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(block) = kept.iter().find(|b| b.key == key) {
            return Some(block.inverse.clone());
        }
        let mut block = self.slow_body_stiffness() * (0.25 * h * h) + self.slow_body_damping(modal_ratio) * (0.5 * h);
        for k in 0..block.nrows() {
            block[(k, k)] += 1.0;
        }
        let inverse = std::sync::Arc::new(block.try_inverse()?);
        if kept.len() >= ITERATION_BLOCKS_KEPT {
            kept.remove(0);
        }
        kept.push(IterationBlock { key, inverse: inverse.clone() });
        Some(inverse)
    }

    /// η += Q·ξ (n_k).
    pub(super) fn add_slow(&self, xi: &[f64], eta: &mut [f64]) {
        let low = &self.slow_map.retained;
        match &self.slow_map.reflector {
            None => low.iter().zip(xi).for_each(|(&j, x)| eta[j] += x),
            Some((v, scale)) => {
                // H·[0; ξ] = [0; ξ] − s·v·(v[1..]·ξ).
                let along = scale * v.iter().skip(1).zip(xi).map(|(v, x)| v * x).sum::<f64>();
                eta[low[0]] -= along * v[0];
                for (r, &j) in low.iter().enumerate().skip(1) {
                    eta[j] += xi[r - 1] - along * v[r];
                }
            }
        }
    }

    /// Qᵀ(f_Φ − b·f_θ/J): a force on (θ, η_Φ) on ξ.
    pub(super) fn force_on_slow(&self, f_theta: f64, f_phi: &[f64]) -> DVector<f64> {
        let mut out = DVector::zeros(self.slow_size());
        self.force_on_slow_into(f_theta, f_phi, out.as_mut_slice());
        out
    }

    /// `force_on_slow` written into `out` (n_ξ): the step path's form, no allocation.
    pub(super) fn force_on_slow_into(&self, f_theta: f64, f_phi: &[f64], out: &mut [f64]) {
        let per_theta = f_theta / self.inertia_kgm2;
        let b = self.b.as_slice();
        let low = &self.slow_map.retained;
        let x = |r: usize| f_phi[low[r]] - b[low[r]] * per_theta;
        match &self.slow_map.reflector {
            None => out.iter_mut().enumerate().for_each(|(r, o)| *o = x(r)),
            Some((v, scale)) => {
                // (H·x)[1..] = x[1..] − s·v[1..]·(v·x).
                let along = scale * (0..low.len()).map(|r| v[r] * x(r)).sum::<f64>();
                for (r, o) in out.iter_mut().enumerate() {
                    *o = x(r + 1) - along * v[r + 1];
                }
            }
        }
    }

    /// ξ̈ = M_ξ⁻¹·f_ξ, in place.
    pub(super) fn xi_acceleration(&self, force: &mut DVector<f64>) {
        if !self.xi_mass_is_unit {
            *force = &self.xi_mass_inverse * &*force;
        }
    }

    /// Slow coordinates besides φ: n_ξ.
    pub fn slow_size(&self) -> usize {
        self.basis.ncols()
    }

    /// Fast body coordinates: n_f (the hub direction and the condensed modes).
    pub fn fast_body_size(&self) -> usize {
        self.fast_basis.ncols()
    }

    /// Fast coordinates: the fast body coordinates and η_Ψ.
    pub fn fast_size(&self, shapes: usize) -> usize {
        self.fast_body_size() + shapes
    }
}

/// A matrix's nonzero entries (row, value) per column.
pub(super) fn nonzero_columns(m: &DMatrix<f64>) -> Vec<Vec<(usize, f64)>> {
    m.column_iter().map(|c| c.iter().enumerate().filter(|(_, v)| **v != 0.0).map(|(j, v)| (j, *v)).collect()).collect()
}

/// An orthonormal basis of the complement of the unit vector `u` (n × (n − 1)): the last
/// n − 1 columns of the Householder reflection H = I − 2vvᵀ/vᵀv, v = u ± e₁, which maps u to ∓e₁.
pub(super) fn complement(u: &DVector<f64>) -> DMatrix<f64> {
    let n = u.len();
    let v = householder_vector(u);
    let h = DMatrix::identity(n, n) - &v * v.transpose() * (2.0 / v.norm_squared());
    h.columns(1, n - 1).into_owned()
}

/// v of the reflection I − 2vvᵀ/(vᵀv) whose first column is ∓u (u a unit vector).
fn householder_vector(u: &DVector<f64>) -> DVector<f64> {
    let mut v = u.clone();
    v[0] += if u[0] >= 0.0 { 1.0 } else { -1.0 };
    v
}

/// Q of a split, as applied on the step path (`GearSplit::slow_map`).
#[derive(Debug, Clone)]
struct SlowMap {
    /// The retained body modes' indices in η_Φ (n_l).
    retained: Vec<usize>,
    /// (v, 2/vᵀv) of the reflection whose columns 2… are Q on the retained modes; `None`: Q is
    /// the identity there.
    reflector: Option<(DVector<f64>, f64)>,
}

/// The condensation of both gears, and the fast coordinates of the last solve (the next
/// Newton's start).
pub struct QuasiStatic {
    /// Shared: an FMU makes them once per inertia set and hands them to every doStep's dynamics.
    pub splits: std::sync::Arc<[GearSplit; 2]>,
    pub(super) fast: RefCell<[Vec<f64>; 2]>,
    /// The last solve's linearization, the next solve's start where it exists (`Prediction`).
    pub(super) prediction: RefCell<Option<Prediction>>,
    /// Contact evaluations and solves so far (Newton's cost, for the benchmarks).
    pub counts: std::cell::Cell<(usize, usize)>,
    /// Whether a time stepper is calling (`STEP_RELATIVE_DECREMENT`), else every solve is
    /// tight (the linearization's differences need that).
    pub(super) stepping: std::cell::Cell<bool>,
    /// Whether the next solve is a discrete-gradient step's first, at its predictor
    /// (`PREDICTOR_RELATIVE_DECREMENT`), and whether the last solve met the step's own tolerance.
    pub(super) at_predictor: std::cell::Cell<bool>,
    pub(super) last_solve_tight: std::cell::Cell<bool>,
    /// −∂a/∂q of the slow coordinates' bodies, assembled once (`discrete_gradient_matrix`).
    pub(super) body_acceleration_stiffness: std::cell::OnceCell<DMatrix<f64>>,
    /// The same bodies' modal damping as accelerations (`GearSplit::slow_body_damping`).
    pub(super) body_acceleration_damping: std::cell::OnceCell<DMatrix<f64>>,
}

impl QuasiStatic {
    pub fn new(dynamics_model: &super::model::PmorModel, added_inertia_kgm2: [f64; 2]) -> Result<Self, String> {
        Self::with_cutoff(dynamics_model, added_inertia_kgm2, body_cutoff_hz(dynamics_model))
    }

    /// With another body-mode cut-off than the model's (Hz; infinite: every body mode dynamic,
    /// the condensation before the cut-off): the baseline the benchmarks and tests compare with.
    pub fn with_cutoff(
        dynamics_model: &super::model::PmorModel,
        added_inertia_kgm2: [f64; 2],
        cutoff_hz: f64,
    ) -> Result<Self, String> {
        let splits = [
            GearSplit::new(&dynamics_model.gears[0], added_inertia_kgm2[0], cutoff_hz)?,
            GearSplit::new(&dynamics_model.gears[1], added_inertia_kgm2[1], cutoff_hz)?,
        ];
        Ok(Self::from_splits(dynamics_model, std::sync::Arc::new(splits)))
    }

    /// From splits made before (`GearSplit::new` costs an eigen-decomposition per gear).
    pub fn from_splits(dynamics_model: &super::model::PmorModel, splits: std::sync::Arc<[GearSplit; 2]>) -> Self {
        let fast = [0, 1].map(|i| vec![0.0; splits[i].fast_size(dynamics_model.gears[i].shapes)]);
        QuasiStatic {
            splits,
            fast: RefCell::new(fast),
            prediction: RefCell::new(None),
            counts: Default::default(),
            stepping: Default::default(),
            at_predictor: Default::default(),
            last_solve_tight: Default::default(),
            body_acceleration_stiffness: std::cell::OnceCell::new(),
            body_acceleration_damping: std::cell::OnceCell::new(),
        }
    }
}

/// The elastic part D of Newton's matrix on the fast coordinates: block diagonal, per gear the
/// fast body coordinates' FᵀΛF (diagonal: b̂ lies on the retained modes, the condensed modes are
/// unit vectors) and the shapes' K_Ψ. The contact adds one rank-one term k_s·g_s g_sᵀ per loaded
/// section; Newton's matrix is solved in that structure (`FastTangent::solve`).
pub(super) struct FastTangent {
    /// (index in z, stiffness) of every fast body coordinate.
    pub(super) body: Vec<(usize, f64)>,
    /// (offset in z, K_Ψ⁻¹) per gear with shapes (n_t × n_t, from its Cholesky factor).
    pub(super) shapes: Vec<(usize, DMatrix<f64>)>,
    /// W = D⁻¹G and the Cholesky factor of K_s⁻¹ + GᵀW: what the Woodbury identity needs of
    /// the matrix alone, made at the first solve and kept for the next (the next time step's
    /// start, `Prediction`, solves with the same matrix).
    pub(super) woodbury: std::cell::OnceCell<(Vec<DVector<f64>>, nalgebra::Cholesky<f64, nalgebra::Dyn>)>,
}

/// Adds to `force` the fast coordinates' load of a slow move x through the loaded sections,
/// −Σ_s k_s·g_s·(r_s·x) (r_s a section's row in the slow positions, g_s in the fast
/// coordinates, k_s its Hertz stiffness): what the fast tangent turns into their move with the
/// slow one, K·Δz = that load (the implicit function theorem). The prediction of a solve's
/// start, the fast coordinates' rate and the move a Newton step takes without a solve share it.
pub(super) fn add_fast_load_of_slow_move(
    fast_rows: &[DVector<f64>],
    stiffness: &[f64],
    slow_rows: &[Vec<f64>],
    x: &[f64],
    force: &mut DVector<f64>,
) {
    for ((g, k), r) in fast_rows.iter().zip(stiffness).zip(slow_rows) {
        let approach: f64 = r.iter().zip(x).map(|(r, x)| r * x).sum();
        force.axpy(-k * approach, g, 1.0);
    }
}

impl FastTangent {
    pub(super) fn new() -> Self {
        FastTangent { body: Vec::new(), shapes: Vec::new(), woodbury: std::cell::OnceCell::new() }
    }

    /// v ← D⁻¹v.
    pub(super) fn apply_elastic_inverse(&self, v: &mut [f64]) {
        for &(k, d) in &self.body {
            v[k] /= d;
        }
        for (offset, inverse) in &self.shapes {
            let n = inverse.nrows();
            let mut part = [0.0; 64];
            let part = if n <= part.len() { &mut part[..n] } else { &mut vec![0.0; n][..] };
            part.copy_from_slice(&v[*offset..*offset + n]);
            for (r, out) in v[*offset..*offset + n].iter_mut().enumerate() {
                *out = (0..n).map(|c| inverse[(r, c)] * part[c]).sum();
            }
        }
    }

    /// Δz = (D + Σ_s k_s·g_s g_sᵀ)⁻¹·r by the Woodbury identity: with u = D⁻¹r and W = D⁻¹G,
    /// Δz = u − W·(K_s⁻¹ + GᵀW)⁻¹·Gᵀu — blockwise solves and one n_s × n_s system (n_s the loaded
    /// sections, ≤ 10 or so) instead of a dense factorization of order n_z (≈ 30 with condensed
    /// body modes).
    pub(super) fn solve(
        &self,
        residual: &DVector<f64>,
        rows: &[DVector<f64>],
        stiffness: &[f64],
    ) -> Result<DVector<f64>, String> {
        let mut u = residual.clone();
        self.apply_elastic_inverse(u.as_mut_slice());
        let n_s = rows.len();
        if n_s == 0 {
            return Ok(u);
        }
        if self.woodbury.get().is_none() {
            let w: Vec<DVector<f64>> = rows
                .iter()
                .map(|g| {
                    let mut v = g.clone();
                    self.apply_elastic_inverse(v.as_mut_slice());
                    v
                })
                .collect();
            let capacitance =
                DMatrix::from_fn(n_s, n_s, |a, b| rows[a].dot(&w[b]) + if a == b { 1.0 / stiffness[a] } else { 0.0 });
            let factor =
                capacitance.cholesky().ok_or("the quasi-static coordinates' stiffness is not positive definite")?;
            let _ = self.woodbury.set((w, factor));
        }
        let (w, factor) = self.woodbury.get().expect("set above");
        let projected = DVector::from_fn(n_s, |a, _| rows[a].dot(&u));
        let y = factor.solve(&projected);
        for (w_s, y_s) in w.iter().zip(y.iter()) {
            u.axpy(-y_s, w_s, 1.0);
        }
        Ok(u)
    }
}

/// What a solve leaves for the next one's start: Newton's matrix K at its solution and, per loaded
/// section, its rows in the fast coordinates g_s and in the slow positions r_s = ∂α_s/∂y. To
/// first order in the slow motion Δy (the implicit function theorem), the fast coordinates
/// follow K·Δz = −Σ_s k_s·g_s·(r_s·Δy): the tangent of z(y), where the secant through the last
/// two solves misses the curvature of the path (the mesh vibration at 3.6 kHz turns by ωh ≈ 0.45
/// in a 20 µs step).
pub(super) struct Prediction {
    pub(super) positions: Vec<f64>,
    /// The torques it was solved under: a torque change moves the fast body coordinates through
    /// the bore (−(Fᵀb/J)·Δτ on z_Φ).
    pub(super) torques: [f64; 2],
    pub(super) tangent: FastTangent,
    pub(super) fast_rows: Vec<DVector<f64>>,
    pub(super) stiffness: Vec<f64>,
    pub(super) slow_rows: Vec<Vec<f64>>,
}
