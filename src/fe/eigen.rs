//! The lowest eigenpairs of K x = λ M x (K positive definite: the bore clamped), by shift-invert
//! subspace iteration on the Cholesky factor of K with Rayleigh–Ritz (Bathe), under an iteration
//! cap; residual norms reported; and a Sturm count — the negative pivots of an LDLᵀ of K − σM —
//! proving that no eigenvalue below σ was missed (design §4.2).

use super::assembly::Cholesky;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::matmul::sparse_dense_matmul;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMat, Triplet};
use faer::{get_global_parallelism, Accum, Mat, Par, Side};
use nalgebra::DMatrix;

#[derive(Debug, Clone)]
pub struct Modes {
    /// Eigenvalues λ = ω² (rad²/s²), ascending.
    pub eigenvalues: Vec<f64>,
    /// Mass-normalized eigenvectors (free DOFs), one column per mode.
    pub vectors: Mat<f64>,
    /// ‖K x − λ M x‖ / ‖K x‖ per mode.
    pub residuals: Vec<f64>,
    pub iterations: usize,
    /// Eigenvalues below the shift σ (between λ_count and the next distinct Ritz value) by the
    /// Sturm count; equal to `ritz_values_below_shift` when no mode was missed.
    pub sturm_count: usize,
    pub ritz_values_below_shift: usize,
}

impl Modes {
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.eigenvalues.iter().map(|l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)).collect()
    }
}

/// A·X for sparse A and a dense block X (faer's sparse × dense product, parallel).
fn mat_mul_sparse(a: &SparseColMat<usize, f64>, x: &Mat<f64>) -> Mat<f64> {
    let mut y = Mat::zeros(a.nrows(), x.ncols());
    sparse_dense_matmul(y.as_mut(), Accum::Replace, a.as_ref(), x.as_ref(), 1.0, get_global_parallelism());
    y
}

/// AᵀB (q×q) by faer's dense product, copied into nalgebra for the small eigenproblem.
fn gram(a: &Mat<f64>, b: &Mat<f64>) -> DMatrix<f64> {
    let g = a.transpose() * b;
    DMatrix::from_fn(g.nrows(), g.ncols(), |i, j| g[(i, j)])
}

/// The `count` lowest eigenpairs, to relative eigenvalue change `tolerance`, in at most
/// `max_iterations` subspace iterations; `progress` is told (iteration, converged count).
pub fn lowest_modes(
    k: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
    count: usize,
    tolerance: f64,
    max_iterations: usize,
    progress: impl FnMut(usize, usize),
) -> Result<Modes, String> {
    lowest_modes_factored(k, m, &Cholesky::new(k)?, count, tolerance, max_iterations, progress)
}

/// As [`lowest_modes`], with K's Cholesky factor supplied (e.g. nested-dissection ordered).
pub fn lowest_modes_factored(
    k: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
    chol: &Cholesky,
    count: usize,
    tolerance: f64,
    max_iterations: usize,
    mut progress: impl FnMut(usize, usize),
) -> Result<Modes, String> {
    let n = k.nrows();
    let q = (2 * count).max(count + 8).min(n);
    if count == 0 || count > n {
        return Err(format!("cannot compute {count} modes of a {n}-DOF model"));
    }
    // Start vectors: the diagonal of M (all DOFs excited), then pseudo-random columns.
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut x = Mat::from_fn(n, q, |i, j| {
        if j == 0 {
            1.0
        } else {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            let _ = i;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    });
    let mut previous = vec![f64::INFINITY; q];
    let mut eigenvalues = Vec::new();
    let mut iterations = 0;
    for it in 1..=max_iterations {
        iterations = it;
        let mx = mat_mul_sparse(m, &x);
        let mut y = mx.clone();
        chol.solve_block(&mut y); // Y = K⁻¹ M X
        let kr = gram(&y, &mx); // Yᵀ K Y = Yᵀ M X
        let my = mat_mul_sparse(m, &y);
        let mr = gram(&y, &my);
        let kr = (&kr + kr.transpose()) * 0.5;
        let mr = (&mr + mr.transpose()) * 0.5;
        // Reduced problem Kr Q = Mr Q Λ through Mr = LLᵀ.
        let l = mr.clone().cholesky().ok_or("subspace lost rank (M-Gram matrix not positive definite)")?.l();
        let l_inv = l.clone().try_inverse().ok_or("singular reduced mass")?;
        let a = &l_inv * &kr * l_inv.transpose();
        let eig = nalgebra::SymmetricEigen::new((&a + a.transpose()) * 0.5);
        let mut order: Vec<usize> = (0..q).collect();
        order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
        let qmat = l_inv.transpose() * &eig.eigenvectors;
        eigenvalues = order.iter().map(|&i| eig.eigenvalues[i]).collect();
        let ritz = Mat::from_fn(q, q, |t, c| qmat[(t, order[c])]);
        x = &y * &ritz;
        let converged =
            (0..count).take_while(|&i| ((eigenvalues[i] - previous[i]) / eigenvalues[i]).abs() < tolerance).count();
        progress(it, converged);
        if converged == count {
            break;
        }
        previous = eigenvalues.clone();
    }
    let kx = mat_mul_sparse(k, &x);
    let mx = mat_mul_sparse(m, &x);
    let residuals: Vec<f64> = (0..count)
        .map(|c| {
            let (mut num, mut den) = (0.0, 0.0);
            for r in 0..n {
                num += (kx[(r, c)] - eigenvalues[c] * mx[(r, c)]).powi(2);
                den += kx[(r, c)].powi(2);
            }
            (num / den).sqrt()
        })
        .collect();
    // The shift: midway between λ_count and the next distinct Ritz value (cyclic symmetry makes
    // gear modes come in equal pairs). Ritz values bound the true ones from above, so a Sturm
    // count larger than the Ritz values below σ means a missed mode, never the reverse.
    let last = eigenvalues[count - 1];
    let next = eigenvalues[count..].iter().copied().find(|&l| l > last * (1.0 + 1e-6)).unwrap_or(1.02 * last);
    let sigma = 0.5 * (last + next);
    let expected = eigenvalues.iter().filter(|&&l| l < sigma).count();
    let sturm = sturm_count(k, m, sigma)?;
    Ok(Modes {
        eigenvalues: eigenvalues[..count].to_vec(),
        vectors: Mat::from_fn(n, count, |r, c| x[(r, c)]),
        residuals,
        iterations,
        sturm_count: sturm,
        ritz_values_below_shift: expected,
    })
}

/// Number of eigenvalues of K x = λ M x below σ: by Sylvester's law of inertia, the number of
/// negative pivots of an LDLᵀ factorization of K − σM (simplicial, so D sits on L's diagonal).
pub fn sturm_count(k: &SparseColMat<usize, f64>, m: &SparseColMat<usize, f64>, sigma: f64) -> Result<usize, String> {
    let n = k.nrows();
    let mut triplets = Vec::with_capacity(k.compute_nnz() + m.compute_nnz());
    for (a, scale) in [(k, 1.0), (m, -sigma)] {
        let a = a.as_ref();
        for j in 0..n {
            for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                triplets.push(Triplet::new(i, j, scale * v));
            }
        }
    }
    let shifted = SparseColMat::try_new_from_triplets(n, n, &triplets).map_err(|e| format!("{e:?}"))?;
    let symbolic = factorize_symbolic_cholesky(
        shifted.symbolic(),
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        },
    )
    .map_err(|e| format!("symbolic LDLᵀ: {e:?}"))?;
    let mut values = vec![0.0; symbolic.len_val()];
    let mut buffer = MemBuffer::new(symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()));
    symbolic
        .factorize_numeric_ldlt(
            &mut values,
            shifted.as_ref(),
            Side::Lower,
            LdltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut buffer),
            Default::default(),
        )
        .map_err(|e| format!("LDLᵀ of K − σM failed (σ on an eigenvalue?): {e:?}"))?;
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => Ok((0..n).filter(|&j| values[s.col_ptr()[j]] < 0.0).count()),
        SymbolicCholeskyRaw::Supernodal(_) => Err("expected a simplicial factorization".into()),
    }
}
