//! The reduced gear pair as plain data: what `fmu-build` computes offline and the FMU reads from
//! its model file. Nothing here is O(n_FE): the FE fields enter only through their Gram products
//! (the mass and stiffness invariants) and their rows at the loadable flank nodes.
//!
//! Per gear, in its floating frame (design §4.5): u = V(ϑ)η with V = [Φ, Ψ(ϑ)], Φ the n_k lowest
//! fixed-bore eigenmodes (mass-normalized), Ψ(ϑ) = Σₐ wₐ(ϑ)·S_a the interpolated global contact
//! shapes (n_t columns per angular sample: per loaded flank, drive then coast, one per torque
//! level and then the load-sharing shapes of `rom::sharing`; residual against Φ and of unit
//! modal mass each).
//! ϑ is the gear's angle within its reference pitch; the samples are ϑ_s = s·Δϑ and one pitch on
//! a shape is the one-tooth rotation of the first (S_{s+n_θ} = P·S_s), stored explicitly for
//! s = −2 … n_θ + 2 so that every interpolation interval in [−Δϑ, pitch + Δϑ) has its four
//! neighbours. G is the generator of rotations about the axis (per node: ẑ×), x the node
//! positions; the products are taken with the unclamped consistent mass, so (Gx)ᵀM(Gx) is the
//! gear's polar moment of inertia.

use crate::contact::flank_grid::FlankGrid;
use crate::contact::hertz::ApproachLaw;
use crate::contact::mesh_kinematics::Flank;
use crate::gear::GearPair;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// How Ψ(ϑ) is interpolated between the angular samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Interpolation {
    /// The paper's Eqs. 15–16: C⁰, so ∂Ψ/∂ϑ jumps at every sample.
    Linear,
    /// Catmull–Rom (cubic Hermite with central-difference slopes over the periodic samples): C¹.
    CatmullRom,
}

/// Products of one sample S_a with the rigid-body and eigenmode fields.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SampleInvariants {
    /// (Gx)ᵀM S_a (n_t).
    pub gx_s: DVector<f64>,
    /// Φᵀ M S_a (n_k × n_t; ≈ 0 by residualization, kept so that nothing is assumed).
    pub phi_s: DMatrix<f64>,
}

/// Products of two samples S_a, S_b (|a − b| ≤ 3), n_t × n_t each: S_aᵀMS_b and S_aᵀKS_b.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairInvariants {
    pub s_s: DMatrix<f64>,
    pub k_ss: DMatrix<f64>,
}

/// One reduced gear.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PmorGear {
    pub teeth: u32,
    pub base_radius_m: f64,
    /// Angular samples per pitch n_θ.
    pub samples: usize,
    /// Eigenvalues ω² of Φ (rad²/s²), ascending.
    pub eigenvalues: Vec<f64>,
    /// Shapes per sample n_t: on the drive flanks one per torque level and the load-sharing
    /// shapes, then the same on the coast flanks (`rom::dynamic_reductor`).
    pub shapes: usize,
    /// R = ΦᵀM P⁻¹Φ: the coordinates of Φ one pitch back in Φ (orthogonal when span Φ is
    /// invariant under the tooth rotation). When ϑ passes a pitch, η_Φ ← R·η_Φ.
    pub pitch_map: DMatrix<f64>,
    /// max over columns of ‖P⁻¹φ − Φ R φ‖_M: how far span Φ is from invariant.
    pub invariance_residual: f64,
    /// (Gx)ᵀM(Gx) (kg·m²): the undeformed polar moment of inertia.
    pub polar_inertia_kgm2: f64,
    /// (Gx)ᵀMΦ and ΦᵀMΦ.
    pub gx_phi: DVector<f64>,
    pub phi_phi: DMatrix<f64>,
    /// Per stored sample (index a = s + 2, s = −2 … n_θ + 2).
    pub sample: Vec<SampleInvariants>,
    /// Per stored sample a and offset d = b − a + 3 ∈ 0…6 (None where b is out of range).
    pub pair: Vec<Option<PairInvariants>>,
    /// Per stored sample a, the shapes' damping at unit ratio with their true modal mass:
    /// M_a·V·√Λ·Vᵀ·M_a from K_a v = λ M_a v, Vᵀ M_a V = I (`equations::modal_damping_root`).
    /// The shape damping at ratio ζ is 2ζ times it, interpolated between the samples with the
    /// linear (never negative) weights so that it stays positive semi-definite.
    pub shape_damping_roots: Vec<DMatrix<f64>>,
    /// The loadable nodes of the drive and the coast flanks (`Flank::Drive as usize`, …) of the
    /// teeth that can mesh (reference pitch), with the rows of Φ and of the shapes there.
    pub flanks: [FlankRows; 2],
}

/// One flank's loadable nodes and the basis rows there: all the contact reads of the FE fields.
/// The rows are stored node-major (one row of Φ or of a sample S_a is a contiguous slice): the
/// contact reads a few nodes' rows at a time, and a column-major row stride of 3 × nodes would
/// miss the cache on every coefficient.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlankRows {
    pub grid: FlankGrid,
    /// Φᵀ at the nodes: column r = 3·node + c (x, y, z) is that row of Φ (n_k entries).
    phi_rows: DMatrix<f64>,
    /// Per stored sample, S_aᵀ at the nodes (n_t × 3·nodes), laid out as `phi_rows`.
    shape_rows: Vec<DMatrix<f64>>,
    /// The largest Frobenius norm of a node's 3 rows of Φ, and of a stored sample's: they bound
    /// every node's displacement by the size of η ([`PmorGear::flank_displacement_bound`]).
    pub largest_node_rows: [f64; 2],
    /// The rows along each node's own flank normal, made from the above on first use (not
    /// stored in the model file).
    #[serde(skip)]
    normal_rows: Derived<DirectionRows>,
    /// The rows along each node's transverse flank tangent (`FlankGrid::transverse_tangent`),
    /// tooth friction's direction: made on first use where friction is on.
    #[serde(skip)]
    tangent_rows: Derived<DirectionRows>,
}

/// Which of a node's directions a row is taken along.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeDirection {
    /// The outward flank normal n_k: the Hertz pressure's.
    Normal,
    /// The transverse flank tangent t_k (`FlankGrid::transverse_tangent`): tooth friction's.
    Tangent,
}

/// The basis rows along one direction per node, dᵀΦ_k and dᵀS_{a,k}: the Hertz band loads every
/// node along its own normal (friction along its own tangent), so a generalized force needs one
/// row per node, not three.
#[derive(Debug, Clone)]
pub struct DirectionRows {
    /// nodes × n_k, node-major.
    phi: Vec<f64>,
    /// Per stored sample, nodes × n_t, node-major.
    shapes: Vec<Vec<f64>>,
}

/// Data derived from a struct's stored fields, made once on first use: equal whenever the stored
/// fields are, so it does not enter the comparison.
#[derive(Debug, Clone)]
pub struct Derived<T>(std::sync::OnceLock<T>);

impl<T> Default for Derived<T> {
    fn default() -> Self {
        Derived(std::sync::OnceLock::new())
    }
}

impl<T> PartialEq for Derived<T> {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl FlankRows {
    /// From the rows of Φ (3·nodes × n_k) and of each stored sample (3·nodes × n_t).
    pub fn new(grid: FlankGrid, phi: DMatrix<f64>, shapes: Vec<DMatrix<f64>>) -> Self {
        let node_norm = |m: &DMatrix<f64>, k: usize| m.rows(3 * k, 3).norm();
        let largest = |m: &DMatrix<f64>| (0..grid.len()).map(|k| node_norm(m, k)).fold(0.0, f64::max);
        let largest_node_rows = [largest(&phi), shapes.iter().map(largest).fold(0.0, f64::max)];
        FlankRows {
            grid,
            phi_rows: phi.transpose(),
            shape_rows: shapes.iter().map(|s| s.transpose()).collect(),
            largest_node_rows,
            normal_rows: Derived::default(),
            tangent_rows: Derived::default(),
        }
    }

    fn direction_rows(&self, along: NodeDirection) -> &DirectionRows {
        let cell = match along {
            NodeDirection::Normal => &self.normal_rows,
            NodeDirection::Tangent => &self.tangent_rows,
        };
        cell.0.get_or_init(|| self.rows_along(along))
    }

    /// The rows of Φ and of every stored sample projected on each node's direction.
    fn rows_along(&self, along: NodeDirection) -> DirectionRows {
        let direction = |k: usize| match along {
            NodeDirection::Normal => self.grid.nodes[k].1,
            NodeDirection::Tangent => self.grid.transverse_tangent(k),
        };
        let project = |rows: &DMatrix<f64>| -> Vec<f64> {
            let n = rows.nrows();
            let mut out = Vec::with_capacity(n * self.grid.len());
            for k in 0..self.grid.len() {
                let d = direction(k);
                let node = &rows.as_slice()[3 * k * n..3 * (k + 1) * n];
                out.extend((0..n).map(|j| d[0] * node[j] + d[1] * node[n + j] + d[2] * node[2 * n + j]));
            }
            out
        };
        DirectionRows { phi: project(&self.phi_rows), shapes: self.shape_rows.iter().map(project).collect() }
    }

    /// dᵀΦ_k at a node along its normal or tangent (n_k entries).
    #[inline]
    pub fn phi_row_along(&self, along: NodeDirection, node: usize) -> &[f64] {
        let n = self.phi_rows.nrows();
        &self.direction_rows(along).phi[node * n..(node + 1) * n]
    }

    /// dᵀS_{a,k} of stored sample a at a node along its normal or tangent (n_t entries).
    #[inline]
    pub fn shape_row_along(&self, along: NodeDirection, a: usize, node: usize) -> &[f64] {
        let n = self.shape_rows[a].nrows();
        &self.direction_rows(along).shapes[a][node * n..(node + 1) * n]
    }

    /// Row r = 3·node + c of Φ (n_k entries).
    #[inline]
    pub fn phi_row(&self, r: usize) -> &[f64] {
        let n = self.phi_rows.nrows();
        &self.phi_rows.as_slice()[r * n..(r + 1) * n]
    }

    /// The three rows (x, y, z) of Φ at a node, one after the other (3·n_k entries).
    #[inline]
    pub fn phi_rows_of_node(&self, node: usize) -> &[f64] {
        let n = self.phi_rows.nrows();
        &self.phi_rows.as_slice()[3 * node * n..3 * (node + 1) * n]
    }

    /// The three rows of stored sample a at a node (3·n_t entries).
    #[inline]
    pub fn shape_rows_of_node(&self, a: usize, node: usize) -> &[f64] {
        let m = &self.shape_rows[a];
        let n = m.nrows();
        &m.as_slice()[3 * node * n..3 * (node + 1) * n]
    }

    /// Row r of stored sample a (n_t entries).
    #[inline]
    pub fn shape_row(&self, a: usize, r: usize) -> &[f64] {
        let m = &self.shape_rows[a];
        let n = m.nrows();
        &m.as_slice()[r * n..(r + 1) * n]
    }
}

impl PmorGear {
    pub fn modes(&self) -> usize {
        self.eigenvalues.len()
    }

    /// Coordinates per gear besides the angle: n_k + n_t.
    pub fn elastic_size(&self) -> usize {
        self.modes() + self.shapes
    }

    pub fn pitch_rad(&self) -> f64 {
        2.0 * std::f64::consts::PI / self.teeth as f64
    }

    pub fn sample_step_rad(&self) -> f64 {
        self.pitch_rad() / self.samples as f64
    }

    pub fn flank(&self, flank: Flank) -> &FlankRows {
        &self.flanks[flank as usize]
    }

    pub fn pair_invariants(&self, a: usize, b: usize) -> &PairInvariants {
        let d = b + 3 - a;
        self.pair[a * 7 + d].as_ref().expect("sample pair within the interpolation stencil")
    }
}

/// The contact law between the deformed flanks, offline (the statics that make the contact
/// shapes) and online alike.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum FlankContact {
    /// PMOR-Hertz: the Hertz line contact of each axial section, its local deformation left out
    /// of the basis (the default).
    Hertz,
    /// The standard PMOR of the paper (Sects. 4.1, 5.2; `--model pmor-penalty`), the reference
    /// PMOR-Hertz is compared with: shapes from the standard CMS statics, node-to-surface penalty
    /// contact, each node's stiffness `factor` × its share of ISO 6336-1's c_γα
    /// (`PmorBuildInfo::penalty_layer_stiffness_n_per_m`). Drive flanks only.
    Penalty { factor: f64 },
}

/// How the offline build was made (reported, and used by the online contact law).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PmorBuildInfo {
    pub contact: FlankContact,
    pub rom_torques_nm: Vec<f64>,
    /// Load-sharing shapes per sample and flank (`rom::sharing`).
    pub sharing_shapes: usize,
    pub depth_m: f64,
    pub law: ApproachLaw,
    pub p_en: f64,
    pub mesh: String,
    /// The penalty reference's node stiffness per axial layer of the drive flank (N/m; empty for
    /// PMOR-Hertz): `rom::statics::penalty_node_stiffness_n_per_m`, evaluated by the build so
    /// the FMU's contact law reads it instead of calling offline code (design §2's seam).
    pub penalty_layer_stiffness_n_per_m: Vec<f64>,
}

/// The reduced pair: everything the FMU steps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PmorModel {
    pub pair: GearPair,
    pub gears: [PmorGear; 2],
    pub interpolation: Interpolation,
    /// Modal damping as a fraction of critical, on Φ and on the shapes (the paper's Table 9
    /// values, 1 % and 5 %, taken at each coordinate's own frequency: `equations::Damping`).
    pub modal_damping_ratio: f64,
    pub shape_damping_ratio: f64,
    /// The pair's mean tangent mesh stiffness at the reference mesh force (N/m,
    /// `linear::mean_mesh_stiffness`): the mesh damper c = g·2ζ√(k̄·m_e) is sized on it.
    pub mesh_stiffness_n_per_m: f64,
    /// g in that rule: the damper acts on the sections' approach from the gears' rotation and
    /// body modes, not on the teeth's bending, so c = 2ζ√(k̄·m_e) alone gives the mesh mode
    /// less than ζ; g is measured by the build on the linearized mesh mode
    /// (`linear::mesh_damper_gain`) so that the mode gets the ratio asked.
    pub mesh_damper_gain: f64,
    /// The time integrator the FMU steps with (`integrator`).
    pub integrator: Integrator,
    /// Whether the contact shapes and the hub direction are quasi-static (`quasi_static`).
    pub condensation: Condensation,
    /// The internal step bound the FMU starts with (s): a fraction of the integrator's stability
    /// limit on the pair linearized at a load above its range (`rom::dynamic_reductor`), so the
    /// step follows the stiffest mode of this model instead of a constant.
    pub max_step_s: f64,
    /// The integrator's stability limit on that linearization (s): the FMU refuses a max_step
    /// above it at ExitInitializationMode (issue 13's stability contract).
    pub stability_limit_s: f64,
    /// The load on gear 1 (N·m) that limit was found at, the top of the model's load range
    /// (`linear::default_step`); 0 while the build has not yet found it.
    pub step_checked_torque_nm: f64,
    pub info: PmorBuildInfo,
}

/// The time integrator of the FMU (`integrator`: the steppers and their stability limits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Integrator {
    Rk4,
    Verlet,
    /// Energy-conserving: Gonzalez's discrete gradient on the trapezoid, implicit, on the
    /// quasi-statically condensed pair only (`discrete_gradient_advance`). Unconditionally
    /// stable; its default step is velocity Verlet's (the accuracy the DTE was measured at).
    DiscreteGradient,
}

/// How the elastic coordinates are integrated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Condensation {
    /// Every coordinate carries its inertia (the paper's model). The step is bounded by the
    /// shapes against the contact (≈ 100 kHz) and the hub mode.
    None,
    /// The contact shapes and the hub direction quasi-static (`quasi_static`); the step is bounded
    /// by the retained body modes and the mesh.
    QuasiStatic,
}

/// The load of the step-limit linearization as a multiple of the largest ROM torque
/// (`stability_limit_under_load`): the stiffest mode is the Hertz contact's, which stiffens (slowly,
/// logarithmically) with load; at 4× the limit is 11 % shorter than at the ROM load on the
/// default spur pair.
pub const STEP_LOAD_FACTOR: f64 = 4.0;

impl PmorModel {
    /// The load (N·m on gear 1) the step limit is proven at, and the top of the model's load
    /// range: the one the build found (`step_checked_torque_nm`), else the first it tries,
    /// [`step_load_ceiling_nm`].
    pub fn linearization_torque_nm(&self) -> f64 {
        if self.step_checked_torque_nm > 0.0 {
            self.step_checked_torque_nm
        } else {
            step_load_ceiling_nm(self)
        }
    }
}

/// `STEP_LOAD_FACTOR` × the largest ROM torque, but no more than the pair's yield torque
/// (`closed_forms::rating`): beyond it the teeth yield and no linear-elastic model holds.
pub fn step_load_ceiling_nm(model: &PmorModel) -> f64 {
    step_load_ceiling_of(&model.pair, &model.info.rom_torques_nm)
}

/// [`step_load_ceiling_nm`] of a pair built at `rom_torques_nm` (before its model exists).
pub fn step_load_ceiling_of(pair: &crate::gear::GearPair, rom_torques_nm: &[f64]) -> f64 {
    let rom = rom_torques_nm.iter().cloned().fold(0.0, f64::max);
    (STEP_LOAD_FACTOR * rom).min(crate::closed_forms::rating::yield_torque_nm(pair).max(rom))
}
