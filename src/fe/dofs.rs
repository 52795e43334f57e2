//! The numbering of a gear's DOFs: which are free and their equation numbers, the rest clamped
//! (the bore in the floating frame, a partial model's section). Assembly, solvers and the FE
//! orderings all number by it.

use faer::sparse::SparseColMat;

/// Numbering of the free DOFs: `free[3·node + c]` is the equation number, `None` if clamped.
#[derive(Debug, Clone)]
pub struct DofMap {
    pub free: Vec<Option<usize>>,
    pub n_free: usize,
}

impl DofMap {
    /// All DOFs of the `clamped` nodes are eliminated (the floating frame's attachment).
    pub fn new(n_nodes: usize, clamped: &[bool]) -> Self {
        let mut free = vec![None; 3 * n_nodes];
        let mut n_free = 0;
        for node in 0..n_nodes {
            if !clamped[node] {
                for c in 0..3 {
                    free[3 * node + c] = Some(n_free);
                    n_free += 1;
                }
            }
        }
        DofMap { free, n_free }
    }

    pub fn unclamped(n_nodes: usize) -> Self {
        Self::new(n_nodes, &vec![false; n_nodes])
    }

    /// The free-DOF load vector of nodal forces (forces on clamped DOFs go to the support).
    pub fn load_vector(&self, load: &[(usize, [f64; 3])]) -> Vec<f64> {
        let mut f = vec![0.0; self.n_free];
        for &(node, force) in load {
            for c in 0..3 {
                if let Some(i) = self.free[3 * node + c] {
                    f[i] += force[c];
                }
            }
        }
        f
    }

    /// Expands a vector of free DOFs to all DOFs (zeros at clamped ones).
    pub fn expand(&self, x: &[f64]) -> Vec<f64> {
        self.free.iter().map(|f| f.map_or(0.0, |i| x[i])).collect()
    }

    /// The free rows and columns of a matrix over all DOFs (`full` assembled with
    /// [`DofMap::unclamped`]): what assembling over this map gives, without a second assembly.
    /// The free numbering follows the DOF order, so each column's rows stay sorted.
    pub fn restrict(&self, full: &SparseColMat<usize, f64>) -> SparseColMat<usize, f64> {
        assert_eq!(full.ncols(), self.free.len(), "a matrix over all DOFs");
        let full = full.as_ref();
        let mut col_ptr = Vec::with_capacity(self.n_free + 1);
        let (mut row_idx, mut values) = (Vec::new(), Vec::new());
        col_ptr.push(0);
        for (d, slot) in self.free.iter().enumerate() {
            if slot.is_none() {
                continue;
            }
            for (r, &v) in full.row_idx_of_col(d).zip(full.val_of_col(d)) {
                if let Some(i) = self.free[r] {
                    row_idx.push(i);
                    values.push(v);
                }
            }
            col_ptr.push(row_idx.len());
        }
        let symbolic =
            faer::sparse::SymbolicSparseColMat::new_checked(self.n_free, self.n_free, col_ptr, None, row_idx);
        SparseColMat::new(symbolic, values)
    }
}
