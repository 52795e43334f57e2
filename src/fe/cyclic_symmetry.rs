//! Cyclic symmetry of the clamped gear (issue 40): every tooth sector is meshed alike, so the
//! gear's stiffness and mass commute with the one-tooth rotation P (design §4.5), and every
//! field splits into z Bloch waves u_k = Qᵏ e^{ikφ_h} û (sector k, φ_h = 2πh/z, Q the rotation
//! by one pitch about the gear axis). On a wave of harmonic h the gear is one sector whose right
//! edge is its left edge turned by Q and shifted in phase by e^{iφ_h}: the Hermitian sector
//! matrices K_h = Tᴴ K_sector T (and M_h alike), the standard reduction of bladed disks and
//! gears. Harmonics h and z − h are complex conjugates: for 0 < h < z/2 the pair is the real
//! symmetric form [[A, −B], [B, A]] of K_h = A + iB on [Re û; Im û], whose spectrum is K_h's
//! twice — exactly the gear's double eigenvalues of nodal diameter h. h = 0 (and h = z/2 for
//! even z) are real and single.
//!
//! What the whole gear needed — one Cholesky factor of the full K — becomes ⌊z/2⌋ + 1 factors of
//! matrices 2/z of its size: eigenmodes by harmonic (shift-invert Lanczos on each, the Sturm
//! count summed over the harmonics as the proof that no mode was missed), and static responses
//! by the discrete Fourier transform of the load over the sectors, a solve per harmonic and the
//! inverse transform.

use super::assembly::{symmetric_times_block, Cholesky, CholeskyAnalysis, LinearSolve};
use super::clamped_gear::ClampedGear;
use super::eigen::{self, Modes};
use super::hex8;
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Where sector 0's free DOFs sit in the whole gear, sector by sector.
struct SectorLayout {
    teeth: usize,
    /// Free DOFs of one sector (3 per free node of sector 0).
    n_sector: usize,
    /// `gear_dof[k·n_sector + d]`: the whole gear's free DOF of sector DOF d turned on by k teeth.
    gear_dof: Vec<usize>,
}

/// One harmonic's sector matrices (the real form for 0 < h < z/2).
struct HarmonicMatrices {
    harmonic: usize,
    /// [Re û; Im û] (2·n_sector) for 0 < h < z/2, û alone (n_sector) for h = 0 and h = z/2.
    doubled: bool,
    stiffness: SparseColMat<usize, f64>,
    mass: SparseColMat<usize, f64>,
}

/// The clamped gear by harmonics, its sector matrices assembled and analysed (before any
/// numeric factorization: `factor_nnz` is what the build's memory estimate counts).
pub struct CyclicGear {
    layout: SectorLayout,
    harmonics: Vec<HarmonicMatrices>,
    analyses: Vec<CholeskyAnalysis>,
}

/// The same with each harmonic's Cholesky factor: the gear's eigenmodes and static responses.
pub struct FactoredCyclicGear {
    layout: SectorLayout,
    harmonics: Vec<(HarmonicMatrices, Cholesky)>,
}

/// The rotation by `angle` about the gear axis (z), row-major.
fn rotation(angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = angle.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

impl CyclicGear {
    /// The gear's sector matrices for every harmonic, or `None` where the mesh is not an exact
    /// image of its first sector (element by element and node by node under
    /// `GearMesh::node_turned_by_teeth`), or a node is clamped in some directions only: then
    /// the whole gear must be solved.
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
        let mut images: std::collections::HashSet<[usize; 8]> = std::collections::HashSet::with_capacity(elements.len());
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
        // The element matrices of sector 0, each with its nodes' place in the sector: (sector
        // DOF of the node's first direction or None if clamped, whether it lies one sector on).
        let d = hex8::elasticity(model.material.youngs_modulus_pa, model.material.poisson_ratio);
        let element_data: Vec<(hex8::Mat24, hex8::Mat24, [(Option<usize>, bool); 8])> = first
            .par_iter()
            .map(|&e| {
                let coords = gear.mesh.element_coords(e);
                let places = elements[e].map(|n| {
                    let next = sector_of(n) == 1;
                    let image = if next { gear.node_turned_by_teeth(n, -1) } else { n };
                    (sector_dof[3 * image], next)
                });
                (
                    hex8::stiffness(&coords, &d, model.formulation),
                    hex8::mass(&coords, model.material.density_kg_m3),
                    places,
                )
            })
            .collect();
        let harmonics: Vec<HarmonicMatrices> =
            (0..=z / 2).into_par_iter().map(|h| harmonic_matrices(&element_data, n_sector, z, h)).collect();
        let analyses =
            harmonics.par_iter().map(|m| Cholesky::analyse(&m.stiffness, None)).collect::<Result<Vec<_>, _>>()?;
        Ok(Some(CyclicGear { layout, harmonics, analyses }))
    }

    /// Harmonics ⌊z/2⌋ + 1 and the size of each sector problem (free DOFs of one sector).
    pub fn harmonics(&self) -> usize {
        self.harmonics.len()
    }

    pub fn sector_dofs(&self) -> usize {
        self.layout.n_sector
    }

    /// Non-zeros of all harmonics' factors together (held at once).
    pub fn factor_nnz(&self) -> usize {
        self.analyses.iter().map(|a| a.factor_nnz()).sum()
    }

    /// Non-zeros of all harmonics' stiffness and mass matrices.
    pub fn matrix_nnz(&self) -> usize {
        self.harmonics.iter().map(|m| m.stiffness.compute_nnz() + m.mass.compute_nnz()).sum()
    }

    /// The largest factorization work space of one harmonic (bytes).
    pub fn factorization_scratch_bytes(&self) -> usize {
        self.analyses.iter().map(|a| a.factorization_scratch_bytes()).max().unwrap_or(0)
    }

    /// Each harmonic's Cholesky factor (harmonics in parallel).
    pub fn factorize(self) -> Result<FactoredCyclicGear, String> {
        let CyclicGear { layout, harmonics, analyses } = self;
        let harmonics = harmonics
            .into_par_iter()
            .zip(analyses)
            .map(|(m, a)| {
                let factor = a.factorize(&m.stiffness)?;
                Ok((m, factor))
            })
            .collect::<Result<Vec<_>, String>>()?;
        Ok(FactoredCyclicGear { layout, harmonics })
    }
}

/// K_h and M_h of harmonic h, from sector 0's element matrices: per element T_eᵀ K_e T_e with
/// T_e = C + iS, C = I and S = 0 on the sector's own nodes, C = cos φ_h·Q and S = sin φ_h·Q on
/// the nodes one sector on; A = CᵀKC + SᵀKS, B = CᵀKS − SᵀKC. B is written wherever a node one
/// sector on takes part (zero or not), so that K_h and M_h share a pattern (the Sturm count's
/// LDLᵀ of K_h − σM_h runs on K_h's analysis).
fn harmonic_matrices(
    elements: &[(hex8::Mat24, hex8::Mat24, [(Option<usize>, bool); 8])],
    n_sector: usize,
    z: usize,
    h: usize,
) -> HarmonicMatrices {
    let doubled = 2 * h != z && h != 0;
    let phase = 2.0 * PI * h as f64 / z as f64;
    let (sin, cos) = if doubled { phase.sin_cos() } else if h == 0 { (0.0, 1.0) } else { (0.0, -1.0) };
    let q = rotation(2.0 * PI / z as f64);
    let mut c = hex8::Mat24::zeros();
    let mut s = hex8::Mat24::zeros();
    let transform = |places: &[(Option<usize>, bool); 8], c: &mut hex8::Mat24, s: &mut hex8::Mat24| {
        c.fill(0.0);
        s.fill(0.0);
        for (a, &(_, next)) in places.iter().enumerate() {
            for i in 0..3 {
                for j in 0..3 {
                    if next {
                        c[(3 * a + i, 3 * a + j)] = cos * q[i][j];
                        s[(3 * a + i, 3 * a + j)] = sin * q[i][j];
                    } else if i == j {
                        c[(3 * a + i, 3 * a + j)] = 1.0;
                    }
                }
            }
        }
    };
    let size = if doubled { 2 * n_sector } else { n_sector };
    let mut k_triplets = Vec::new();
    let mut m_triplets = Vec::new();
    for (k_e, m_e, places) in elements {
        transform(places, &mut c, &mut s);
        for (matrix, triplets) in [(k_e, &mut k_triplets), (m_e, &mut m_triplets)] {
            let a = c.transpose() * matrix * c + s.transpose() * matrix * s;
            let b = c.transpose() * matrix * s - s.transpose() * matrix * c;
            for (ea, &(da, next_a)) in places.iter().enumerate() {
                let Some(da) = da else { continue };
                for (eb, &(db, next_b)) in places.iter().enumerate() {
                    let Some(db) = db else { continue };
                    let coupled = doubled && (next_a || next_b);
                    for i in 0..3 {
                        for j in 0..3 {
                            let (row, col) = (da + i, db + j);
                            let v = a[(3 * ea + i, 3 * eb + j)];
                            triplets.push(Triplet::new(row, col, v));
                            if doubled {
                                triplets.push(Triplet::new(n_sector + row, n_sector + col, v));
                            }
                            if coupled {
                                let w = b[(3 * ea + i, 3 * eb + j)];
                                triplets.push(Triplet::new(row, n_sector + col, -w));
                                triplets.push(Triplet::new(n_sector + row, col, w));
                            }
                        }
                    }
                }
            }
        }
    }
    let assemble = |t: &[Triplet<usize, usize, f64>]| {
        SparseColMat::try_new_from_triplets(size, size, t).expect("sector DOFs within the sector")
    };
    HarmonicMatrices { harmonic: h, doubled, stiffness: assemble(&k_triplets), mass: assemble(&m_triplets) }
}

impl FactoredCyclicGear {
    fn phase(&self, h: usize, k: usize) -> (f64, f64) {
        (2.0 * PI * ((h * k) % self.layout.teeth) as f64 / self.layout.teeth as f64).sin_cos()
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

    /// The whole-gear field (free DOFs) of a harmonic's sector vector: Re(Qᵏ e^{ikφ_h} û) on
    /// sector k, û = x + iy the halves of a real-form vector (y = 0 when h is single).
    fn expand(&self, m: &HarmonicMatrices, vector: &[f64], gear: &mut [f64], weight: f64) {
        let n = self.layout.n_sector;
        let mut sector = vec![0.0; n];
        for k in 0..self.layout.teeth {
            let (s, c) = self.phase(m.harmonic, k);
            for d in 0..n {
                sector[d] = if m.doubled { c * vector[d] - s * vector[n + d] } else { c * vector[d] };
            }
            self.add_to_sector(k, weight, &sector, gear);
        }
    }

    /// The `count` lowest eigenpairs of the whole clamped gear, K x = λ M x (free DOFs), by
    /// harmonics: each harmonic's lowest pairs until every harmonic's last computed eigenvalue
    /// lies above the gear's `count`-th, so that the union holds the gear's lowest `count`
    /// (and the next distinct one, for the shift). The Sturm count is the sum over the
    /// harmonics of the negative pivots of K_h − σM_h; the residuals are the whole gear's
    /// (‖Kx − λMx‖/‖Kx‖ with the whole K and M), so the expansion is checked too.
    pub fn lowest_modes(
        &self,
        k: &SparseColMat<usize, f64>,
        m: &SparseColMat<usize, f64>,
        count: usize,
        tolerance: f64,
        max_iterations: usize,
    ) -> Result<Modes, String> {
        let n = self.layout.n_sector * self.layout.teeth;
        if count == 0 || count > n || k.nrows() != n {
            return Err(format!("cannot compute {count} modes of a {n}-DOF model"));
        }
        // A first guess: the cyclic spectrum spreads over the harmonics, a few each.
        let size = |hm: &HarmonicMatrices| hm.stiffness.nrows();
        let first = (2 * count).div_ceil(self.harmonics.len()).max(4);
        let cap = |hm: &HarmonicMatrices| size(hm) / 2;
        let mut wanted: Vec<usize> = self.harmonics.iter().map(|(hm, _)| first.min(cap(hm))).collect();
        let mut found: Vec<Option<Modes>> = (0..self.harmonics.len()).map(|_| None).collect();
        loop {
            let solved: Vec<Result<Modes, String>> = self
                .harmonics
                .par_iter()
                .zip(&wanted)
                .zip(&found)
                .filter(|(_, f)| f.is_none())
                .map(|(((hm, factor), &w), _)| {
                    eigen::lowest_modes_factored(&hm.stiffness, &hm.mass, factor, w, tolerance, max_iterations, |_, _| {})
                        .map_err(|e| format!("harmonic {}: {e}", hm.harmonic))
                })
                .collect();
            let mut solved = solved.into_iter();
            for f in found.iter_mut().filter(|f| f.is_none()) {
                *f = Some(solved.next().expect("one result per harmonic solved")?);
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
            for h in 0..self.harmonics.len() {
                let modes = found[h].as_ref().expect("solved");
                let top = *modes.eigenvalues.last().expect("at least one mode");
                if top <= last_wanted * (1.0 + 1e-6) && wanted[h] < cap(&self.harmonics[h].0) {
                    wanted[h] = (2 * wanted[h]).min(cap(&self.harmonics[h].0));
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
        let sturm = self
            .harmonics
            .par_iter()
            .map(|(hm, factor)| eigen::sturm_count_factored(&hm.stiffness, &hm.mass, sigma, factor))
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .sum();
        // The whole gear's modes: each harmonic vector expanded, mass-normalized (a wave's mass
        // is z/2 times its sector form's, z times for a single harmonic: checked by the M norm).
        let mut vectors = Mat::<f64>::zeros(n, count);
        vectors.par_col_chunks_mut(1).enumerate().for_each(|(j, mut column)| {
            let (_, h, index) = pool[j];
            let (hm, _) = &self.harmonics[h];
            let mode = &found[h].vectors;
            let vector: Vec<f64> = (0..mode.nrows()).map(|r| mode[(r, index)]).collect();
            let weight = if hm.doubled { (2.0 / self.layout.teeth as f64).sqrt() } else { 1.0 / (self.layout.teeth as f64).sqrt() };
            let mut gear = vec![0.0; n];
            self.expand(hm, &vector, &mut gear, weight);
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
        let responses: Vec<Mat<f64>> = self
            .harmonics
            .iter()
            .map(|(hm, factor)| {
                let size = hm.stiffness.nrows();
                let mut rhs = Mat::<f64>::zeros(size, cols);
                for (k, f) in &loaded {
                    let (s, c) = self.phase(hm.harmonic, *k);
                    for j in 0..cols {
                        for d in 0..n {
                            rhs[(d, j)] += c * f[(d, j)];
                            if hm.doubled {
                                rhs[(n + d, j)] -= s * f[(d, j)];
                            }
                        }
                    }
                }
                factor.solve_block(&mut rhs);
                rhs
            })
            .collect();
        b.par_col_chunks_mut(1).enumerate().for_each(|(j, mut column)| {
            let mut gear = vec![0.0; n * z];
            for ((hm, _), u) in self.harmonics.iter().zip(&responses) {
                let weight = if hm.doubled { 2.0 } else { 1.0 } / z as f64;
                let vector: Vec<f64> = (0..u.nrows()).map(|r| u[(r, j)]).collect();
                self.expand(hm, &vector, &mut gear, weight);
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
