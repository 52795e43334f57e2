//! Cyclic symmetry of the clamped gear (issue 40): every tooth sector is meshed alike, so the
//! gear's stiffness and mass commute with the one-tooth rotation P (design §4.5), and every
//! field splits into z Bloch waves u_k = Qᵏ e^{ikφ_h} û (sector k, φ_h = 2πh/z, Q the rotation
//! by one pitch about the gear axis). On a wave of harmonic h the gear is one sector whose right
//! edge is its left edge turned by Q and shifted in phase by e^{iφ_h}: the Hermitian sector
//! matrix K_h (and M_h alike), the standard reduction of bladed disks and gears. Harmonics h
//! and z − h are complex conjugates: for 0 < h < z/2 the pair is the real symmetric form
//! [[A, −B], [B, A]] of K_h = A + iB on [Re û; Im û], whose spectrum is K_h's twice — exactly
//! the gear's double eigenvalues of nodal diameter h. h = 0 (and h = z/2 for even z) are real
//! and single.
//!
//! The phase lives on the sector's edge only. The sector's interior DOFs (every DOF but those
//! of its left edge, B) couple to each other alike in every harmonic, so K_II is factorized
//! once, real, and each harmonic is its edge's dense Schur complement
//! S_h = K_BB(h) − K_BI(h) K_II⁻¹ K_IB(h), formed from four products computed once. A sparse
//! factor per harmonic would refactorize the interior ⌊z/2⌋ + 1 times, and on a gear's ring the
//! interior is most of the work: measured on the Kurokawa helical pair, the harmonics' sparse
//! factors took longer than the whole gear's.
//!
//! Static responses: the load's discrete Fourier transform over the sectors, a solve per
//! harmonic, the inverse transform. Eigenpairs: shift-invert Lanczos per harmonic. The Sturm
//! count of K_h − σM_h is, by Haynsworth's inertia additivity, the interior's (one sparse LDLᵀ
//! of K_II − σM_II for all harmonics) plus the Schur complement's (a dense LDLᵀ per harmonic),
//! summed over the harmonics: the proof that no mode was missed.

use super::assembly::{symmetric_times_block, Cholesky, CholeskyAnalysis, LinearSolve};
use super::clamped_gear::ClampedGear;
use super::eigen::{self, Modes};
use super::hex8;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::{Llt, Solve};
use faer::sparse::linalg::cholesky::LdltRef;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Mat, Par, Side};
use rayon::prelude::*;
use std::f64::consts::PI;

/// K's solver for static responses: the gear by harmonics where its mesh is cyclic (every mesh
/// `gear_mesh` makes: one sector's interior factor and an edge per harmonic), the whole gear's
/// Cholesky factor otherwise.
pub fn static_solver(gear: &ClampedGear) -> Result<Box<dyn LinearSolve>, String> {
    Ok(match CyclicGear::new(gear)? {
        Some(cyclic) => Box::new(cyclic.factorize()?),
        None => Box::new(gear.factorize()?),
    })
}

/// Where sector 0's free DOFs sit in the whole gear, sector by sector.
struct SectorLayout {
    teeth: usize,
    /// Free DOFs of one sector (3 per free node of sector 0).
    n_sector: usize,
    /// `gear_dof[k·n_sector + d]`: the whole gear's free DOF of sector DOF d turned on by k teeth.
    gear_dof: Vec<usize>,
}

/// The sector's DOFs split into its interior I and its left edge B (the images of the nodes one
/// sector on): `place[d]` is (on the edge, index within I or B).
struct EdgeSplit {
    interior: Vec<usize>,
    edge: Vec<usize>,
    place: Vec<(bool, usize)>,
}

/// The clamped gear by harmonics before any numeric factorization: its sector parts, the
/// interior/edge split and the interior's symbolic analysis (what the memory estimate counts).
pub struct CyclicGear {
    layout: SectorLayout,
    stiffness: SectorParts,
    mass: SectorParts,
    split: EdgeSplit,
    interior_stiffness: SparseColMat<usize, f64>,
    interior_analysis: CholeskyAnalysis,
}

/// A sector matrix (stiffness, or K − σM) condensed onto the edge: the interior's couplings to
/// the edge from the sector's own nodes (X0) and from those one sector on (X1), and the edge's
/// Schur parts E0 = own_BB − X0ᵀY0 − X1ᵀY1 and E1 = next_BB − X0ᵀY1 (Y = A_II⁻¹X, formed and
/// dropped), so that S_h = E0 + e^{iφ}E1 + e^{−iφ}E1ᵀ, since K_IB(h) = X0 + e^{iφ}X1.
struct Condensed {
    x0: SparseColMat<usize, f64>,
    x1: SparseColMat<usize, f64>,
    e0: Mat<f64>,
    e1: Mat<f64>,
}

/// The gear by harmonics, factorized: K_II's Cholesky factor, the condensed stiffness and each
/// harmonic's Schur complement factor.
pub struct FactoredCyclicGear {
    layout: SectorLayout,
    stiffness: SectorParts,
    mass: SectorParts,
    split: EdgeSplit,
    interior: Cholesky,
    condensed: Condensed,
    schur: Vec<Llt<f64>>,
}

/// The rotation by `angle` about the gear axis (z), row-major.
fn rotation(angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = angle.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

impl CyclicGear {
    /// The gear's sector matrices, or `None` where the mesh is not an exact image of its first
    /// sector (element by element and node by node under `GearMesh::node_turned_by_teeth`), or
    /// a node is clamped in some directions only: then the whole gear must be solved.
    pub fn new(model: &ClampedGear) -> Result<Option<CyclicGear>, String> {
        let gear = &model.mesh;
        let z = gear.teeth;
        let elements = &gear.mesh.elements;
        let nodes = gear.mesh.nodes.len();
        if z < 3 || elements.len() % z != 0 || nodes % (z * gear.nodes_per_sector) != 0 {
            return Ok(None);
        }
        let sector_of = |node: usize| (node % (z * gear.nodes_per_sector)) / gear.nodes_per_sector;
        // Sector 0's elements: every node in sectors 0 and 1, one at least in 0 (z ≥ 3, so an
        // element of sector z − 1, reaching into 0, is not taken). Whether they are one sector's
        // worth, and the whole mesh their images, is checked below.
        let per_sector = elements.len() / z;
        let first: Vec<usize> = (0..elements.len())
            .filter(|&e| {
                let sectors = elements[e].map(sector_of);
                sectors.iter().all(|&k| k <= 1) && sectors.contains(&0)
            })
            .collect();
        if first.len() != per_sector {
            return Ok(None);
        }
        // Every element is the image of one of sector 0's: the turned element sets are the mesh.
        let mut images: std::collections::HashSet<[usize; 8]> =
            std::collections::HashSet::with_capacity(elements.len());
        for k in 0..z as i64 {
            for &e in &first {
                images.insert(elements[e].map(|n| gear.node_turned_by_teeth(n, k)));
            }
        }
        if images.len() != elements.len() || !elements.iter().all(|el| images.contains(el)) {
            return Ok(None);
        }
        // Sector 0's nodes and their free DOFs, all three directions or none.
        let dofs = &model.dofs;
        let mut sector_dof = vec![None; 3 * nodes];
        let mut own_nodes = Vec::new();
        for node in (0..nodes).filter(|&n| sector_of(n) == 0) {
            let free = (0..3).filter(|&c| dofs.free[3 * node + c].is_some()).count();
            match free {
                0 => {}
                3 => {
                    for c in 0..3 {
                        sector_dof[3 * node + c] = Some(3 * own_nodes.len() + c);
                    }
                    own_nodes.push(node);
                }
                _ => return Ok(None),
            }
        }
        let n_sector = 3 * own_nodes.len();
        let mut gear_dof = Vec::with_capacity(z * n_sector);
        for k in 0..z as i64 {
            for &node in &own_nodes {
                let turned = gear.node_turned_by_teeth(node, k);
                for c in 0..3 {
                    match dofs.free[3 * turned + c] {
                        Some(i) => gear_dof.push(i),
                        None => return Ok(None), // clamped in one sector, free in another
                    }
                }
            }
        }
        if z * n_sector != dofs.n_free {
            return Ok(None);
        }
        let layout = SectorLayout { teeth: z, n_sector, gear_dof };
        // Sector 0's stiffness and mass split by where the element nodes lie, the nodes one
        // sector on turned back onto their images in sector 0.
        let d = hex8::elasticity(model.material.youngs_modulus_pa, model.material.poisson_ratio);
        let places = |e: usize| {
            elements[e].map(|n| {
                let next = sector_of(n) == 1;
                let image = if next { gear.node_turned_by_teeth(n, -1) } else { n };
                (sector_dof[3 * image], next)
            })
        };
        let q = rotation(2.0 * PI / z as f64);
        let stiffness = SectorParts::assemble(&first, n_sector, &q, places, |e| {
            hex8::stiffness(&gear.mesh.element_coords(e), &d, model.formulation)
        });
        let mass = SectorParts::assemble(&first, n_sector, &q, places, |e| {
            hex8::mass(&gear.mesh.element_coords(e), model.material.density_kg_m3)
        });
        // The edge: every DOF a node one sector on turns back onto (the columns of `next`).
        let mut on_edge = vec![false; n_sector];
        let next = stiffness.next.as_ref();
        for j in 0..n_sector {
            if next.row_idx_of_col(j).next().is_some() {
                on_edge[j] = true;
            }
        }
        let (mut interior, mut edge, mut place) = (Vec::new(), Vec::new(), Vec::with_capacity(n_sector));
        for (d, &e) in on_edge.iter().enumerate() {
            if e {
                place.push((true, edge.len()));
                edge.push(d);
            } else {
                place.push((false, interior.len()));
                interior.push(d);
            }
        }
        let split = EdgeSplit { interior, edge, place };
        // K_II ordered by nested dissection of the interior's node graph (an open slab: the
        // edge that closes the sector onto itself is not in it).
        let mut node_of_interior = vec![usize::MAX; own_nodes.len()];
        let mut interior_nodes = 0;
        for (node, slot) in node_of_interior.iter_mut().enumerate() {
            if !split.place[3 * node].0 {
                *slot = interior_nodes;
                interior_nodes += 1;
            }
        }
        let mut neighbours: Vec<Vec<i32>> = vec![Vec::new(); interior_nodes];
        for &e in &first {
            let nodes = places(e);
            for &(a, _) in &nodes {
                for &(b, _) in &nodes {
                    if let (Some(a), Some(b)) = (a, b) {
                        let (a, b) = (node_of_interior[a / 3], node_of_interior[b / 3]);
                        if a != b && a != usize::MAX && b != usize::MAX {
                            neighbours[a].push(b as i32);
                        }
                    }
                }
            }
        }
        // A node with some DOFs on the edge and some off it (not a mesh `gear_mesh` makes): the
        // node graph below could not order it whole; solved as the whole gear instead.
        if (0..own_nodes.len()).any(|node| (0..3).any(|c| split.place[3 * node + c].0 != split.place[3 * node].0)) {
            return Ok(None);
        }
        let ordering =
            super::ordering::nested_dissection_of_nodes(neighbours, |node| (0..3).map(|c| 3 * node + c).collect())?;
        let interior_stiffness = block(&stiffness.own, &split, false, false);
        let interior_analysis = Cholesky::analyse(&interior_stiffness, Some(&ordering))?;
        Ok(Some(CyclicGear { layout, stiffness, mass, split, interior_stiffness, interior_analysis }))
    }

    /// Harmonics ⌊z/2⌋ + 1.
    pub fn harmonics(&self) -> usize {
        self.layout.teeth / 2 + 1
    }

    /// Free DOFs of one sector, and of its edge.
    pub fn sector_dofs(&self) -> usize {
        self.layout.n_sector
    }

    pub fn edge_dofs(&self) -> usize {
        self.split.edge.len()
    }

    /// Non-zeros of the interior's Cholesky factor.
    pub fn factor_nnz(&self) -> usize {
        self.interior_analysis.factor_nnz()
    }

    /// Non-zeros of the sector parts (stiffness and mass, own and next).
    pub fn matrix_nnz(&self) -> usize {
        [&self.stiffness, &self.mass].iter().map(|p| p.own.compute_nnz() + p.next.compute_nnz()).sum()
    }

    /// The interior factorization's work space (bytes).
    pub fn factorization_scratch_bytes(&self) -> usize {
        self.interior_analysis.factorization_scratch_bytes()
    }

    /// Dense entries the factorized gear holds at its fullest: the interior solutions of the
    /// edge couplings while they are condensed (Y0, Y1), the edge's parts, and each harmonic's
    /// Schur factor (the real form of the pairs, 2n_B square).
    pub fn dense_entries(&self) -> usize {
        let (n_i, n_b) = (self.split.interior.len(), self.split.edge.len());
        2 * n_i * n_b + 4 * n_b * n_b + self.harmonics() * 4 * n_b * n_b
    }

    /// K_II's factor, the condensed stiffness and every harmonic's Schur complement factor.
    pub fn factorize(self) -> Result<FactoredCyclicGear, String> {
        let CyclicGear { layout, stiffness, mass, split, interior_stiffness, interior_analysis } = self;
        let interior = interior_analysis.factorize(&interior_stiffness)?;
        let condensed = condense(&stiffness.own, &stiffness.next, &split, |y| interior.solve_block(y));
        let z = layout.teeth;
        let schur = (0..=z / 2)
            .into_par_iter()
            .map(|h| {
                let (doubled, cos, sin) = phase_of_harmonic(h, z);
                schur_complement(&condensed, doubled, cos, sin).llt(Side::Lower).map_err(|e| {
                    format!("harmonic {h}: Schur complement of the sector edge not positive definite: {e:?}")
                })
            })
            .collect::<Result<Vec<_>, String>>()?;
        Ok(FactoredCyclicGear { layout, stiffness, mass, split, interior, condensed, schur })
    }
}

/// A's block on the interior or edge rows and columns (`rows_on_edge`, `cols_on_edge`).
fn block(
    a: &SparseColMat<usize, f64>,
    split: &EdgeSplit,
    rows_on_edge: bool,
    cols_on_edge: bool,
) -> SparseColMat<usize, f64> {
    let size = |edge: bool| if edge { split.edge.len() } else { split.interior.len() };
    let a = a.as_ref();
    let mut t = Vec::new();
    for j in 0..a.ncols() {
        let (on_edge, col) = split.place[j];
        if on_edge != cols_on_edge {
            continue;
        }
        for (i, &v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            let (on_edge, row) = split.place[i];
            if on_edge == rows_on_edge {
                t.push(Triplet::new(row, col, v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(size(rows_on_edge), size(cols_on_edge), &t).expect("indices within the blocks")
}

/// A sparse matrix dense.
fn dense(a: &SparseColMat<usize, f64>) -> Mat<f64> {
    let mut d = Mat::zeros(a.nrows(), a.ncols());
    let a = a.as_ref();
    for j in 0..a.ncols() {
        for (i, &v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            d[(i, j)] += v;
        }
    }
    d
}

/// Xᵀ·Y for a sparse X (n × p) and a dense Y (n × q): p × q. X couples the interior to the
/// edge through one layer of nodes, so this is nnz(X)·q operations.
fn transpose_times(x: &SparseColMat<usize, f64>, y: &Mat<f64>) -> Mat<f64> {
    let x = x.as_ref();
    let mut out = Mat::zeros(x.ncols(), y.ncols());
    out.par_col_chunks_mut(1).enumerate().for_each(|(j, mut column)| {
        for a in 0..x.ncols() {
            column[(a, 0)] = x.row_idx_of_col(a).zip(x.val_of_col(a)).map(|(i, &v)| v * y[(i, j)]).sum();
        }
    });
    out
}

/// The condensation of a sector matrix given by its parts `own` and `next`, with the interior
/// solve `solve` (in place, a block of columns).
fn condense(
    own: &SparseColMat<usize, f64>,
    next: &SparseColMat<usize, f64>,
    split: &EdgeSplit,
    solve: impl Fn(&mut Mat<f64>),
) -> Condensed {
    let x0 = block(own, split, false, true);
    let x1 = block(next, split, false, true);
    let (mut y0, mut y1) = (dense(&x0), dense(&x1));
    solve(&mut y0);
    solve(&mut y1);
    let g01 = transpose_times(&x0, &y1);
    let e0 = dense(&block(own, split, true, true)) - transpose_times(&x0, &y0) - transpose_times(&x1, &y1);
    let e1 = dense(&block(next, split, true, true)) - g01;
    Condensed { x0, x1, e0, e1 }
}

/// The real form of the edge's Schur complement S_h = E0 + e^{iφ}E1 + e^{−iφ}E1ᵀ: Re = E0 +
/// cos φ (E1 + E1ᵀ), Im = sin φ (E1 − E1ᵀ); [[Re, −Im], [Im, Re]] for a pair, Re alone else.
fn schur_complement(c: &Condensed, doubled: bool, cos: f64, sin: f64) -> Mat<f64> {
    let n = c.e0.nrows();
    let re = |i: usize, j: usize| c.e0[(i, j)] + cos * (c.e1[(i, j)] + c.e1[(j, i)]);
    if !doubled {
        return Mat::from_fn(n, n, re);
    }
    let im = |i: usize, j: usize| sin * (c.e1[(i, j)] - c.e1[(j, i)]);
    Mat::from_fn(2 * n, 2 * n, |i, j| match (i < n, j < n) {
        (true, true) => re(i, j),
        (false, false) => re(i - n, j - n),
        (true, false) => -im(i, j - n),
        (false, true) => im(i - n, j),
    })
}

/// Whether harmonic h of z is a conjugate pair (its real form doubled), and cos φ_h, sin φ_h
/// (exact for the single harmonics h = 0 and h = z/2).
fn phase_of_harmonic(h: usize, z: usize) -> (bool, f64, f64) {
    let doubled = h != 0 && 2 * h != z;
    let (sin, cos) = if doubled {
        (2.0 * PI * h as f64 / z as f64).sin_cos()
    } else if h == 0 {
        (0.0, 1.0)
    } else {
        (0.0, -1.0)
    };
    (doubled, cos, sin)
}

/// Sector 0's stiffness (or mass) with the nodes one sector on turned back by Q onto their
/// images: `own` couples DOFs whose nodes are both the sector's own or both one sector on,
/// `next` a node of its own (row) to one a sector on (column). On a wave of harmonic h those
/// nodes carry the phase e^{iφ_h}, so the sector matrix is
/// K_h = own + e^{iφ_h}·next + e^{−iφ_h}·nextᵀ = A + iB with A = own + cos φ_h (next + nextᵀ)
/// and B = sin φ_h (next − nextᵀ): no element matrix is formed again per harmonic.
struct SectorParts {
    own: SparseColMat<usize, f64>,
    next: SparseColMat<usize, f64>,
}

impl SectorParts {
    fn assemble(
        first: &[usize],
        n_sector: usize,
        q: &[[f64; 3]; 3],
        places: impl Fn(usize) -> [(Option<usize>, bool); 8] + Sync,
        element: impl Fn(usize) -> hex8::Mat24 + Sync,
    ) -> SectorParts {
        type Triplets = Vec<Triplet<usize, usize, f64>>;
        let (own, next): (Vec<Triplets>, Vec<Triplets>) = first
            .par_iter()
            .map(|&e| {
                let (k_e, places) = (element(e), places(e));
                let (mut own, mut next) = (Vec::with_capacity(576), Vec::new());
                for (a, &(da, next_a)) in places.iter().enumerate() {
                    let Some(da) = da else { continue };
                    for (b, &(db, next_b)) in places.iter().enumerate() {
                        let Some(db) = db else { continue };
                        // A row on a node one sector on, a column on the sector's own: the
                        // transpose of the pair (b, a), which `next` holds.
                        if next_a && !next_b {
                            continue;
                        }
                        // The 3 × 3 block turned back: R_aᵀ K_ab R_b, R = Q one sector on, I else.
                        let block = |i: usize, j: usize| -> f64 {
                            let mut v = 0.0;
                            for r in 0..3 {
                                let ra = if next_a { q[r][i] } else { (r == i) as u8 as f64 };
                                if ra == 0.0 {
                                    continue;
                                }
                                for c in 0..3 {
                                    let rb = if next_b { q[c][j] } else { (c == j) as u8 as f64 };
                                    v += ra * k_e[(3 * a + r, 3 * b + c)] * rb;
                                }
                            }
                            v
                        };
                        let target = if !next_a && next_b { &mut next } else { &mut own };
                        for i in 0..3 {
                            for j in 0..3 {
                                target.push(Triplet::new(da + i, db + j, block(i, j)));
                            }
                        }
                    }
                }
                (own, next)
            })
            .unzip();
        let assemble = |t: Vec<Triplets>| {
            let t: Triplets = t.into_iter().flatten().collect();
            SparseColMat::try_new_from_triplets(n_sector, n_sector, &t).expect("sector DOFs within the sector")
        };
        SectorParts { own: assemble(own), next: assemble(next) }
    }

    /// The real form of K_h: [[A, −B], [B, A]] for a conjugate pair, A alone (B = 0) for a
    /// single harmonic. Every entry of `next` is written whatever its coefficient, so that all
    /// harmonics of a kind share one pattern (one symbolic analysis; K_h − σM_h for the Sturm
    /// count has it too).
    fn harmonic(&self, doubled: bool, cos: f64, sin: f64) -> SparseColMat<usize, f64> {
        let n = self.own.nrows();
        let size = if doubled { 2 * n } else { n };
        let mut t =
            Vec::with_capacity(if doubled { 2 } else { 1 } * (self.own.compute_nnz() + 4 * self.next.compute_nnz()));
        let mut both = |i: usize, j: usize, v: f64| {
            t.push(Triplet::new(i, j, v));
            if doubled {
                t.push(Triplet::new(n + i, n + j, v));
            }
        };
        let (own, next) = (self.own.as_ref(), self.next.as_ref());
        for j in 0..n {
            for (i, &v) in own.row_idx_of_col(j).zip(own.val_of_col(j)) {
                both(i, j, v);
            }
            for (i, &v) in next.row_idx_of_col(j).zip(next.val_of_col(j)) {
                both(i, j, cos * v);
                both(j, i, cos * v);
            }
        }
        if doubled {
            for j in 0..n {
                for (i, &v) in next.row_idx_of_col(j).zip(next.val_of_col(j)) {
                    // B(i, j) = sin·v, B(j, i) = −sin·v; the real form has −B above, B below.
                    t.push(Triplet::new(i, n + j, -sin * v));
                    t.push(Triplet::new(n + i, j, sin * v));
                    t.push(Triplet::new(j, n + i, sin * v));
                    t.push(Triplet::new(n + j, i, -sin * v));
                }
            }
        }
        SparseColMat::try_new_from_triplets(size, size, &t).expect("sector DOFs within the sector")
    }
}

/// X·U for a sparse X (n × p) and a dense U (p × q).
fn times(x: &SparseColMat<usize, f64>, u: &Mat<f64>) -> Mat<f64> {
    let x = x.as_ref();
    let mut out = Mat::zeros(x.nrows(), u.ncols());
    out.par_col_chunks_mut(1).enumerate().for_each(|(j, mut column)| {
        for a in 0..x.ncols() {
            let ua = u[(a, j)];
            if ua != 0.0 {
                for (i, &v) in x.row_idx_of_col(a).zip(x.val_of_col(a)) {
                    column[(i, 0)] += v * ua;
                }
            }
        }
    });
    out
}

/// One harmonic's real-form solve, for the Lanczos steps of that harmonic.
struct HarmonicSolver<'a> {
    gear: &'a FactoredCyclicGear,
    harmonic: usize,
}

impl LinearSolve for HarmonicSolver<'_> {
    fn solve_block(&self, b: &mut Mat<f64>) {
        self.gear.solve_harmonic(self.harmonic, b)
    }
    fn dimension(&self) -> usize {
        let doubled = phase_of_harmonic(self.harmonic, self.gear.layout.teeth).0;
        self.gear.layout.n_sector * if doubled { 2 } else { 1 }
    }
}

impl FactoredCyclicGear {
    fn phase(&self, h: usize, k: usize) -> (f64, f64) {
        (2.0 * PI * ((h * k) % self.layout.teeth) as f64 / self.layout.teeth as f64).sin_cos()
    }

    /// K_h u = b in the real form, in place (rows: Re on the sector DOFs, then Im for a pair),
    /// through the edge: with b = f + ig,
    /// z + iw = K_II⁻¹ b_I, the edge's load r = b_B − (X0 + e^{−iφ}X1)ᵀ(z + iw), its response
    /// u_B = S_h⁻¹ r, and the interior's u_I = K_II⁻¹(b_I − (X0 + e^{iφ}X1) u_B).
    fn solve_harmonic(&self, h: usize, b: &mut Mat<f64>) {
        let (doubled, cos, sin) = phase_of_harmonic(h, self.layout.teeth);
        let (n, cols) = (self.layout.n_sector, b.ncols());
        let parts = if doubled { 2 } else { 1 };
        let (n_i, n_b) = (self.split.interior.len(), self.split.edge.len());
        let c = &self.condensed;
        // Columns [Re | Im] of the interior and edge loads.
        let gather =
            |dofs: &[usize]| Mat::from_fn(dofs.len(), parts * cols, |r, j| b[((j / cols) * n + dofs[r], j % cols)]);
        let (mut zw, edge_load) = (gather(&self.split.interior), gather(&self.split.edge));
        self.interior.solve_block(&mut zw);
        let (t0, t1) = (transpose_times(&c.x0, &zw), transpose_times(&c.x1, &zw));
        // r = b_B − X0ᵀ(z + iw) − e^{−iφ} X1ᵀ(z + iw), e^{−iφ}(t + it') = (c t + s t') + i(c t' − s t).
        let mut r = Mat::from_fn(parts * n_b, cols, |row, j| {
            let (part, a) = (row / n_b, row % n_b);
            let (t1_re, t1_im) = (t1[(a, j)], if doubled { t1[(a, cols + j)] } else { 0.0 });
            let rotated = if part == 0 { cos * t1_re + sin * t1_im } else { cos * t1_im - sin * t1_re };
            edge_load[(a, part * cols + j)] - t0[(a, part * cols + j)] - rotated
        });
        self.schur[h].solve_in_place(r.as_mut());
        // u_B = p + iq; X0·u_B + e^{iφ}X1·u_B, e^{iφ}(v + iv') = (c v − s v') + i(s v + c v').
        let pq = Mat::from_fn(n_b, parts * cols, |a, j| r[((j / cols) * n_b + a, j % cols)]);
        let (v0, v1) = (times(&c.x0, &pq), times(&c.x1, &pq));
        let mut interior_load = Mat::from_fn(n_i, parts * cols, |i, j| {
            let (part, col) = (j / cols, j % cols);
            let (v_re, v_im) = (v1[(i, col)], if doubled { v1[(i, cols + col)] } else { 0.0 });
            let rotated = if part == 0 { cos * v_re - sin * v_im } else { sin * v_re + cos * v_im };
            b[(part * n + self.split.interior[i], col)] - v0[(i, j)] - rotated
        });
        self.interior.solve_block(&mut interior_load);
        for j in 0..parts * cols {
            let (part, col) = (j / cols, j % cols);
            for (i, &d) in self.split.interior.iter().enumerate() {
                b[(part * n + d, col)] = interior_load[(i, j)];
            }
            for (a, &d) in self.split.edge.iter().enumerate() {
                b[(part * n + d, col)] = pq[(a, j)];
            }
        }
    }

    /// A sector field (n_sector, sector 0's frame) placed in sector k of a whole-gear field:
    /// turned by Qᵏ and added with `weight`.
    fn add_to_sector(&self, k: usize, weight: f64, sector: &[f64], gear: &mut [f64]) {
        let n = self.layout.n_sector;
        let q = rotation(2.0 * PI * k as f64 / self.layout.teeth as f64);
        let rows = &self.layout.gear_dof[k * n..(k + 1) * n];
        for node in 0..n / 3 {
            let v = &sector[3 * node..3 * node + 3];
            for i in 0..3 {
                gear[rows[3 * node + i]] += weight * (q[i][0] * v[0] + q[i][1] * v[1] + q[i][2] * v[2]);
            }
        }
    }

    /// The whole-gear field (free DOFs) of harmonic h's real-form vector, added with `weight`:
    /// Re(Qᵏ e^{ikφ_h} û) on sector k, û = x + iy the halves of the vector (y = 0 when single).
    fn expand(&self, h: usize, vector: &[f64], gear: &mut [f64], weight: f64) {
        let doubled = phase_of_harmonic(h, self.layout.teeth).0;
        let n = self.layout.n_sector;
        let mut sector = vec![0.0; n];
        for k in 0..self.layout.teeth {
            let (s, c) = self.phase(h, k);
            for d in 0..n {
                sector[d] = if doubled { c * vector[d] - s * vector[n + d] } else { c * vector[d] };
            }
            self.add_to_sector(k, weight, &sector, gear);
        }
    }

    /// The number of eigenvalues of the whole gear below σ: per harmonic, by Haynsworth, the
    /// negative pivots of the interior's LDLᵀ of K_II − σM_II (one for all harmonics, twice
    /// for a pair's real form) plus those of the dense LDLᵀ of the edge's Schur complement of
    /// K_h − σM_h; summed over the harmonics.
    fn sturm_count(&self, sigma: f64) -> Result<usize, String> {
        let own = eigen::shifted(&self.stiffness.own, &self.mass.own, sigma)?;
        let next = eigen::shifted(&self.stiffness.next, &self.mass.next, sigma)?;
        let interior = block(&own, &self.split, false, false);
        let symbolic = self.interior.symbolic();
        let values = eigen::ldlt_values(symbolic, &interior)?;
        let interior_negative = eigen::negative_pivots(symbolic, &values);
        let ldlt = LdltRef::new(symbolic, &values);
        let condensed = condense(&own, &next, &self.split, |y| {
            let mut buffer = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(y.ncols(), Par::Seq));
            ldlt.solve_in_place_with_conj(Conj::No, y.as_mut(), Par::Seq, MemStack::new(&mut buffer));
        });
        let z = self.layout.teeth;
        let counts = (0..=z / 2)
            .into_par_iter()
            .map(|h| {
                let (doubled, cos, sin) = phase_of_harmonic(h, z);
                let schur = schur_complement(&condensed, doubled, cos, sin).ldlt(Side::Lower).map_err(|e| {
                    format!("harmonic {h}: LDLᵀ of the edge's K − σM failed (σ on an eigenvalue?): {e:?}")
                })?;
                let d = schur.D();
                let edge_negative = (0..d.dim()).filter(|&i| d[i] < 0.0).count();
                Ok(if doubled { 2 } else { 1 } * interior_negative + edge_negative)
            })
            .collect::<Result<Vec<usize>, String>>()?;
        Ok(counts.into_iter().sum())
    }

    /// The `count` lowest eigenpairs of the whole clamped gear, K x = λ M x (free DOFs), by
    /// harmonics: each harmonic's lowest pairs until every harmonic's last computed eigenvalue
    /// lies above the gear's `count`-th, so that the union holds the gear's lowest `count`
    /// (and the next distinct one, for the shift). The Sturm count is the sum over the
    /// harmonics (`sturm_count`); the residuals are the whole gear's (‖Kx − λMx‖/‖Kx‖ with
    /// the whole K and M), so the expansion is checked too.
    pub fn lowest_modes(
        &self,
        k: &SparseColMat<usize, f64>,
        m: &SparseColMat<usize, f64>,
        count: usize,
        tolerance: f64,
        max_iterations: usize,
    ) -> Result<Modes, String> {
        let z = self.layout.teeth;
        let n = self.layout.n_sector * z;
        if count == 0 || count > n || k.nrows() != n {
            return Err(format!("cannot compute {count} modes of a {n}-DOF model"));
        }
        let harmonics = z / 2 + 1;
        let size = |h: usize| self.layout.n_sector * if phase_of_harmonic(h, z).0 { 2 } else { 1 };
        let cap = |h: usize| size(h) / 2;
        // A first guess: the cyclic spectrum spreads over the harmonics, a few each.
        let first = (2 * count).div_ceil(harmonics).max(4);
        let mut wanted: Vec<usize> = (0..harmonics).map(|h| first.min(cap(h))).collect();
        let mut found: Vec<Option<Modes>> = (0..harmonics).map(|_| None).collect();
        loop {
            let unsolved: Vec<usize> = (0..harmonics).filter(|&h| found[h].is_none()).collect();
            let solved: Vec<Result<Modes, String>> = unsolved
                .par_iter()
                .map(|&h| {
                    let (doubled, cos, sin) = phase_of_harmonic(h, z);
                    let k_h = self.stiffness.harmonic(doubled, cos, sin);
                    let m_h = self.mass.harmonic(doubled, cos, sin);
                    let solver = HarmonicSolver { gear: self, harmonic: h };
                    // Counted once below, at the gear's shift, not at each harmonic's own.
                    eigen::lowest_modes_before_sturm_count(
                        &k_h,
                        &m_h,
                        &solver,
                        wanted[h],
                        tolerance,
                        max_iterations,
                        |_, _| {},
                    )
                    .map(|(modes, _)| modes)
                    .map_err(|e| format!("harmonic {h}: {e}"))
                })
                .collect();
            for (h, modes) in unsolved.into_iter().zip(solved) {
                found[h] = Some(modes?);
            }
            let mut all: Vec<f64> = found.iter().flatten().flat_map(|m| m.eigenvalues.iter().cloned()).collect();
            all.sort_by(f64::total_cmp);
            if all.len() < count {
                return Err(format!("the harmonics hold fewer than {count} modes"));
            }
            let last_wanted = all[count - 1];
            // A harmonic whose last computed eigenvalue is not above the gear's count-th may
            // hold more below it: asked again for twice as many.
            let mut again = false;
            for h in 0..harmonics {
                let top = *found[h].as_ref().expect("solved").eigenvalues.last().expect("at least one mode");
                if top <= last_wanted * (1.0 + 1e-6) && wanted[h] < cap(h) {
                    wanted[h] = (2 * wanted[h]).min(cap(h));
                    found[h] = None;
                    again = true;
                }
            }
            if !again {
                break;
            }
        }
        let found: Vec<Modes> = found.into_iter().map(|m| m.expect("solved")).collect();
        // The gear's lowest `count` pairs from the union, ascending.
        let mut pool: Vec<(f64, usize, usize)> = found
            .iter()
            .enumerate()
            .flat_map(|(h, m)| m.eigenvalues.iter().enumerate().map(move |(j, &l)| (l, h, j)))
            .collect();
        pool.sort_by(|a, b| a.0.total_cmp(&b.0));
        let last = pool[count - 1].0;
        let next = pool[count..]
            .iter()
            .map(|p| p.0)
            .find(|&l| l > last * (1.0 + 1e-6))
            .ok_or("no eigenvalue above the wanted ones: the shift for the Sturm count has no place")?;
        let sigma = 0.5 * (last + next);
        let expected = pool.iter().filter(|p| p.0 < sigma).count();
        let sturm = self.sturm_count(sigma)?;
        // The whole gear's modes: each harmonic vector expanded, mass-normalized (a wave's mass
        // is z/2 times its sector form's, z times for a single harmonic: the whole M checks it).
        let mut vectors = Mat::<f64>::zeros(n, count);
        vectors.par_col_chunks_mut(1).enumerate().for_each(|(j, mut column)| {
            let (_, h, index) = pool[j];
            let mode = &found[h].vectors;
            let vector: Vec<f64> = (0..mode.nrows()).map(|r| mode[(r, index)]).collect();
            let doubled = phase_of_harmonic(h, z).0;
            let weight = if doubled { (2.0 / z as f64).sqrt() } else { 1.0 / (z as f64).sqrt() };
            let mut gear = vec![0.0; n];
            self.expand(h, &vector, &mut gear, weight);
            for (r, v) in gear.into_iter().enumerate() {
                column[(r, 0)] = v;
            }
        });
        let eigenvalues: Vec<f64> = pool[..count].iter().map(|p| p.0).collect();
        let kx = symmetric_times_block(k, vectors.as_ref());
        let mx = symmetric_times_block(m, vectors.as_ref());
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
        let residual_bound = tolerance.sqrt();
        if let Some(worst) = residuals.iter().cloned().reduce(f64::max).filter(|&r| !(r <= residual_bound)) {
            return Err(format!(
                "whole-gear residual {worst:.1e} of the modes expanded from the harmonics (asked {residual_bound:.1e})"
            ));
        }
        Ok(Modes {
            eigenvalues,
            vectors,
            residuals,
            iterations: found.iter().map(|m| m.iterations).sum(),
            sturm_count: sturm,
            ritz_values_below_shift: expected,
        })
    }
}

impl LinearSolve for FactoredCyclicGear {
    /// K X = B by harmonics: the load's discrete Fourier transform over the sectors
    /// (F_h = Σ_k e^{−ikφ_h} Q⁻ᵏ f_k, sectors without load skipped), one sector solve per
    /// harmonic and right-hand side, and the inverse transform
    /// u_k = (1/z) Qᵏ Σ_h w_h Re(e^{ikφ_h} U_h), w_h = 2 for the harmonic pairs, 1 for the single.
    fn solve_block(&self, b: &mut Mat<f64>) {
        let (z, n) = (self.layout.teeth, self.layout.n_sector);
        let cols = b.ncols();
        // The sector loads in sector 0's frame, per sector with any load.
        let loaded: Vec<(usize, Mat<f64>)> = (0..z)
            .filter_map(|k| {
                let rows = &self.layout.gear_dof[k * n..(k + 1) * n];
                if (0..cols).all(|j| rows.iter().all(|&r| b[(r, j)] == 0.0)) {
                    return None;
                }
                let q = rotation(-2.0 * PI * k as f64 / z as f64);
                Some((
                    k,
                    Mat::from_fn(n, cols, |d, j| {
                        let (node, i) = (d / 3, d % 3);
                        (0..3).map(|c| q[i][c] * b[(rows[3 * node + c], j)]).sum()
                    }),
                ))
            })
            .collect();
        let responses: Vec<Mat<f64>> = (0..=z / 2)
            .map(|h| {
                let doubled = phase_of_harmonic(h, z).0;
                let mut rhs = Mat::<f64>::zeros(if doubled { 2 * n } else { n }, cols);
                for (k, f) in &loaded {
                    let (s, c) = self.phase(h, *k);
                    for j in 0..cols {
                        for d in 0..n {
                            rhs[(d, j)] += c * f[(d, j)];
                            if doubled {
                                rhs[(n + d, j)] -= s * f[(d, j)];
                            }
                        }
                    }
                }
                self.solve_harmonic(h, &mut rhs);
                rhs
            })
            .collect();
        b.par_col_chunks_mut(1).enumerate().for_each(|(j, mut column)| {
            let mut gear = vec![0.0; n * z];
            for (h, u) in responses.iter().enumerate() {
                let weight = if phase_of_harmonic(h, z).0 { 2.0 } else { 1.0 } / z as f64;
                let vector: Vec<f64> = (0..u.nrows()).map(|r| u[(r, j)]).collect();
                self.expand(h, &vector, &mut gear, weight);
            }
            for (r, v) in gear.into_iter().enumerate() {
                column[(r, 0)] = v;
            }
        });
    }

    fn dimension(&self) -> usize {
        self.layout.n_sector * self.layout.teeth
    }
}
