//! SVD compression of the global attachment modes (paper Algorithm 1, Table 1):
//! K_r = ψᵀKψ, K_r = UΣVᵀ, keep the first n_sv singular vectors that hold the share p_en of the
//! "deformation energy" √(Σσᵢ²), and ψ_sv = ψ·Ũ.
//!
//! The paper prints the criterion as √(Σ₁^{n_sv}σᵢ²)/√(Σσᵢ²) < p_en/100, which read literally picks
//! the largest n_sv still *below* the target; we take the smallest n_sv that reaches it (≥).
//!
//! K_r comes in formed: from the partial models' section reactions where ψ are global attachment
//! modes (`attachment::GlobalAttachmentModes::reduced_stiffness`, no product with K), or by
//! [`projected_stiffness`]. ψ is the largest array of the build (n_FE × n_c: 1.2 GB for the small
//! helical gear 2), so nothing here makes a second one: ψ·Ũ overwrites ψ a block of rows at a
//! time, and the compressed basis' stiffness ŨᵀK_rŨ is formed in the small space.

use crate::fe::assembly::symmetric_times_block;
use faer::linalg::matmul::matmul;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::SparseColMat;
use faer::{get_global_parallelism, Accum, Mat, MatRef};
use nalgebra::DMatrix;
use rayon::prelude::*;

pub struct Compression {
    /// ψ_sv = ψ_glob·Ũ (free DOFs × n_sv).
    pub basis: Mat<f64>,
    /// ψ_svᵀKψ_sv = ŨᵀK_rŨ (n_sv × n_sv), formed in the small space: diagonal (σ) up to how far
    /// the SVD's Ũ is from K_r's eigenvectors.
    pub stiffness: Mat<f64>,
    pub singular_values: Vec<f64>,
    pub n_sv: usize,
    /// The retained share √(Σ₁^{n_sv}σᵢ²)/√(Σσᵢ²).
    pub retained: f64,
}

/// Columns of the basis per sparse product in [`projected_stiffness`]: K·B is held for this
/// many columns only (n_FE × 64 instead of n_FE × n_c).
pub const PROJECTION_BLOCK: usize = 64;

/// Rows per block of [`right_multiply_in_place`].
const ROW_BLOCK: usize = 4096;

/// The Galerkin projection BᵀKB of a sparse stiffness onto a basis, symmetrized (the two halves
/// differ by round-off only).
pub fn projected_stiffness(k: &SparseColMat<usize, f64>, basis: &Mat<f64>) -> Mat<f64> {
    let (n, m) = (basis.nrows(), basis.ncols());
    let par = get_global_parallelism();
    let mut kr = Mat::zeros(m, m);
    assert_eq!(k.nrows(), n);
    for start in (0..m).step_by(PROJECTION_BLOCK) {
        let width = PROJECTION_BLOCK.min(m - start);
        let kb = symmetric_times_block(k, basis.as_ref().subcols(start, width));
        matmul(kr.as_mut().subcols_mut(start, width), Accum::Replace, basis.transpose(), kb.as_ref(), 1.0, par);
    }
    Mat::from_fn(m, m, |i, j| 0.5 * (kr[(i, j)] + kr[(j, i)]))
}

/// A ← A·T in A's own storage (T: A.ncols × k, k ≤ A.ncols), a block of rows at a time; A keeps
/// its first k columns. The rows are independent, so the blocks run in parallel.
pub fn right_multiply_in_place(a: &mut Mat<f64>, t: MatRef<'_, f64>) {
    let k = t.ncols();
    assert!(t.nrows() == a.ncols() && k <= a.ncols(), "A·T needs T with A's columns as rows and no more columns");
    a.as_mut().par_row_chunks_mut(ROW_BLOCK).for_each(|mut rows| {
        let product = rows.rb() * t;
        rows.rb_mut().subcols_mut(0, k).copy_from(&product);
    });
    a.truncate(a.nrows(), k);
}

/// The default share of the deformation energy kept, chosen by measured accuracy
/// (`scripts/p_en_accuracy.py`, BENCHMARKS): against the full attachment basis, at every torque
/// of the paper's Tables 4 and 7 on both example pairs, 1 − 10⁻⁶ leaves the mean STE within
/// 0.07 % and the peak-to-peak within 0.53 %; the paper's 0.99 leaves them 5.5–8 % and 20–29 %
/// low (truncation can only stiffen), 0.9999 still 0.6–1.1 % and 3–8 %. The attachment modes'
/// energy spectrum is flat: the last 10⁻⁴ of the energy carries the peak-to-peak.
pub const DEFAULT_P_EN: f64 = 0.999999;

/// Compresses ψ (free DOFs × n_c) whose stiffness K_r = ψᵀKψ is given (`projected_stiffness`,
/// or `attachment::GlobalAttachmentModes::reduced_stiffness` without the product with K),
/// keeping the share `p_en` of the energy.
pub fn compress(reduced_stiffness: &Mat<f64>, mut psi: Mat<f64>, p_en: f64) -> Compression {
    let n_c = psi.ncols();
    assert!(reduced_stiffness.nrows() == n_c && reduced_stiffness.ncols() == n_c, "K_r is n_c × n_c");
    let k_r = DMatrix::from_fn(n_c, n_c, |i, j| reduced_stiffness[(i, j)]);
    let svd = k_r.svd(true, false);
    let mut order: Vec<usize> = (0..n_c).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let sigma: Vec<f64> = order.iter().map(|&i| svd.singular_values[i]).collect();
    let total: f64 = sigma.iter().map(|s| s * s).sum::<f64>().sqrt();
    let mut acc = 0.0;
    let mut n_sv = n_c;
    for (i, s) in sigma.iter().enumerate() {
        acc += s * s;
        if acc.sqrt() / total >= p_en {
            n_sv = i + 1;
            break;
        }
    }
    let u = svd.u.expect("U requested");
    let u_tilde = Mat::from_fn(n_c, n_sv, |i, j| u[(i, order[j])]);
    let retained = sigma[..n_sv].iter().map(|s| s * s).sum::<f64>().sqrt() / total;
    right_multiply_in_place(&mut psi, u_tilde.as_ref());
    let stiffness = u_tilde.transpose() * reduced_stiffness * &u_tilde;
    let stiffness = Mat::from_fn(n_sv, n_sv, |i, j| 0.5 * (stiffness[(i, j)] + stiffness[(j, i)]));
    Compression { basis: psi, stiffness, singular_values: sigma, n_sv, retained }
}
