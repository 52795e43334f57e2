//! Sparse assembly of K and M (faer, parallel over elements with rayon), elimination of clamped
//! DOFs, and the sparse Cholesky factorization with a residual check.

use super::hex8::{self, Formulation};
use super::mesh::Mesh;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::reborrow::ReborrowMut;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering};
use faer::sparse::SparseColMat;
use faer::{get_global_parallelism, Conj, Mat, MatRef, Par, Side};
use std::sync::Arc;

pub use super::dofs::DofMap;
pub use super::ordering::Ordering;
use rayon::prelude::*;

/// Linear elastic isotropic material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    pub youngs_modulus_pa: f64,
    pub poisson_ratio: f64,
    pub density_kg_m3: f64,
}

impl Material {
    /// The pair's material.
    pub fn of(pair: &crate::gear::GearPair) -> Self {
        Material {
            youngs_modulus_pa: pair.youngs_modulus_pa,
            poisson_ratio: pair.poisson_ratio,
            density_kg_m3: pair.density_kg_m3,
        }
    }
}

/// Σ over the elements of their matrices, on the free DOFs. The pattern is laid out first from
/// the node graph (each free DOF's column holds the free DOFs of every node its node shares an
/// element with), then each element's matrix is added in place, the matrices formed in parallel
/// chunks. No triplet list: it held 24 bytes per entry of every element matrix, twice, and was
/// the build's peak while the full mass was assembled beside the factors (1.5 GB on the
/// Kurokawa helical gear 2). The DOFs are numbered in node order (`DofMap::new` does), so the
/// rows of a column come out sorted.
fn assemble(
    mesh: &Mesh,
    dofs: &DofMap,
    element: impl Fn(&[[f64; 3]; 8]) -> hex8::Mat24 + Sync,
) -> SparseColMat<usize, f64> {
    let n_nodes = mesh.nodes.len();
    let numbered: Vec<usize> = dofs.free.iter().flatten().cloned().collect();
    assert!(numbered.windows(2).all(|w| w[0] < w[1]), "free DOFs numbered in node order");
    // Free directions of each node, and the rank of direction r among them.
    let free_count: Vec<usize> =
        (0..n_nodes).map(|n| (0..3).filter(|&c| dofs.free[3 * n + c].is_some()).count()).collect();
    let rank = |b: usize, r: usize| (0..r).filter(|&c| dofs.free[3 * b + c].is_some()).count();
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n_nodes];
    for el in &mesh.elements {
        for &a in el.iter().filter(|&&a| free_count[a] > 0) {
            neighbours[a].extend(el.iter().filter(|&&b| free_count[b] > 0).map(|&b| b as u32));
        }
    }
    neighbours.par_iter_mut().for_each(|list| {
        list.sort_unstable();
        list.dedup();
        list.shrink_to_fit();
    });
    // offset[a][slot]: the free DOFs of node a's neighbours before the one in `slot`.
    let offset: Vec<Vec<u32>> = neighbours
        .par_iter()
        .map(|list| {
            let mut at = 0u32;
            let mut out = Vec::with_capacity(list.len());
            for &b in list {
                out.push(at);
                at += free_count[b as usize] as u32;
            }
            out
        })
        .collect();
    let mut col_ptr = Vec::with_capacity(dofs.n_free + 1);
    col_ptr.push(0usize);
    let mut row_idx = Vec::new();
    for node in 0..n_nodes {
        for c in 0..3 {
            if dofs.free[3 * node + c].is_none() {
                continue;
            }
            for &b in &neighbours[node] {
                row_idx.extend((0..3).filter_map(|r| dofs.free[3 * b as usize + r]));
            }
            col_ptr.push(row_idx.len());
        }
    }
    let mut values = vec![0.0; row_idx.len()];
    const CHUNK: usize = 4096;
    for start in (0..mesh.elements.len()).step_by(CHUNK) {
        let end = (start + CHUNK).min(mesh.elements.len());
        let matrices: Vec<hex8::Mat24> =
            (start..end).into_par_iter().map(|e| element(&mesh.element_coords(e))).collect();
        for (k, nodes) in matrices.iter().zip(&mesh.elements[start..end]) {
            for (ia, &a) in nodes.iter().enumerate() {
                for (ib, &b) in nodes.iter().enumerate() {
                    if free_count[a] == 0 || free_count[b] == 0 {
                        continue;
                    }
                    let slot = neighbours[a].binary_search(&(b as u32)).expect("b shares an element with a");
                    let base = offset[a][slot] as usize;
                    for c in 0..3 {
                        let Some(column) = dofs.free[3 * a + c] else { continue };
                        for r in 0..3 {
                            if dofs.free[3 * b + r].is_some() {
                                values[col_ptr[column] + base + rank(b, r)] += k[(3 * ib + r, 3 * ia + c)];
                            }
                        }
                    }
                }
            }
        }
    }
    let symbolic = faer::sparse::SymbolicSparseColMat::new_checked(dofs.n_free, dofs.n_free, col_ptr, None, row_idx);
    SparseColMat::new(symbolic, values)
}

/// Global stiffness over the free DOFs (duplicates summed).
pub fn stiffness(
    mesh: &Mesh,
    material: &Material,
    formulation: Formulation,
    dofs: &DofMap,
) -> SparseColMat<usize, f64> {
    let d = hex8::elasticity(material.youngs_modulus_pa, material.poisson_ratio);
    assemble(mesh, dofs, |c| hex8::stiffness(c, &d, formulation))
}

/// Global consistent mass over the free DOFs.
pub fn mass(mesh: &Mesh, material: &Material, dofs: &DofMap) -> SparseColMat<usize, f64> {
    assemble(mesh, dofs, |c| hex8::mass(c, material.density_kg_m3))
}

/// y = A·x for a sparse A.
pub fn mul(a: &SparseColMat<usize, f64>, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.nrows()];
    let a = a.as_ref();
    for (j, &xj) in x.iter().enumerate() {
        if xj != 0.0 {
            for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                y[i] += v * xj;
            }
        }
    }
    y
}

/// Y = A·X for a symmetric sparse A stored whole (both triangles, as `stiffness` and `mass`
/// assemble it) and a block X of columns. By symmetry row j of Y is Σᵢ A[i,j]·(row i of X): with
/// X's rows made contiguous (Xᵀ), A streams once for the whole block, each nonzero an axpy of the
/// block's width, and the rows of Y split over the threads. (faer's sparse × dense product is
/// sequential and streams A once per column of X: it was the eigen and shapes stages' largest
/// cost.)
pub fn symmetric_times_block(a: &SparseColMat<usize, f64>, x: MatRef<'_, f64>) -> Mat<f64> {
    let (n, m) = (x.nrows(), x.ncols());
    assert!(a.nrows() == n && a.ncols() == n, "A (n × n) times X (n × m)");
    let xt = x.transpose().to_owned();
    let mut yt = Mat::<f64>::zeros(m, n);
    let a = a.as_ref();
    const ROWS_PER_TASK: usize = 256;
    yt.as_mut().par_col_chunks_mut(ROWS_PER_TASK).enumerate().for_each(|(chunk, mut rows)| {
        for local in 0..rows.ncols() {
            let j = chunk * ROWS_PER_TASK + local;
            let mut out = rows.rb_mut().col_mut(local);
            let out = out.rb_mut().try_as_col_major_mut().expect("an owned column is contiguous").as_slice_mut();
            for (i, &v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                let xi = xt.col(i).try_as_col_major().expect("an owned column is contiguous").as_slice();
                out.iter_mut().zip(xi).for_each(|(y, x)| *y += v * x);
            }
        }
    });
    yt.transpose().to_owned()
}

/// Columns of A·F formed at a time in [`symmetric_gram`].
pub const GRAM_BLOCK: usize = 32;

/// FᵀAF for a symmetric sparse A stored whole: A·F formed `GRAM_BLOCK` columns at a time, so
/// that beside F only a block (and its two transposes) is held, not a second array of F's size.
pub fn symmetric_gram(a: &SparseColMat<usize, f64>, f: MatRef<'_, f64>) -> Mat<f64> {
    let m = f.ncols();
    let mut gram = Mat::<f64>::zeros(m, m);
    for start in (0..m).step_by(GRAM_BLOCK) {
        let width = GRAM_BLOCK.min(m - start);
        let af = symmetric_times_block(a, f.subcols(start, width));
        gram.as_mut().subcols_mut(start, width).copy_from(f.transpose() * &af);
    }
    gram
}

/// A sparse Cholesky factorization K = LLᵀ (faer, supernodal), with a fill-reducing ordering:
/// the clamped gear passes METIS nested dissection (`ClampedGear::ordering`), AMD is the
/// fallback. The symbolic part is kept so that `refactor` reuses it for a new K of the same
/// pattern. Blocks of right-hand sides are solved in parallel, one block per thread with a sequential solve each: faer's solve does not
/// parallelize inside one call (design §4.2).
pub struct Cholesky {
    symbolic: Arc<SymbolicCholesky<usize>>,
    values: Vec<f64>,
    n: usize,
}

/// Right-hand sides per block in `solve_block` (at most).
pub const SOLVE_BLOCK: usize = 64;

/// A Cholesky factorization's symbolic part, before the numeric one (`Cholesky::analyse`).
#[derive(Clone)]
pub struct CholeskyAnalysis(Arc<SymbolicCholesky<usize>>);

impl CholeskyAnalysis {
    /// Non-zeros the factor L will have.
    pub fn factor_nnz(&self) -> usize {
        self.0.len_val()
    }

    /// Work space (bytes) the numeric factorization takes besides the factor, LLᵀ or LDLᵀ
    /// whichever is larger (the Sturm check's LDLᵀ runs on this analysis too).
    pub fn factorization_scratch_bytes(&self) -> usize {
        let par = get_global_parallelism();
        let llt = self.0.factorize_numeric_llt_scratch::<f64>(par, Default::default()).size_bytes();
        let ldlt = self.0.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()).size_bytes();
        llt.max(ldlt)
    }

    /// The numeric factorization of K (the matrix this was analysed on, or one of its pattern).
    pub fn factorize(self, k: &SparseColMat<usize, f64>) -> Result<Cholesky, String> {
        Cholesky::numeric(self.0, k)
    }
}

impl Cholesky {
    /// Factorizes K with the AMD ordering.
    pub fn new(k: &SparseColMat<usize, f64>) -> Result<Self, String> {
        Self::with_ordering(k, None)
    }

    /// Factorizes K with a given fill-reducing ordering (e.g. nested dissection), AMD if `None`.
    pub fn with_ordering(k: &SparseColMat<usize, f64>, ordering: Option<&Ordering>) -> Result<Self, String> {
        Self::analyse(k, ordering)?.factorize(k)
    }

    /// The symbolic analysis of K alone (ordering, elimination tree, supernodes): the factor's
    /// size before any of it is allocated.
    pub fn analyse(k: &SparseColMat<usize, f64>, ordering: Option<&Ordering>) -> Result<CholeskyAnalysis, String> {
        let ord = match ordering {
            Some(o) => SymmetricOrdering::Custom(PermRef::new_checked(&o.forward, &o.inverse, k.nrows())),
            None => SymmetricOrdering::Amd,
        };
        let symbolic = factorize_symbolic_cholesky(k.symbolic(), Side::Lower, ord, Default::default())
            .map_err(|e| format!("symbolic Cholesky: {e:?}"))?;
        Ok(CholeskyAnalysis(Arc::new(symbolic)))
    }

    /// Factorizes another matrix with the same sparsity pattern, reusing this symbolic analysis
    /// (ordering, elimination tree, supernodes).
    pub fn refactor(&self, k: &SparseColMat<usize, f64>) -> Result<Self, String> {
        Self::numeric(self.symbolic.clone(), k)
    }

    fn numeric(symbolic: Arc<SymbolicCholesky<usize>>, k: &SparseColMat<usize, f64>) -> Result<Self, String> {
        let mut values = vec![0.0; symbolic.len_val()];
        let par = get_global_parallelism();
        let mut buffer = MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
        symbolic
            .factorize_numeric_llt(
                &mut values,
                k.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut buffer),
                Default::default(),
            )
            .map_err(|e| {
                format!("Cholesky failed (matrix not positive definite: a rigid-body mode not clamped?): {e:?}")
            })?;
        Ok(Cholesky { symbolic, values, n: k.nrows() })
    }

    /// The symbolic analysis (ordering, elimination tree, supernodes), for another factorization
    /// of a matrix with K's pattern (the Sturm check's LDLᵀ of K − σM).
    pub fn symbolic(&self) -> &SymbolicCholesky<usize> {
        &self.symbolic
    }

    /// The fill-reducing ordering of the factor (None: identity).
    pub fn ordering(&self) -> Option<PermRef<'_, usize>> {
        self.symbolic.perm()
    }

    /// Non-zeros of the factor L.
    pub fn factor_nnz(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Solves K X = B for a block of right-hand sides (columns of `b`), in place: the columns
    /// split into one chunk per thread (at most `SOLVE_BLOCK` wide), each solved sequentially.
    /// A Lanczos block of 8 is then two solves of 4 on two cores, not one of 8 on one: the
    /// solve streams the whole factor per chunk, and the eigen stage is mostly these solves.
    pub fn solve_block(&self, b: &mut Mat<f64>) {
        assert_eq!(b.nrows(), self.n);
        let llt = LltRef::new(&self.symbolic, &self.values);
        let chunk = b.ncols().div_ceil(rayon::current_num_threads()).clamp(1, SOLVE_BLOCK);
        b.as_mut().par_col_chunks_mut(chunk).for_each(|block| {
            let mut buffer = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(block.ncols(), Par::Seq));
            llt.solve_in_place_with_conj(Conj::No, block, Par::Seq, MemStack::new(&mut buffer));
        });
    }

    /// Solves K x = f.
    pub fn solve(&self, f: &[f64]) -> Vec<f64> {
        let mut b = Mat::from_fn(self.n, 1, |i, _| f[i]);
        self.solve_block(&mut b);
        (0..self.n).map(|i| b[(i, 0)]).collect()
    }
}

/// K X = B for blocks of right-hand sides: the whole gear's Cholesky factor, or the gear by
/// harmonics (`cyclic_symmetry::FactoredCyclicGear`), whichever the build factorized.
pub trait LinearSolve: Sync {
    /// Solves in place, one column per right-hand side.
    fn solve_block(&self, b: &mut Mat<f64>);
    /// The number of equations.
    fn dimension(&self) -> usize;
    /// Solves K x = f.
    fn solve(&self, f: &[f64]) -> Vec<f64> {
        let mut b = Mat::from_fn(self.dimension(), 1, |i, _| f[i]);
        self.solve_block(&mut b);
        (0..self.dimension()).map(|i| b[(i, 0)]).collect()
    }
}

impl LinearSolve for Cholesky {
    fn solve_block(&self, b: &mut Mat<f64>) {
        Cholesky::solve_block(self, b)
    }
    fn dimension(&self) -> usize {
        self.n
    }
}

/// Relative residual ‖Kx − f‖/‖f‖ (the check after each factorization, design §4.2).
pub fn relative_residual(k: &SparseColMat<usize, f64>, x: &[f64], f: &[f64]) -> f64 {
    let r = mul(k, x);
    let num: f64 = r.iter().zip(f).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
    let den: f64 = f.iter().map(|v| v * v).sum::<f64>().sqrt();
    num / den.max(f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fe::mesh::box_mesh;

    /// The small steel box every test here assembles on (4 × 3 × 2 hexahedra).
    fn steel_box() -> (Mesh, Material) {
        let mesh = box_mesh([0.02, 0.01, 0.005], [4, 3, 2]);
        (mesh, Material { youngs_modulus_pa: 210e9, poisson_ratio: 0.3, density_kg_m3: 7850.0 })
    }

    /// The symmetric block product against faer's sparse × dense product (the library's, a
    /// different loop order), on the clamped box's stiffness and a block of 7 columns.
    #[test]
    fn the_symmetric_block_product_is_the_sparse_dense_product() {
        use faer::sparse::linalg::matmul::sparse_dense_matmul;
        let (mesh, material) = steel_box();
        let clamped: Vec<bool> = mesh.nodes.iter().map(|p| p[0] == 0.0).collect();
        let dofs = DofMap::new(mesh.nodes.len(), &clamped);
        let k = stiffness(&mesh, &material, Formulation::IncompatibleModes, &dofs);
        let x = Mat::from_fn(dofs.n_free, 7, |i, j| ((i * 31 + j * 17) % 13) as f64 - 6.0);
        let mut reference = Mat::zeros(dofs.n_free, 7);
        sparse_dense_matmul(reference.as_mut(), faer::Accum::Replace, k.as_ref(), x.as_ref(), 1.0, Par::Seq);
        let y = symmetric_times_block(&k, x.as_ref());
        let scale = reference.norm_max();
        assert!(
            (&y - &reference).norm_max() <= 1e-13 * scale,
            "differ by {:e} of {scale:e}",
            (&y - &reference).norm_max()
        );
    }

    /// The in-place assembly against faer's triplet assembly (duplicates summed: the library's
    /// own), entry by entry, with nodes clamped in all and in some directions.
    #[test]
    fn the_assembly_in_place_is_the_triplet_sum() {
        use faer::sparse::Triplet;
        let (mesh, material) = steel_box();
        let mut free = vec![None; mesh.dofs()];
        let mut n_free = 0;
        for (node, p) in mesh.nodes.iter().enumerate() {
            for c in 0..3 {
                let held = p[0] == 0.0 && (c == 0 || p[1] == 0.0);
                if !held {
                    free[3 * node + c] = Some(n_free);
                    n_free += 1;
                }
            }
        }
        let dofs = DofMap { free, n_free };
        let d = hex8::elasticity(material.youngs_modulus_pa, material.poisson_ratio);
        let mut triplets = Vec::new();
        for e in 0..mesh.elements.len() {
            let k = hex8::stiffness(&mesh.element_coords(e), &d, Formulation::IncompatibleModes);
            let nodes = mesh.elements[e];
            for i in 0..24 {
                for j in 0..24 {
                    if let (Some(r), Some(c)) =
                        (dofs.free[3 * nodes[i / 3] + i % 3], dofs.free[3 * nodes[j / 3] + j % 3])
                    {
                        triplets.push(Triplet::new(r, c, k[(i, j)]));
                    }
                }
            }
        }
        let reference = SparseColMat::try_new_from_triplets(n_free, n_free, &triplets).unwrap().to_dense();
        let k = stiffness(&mesh, &material, Formulation::IncompatibleModes, &dofs).to_dense();
        let scale = reference.norm_max();
        assert!((&k - &reference).norm_max() <= 1e-14 * scale, "differ by {:e}", (&k - &reference).norm_max());
    }

    /// The blocked Gram product against FᵀAF formed from the whole product (70 columns: two
    /// full blocks and a partial one).
    #[test]
    fn the_blocked_gram_product_is_the_whole_one() {
        let (mesh, material) = steel_box();
        let dofs = DofMap::unclamped(mesh.nodes.len());
        let m = mass(&mesh, &material, &dofs);
        let f = Mat::from_fn(dofs.n_free, 70, |i, j| ((i * 37 + j * 11) % 17) as f64 - 8.0);
        let reference = f.transpose() * symmetric_times_block(&m, f.as_ref());
        let gram = symmetric_gram(&m, f.as_ref());
        let scale = reference.norm_max();
        assert!((&gram - &reference).norm_max() <= 1e-13 * scale, "differ by {:e}", (&gram - &reference).norm_max());
    }

    /// Restricting the mass over all DOFs to the free ones is assembling over the free ones:
    /// the same element sums, entry by entry (a clamped face, so rows and columns drop out).
    #[test]
    fn restricting_the_full_mass_is_assembling_the_clamped_one() {
        let (mesh, material) = steel_box();
        let clamped: Vec<bool> = mesh.nodes.iter().map(|p| p[0] == 0.0).collect();
        assert!(clamped.iter().any(|&c| c) && !clamped.iter().all(|&c| c));
        let dofs = DofMap::new(mesh.nodes.len(), &clamped);
        let direct = mass(&mesh, &material, &dofs);
        let restricted = dofs.restrict(&mass(&mesh, &material, &DofMap::unclamped(mesh.nodes.len())));
        assert_eq!((restricted.nrows(), restricted.ncols()), (dofs.n_free, dofs.n_free));
        let dense = |a: &SparseColMat<usize, f64>| a.to_dense();
        let (d, r) = (dense(&direct), dense(&restricted));
        let scale = (0..d.nrows()).map(|i| d[(i, i)].abs()).fold(0.0, f64::max);
        let max_diff = (0..d.nrows())
            .flat_map(|i| (0..d.ncols()).map(move |j| (i, j)))
            .map(|(i, j)| (d[(i, j)] - r[(i, j)]).abs())
            .fold(0.0, f64::max);
        assert!(max_diff <= 1e-14 * scale, "max |M_direct − M_restricted| = {max_diff:e} of {scale:e}");
        assert_eq!(direct.compute_nnz(), restricted.compute_nnz(), "the same pattern");
    }
}
