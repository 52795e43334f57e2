//! The lowest eigenpairs of K x = λ M x (K positive definite: the bore clamped), by shift-invert
//! block Lanczos on the Cholesky factor of K with full reorthogonalization and Rayleigh–Ritz,
//! under a cap on the block steps; residual norms reported; and a Sturm count — the negative
//! pivots of an LDLᵀ of K − σM — proving that no eigenvalue below σ was missed (design §4.2).

use super::assembly::{symmetric_times_block, Cholesky, LinearSolve};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLdltRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::{SparseColMat, Triplet};
use faer::{get_global_parallelism, Mat, Side};
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

/// AᵀB (q×q) by faer's dense product, copied into nalgebra for the small eigenproblem.
fn gram(a: &Mat<f64>, b: &Mat<f64>) -> DMatrix<f64> {
    let g = a.transpose() * b;
    DMatrix::from_fn(g.nrows(), g.ncols(), |i, j| g[(i, j)])
}

/// The `count` lowest eigenpairs, each to a relative residual ‖Kx − λMx‖/‖Kx‖ ≤ √`tolerance`
/// (so the eigenvalue, a Rayleigh quotient, to about `tolerance`), in at most `max_iterations`
/// block steps; `progress` is told (step, converged count).
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

/// Vectors per block of the Krylov space: enough for the double eigenvalues of a cyclic gear
/// (a block Krylov space holds a multiplicity up to its block size) and a few more. Measured on
/// the spur pair at 10/12/10 (26 modes + the shift's), in one build of this solver: blocks of 8
/// took 19 / 17 steps (gear 1 / 2), 10.4 / 13.6 s; of 16 12 / 12 steps, 11.2 / 17.9 s; of 32
/// 9 / 8 steps, 17.4 / 23.6 s: the cost is in the columns (solves, reorthogonalization), not in
/// the steps.
const KRYLOV_BLOCK: usize = 8;

/// Columns reserved for the Krylov space (each of V, KV and MV) when `count` modes of an
/// n-DOF model are sought: what the build's memory estimate counts.
pub fn krylov_capacity(count: usize, n: usize) -> usize {
    (6 * count + 4 * KRYLOV_BLOCK.min(n)).min(n)
}

/// As [`lowest_modes`], with K's Cholesky factor supplied (e.g. nested-dissection ordered).
///
/// Block shift-invert Lanczos with full reorthogonalization: the space V grows by one block
/// Y = K⁻¹M·X_last per step, M-orthonormalized against what it holds, and Rayleigh–Ritz on it
/// gives the pairs (VᵀMV = I, so the projected problem is VᵀKV q = λq). The Krylov space of
/// K⁻¹M reaches the low end of the spectrum in far fewer solves than subspace iteration, whose
/// convergence per step is only λᵢ/λ_q+1 (gear 1 of the spur pair at 8/8/8: 33 iterations of
/// 52 solves, 1716 in all, where this takes 19 steps of 8). Ritz values bound the eigenvalues
/// from above, so the Sturm count below a shift between converged Ritz values can only find a
/// missed mode, never invent one.
pub fn lowest_modes_factored(
    k: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
    chol: &Cholesky,
    count: usize,
    tolerance: f64,
    max_iterations: usize,
    progress: impl FnMut(usize, usize),
) -> Result<Modes, String> {
    let (mut modes, sigma) = lowest_modes_before_sturm_count(k, m, chol, count, tolerance, max_iterations, progress)?;
    modes.sturm_count = sturm_count_factored(k, m, sigma, chol)?;
    Ok(modes)
}

/// As [`lowest_modes_factored`] without the Sturm count (`sturm_count` left 0): the modes and
/// the shift σ, midway between λ_count and the next distinct Ritz value, where it is to be
/// taken. For a caller that counts at a shift of its own (the gear by harmonics counts once, at
/// the gear's shift, on every harmonic).
pub fn lowest_modes_before_sturm_count(
    k: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
    chol: &dyn LinearSolve,
    count: usize,
    tolerance: f64,
    max_iterations: usize,
    mut progress: impl FnMut(usize, usize),
) -> Result<(Modes, f64), String> {
    // Generic only at the door: the body below is compiled once, here, not again in
    // every crate (each test, fmu-build) that passes a progress closure of its own.
    lowest_modes_before_sturm_count_dyn(k, m, chol, count, tolerance, max_iterations, &mut progress)
}

fn lowest_modes_before_sturm_count_dyn(
    k: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
    chol: &dyn LinearSolve,
    count: usize,
    tolerance: f64,
    max_iterations: usize,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Modes, f64), String> {
    let n = k.nrows();
    if count == 0 || count > n {
        return Err(format!("cannot compute {count} modes of a {n}-DOF model"));
    }
    let b = KRYLOV_BLOCK.min(n);
    // Start vectors: the diagonal of M (all DOFs excited), then pseudo-random columns.
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let x = Mat::from_fn(n, b, |_, j| {
        if j == 0 {
            1.0
        } else {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    });
    let mut mx = symmetric_times_block(m, x.as_ref());
    // The space V (M-orthonormal columns), with KV and MV kept for the residuals, and the
    // projection VᵀKV grown by one block row and column per step.
    let (mut v, mut kv, mut mv) = (Mat::<f64>::zeros(n, 0), Mat::<f64>::zeros(n, 0), Mat::<f64>::zeros(n, 0));
    let capacity = krylov_capacity(count, n);
    for a in [&mut v, &mut kv, &mut mv] {
        a.reserve(n, capacity);
    }
    let mut kr = DMatrix::<f64>::zeros(0, 0);
    let mut steps = 0;
    let mut ritz: Option<(Vec<f64>, DMatrix<f64>, usize)> = None;
    let mut converged_residuals: Option<Vec<f64>> = None;
    let mut previous: Vec<f64> = Vec::new();
    let residual_bound = tolerance.sqrt();
    for step in 1..=max_iterations {
        steps = step;
        let mut y = mx;
        chol.solve_block(&mut y); // Y = K⁻¹ M X
        let (y, my) = m_orthonormal_complement(m, &v, &mv, y);
        if y.ncols() == 0 {
            break; // V is an invariant subspace: nothing new to add.
        }
        let ky = symmetric_times_block(k, y.as_ref());
        let (old, new) = (v.ncols(), y.ncols());
        let cross = v.transpose() * &ky;
        let own = y.transpose() * &ky;
        kr = kr.resize(old + new, old + new, 0.0);
        for j in 0..new {
            for i in 0..old {
                kr[(i, old + j)] = cross[(i, j)];
                kr[(old + j, i)] = cross[(i, j)];
            }
            for i in 0..new {
                kr[(old + i, old + j)] = 0.5 * (own[(i, j)] + own[(j, i)]);
            }
        }
        append(&mut v, &y);
        append(&mut kv, &ky);
        append(&mut mv, &my);
        mx = my; // the next block is K⁻¹M·Y: M·Y is at hand
        if v.ncols() <= count {
            continue;
        }
        // Rayleigh–Ritz on V.
        let eig = nalgebra::SymmetricEigen::new(kr.clone());
        let mut order: Vec<usize> = (0..v.ncols()).collect();
        order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
        let values: Vec<f64> = order.iter().map(|&i| eig.eigenvalues[i]).collect();
        let q = DMatrix::from_fn(v.ncols(), v.ncols(), |r, c| eig.eigenvectors[(r, order[c])]);
        // The pairs that must converge: the wanted ones and, for the Sturm shift, the first Ritz
        // value beyond them that is distinct from the last wanted one.
        let last = values[count - 1];
        let Some(next) = (count..values.len()).find(|&j| values[j] > last * (1.0 + 1e-6)) else {
            continue;
        };
        // The residuals (a product with all of KV and MV) only once the Ritz values have settled.
        let settled =
            previous.len() > next && (0..=next).all(|j| ((values[j] - previous[j]) / values[j]).abs() < tolerance);
        previous = values.clone();
        let residuals = if settled { ritz_residuals(&kv, &mv, &values, &q, next + 1) } else { Vec::new() };
        let converged = residuals.iter().take_while(|&&r| r <= residual_bound).count();
        progress(step, converged.min(count));
        ritz = Some((values, q, next));
        if converged > next {
            converged_residuals = Some(residuals);
            break;
        }
    }
    let (values, q, next) = ritz.ok_or("the Krylov space stayed smaller than the modes asked for")?;
    let q_wanted = q.columns(0, count).into_owned();
    let x = &v * &to_faer(&q_wanted);
    let mut residuals = converged_residuals.unwrap_or_else(|| ritz_residuals(&kv, &mv, &values, &q, count));
    residuals.truncate(count);
    if residuals.iter().any(|&r| r > residual_bound) {
        return Err(format!(
            "eigenpairs not converged in {steps} block steps: largest relative residual {:.1e} (asked {residual_bound:.1e})",
            residuals.iter().cloned().fold(0.0, f64::max)
        ));
    }
    // The shift: midway between λ_count and the next distinct (converged) Ritz value.
    let sigma = 0.5 * (values[count - 1] + values[next]);
    let expected = values.iter().filter(|&&l| l < sigma).count();
    // The Krylov space (V, KV, MV: three n × (steps·block) arrays) is done with: freed before
    // the Sturm LDLᵀ, whose factor is as large as K's Cholesky factor, is allocated.
    drop((v, kv, mv));
    Ok((
        Modes {
            eigenvalues: values[..count].to_vec(),
            vectors: x,
            residuals,
            iterations: steps,
            sturm_count: 0,
            ritz_values_below_shift: expected,
        },
        sigma,
    ))
}

/// Y with V's span removed and its columns made M-orthonormal (VᵀMY = 0, YᵀMY = I), returned
/// with M·Y: two passes of block Gram–Schmidt in the M inner product, then the symmetric
/// orthonormalization through the eigenvectors of YᵀMY; directions that are (numerically)
/// already in V are dropped. M·Y is formed once, after the Gram–Schmidt passes, and follows Y
/// through each orthonormalization (M·(Y S) = (M·Y) S): the sparse products with M were the
/// largest single cost of a block step.
fn m_orthonormal_complement(
    m: &SparseColMat<usize, f64>,
    v: &Mat<f64>,
    mv: &Mat<f64>,
    mut y: Mat<f64>,
) -> (Mat<f64>, Mat<f64>) {
    // Twice is enough (Kahan–Parlett): the second pass removes what round-off left of V.
    for _ in 0..2 {
        if v.ncols() > 0 {
            let c = mv.transpose() * &y;
            y -= v * &c;
        }
    }
    let mut my = symmetric_times_block(m, y.as_ref());
    // The second normalization makes Y's own columns orthonormal to round-off.
    for _ in 0..2 {
        let g = gram(&y, &my);
        let eig = nalgebra::SymmetricEigen::new((&g + g.transpose()) * 0.5);
        let largest = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
        let keep: Vec<usize> = (0..g.ncols()).filter(|&j| eig.eigenvalues[j] > 1e-12 * largest).collect();
        let scale = to_faer(&DMatrix::from_fn(g.ncols(), keep.len(), |r, c| {
            eig.eigenvectors[(r, keep[c])] / eig.eigenvalues[keep[c]].sqrt()
        }));
        y = &y * &scale;
        my = &my * &scale;
    }
    (y, my)
}

/// ‖K x − λ M x‖ / ‖K x‖ of the first `count` Ritz pairs (x = V q), from KV and MV.
fn ritz_residuals(kv: &Mat<f64>, mv: &Mat<f64>, values: &[f64], q: &DMatrix<f64>, count: usize) -> Vec<f64> {
    let qc = to_faer(&q.columns(0, count).into_owned());
    let (kx, mx) = (kv * &qc, mv * &qc);
    (0..count)
        .map(|c| {
            let (mut num, mut den) = (0.0, 0.0);
            for r in 0..kx.nrows() {
                num += (kx[(r, c)] - values[c] * mx[(r, c)]).powi(2);
                den += kx[(r, c)].powi(2);
            }
            (num / den).sqrt()
        })
        .collect()
}

fn to_faer(a: &DMatrix<f64>) -> Mat<f64> {
    Mat::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)])
}

/// A ← [A | B] (A's columns reserved ahead, so a step copies only B).
fn append(a: &mut Mat<f64>, b: &Mat<f64>) {
    let (n, p) = (b.nrows(), a.ncols());
    a.resize_with(n, p + b.ncols(), |i, j| b[(i, j - p)]);
}

/// Number of eigenvalues of K x = λ M x below σ: by Sylvester's law of inertia, the number of
/// negative pivots of an LDLᵀ factorization of K − σM (AMD ordering).
pub fn sturm_count(k: &SparseColMat<usize, f64>, m: &SparseColMat<usize, f64>, sigma: f64) -> Result<usize, String> {
    let shifted = shifted(k, m, sigma)?;
    let symbolic =
        factorize_symbolic_cholesky(shifted.symbolic(), Side::Lower, SymmetricOrdering::Amd, Default::default())
            .map_err(|e| format!("symbolic LDLᵀ: {e:?}"))?;
    negative_pivots_of_ldlt(&symbolic, &shifted)
}

/// As [`sturm_count`], on the symbolic analysis of K's own Cholesky factor (its nested
/// dissection, elimination tree and supernodes): K − σM has K's pattern (a consistent mass
/// couples only what the stiffness couples), so nothing is analysed twice, and the LDLᵀ is
/// supernodal and parallel like the Cholesky factorization. The small helical pair's gear 2
/// (z = 41) spent most of its eigenmode stage in the simplicial, sequential LDLᵀ this replaced.
pub fn sturm_count_factored(
    k: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
    sigma: f64,
    chol: &Cholesky,
) -> Result<usize, String> {
    negative_pivots_of_ldlt(chol.symbolic(), &shifted(k, m, sigma)?)
}

/// K − σM, assembled from both matrices' entries (also the gear by harmonics' sector parts).
pub fn shifted(
    k: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
    sigma: f64,
) -> Result<SparseColMat<usize, f64>, String> {
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
    SparseColMat::try_new_from_triplets(n, n, &triplets).map_err(|e| format!("{e:?}"))
}

/// The negative entries of D in A = L D Lᵀ (L unit lower triangular, no pivoting: the inertia
/// is A's whenever the factorization exists). faer keeps D on the factor's diagonal: first in
/// each column of a simplicial factor, on the diagonal of each supernode's top block otherwise.
fn negative_pivots_of_ldlt(symbolic: &SymbolicCholesky<usize>, a: &SparseColMat<usize, f64>) -> Result<usize, String> {
    Ok(negative_pivots(symbolic, &ldlt_values(symbolic, a)?))
}

/// The values of the LDLᵀ factor of A (no pivoting) on a symbolic analysis of A's pattern:
/// for the inertia (`negative_pivots`) and for solves (faer's `LdltRef`).
pub fn ldlt_values(symbolic: &SymbolicCholesky<usize>, a: &SparseColMat<usize, f64>) -> Result<Vec<f64>, String> {
    let mut values = vec![0.0; symbolic.len_val()];
    let par = get_global_parallelism();
    let mut buffer = MemBuffer::new(symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()));
    symbolic
        .factorize_numeric_ldlt(
            &mut values,
            a.as_ref(),
            Side::Lower,
            LdltRegularization::default(),
            par,
            MemStack::new(&mut buffer),
            Default::default(),
        )
        .map_err(|e| format!("LDLᵀ of K − σM failed (σ on an eigenvalue?): {e:?}"))?;
    Ok(values)
}

/// The negative entries of D of an LDLᵀ factor (`ldlt_values`): the negative eigenvalues of A.
pub fn negative_pivots(symbolic: &SymbolicCholesky<usize>, values: &[f64]) -> usize {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => (0..symbolic.nrows()).filter(|&j| values[s.col_ptr()[j]] < 0.0).count(),
        SymbolicCholeskyRaw::Supernodal(s) => {
            let factor = SupernodalLdltRef::new(s, values);
            (0..s.n_supernodes())
                .map(|i| {
                    let block = factor.supernode(i).val();
                    (0..block.ncols()).filter(|&j| block[(j, j)] < 0.0).count()
                })
                .sum()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::linalg::SupernodalThreshold;

    /// The 5-point Laplacian on an n × n grid, fixed on its boundary (K), with M = I: its
    /// eigenvalues are 4 sin²(pπ/2(n+1)) + 4 sin²(qπ/2(n+1)), p, q = 1…n (closed form).
    fn grid_laplacian(n: usize) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>, Vec<f64>) {
        let index = |i: usize, j: usize| i * n + j;
        let mut k = Vec::new();
        for i in 0..n {
            for j in 0..n {
                k.push(Triplet::new(index(i, j), index(i, j), 4.0));
                if i + 1 < n {
                    k.push(Triplet::new(index(i, j), index(i + 1, j), -1.0));
                    k.push(Triplet::new(index(i + 1, j), index(i, j), -1.0));
                }
                if j + 1 < n {
                    k.push(Triplet::new(index(i, j), index(i, j + 1), -1.0));
                    k.push(Triplet::new(index(i, j + 1), index(i, j), -1.0));
                }
            }
        }
        let m: Vec<_> = (0..n * n).map(|i| Triplet::new(i, i, 1.0)).collect();
        let s = |p: usize| (p as f64 * std::f64::consts::PI / (2.0 * (n + 1) as f64)).sin().powi(2);
        let mut exact: Vec<f64> = (1..=n).flat_map(|p| (1..=n).map(move |q| 4.0 * s(p) + 4.0 * s(q))).collect();
        exact.sort_by(f64::total_cmp);
        (
            SparseColMat::try_new_from_triplets(n * n, n * n, &k).unwrap(),
            SparseColMat::try_new_from_triplets(n * n, n * n, &m).unwrap(),
            exact,
        )
    }

    /// The Sturm count reads D off a simplicial and off a supernodal LDLᵀ alike: at shifts between
    /// the closed-form eigenvalues, the negative pivots of K − σM are the eigenvalues below σ.
    #[test]
    fn sturm_count_of_both_factor_layouts_is_the_closed_form_count() {
        let (k, m, exact) = grid_laplacian(24);
        for threshold in [SupernodalThreshold::FORCE_SIMPLICIAL, SupernodalThreshold::FORCE_SUPERNODAL] {
            let symbolic = factorize_symbolic_cholesky(
                k.symbolic(),
                Side::Lower,
                SymmetricOrdering::Amd,
                faer::sparse::linalg::cholesky::CholeskySymbolicParams {
                    supernodal_flop_ratio_threshold: threshold,
                    ..Default::default()
                },
            )
            .unwrap();
            if threshold == SupernodalThreshold::FORCE_SUPERNODAL {
                match symbolic.raw() {
                    SymbolicCholeskyRaw::Supernodal(s) => {
                        let widest =
                            (0..s.n_supernodes()).map(|i| s.supernode_end()[i] - s.supernode_begin()[i]).max().unwrap();
                        assert!(widest > 1, "the test needs supernodes wider than a column");
                    }
                    SymbolicCholeskyRaw::Simplicial(_) => panic!("asked for a supernodal factor"),
                }
            }
            for below in [1, 7, 50, 200, 400] {
                // Midway between distinct eigenvalues (the grid's spectrum has double values).
                let next = (below..exact.len()).find(|&j| exact[j] > exact[below - 1] * (1.0 + 1e-9)).unwrap();
                let sigma = 0.5 * (exact[below - 1] + exact[next]);
                let count = negative_pivots_of_ldlt(&symbolic, &shifted(&k, &m, sigma).unwrap()).unwrap();
                assert_eq!(count, next, "σ = {sigma}: {threshold:?}");
            }
        }
    }
}
