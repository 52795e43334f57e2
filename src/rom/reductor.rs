//! Reductors: a clamped gear's FE model in, a reduced model out (plain data, all the static
//! contact analyses need), plus a reconstructor that lifts reduced coordinates back to FE fields.
//!
//! - [`pmor_hertz`] (paper Sect. 4.2): global attachment modes of the loadable flank nodes (local
//!   deformation removed, the Hertz contact supplies it), compressed by SVD (Algorithm 1) and
//!   scaled so that the reduced stiffness is the identity.
//! - [`standard_cms`] (Sect. 4.1, the baseline): one attachment mode per loadable node — the
//!   static response to a unit load along its normal — so that the reduced statics are exact FE
//!   statics for any load on those nodes.

use super::attachment::global_attachment_modes_of_teeth;
use super::flank::{FlankGrid, Shares};
use super::svd::compress;
use crate::fe::assembly::{DofMap, LinearSolve};
use crate::fe::clamped_gear::ClampedGear;
use faer::Mat;

/// A reduced gear: what the static contact solver needs.
#[derive(Debug, Clone)]
pub struct ReducedGear {
    pub flank: FlankGrid,
    /// Rows of the reduction basis at the loadable nodes: row 3k + c is DOF c of node k
    /// (`flank.nodes[k]`), columns are the reduced coordinates.
    pub flank_modes: Mat<f64>,
    /// Reduced stiffness (n_r × n_r).
    pub stiffness: Mat<f64>,
    /// What the reduced coordinates are; it decides how a flank load condenses.
    pub coordinates: Coordinates,
    /// The depth h below the flank whose local deformation the basis leaves out for the Hertz
    /// law to supply (PMOR-Hertz); `None` where the basis keeps it (standard CMS). The contact
    /// law reads h here, so that reduction and law cannot disagree.
    pub local_depth_m: Option<f64>,
}

/// The default depth h of PMOR-Hertz (partial models and Hertz approach alike): 3 mm, half the
/// Kurokawa pairs' module. It must reach past the flank elements (the partial model is refused
/// otherwise) and stay four Hertz half-widths deep (`contact::hertz::MAX_HALF_WIDTH_OVER_DEPTH`);
/// the STE moves by under 1 % between 2 and 4 mm (BENCHMARKS, "Mesh independence").
pub const DEFAULT_CONTACT_DEPTH_M: f64 = 3e-3;

/// The default depth over the normal module: 3 mm on the Kurokawa pairs' 6 mm, and the same
/// share of the tooth on any other pair (a fixed 3 mm would reach through a 2 mm tooth).
pub const CONTACT_DEPTH_OVER_MODULE: f64 = 0.5;

/// The default depth h of a pair (m): `CONTACT_DEPTH_OVER_MODULE` × its normal module.
pub fn contact_depth_m(pair: &crate::gear::GearPair) -> f64 {
    CONTACT_DEPTH_OVER_MODULE * pair.normal_module_m
}

/// What a gear's reduced coordinates are. The static contact problem is condensed onto the
/// contact forces through the response q = K_r⁻¹·b of the reduced load b of a flank load; both
/// reductions make that response free, for different reasons.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Coordinates {
    /// K_r = I (PMOR-Hertz's SVD basis scaled to unit stiffness, checked when it is built): the
    /// response to a reduced load is the load itself.
    UnitStiffness,
    /// K_r = C, the flexibility of the loadable nodes along their load directions (standard CMS,
    /// one attachment mode per node and direction): q are the nodal forces, and the response to
    /// unit forces along the node normals, shared as w, is w. With `tangents`, a second block of
    /// n_c coordinates holds the forces along the nodes' transverse flank tangents (tooth
    /// friction's, `FlankGrid::transverse_tangent`), so that the statics stay exact FE statics
    /// under friction too.
    NodalForces { tangents: bool },
}

/// The reduced coordinates a flank load produces, K_r⁻¹·b: dense, or sparse where the
/// coordinates are nodal forces.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadResponse {
    Dense(Vec<f64>),
    Sparse(Shares),
}

impl LoadResponse {
    /// rowᵀ·q: how a gap row (`ReducedGear::projected_row`) sees the response.
    pub fn dot(&self, row: &[f64]) -> f64 {
        match self {
            LoadResponse::Dense(q) => q.iter().zip(row).map(|(a, b)| a * b).sum(),
            LoadResponse::Sparse(w) => w.iter().map(|&(k, v)| v * row[k]).sum(),
        }
    }

    /// q += scale·response.
    pub fn add_to(&self, scale: f64, q: &mut [f64]) {
        match self {
            LoadResponse::Dense(r) => q.iter_mut().zip(r).for_each(|(a, b)| *a += scale * b),
            LoadResponse::Sparse(w) => w.iter().for_each(|&(k, v)| q[k] += scale * v),
        }
    }
}

/// Lifts reduced coordinates back to the free DOFs of the FE model.
pub struct Reconstructor {
    pub basis: Mat<f64>,
    pub dofs: DofMap,
}

impl Reconstructor {
    /// The FE displacement field (all DOFs, node-major) of reduced coordinates q.
    pub fn displacement(&self, q: &[f64]) -> Vec<f64> {
        self.displacements(&[q]).remove(0)
    }

    /// The FE displacement fields of several reduced coordinate vectors: one product with the
    /// basis, which is then read once rather than once per field.
    pub fn displacements(&self, qs: &[&[f64]]) -> Vec<Vec<f64>> {
        let q = Mat::from_fn(self.basis.ncols(), qs.len(), |r, c| qs[c][r]);
        let free = &self.basis * &q;
        (0..qs.len())
            .map(|c| {
                self.dofs.expand(free.col(c).try_as_col_major().expect("an owned column is contiguous").as_slice())
            })
            .collect()
    }
}

/// What the SVD kept (Algorithm 1).
#[derive(Debug, Clone)]
pub struct CompressionReport {
    pub n_c: usize,
    pub n_sv: usize,
    pub retained: f64,
    pub singular_values: Vec<f64>,
}

impl ReducedGear {
    pub fn size(&self) -> usize {
        self.stiffness.ncols()
    }

    /// The reduced row of a field's projection on `direction` at a point given by its shares:
    /// Σ w_k·directionᵀ·Ψ_k.
    pub fn projected_row(&self, shares: &Shares, direction: [f64; 3]) -> Vec<f64> {
        let mut row = vec![0.0; self.size()];
        for &(k, w) in shares {
            for c in 0..3 {
                let s = w * direction[c];
                if s != 0.0 {
                    for (j, v) in row.iter_mut().enumerate() {
                        *v += s * self.flank_modes[(3 * k + c, j)];
                    }
                }
            }
        }
        row
    }

    /// The reduced coordinates that unit forces along the node normals (inward), shared as
    /// given, produce: K_r⁻¹ times [`ReducedGear::inward_load_row`].
    pub fn load_response(&self, shares: &Shares) -> LoadResponse {
        match self.coordinates {
            Coordinates::UnitStiffness => LoadResponse::Dense(self.inward_load_row(shares)),
            Coordinates::NodalForces { .. } => LoadResponse::Sparse(shares.clone()),
        }
    }

    /// The reduced coordinates that unit forces along the nodes' transverse flank tangents
    /// (`FlankGrid::transverse_tangent`), shared as given, produce: K_r⁻¹ times
    /// [`ReducedGear::tangential_load_row`].
    pub fn tangential_load_response(&self, shares: &Shares) -> Result<LoadResponse, String> {
        self.flank_load_response(shares, 0.0, 1.0)
    }

    /// The reduced coordinates of the flank load [`ReducedGear::flank_load_row`] describes,
    /// K_r⁻¹ times it. `Err` where it has a tangential part and the basis is a standard CMS one
    /// built without the tangents: its span does not hold the response, and a Galerkin answer in
    /// it would pass a basis error off as the baseline's.
    pub fn flank_load_response(&self, shares: &Shares, normal: f64, tangential: f64) -> Result<LoadResponse, String> {
        match self.coordinates {
            Coordinates::UnitStiffness => Ok(LoadResponse::Dense(self.flank_load_row(shares, normal, tangential))),
            Coordinates::NodalForces { tangents } => {
                if tangential != 0.0 && !tangents {
                    return Err("tooth friction in the statics needs the standard CMS basis built with the flank \
                                tangents (`standard_cms_with_flank_tangents`)"
                        .into());
                }
                let n_c = self.flank.len();
                let along_normal = shares.iter().filter(|_| normal != 0.0).map(|&(k, w)| (k, normal * w));
                let along_tangent =
                    shares.iter().filter(|_| tangential != 0.0).map(|&(k, w)| (n_c + k, tangential * w));
                Ok(LoadResponse::Sparse(along_normal.chain(along_tangent).collect()))
            }
        }
    }

    /// The reduced load of forces of unit total along each node's transverse flank tangent
    /// t_k (`FlankGrid::transverse_tangent`), shared as given: Σ w_k·t_kᵀ·Ψ_k.
    pub fn tangential_load_row(&self, shares: &Shares) -> Vec<f64> {
        self.flank_load_row(shares, 0.0, 1.0)
    }

    /// The reduced load of forces of unit total along each node's inward normal, shared as given.
    pub fn inward_load_row(&self, shares: &Shares) -> Vec<f64> {
        self.flank_load_row(shares, 1.0, 0.0)
    }

    /// The reduced load of forces shared as given, each node's `normal` along its inward normal
    /// −n_k plus `tangential` along its transverse flank tangent t_k: Σ w_k·(−normal·n_k +
    /// tangential·t_k)ᵀ·Ψ_k. A contact's normal load and its friction in one pass over the rows.
    pub fn flank_load_row(&self, shares: &Shares, normal: f64, tangential: f64) -> Vec<f64> {
        let mut row = vec![0.0; self.size()];
        for &(k, w) in shares {
            let n = self.flank.nodes[k].1;
            let t = if tangential != 0.0 { self.flank.transverse_tangent(k) } else { [0.0; 3] };
            for c in 0..3 {
                let d = -normal * n[c] + tangential * t[c];
                if d != 0.0 {
                    for (j, v) in row.iter_mut().enumerate() {
                        *v += w * d * self.flank_modes[(3 * k + c, j)];
                    }
                }
            }
        }
        row
    }
}

/// Rows of `basis` at the flank nodes.
fn flank_rows(basis: &Mat<f64>, dofs: &DofMap, flank: &FlankGrid) -> Mat<f64> {
    Mat::from_fn(3 * flank.len(), basis.ncols(), |row, j| {
        let (node, c) = (flank.nodes[row / 3].0, row % 3);
        dofs.free[3 * node + c].map_or(0.0, |i| basis[(i, j)])
    })
}

/// PMOR-Hertz: global attachment modes at depth h, SVD-compressed to the share `p_en` of the
/// deformation energy, scaled to unit reduced stiffness.
pub fn pmor_hertz(
    model: &ClampedGear,
    factor: &dyn LinearSolve,
    flank: FlankGrid,
    depth_m: f64,
    p_en: f64,
    progress: impl Fn(usize) + Sync,
) -> Result<(ReducedGear, Reconstructor, CompressionReport), String> {
    // Generic only at the door: the body below is compiled once, here, not again in
    // every crate (each test, fmu-build) that passes a progress closure of its own.
    pmor_hertz_dyn(model, factor, flank, depth_m, p_en, &progress)
}

fn pmor_hertz_dyn(
    model: &ClampedGear,
    factor: &dyn LinearSolve,
    flank: FlankGrid,
    depth_m: f64,
    p_en: f64,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(ReducedGear, Reconstructor, CompressionReport), String> {
    let modes = global_attachment_modes_of_teeth(
        &model.mesh,
        &model.material,
        model.formulation,
        &model.dofs,
        factor,
        &flank,
        depth_m,
        progress,
    )?;
    // K_r from the cuts' reactions (K·ψ_j = −r_j), not from a product of K with every column.
    let k_r = modes.reduced_stiffness(&model.dofs);
    let c = compress(&k_r, modes.psi, p_en);
    // K_sv = Ũᵀ K_r Ũ is diagonal (σ); dividing each column by √σ makes it the identity, which
    // keeps the reduced coordinates well scaled.
    let inverse_sqrt: Vec<f64> = c.singular_values[..c.n_sv].iter().map(|s| 1.0 / s.sqrt()).collect();
    let mut basis = c.basis;
    for (j, s) in inverse_sqrt.iter().enumerate() {
        basis.col_mut(j).iter_mut().for_each(|v| *v *= s);
    }
    // Round-off in the small singular values leaves Ũ slightly off K_r's eigenvectors, and the
    // scaling amplifies it (max |K_sv − I| reaches 1e-8 with 400 vectors). The condensed statics
    // take K_r⁻¹ = I, so the basis is made stiffness-orthonormal: with K_sv = L·Lᵀ (Cholesky),
    // the basis times L⁻ᵀ has stiffness L⁻¹·K_sv·L⁻ᵀ = I. L is within 1e-8 of I: a correction.
    // K_sv is formed in the small space (Ũᵀ K_r Ũ, scaled), not by projecting K again.
    let n = c.n_sv;
    let scaled = nalgebra::DMatrix::from_fn(n, n, |i, j| c.stiffness[(i, j)] * inverse_sqrt[i] * inverse_sqrt[j]);
    let cholesky =
        scaled.clone().cholesky().ok_or("the reduced stiffness of the SVD basis is not positive definite")?;
    let inverse_lt = cholesky
        .l()
        .transpose()
        .solve_upper_triangular(&nalgebra::DMatrix::identity(n, n))
        .ok_or("singular Cholesky factor of the reduced stiffness")?;
    let correction = Mat::from_fn(n, n, |i, j| inverse_lt[(i, j)]);
    super::svd::right_multiply_in_place(&mut basis, correction.as_ref());
    let scaled = Mat::from_fn(n, n, |i, j| scaled[(i, j)]);
    let stiffness = correction.transpose() * &scaled * &correction;
    // The check by the gear's stiffness itself: the basis' last columns (the least energy, where
    // round-off weighs most) projected with K directly. It holds only if K·ψ_j = −r_j holds,
    // that is if the total and the partial responses are solved to round-off.
    let checked = n.min(UNIT_STIFFNESS_CHECKED_COLUMNS);
    let last = basis.as_ref().subcols(n - checked, checked).to_owned();
    let direct = super::svd::projected_stiffness(&model.stiffness, &last);
    let off_identity = (0..checked)
        .flat_map(|i| (0..checked).map(move |j| (i, j)))
        .map(|(i, j)| (direct[(i, j)] - if i == j { 1.0 } else { 0.0 }).abs())
        .fold(0.0, f64::max);
    if off_identity > UNIT_STIFFNESS_TOLERANCE {
        return Err(format!(
            "the SVD basis could not be made stiffness-orthonormal: max |K_r − I| = {off_identity:.2e} > {UNIT_STIFFNESS_TOLERANCE:.0e} on its last {checked} columns"
        ));
    }
    let report =
        CompressionReport { n_c: flank.len(), n_sv: c.n_sv, retained: c.retained, singular_values: c.singular_values };
    let flank_modes = flank_rows(&basis, &model.dofs, &flank);
    Ok((
        ReducedGear {
            flank,
            flank_modes,
            stiffness,
            coordinates: Coordinates::UnitStiffness,
            local_depth_m: Some(depth_m),
        },
        Reconstructor { basis, dofs: model.dofs.clone() },
        report,
    ))
}

/// How far from the identity PMOR-Hertz's reduced stiffness may be (round-off of the SVD and the
/// projection is ~1e-13): the statics solve with K_r⁻¹ = I, so this bounds their error.
pub const UNIT_STIFFNESS_TOLERANCE: f64 = 1e-9;

/// Columns of PMOR-Hertz's basis whose stiffness is checked against K itself.
pub const UNIT_STIFFNESS_CHECKED_COLUMNS: usize = 16;

/// Standard CMS: ψ = K⁻¹F, one column per loadable node (a unit load along its inward normal).
/// Then K_CMS = ψᵀKψ = Fᵀψ, read off the flank rows.
pub fn standard_cms(model: &ClampedGear, factor: &dyn LinearSolve, flank: FlankGrid) -> (ReducedGear, Reconstructor) {
    standard_cms_along(model, factor, flank, false)
}

/// Standard CMS with a second attachment mode per loadable node, a unit load along its
/// transverse flank tangent (`FlankGrid::transverse_tangent`): the baseline of the statics with
/// tooth friction, exact FE statics for any normal and tangential loads on those nodes. Twice
/// the solves of [`standard_cms`].
pub fn standard_cms_with_flank_tangents(
    model: &ClampedGear,
    factor: &dyn LinearSolve,
    flank: FlankGrid,
) -> (ReducedGear, Reconstructor) {
    standard_cms_along(model, factor, flank, true)
}

fn standard_cms_along(
    model: &ClampedGear,
    factor: &dyn LinearSolve,
    flank: FlankGrid,
    tangents: bool,
) -> (ReducedGear, Reconstructor) {
    let n_c = flank.len();
    // Column j's load direction at its node: the inward normal, then (with tangents) the tangent.
    let direction = |j: usize| if j < n_c { flank.nodes[j].1.map(|v| -v) } else { flank.transverse_tangent(j - n_c) };
    let n_r = if tangents { 2 * n_c } else { n_c };
    let mut basis = Mat::zeros(model.dofs.n_free, n_r);
    for j in 0..n_r {
        let (node, d) = (flank.nodes[j % n_c].0, direction(j));
        for c in 0..3 {
            if let Some(i) = model.dofs.free[3 * node + c] {
                basis[(i, j)] = d[c];
            }
        }
    }
    factor.solve_block(&mut basis);
    let flank_modes = flank_rows(&basis, &model.dofs, &flank);
    let stiffness = Mat::from_fn(n_r, n_r, |a, b| {
        let f = |row: usize, col: usize| {
            let d = direction(row);
            (0..3).map(|c| d[c] * flank_modes[(3 * (row % n_c) + c, col)]).sum::<f64>()
        };
        0.5 * (f(a, b) + f(b, a))
    });
    let reduced = ReducedGear {
        flank,
        flank_modes,
        stiffness,
        coordinates: Coordinates::NodalForces { tangents },
        local_depth_m: None,
    };
    (reduced, Reconstructor { basis, dofs: model.dofs.clone() })
}
