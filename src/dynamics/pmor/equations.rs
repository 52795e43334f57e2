//! The equations of motion of one reduced gear in its floating frame (paper Eqs. 25–28; design
//! §4.5), from its Lagrangian.
//!
//! The velocity of the material in body axes is v = θ̇·G(x + Vη) + θ̇·V_θη + Vη̇. On one
//! interpolation interval V = [Φ, Σₐ wₐ S_a] is a combination of the fixed fields
//! B = [Gx | GΦ | Φ | GS_a (a = 0…3) | S_a (a = 0…3)], so v = B·c with coefficients
//!   c = (θ̇, θ̇η_Φ, η̇_Φ, θ̇wₐη_Ψ, wₐη̇_Ψ + θ̇(w′ₐ/Δϑ)η_Ψ) = C(q)·q̇,
//! and T = ½cᵀNc with N = BᵀMB (the stored invariants). With y = Nc the Lagrange equations read
//!   CᵀNC·q̈ = Q + ∂T/∂q − Ċᵀy − CᵀN·(Ċq̇) − ∂U/∂q − Dq̇,
//! where every derivative of C is written out below; U = ½η_ΦᵀΛη_Φ + ½η_ΨᵀK_Ψ(ϑ)η_Ψ (ΦᵀKS = 0
//! makes VᵀKV block-diagonal). Nothing is dropped, so energy is a first integral of the exact
//! flow: the energy test checks these lines.

use super::interpolation::Weights;
use super::model::{Interpolation, PmorGear};
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
        Ok(Stencil { a0: (s as i64 + 1) as usize, weights: interpolation.weights(p), step })
    }

    /// The displacement u = Φ_k η_Φ + Σₐ wₐ S_{a,k} η_Ψ of node k of `flank` (gear frame) and
    /// its derivative ∂u/∂ϑ at fixed η (the shapes' interpolation turning with the gear).
    pub fn node_displacement(&self, flank: Flank, st: &Stencil, node: usize, eta: &[f64]) -> ([f64; 3], [f64; 3]) {
        let rows = self.flank(flank);
        let n_k = self.modes();
        let (eta_phi, eta_psi) = eta.split_at(n_k);
        let (mut u, mut du) = ([0.0; 3], [0.0; 3]);
        for c in 0..3 {
            let r = 3 * node + c;
            u[c] = (0..n_k).map(|j| rows.phi[(r, j)] * eta_phi[j]).sum();
            for a in 0..4 {
                let (w, dw) = (st.weights.w[a], st.weights.dw[a] / st.step);
                if w == 0.0 && dw == 0.0 {
                    continue;
                }
                let s = &rows.shapes[st.a0 + a];
                let v: f64 = (0..self.shapes).map(|t| s[(r, t)] * eta_psi[t]).sum();
                u[c] += w * v;
                du[c] += dw * v;
            }
        }
        (u, du)
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

    /// Row of the basis V = [Φ, Ψ] for a direction at node k of `flank`:
    /// dirᵀ·[Φ_k, Σₐ wₐ S_{a,k}].
    pub fn basis_row(&self, flank: Flank, st: &Stencil, node: usize, dir: [f64; 3], out: &mut [f64]) {
        let rows = self.flank(flank);
        let n_k = self.modes();
        for (j, o) in out[..n_k].iter_mut().enumerate() {
            *o = (0..3).map(|c| dir[c] * rows.phi[(3 * node + c, j)]).sum();
        }
        for t in 0..self.shapes {
            let mut v = 0.0;
            for a in 0..4 {
                let w = st.weights.w[a];
                if w != 0.0 {
                    let s = &rows.shapes[st.a0 + a];
                    v += w * (0..3).map(|c| dir[c] * s[(3 * node + c, t)]).sum::<f64>();
                }
            }
            out[n_k + t] = v;
        }
    }
}

/// One gear's inertia, elastic and damping terms at a state.
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
}

/// Modal damping as a fraction of critical at each coordinate's own frequency: on Φ,
/// D_Φ = diag(2ζ_Φ ω_j); on the (mass-orthonormal) shapes, D_Ψ = 2ζ_Ψ·K_Ψ(ϑ)^½.
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

/// N = BᵀMB of the interval whose stencil starts at stored sample `a0`: the Gram matrix of
/// [Gx | GΦ | Φ | GS_a | S_a], assembled from the stored invariants ((1 + 2n_k + 8n_t)²).
pub fn interval_gram(gear: &PmorGear, a0: usize) -> DMatrix<f64> {
    let (n_k, n_t) = (gear.modes(), gear.shapes);
    let n_b = 1 + 2 * n_k + 8 * n_t;
    let (gphi, phi) = (1, 1 + n_k);
    let gs = |a: usize| 1 + 2 * n_k + a * n_t;
    let sc = |a: usize| 1 + 2 * n_k + 4 * n_t + a * n_t;
    let mut nm = DMatrix::<f64>::zeros(n_b, n_b);
    let mut set = |i: usize, j: usize, v: f64| {
        nm[(i, j)] = v;
        nm[(j, i)] = v;
    };
    set(0, 0, gear.polar_inertia_kgm2);
    for j in 0..n_k {
        set(0, gphi + j, gear.gx_gphi[j]);
        set(0, phi + j, gear.gx_phi[j]);
        for i in 0..n_k {
            set(gphi + i, gphi + j, gear.gphi_gphi[(i, j)]);
            set(gphi + i, phi + j, gear.gphi_phi[(i, j)]);
            set(phi + i, phi + j, gear.phi_phi[(i, j)]);
        }
    }
    for a in 0..4 {
        let s = &gear.sample[a0 + a];
        for t in 0..n_t {
            set(0, gs(a) + t, s.gx_gs[t]);
            set(0, sc(a) + t, s.gx_s[t]);
            for j in 0..n_k {
                set(gphi + j, gs(a) + t, s.gphi_gs[(j, t)]);
                set(gphi + j, sc(a) + t, s.gphi_s[(j, t)]);
                set(phi + j, gs(a) + t, s.phi_gs[(j, t)]);
                set(phi + j, sc(a) + t, s.phi_s[(j, t)]);
            }
        }
        for b in a..4 {
            let p = gear.pair_invariants(a0 + a, a0 + b);
            for r in 0..n_t {
                for c in 0..n_t {
                    set(gs(a) + r, gs(b) + c, p.gs_gs[(r, c)]);
                    set(gs(a) + r, sc(b) + c, p.gs_s[(r, c)]);
                    set(sc(a) + r, gs(b) + c, p.s_gs[(r, c)]);
                    set(sc(a) + r, sc(b) + c, p.s_s[(r, c)]);
                }
            }
        }
    }

    nm
}

/// M(q), Q_v, ∂U/∂q and damping of one gear. `eta`, `eta_dot`: n_k + n_t; `omega` = θ̇.
/// `nm` is [`interval_gram`] of the stencil's interval (callers cache it: it changes only when ϑ
/// crosses a sample).
pub fn gear_terms(
    gear: &PmorGear,
    st: &Stencil,
    nm: &DMatrix<f64>,
    eta: &[f64],
    omega: f64,
    eta_dot: &[f64],
    damping: Damping,
) -> GearTerms {
    let (n_k, n_t) = (gear.modes(), gear.shapes);
    let n_q = 1 + n_k + n_t;
    let n_b = 1 + 2 * n_k + 8 * n_t;
    let (gphi, phi) = (1, 1 + n_k);
    let gs = |a: usize| 1 + 2 * n_k + a * n_t;
    let sc = |a: usize| 1 + 2 * n_k + 4 * n_t + a * n_t;
    let (w, dw, ddw) = (st.weights.w, st.weights.dw, st.weights.ddw);
    let d = st.step;

    let (eta_phi, eta_psi) = eta.split_at(n_k);
    let (etad_phi, etad_psi) = eta_dot.split_at(n_k);
    // C(q) is sparse: its θ column is dense, its η_Φ columns are unit vectors on the Φ rows and
    // its η_Ψ columns are wₐ on the S_a rows. C·x and Cᵀ·v are written out.
    let apply_c = |x: &DVector<f64>| -> DVector<f64> {
        let mut c = DVector::<f64>::zeros(n_b);
        c[0] = x[0];
        for j in 0..n_k {
            c[gphi + j] = x[0] * eta_phi[j];
            c[phi + j] = x[1 + j];
        }
        for a in 0..4 {
            for m in 0..n_t {
                c[gs(a) + m] = x[0] * w[a] * eta_psi[m];
                c[sc(a) + m] = x[0] * dw[a] / d * eta_psi[m] + w[a] * x[1 + n_k + m];
            }
        }
        c
    };
    let apply_ct = |v: &[f64]| -> DVector<f64> {
        let mut r = DVector::<f64>::zeros(n_q);
        let mut t = v[0];
        for j in 0..n_k {
            t += eta_phi[j] * v[gphi + j];
            r[1 + j] = v[phi + j];
        }
        for a in 0..4 {
            for m in 0..n_t {
                t += w[a] * eta_psi[m] * v[gs(a) + m] + dw[a] / d * eta_psi[m] * v[sc(a) + m];
                r[1 + n_k + m] += w[a] * v[sc(a) + m];
            }
        }
        r[0] = t;
        r
    };
    let mut qd = DVector::<f64>::zeros(n_q);
    qd[0] = omega;
    qd.rows_mut(1, n_k + n_t).copy_from_slice(eta_dot);
    let c = apply_c(&qd);
    let y = nm * &c;
    let kinetic = 0.5 * c.dot(&y);
    // M = CᵀNC column by column: N·C·e_j is a product only for the θ column.
    let mut mass = DMatrix::<f64>::zeros(n_q, n_q);
    let mut e = DVector::<f64>::zeros(n_q);
    e[0] = 1.0;
    let col = apply_ct((nm * apply_c(&e)).as_slice());
    mass.set_column(0, &col);
    // N's columns as slices (column-major storage).
    let nm_column = |j: usize| &nm.as_slice()[j * n_b..(j + 1) * n_b];
    for j in 0..n_k {
        mass.set_column(1 + j, &apply_ct(nm_column(phi + j)));
    }
    for m in 0..n_t {
        let mut nc = vec![0.0; n_b];
        for a in 0..4 {
            if w[a] != 0.0 {
                for (x, v) in nc.iter_mut().zip(nm_column(sc(a) + m)) {
                    *x += w[a] * v;
                }
            }
        }
        mass.set_column(1 + n_k + m, &apply_ct(&nc));
    }
    let mass = (&mass + mass.transpose()) * 0.5;

    // ∂T/∂q − Ċᵀy.
    let mut force = DVector::<f64>::zeros(n_q);
    let mut f_theta = 0.0;
    for j in 0..n_k {
        force[1 + j] += y[gphi + j] * omega; // ∂T/∂η_Φ
        f_theta -= y[gphi + j] * etad_phi[j]; // Ċᵀy, θ row
    }
    for a in 0..4 {
        for m in 0..n_t {
            let (yg, ys) = (y[gs(a) + m], y[sc(a) + m]);
            // ∂T/∂θ
            f_theta += yg * omega * dw[a] / d * eta_psi[m]
                + ys * (omega * ddw[a] / (d * d) * eta_psi[m] + dw[a] / d * etad_psi[m]);
            // ∂T/∂η_Ψ
            force[1 + n_k + m] += yg * omega * w[a] + ys * omega * dw[a] / d;
            // Ċᵀy
            f_theta -= yg * (dw[a] * omega / d * eta_psi[m] + w[a] * etad_psi[m])
                + ys * (ddw[a] * omega / (d * d) * eta_psi[m] + dw[a] / d * etad_psi[m]);
            force[1 + n_k + m] -= ys * dw[a] * omega / d;
        }
    }
    force[0] += f_theta;
    // − CᵀN(Ċq̇).
    let mut cdq = DVector::<f64>::zeros(n_b);
    for j in 0..n_k {
        cdq[gphi + j] = omega * etad_phi[j];
    }
    for a in 0..4 {
        for m in 0..n_t {
            cdq[gs(a) + m] = omega * omega * dw[a] / d * eta_psi[m] + omega * w[a] * etad_psi[m];
            cdq[sc(a) + m] = omega * omega * ddw[a] / (d * d) * eta_psi[m] + 2.0 * omega * dw[a] / d * etad_psi[m];
        }
    }
    force -= apply_ct((nm * cdq).as_slice());

    // Elastic: Λ on Φ, K_Ψ(ϑ) = Σ wₐw_b K_ab on the shapes, and its ϑ-derivative.
    let mut k_psi = DMatrix::<f64>::zeros(n_t, n_t);
    let mut dk_psi = DMatrix::<f64>::zeros(n_t, n_t);
    for a in 0..4 {
        for b in 0..4 {
            // K_ab is stored for a ≤ b; K_ba = K_abᵀ.
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            let kab = &gear.pair_invariants(st.a0 + lo, st.a0 + hi).k_ss;
            let (f, df) = (w[a] * w[b], (dw[a] * w[b] + w[a] * dw[b]) / d);
            for r in 0..n_t {
                for c in 0..n_t {
                    let v = if a <= b { kab[(r, c)] } else { kab[(c, r)] };
                    k_psi[(r, c)] += f * v;
                    dk_psi[(r, c)] += df * v;
                }
            }
        }
    }
    let psi = DVector::from_column_slice(eta_psi);
    let psid = DVector::from_column_slice(etad_psi);
    let k_eta = &k_psi * &psi;
    let mut elastic = 0.5 * psi.dot(&k_eta);
    force[0] -= 0.5 * psi.dot(&(&dk_psi * &psi));
    let mut damping_force = DVector::<f64>::zeros(n_q);
    for j in 0..n_k {
        let lam = gear.eigenvalues[j];
        elastic += 0.5 * lam * eta_phi[j] * eta_phi[j];
        let damp = 2.0 * damping.modes_ratio * lam.sqrt() * etad_phi[j];
        force[1 + j] -= lam * eta_phi[j] + damp;
        damping_force[1 + j] = damp;
    }
    let damp_psi = if damping.shapes_ratio > 0.0 {
        let eig = nalgebra::SymmetricEigen::new(k_psi.clone());
        let root = &eig.eigenvectors
            * DMatrix::from_diagonal(&eig.eigenvalues.map(|l| l.max(0.0).sqrt()))
            * eig.eigenvectors.transpose();
        (root * &psid) * (2.0 * damping.shapes_ratio)
    } else {
        DVector::zeros(n_t)
    };
    for m in 0..n_t {
        force[1 + n_k + m] -= k_eta[m] + damp_psi[m];
        damping_force[1 + n_k + m] = damp_psi[m];
    }
    GearTerms { mass, force, kinetic_j: kinetic, elastic_j: elastic, damping_force }
}
