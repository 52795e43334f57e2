//! The equations of motion of one reduced gear in its floating frame (paper Eqs. 25–28; design
//! §4.5), from its Lagrangian.
//!
//! The velocity of the material in body axes is v = θ̇·G(x + Vη) + θ̇·V_θη + Vη̇. Of the
//! rotation's part θ̇·G(x + Vη) only θ̇·Gx is kept: θ̇·GVη, the deformation carried round by the
//! rotation, adds to the kinetic energy terms of relative size θ̇/ω_n (gyroscopic) and
//! (θ̇/ω_n)² (centrifugal) against the elastic modes' ω_n — below 2 % at 3000 rpm for the
//! lowest body mode of the example pair (2.4 kHz), below 10⁻³ in the paper's example 3 — and
//! costs three quarters of the Gram products (BENCHMARKS). It is dropped from T itself, so
//! the equations stay those of a Lagrangian and energy stays a first integral. The shapes'
//! turning with the gear, θ̇·V_θη, is kept: at a sample spacing of a twentieth of a pitch its
//! rate θ̇/Δϑ is not small against ω_n at speed.
//!
//! On one interpolation interval V = [Φ, Σₐ wₐ S_a] is a combination of the fixed fields
//! B = [Gx | Φ | S_a (a = 0…3)], so v = B·c with coefficients
//!   c = (θ̇, η̇_Φ, wₐη̇_Ψ + θ̇(w′ₐ/Δϑ)η_Ψ) = C(q)·q̇,
//! and T = ½cᵀNc with N = BᵀMB (the stored invariants). With y = Nc the Lagrange equations read
//!   CᵀNC·q̈ = Q + ∂T/∂q − Ċᵀy − CᵀN·(Ċq̇) − ∂U/∂q − Dq̇,
//! and ∂T/∂q = Ċᵀy term by term (c depends on q only through wₐ(ϑ) and η_Ψ, the same way Ċ
//! does), so CᵀNC·q̈ = Q − CᵀN·(Ċq̇) − ∂U/∂q − Dq̇, with
//! U = ½η_ΦᵀΛη_Φ + ½η_ΨᵀK_Ψ(ϑ)η_Ψ (ΦᵀKS = 0 makes VᵀKV block-diagonal). The energy test checks
//! these lines.

use super::interpolation::Weights;
use super::model::{Interpolation, NodeDirection, PmorGear};
use crate::contact::mesh_kinematics::Flank;
use nalgebra::{DMatrix, DVector};

/// Where on the stored samples a reference angle ϑ falls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stencil {
    /// Stored index of sample s − 1 (samples a0 … a0 + 3 are used).
    pub a0: usize,
    pub weights: Weights,
    /// Δϑ (rad).
    pub step: f64,
    /// p = (ϑ − ϑ_s)/Δϑ ∈ [0, 1): where in the interval ϑ lies (the linear weights 1 − p, p).
    pub fraction: f64,
}

impl PmorGear {
    /// The interpolation stencil at reference angle ϑ ∈ [−Δϑ, pitch + Δϑ).
    pub fn stencil(&self, interpolation: Interpolation, theta_ref: f64) -> Result<Stencil, String> {
        let step = self.sample_step_rad();
        let x = theta_ref / step;
        let s = x.floor();
        if !(s >= -1.0 && s <= self.samples as f64) || !x.is_finite() {
            return Err(format!("reference angle {theta_ref} rad is outside the stored samples"));
        }
        let p = x - s;
        Ok(Stencil { a0: (s as i64 + 1) as usize, weights: interpolation.weights(p), step, fraction: p })
    }

    /// The displacement u = Φ_k η_Φ + Σₐ wₐ S_{a,k} η_Ψ of node k of `flank` (gear frame) and
    /// its derivative ∂u/∂ϑ at fixed η (the shapes' interpolation turning with the gear).
    pub fn node_displacement(&self, flank: Flank, st: &Stencil, node: usize, eta: &[f64]) -> ([f64; 3], [f64; 3]) {
        let rows = self.flank(flank);
        let (eta_phi, eta_psi) = eta.split_at(self.modes());
        let mut u = dot3(rows.phi_rows_of_node(node), eta_phi);
        let mut du = [0.0; 3];
        for a in 0..4 {
            let (w, dw) = (st.weights.w[a], st.weights.dw[a] / st.step);
            if w == 0.0 && dw == 0.0 {
                continue;
            }
            let v = dot3(rows.shape_rows_of_node(st.a0 + a, node), eta_psi);
            for c in 0..3 {
                u[c] += w * v[c];
                du[c] += dw * v[c];
            }
        }
        (u, du)
    }

    /// dᵀ∂u/∂ϑ of node k of `flank` along its normal or tangent, at fixed η: the shapes'
    /// turning with the gear, Σₐ w′ₐ/Δϑ · dᵀS_{a,k}η_Ψ (from the rows stored along d: one row per
    /// sample, not three).
    pub fn directed_turning(&self, flank: Flank, st: &Stencil, node: usize, along: NodeDirection, eta: &[f64]) -> f64 {
        let rows = self.flank(flank);
        let eta_psi = &eta[self.modes()..];
        let mut turning = 0.0;
        for a in 0..4 {
            let dw = st.weights.dw[a] / st.step;
            if dw != 0.0 {
                let row = rows.shape_row_along(along, st.a0 + a, node);
                turning += dw * row.iter().zip(eta_psi).map(|(r, e)| r * e).sum::<f64>();
            }
        }
        turning
    }

    /// A bound on |u| at every node of `flank`: |Φ_k η_Φ + Σₐ wₐ S_{a,k} η_Ψ| ≤
    /// max‖Φ_k‖·|η_Φ| + Σₐ|wₐ|·max‖S_{a,k}‖·|η_Ψ|. The contact skips a section whose rigid gap
    /// exceeds the two gears' bounds: it cannot close, so nothing is lost by not reading it.
    pub fn flank_displacement_bound(&self, flank: Flank, st: &Stencil, eta: &[f64]) -> f64 {
        let [phi, shapes] = self.flank(flank).largest_node_rows;
        let (eta_phi, eta_psi) = eta.split_at(self.modes());
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let weights: f64 = st.weights.w.iter().map(|w| w.abs()).sum();
        phi * norm(eta_phi) + weights * shapes * norm(eta_psi)
    }

    /// Adds the row of the basis V = [Φ, Ψ] for a direction at node k of `flank` to `out`:
    /// out += dirᵀ·[Φ_k, Σₐ wₐ S_{a,k}] (a weight is the direction's length).
    pub fn add_basis_row(&self, flank: Flank, st: &Stencil, node: usize, dir: [f64; 3], out: &mut [f64]) {
        let rows = self.flank(flank);
        let n_k = self.modes();
        let (phi_part, shape_part) = out.split_at_mut(n_k);
        add_combined3(dir, rows.phi_rows_of_node(node), phi_part);
        for a in 0..4 {
            let w = st.weights.w[a];
            if w != 0.0 {
                add_combined3(dir.map(|d| w * d), rows.shape_rows_of_node(st.a0 + a, node), shape_part);
            }
        }
    }
}

impl PmorGear {
    /// Adds `weight` times the row of the basis V = [Φ, Ψ] along node k's own flank normal (or
    /// transverse tangent) to `out`: out += weight·dᵀ·[Φ_k, Σₐ wₐ S_{a,k}] (`add_basis_row` with
    /// dir = weight·d, from the rows stored along that direction). Accumulating, so that a band's
    /// rows sum in one pass per node.
    pub fn add_directed_basis_row(
        &self,
        flank: Flank,
        st: &Stencil,
        node: usize,
        along: NodeDirection,
        weight: f64,
        out: &mut [f64],
    ) {
        let rows = self.flank(flank);
        let n_k = self.modes();
        let (phi_part, shape_part) = out.split_at_mut(n_k);
        for (o, r) in phi_part.iter_mut().zip(rows.phi_row_along(along, node)) {
            *o += weight * r;
        }
        for a in 0..4 {
            let w = weight * st.weights.w[a];
            if w != 0.0 {
                for (o, r) in shape_part.iter_mut().zip(rows.shape_row_along(along, st.a0 + a, node)) {
                    *o += w * r;
                }
            }
        }
    }
}

/// The three rows (x, y, z) of a node, stored one after the other (3·n entries), each dotted
/// with x: one pass over x, three independent sums.
#[inline]
fn dot3(rows: &[f64], x: &[f64]) -> [f64; 3] {
    let n = x.len();
    let (r0, rest) = rows.split_at(n);
    let (r1, r2) = rest.split_at(n);
    let mut s = [0.0; 3];
    for i in 0..n {
        s[0] += r0[i] * x[i];
        s[1] += r1[i] * x[i];
        s[2] += r2[i] * x[i];
    }
    s
}

/// out += Σ_c d_c·row_c over a node's three rows (3·n entries): one pass over out.
#[inline]
fn add_combined3(d: [f64; 3], rows: &[f64], out: &mut [f64]) {
    let n = out.len();
    let (r0, rest) = rows.split_at(n);
    let (r1, r2) = rest.split_at(n);
    for i in 0..n {
        out[i] += d[0] * r0[i] + d[1] * r1[i] + d[2] * r2[i];
    }
}

/// One gear's inertia, elastic and damping terms at a state, and the work space they are
/// computed in: sized once per gear ([`GearTerms::new`]), so that no step allocates.
pub struct GearTerms {
    /// M(q): (1 + n_e)² over (θ, η).
    pub mass: DMatrix<f64>,
    /// Q_v − ∂U/∂q − Dq̇ (no contact, no external torque).
    pub force: DVector<f64>,
    pub kinetic_j: f64,
    pub elastic_j: f64,
    /// The damping force Dq̇ over (θ, η) (zero on θ). Its power q̇ᵀDq̇ is the dissipation RK4
    /// integrates; velocity Verlet books its work on the step's own displacement instead.
    pub damping_force: DVector<f64>,
    /// The coefficient vectors [c_θ, C_η·η̇, Ċ·q̇] (n_b × 3) and N times them.
    coefficients: DMatrix<f64>,
    products: DMatrix<f64>,
    /// K_Ψ(ϑ), ∂K_Ψ/∂ϑ and the shape damping D_Ψ(ϑ) (n_t × n_t).
    pub(super) k_psi: DMatrix<f64>,
    pub(super) dk_psi: DMatrix<f64>,
    d_psi: DMatrix<f64>,
}

impl GearTerms {
    pub fn new(gear: &PmorGear) -> Self {
        let (n_k, n_t) = (gear.modes(), gear.shapes);
        let (n_q, n_b) = (1 + n_k + n_t, 1 + n_k + 4 * n_t);
        GearTerms {
            mass: DMatrix::zeros(n_q, n_q),
            force: DVector::zeros(n_q),
            kinetic_j: 0.0,
            elastic_j: 0.0,
            damping_force: DVector::zeros(n_q),
            coefficients: DMatrix::zeros(n_b, 3),
            products: DMatrix::zeros(n_b, 3),
            k_psi: DMatrix::zeros(n_t, n_t),
            dk_psi: DMatrix::zeros(n_t, n_t),
            d_psi: DMatrix::zeros(n_t, n_t),
        }
    }
}

/// Modal damping as a fraction of critical at each coordinate's own frequency: on Φ,
/// D_Φ = diag(2ζ_Φ ω_j); on the shapes, at each stored sample a, D_a = 2ζ_Ψ·M_a V√Λ Vᵀ M_a with
/// K_a v = λ M_a v (the shapes' own modal mass M_a: the Gram matrix of the sample's shapes,
/// which are of unit mass each but not mutually orthogonal), interpolated linearly in ϑ
/// ([`PmorGear::shape_damping_roots`]).
///
/// Why not the paper's stiffness-proportional damping (Table 9: ζ at the lowest eigenfrequency,
/// D = βK): it damps a shape at 35 kHz with ζ ≈ 0.7 and, through the shapes' small effective
/// mass against the frame rotation, puts real eigenvalues near −10⁷ s⁻¹ into the system — an
/// explicit step of 0.25 µs instead of 1 µs (measured on the default spur pair). At each
/// coordinate's own frequency the ratios mean what they say and cost no step size.
#[derive(Debug, Clone, Copy)]
pub struct Damping {
    pub modes_ratio: f64,
    pub shapes_ratio: f64,
}

/// M·V·√Λ·Vᵀ·M for the pencil (K, M), V M-orthonormal: the damping matrix that gives every mode
/// of the pencil the ratio ½ (a damping ratio ζ is 2ζ times it). With M = LLᵀ and
/// L⁻¹KL⁻ᵀ = QΛQᵀ it is L·Q√ΛQᵀ·Lᵀ: positive semi-definite by construction.
pub fn modal_damping_root(mass: &DMatrix<f64>, stiffness: &DMatrix<f64>) -> DMatrix<f64> {
    let l = mass.clone().cholesky().expect("the shapes' Gram matrix is positive definite").l();
    let l_inv = l.clone().try_inverse().expect("a Cholesky factor is invertible");
    let a = &l_inv * stiffness * l_inv.transpose();
    let eig = nalgebra::SymmetricEigen::new((&a + a.transpose()) * 0.5);
    let root = &eig.eigenvectors
        * DMatrix::from_diagonal(&eig.eigenvalues.map(|x| x.max(0.0).sqrt()))
        * eig.eigenvectors.transpose();
    &l * root * l.transpose()
}

/// K_Ψ(ϑ) = Σ wₐw_b K_ab, the shapes' stiffness interpolated at the stencil, and its
/// ϑ-derivative, into `k_psi` and `dk_psi` (n_t × n_t).
pub fn shape_stiffness(gear: &PmorGear, st: &Stencil, k_psi: &mut DMatrix<f64>, dk_psi: &mut DMatrix<f64>) {
    shape_stiffness_of_interval(&interval_shape_stiffness(gear, st.a0), st, k_psi, dk_psi);
}

/// The sixteen K_ab (a, b = 0…3) of the interval whose stencil starts at stored sample `a0`,
/// each n_t × n_t column-major, one after the other in (a, b) order, with K_ba = K_abᵀ written
/// out: what [`shape_stiffness_of_interval`] reads (callers cache it per interval).
pub fn interval_shape_stiffness(gear: &PmorGear, a0: usize) -> Vec<f64> {
    let n_t = gear.shapes;
    let mut block = Vec::with_capacity(16 * n_t * n_t);
    for a in 0..4 {
        for b in 0..4 {
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            let kab = &gear.pair_invariants(a0 + lo, a0 + hi).k_ss;
            for c in 0..n_t {
                for r in 0..n_t {
                    block.push(if a <= b { kab[(r, c)] } else { kab[(c, r)] });
                }
            }
        }
    }
    block
}

/// [`shape_stiffness`] from the interval's block ([`interval_shape_stiffness`]).
pub fn shape_stiffness_of_interval(block: &[f64], st: &Stencil, k_psi: &mut DMatrix<f64>, dk_psi: &mut DMatrix<f64>) {
    let n2 = k_psi.len();
    let w = st.weights.w;
    let dw = st.weights.dw.map(|x| x / st.step);
    let (k, dk) = (k_psi.as_mut_slice(), dk_psi.as_mut_slice());
    k.fill(0.0);
    dk.fill(0.0);
    for a in 0..4 {
        for b in 0..4 {
            let (f, df) = (w[a] * w[b], dw[a] * w[b] + w[a] * dw[b]);
            let kab = &block[(4 * a + b) * n2..(4 * a + b + 1) * n2];
            for ((k, dk), &v) in k.iter_mut().zip(dk.iter_mut()).zip(kab) {
                *k += f * v;
                *dk += df * v;
            }
        }
    }
}

/// N = BᵀMB of the interval whose stencil starts at stored sample `a0`: the Gram matrix of
/// [Gx | Φ | S_a], assembled from the stored invariants ((1 + n_k + 4n_t)²).
pub fn interval_gram(gear: &PmorGear, a0: usize) -> DMatrix<f64> {
    let (n_k, n_t) = (gear.modes(), gear.shapes);
    let n_b = 1 + n_k + 4 * n_t;
    let phi = 1;
    let sc = |a: usize| 1 + n_k + a * n_t;
    let mut nm = DMatrix::<f64>::zeros(n_b, n_b);
    let mut set = |i: usize, j: usize, v: f64| {
        nm[(i, j)] = v;
        nm[(j, i)] = v;
    };
    set(0, 0, gear.polar_inertia_kgm2);
    for j in 0..n_k {
        set(0, phi + j, gear.gx_phi[j]);
        for i in 0..n_k {
            set(phi + i, phi + j, gear.phi_phi[(i, j)]);
        }
    }
    for a in 0..4 {
        let s = &gear.sample[a0 + a];
        for t in 0..n_t {
            set(0, sc(a) + t, s.gx_s[t]);
            for j in 0..n_k {
                set(phi + j, sc(a) + t, s.phi_s[(j, t)]);
            }
        }
        for b in a..4 {
            let p = gear.pair_invariants(a0 + a, a0 + b);
            for r in 0..n_t {
                for c in 0..n_t {
                    set(sc(a) + r, sc(b) + c, p.s_s[(r, c)]);
                }
            }
        }
    }
    nm
}

/// M(q), Q_v, ∂U/∂q and damping of one gear, into `out`. `eta`, `eta_dot`: n_k + n_t;
/// `omega` = θ̇. `nm` is [`interval_gram`] of the stencil's interval (callers cache it: it
/// changes only when ϑ crosses a sample).
///
/// With c = C(q)q̇ = θ̇·c_θ + C_η·η̇ (c_θ the θ column of C, C_η its constant η columns) the three
/// products with N that everything needs are taken at once: N·[c_θ, C_η η̇, Ċq̇]. Then
/// y = Nc = θ̇·Nc_θ + N C_η η̇, the mass matrix's θ row is Cᵀ(Nc_θ), its ηη block C_ηᵀNC_η reads
/// N's blocks directly, and CᵀN(Ċq̇) is Cᵀ of the third product.
#[allow(clippy::too_many_arguments)]
pub fn gear_terms(
    gear: &PmorGear,
    st: &Stencil,
    nm: &DMatrix<f64>,
    eta: &[f64],
    omega: f64,
    eta_dot: &[f64],
    damping: Damping,
    out: &mut GearTerms,
) {
    let (n_k, n_t) = (gear.modes(), gear.shapes);
    let phi = 1;
    let sc = |a: usize| 1 + n_k + a * n_t;
    let d = st.step;
    let w = st.weights.w;
    let dw = st.weights.dw.map(|x| x / d);
    let ddw = st.weights.ddw.map(|x| x / (d * d));

    let (eta_phi, eta_psi) = eta.split_at(n_k);
    let (etad_phi, etad_psi) = eta_dot.split_at(n_k);

    // The coefficient vectors: C's θ column c_θ, C_η·η̇ and Ċq̇ (zero where not set).
    let cf = &mut out.coefficients;
    cf.fill(0.0);
    cf[(0, 0)] = 1.0;
    for j in 0..n_k {
        cf[(phi + j, 1)] = etad_phi[j];
    }
    for a in 0..4 {
        for m in 0..n_t {
            cf[(sc(a) + m, 0)] = dw[a] * eta_psi[m];
            cf[(sc(a) + m, 1)] = w[a] * etad_psi[m];
            cf[(sc(a) + m, 2)] = omega * omega * ddw[a] * eta_psi[m] + 2.0 * omega * dw[a] * etad_psi[m];
        }
    }
    out.products.gemm(1.0, nm, cf, 0.0);
    let (cf, z) = (&out.coefficients, &out.products);
    // T = ½cᵀNc, c = θ̇·c_θ + C_η·η̇.
    let mut kinetic = 0.0;
    for k in 0..cf.nrows() {
        kinetic += (omega * cf[(k, 0)] + cf[(k, 1)]) * (omega * z[(k, 0)] + z[(k, 1)]);
    }
    out.kinetic_j = 0.5 * kinetic;
    // Cᵀv of column `col` of the products: (c_θᵀv, v_Φ, Σₐ wₐ v_{S_a}).
    let apply_ct = |col: usize, r: &mut [f64]| {
        let mut t = 0.0;
        for k in 0..cf.nrows() {
            t += cf[(k, 0)] * z[(k, col)];
        }
        r[0] = t;
        for j in 0..n_k {
            r[1 + j] = z[(phi + j, col)];
        }
        for m in 0..n_t {
            r[1 + n_k + m] = (0..4).map(|a| w[a] * z[(sc(a) + m, col)]).sum();
        }
    };

    // M = CᵀNC: the θ row from Nc_θ, the ηη block from N's blocks.
    let mass = &mut out.mass;
    // The θ row, through the damping force's buffer (set below).
    let theta_row = out.damping_force.as_mut_slice();
    apply_ct(0, theta_row);
    for (k, &v) in theta_row.iter().enumerate() {
        mass[(0, k)] = v;
        mass[(k, 0)] = v;
    }
    for i in 0..n_k {
        for j in i..n_k {
            let v = nm[(phi + i, phi + j)];
            mass[(1 + i, 1 + j)] = v;
            mass[(1 + j, 1 + i)] = v;
        }
        for m in 0..n_t {
            let v: f64 = (0..4).map(|a| w[a] * nm[(phi + i, sc(a) + m)]).sum();
            mass[(1 + i, 1 + n_k + m)] = v;
            mass[(1 + n_k + m, 1 + i)] = v;
        }
    }
    for m in 0..n_t {
        for n in m..n_t {
            let mut v = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    v += w[a] * w[b] * nm[(sc(a) + m, sc(b) + n)];
                }
            }
            mass[(1 + n_k + m, 1 + n_k + n)] = v;
            mass[(1 + n_k + n, 1 + n_k + m)] = v;
        }
    }

    // The inertial force −CᵀN(Ċq̇) (∂T/∂q and Ċᵀy cancel).
    let force = &mut out.force;
    apply_ct(2, force.as_mut_slice());
    force.neg_mut();

    // Elastic: Λ on Φ, K_Ψ(ϑ) on the shapes, and its ϑ-derivative.
    let (k_psi, dk_psi) = (&mut out.k_psi, &mut out.dk_psi);
    shape_stiffness(gear, st, k_psi, dk_psi);
    let mut elastic = 0.0;
    for r in 0..n_t {
        let (mut k_eta, mut dk_eta) = (0.0, 0.0);
        for c in 0..n_t {
            k_eta += k_psi[(r, c)] * eta_psi[c];
            dk_eta += dk_psi[(r, c)] * eta_psi[c];
        }
        elastic += 0.5 * eta_psi[r] * k_eta;
        force[0] -= 0.5 * eta_psi[r] * dk_eta;
        force[1 + n_k + r] -= k_eta;
    }
    out.damping_force.fill(0.0);
    for j in 0..n_k {
        let lam = gear.eigenvalues[j];
        elastic += 0.5 * lam * eta_phi[j] * eta_phi[j];
        let damp = 2.0 * damping.modes_ratio * lam.sqrt() * etad_phi[j];
        force[1 + j] -= lam * eta_phi[j] + damp;
        out.damping_force[1 + j] = damp;
    }
    out.elastic_j = elastic;
    if damping.shapes_ratio > 0.0 {
        // D_Ψ(ϑ) = 2ζ·((1 − p)·D_s + p·D_{s+1}): the linear weights, never negative.
        let d_psi = &mut out.d_psi;
        let p = st.fraction;
        let (lo, hi) = (&gear.shape_damping_roots[st.a0 + 1], &gear.shape_damping_roots[st.a0 + 2]);
        for r in 0..n_t {
            for c in 0..n_t {
                d_psi[(r, c)] = 2.0 * damping.shapes_ratio * ((1.0 - p) * lo[(r, c)] + p * hi[(r, c)]);
            }
        }
        for r in 0..n_t {
            let damp: f64 = (0..n_t).map(|c| d_psi[(r, c)] * etad_psi[c]).sum();
            force[1 + n_k + r] -= damp;
            out.damping_force[1 + n_k + r] = damp;
        }
    }
}
