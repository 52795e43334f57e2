//! The dynamic reductor (paper Sects. 3 and 5.1, design §4.5): a pair spec and a mesh in, the
//! reduced gear pair [`PmorModel`] out — plain data, all the FMU needs.
//!
//! Per gear: the lowest fixed-bore eigenmodes Φ (taken whole clusters of the cyclic spectrum, so
//! that span Φ is invariant under a one-tooth rotation P; the residual is measured), the global
//! contact shapes S(ϑ_s, T_j) from PMOR-Hertz statics over one mesh cycle, made residual against
//! Φ (Eq. 14) and of unit modal mass per sample, closed periodically (S_{s+n_θ} = P·S_s), and
//! every Gram product that the floating-frame Lagrangian needs. Nothing O(n_FE) leaves this
//! module.
//!
//! Each sample has a shape loaded on the drive flanks and one loaded on the coast flanks (the
//! back-flank contact across the backlash). The coast shape is the drive statics of the pair
//! turned half a turn about its line of centres (`PairPlacement::half_turn_angles`), turned back
//! onto the gear by the mesh's own half turn (`GearMesh::half_turn_about_x`): no second static
//! solver, no second reduction.

use super::build_memory::{BuildMemory, GearSizes, Schedule};
use super::flank::FlankGrid;
use super::reductor::{pmor_hertz, standard_cms, Reconstructor, ReducedGear};
use super::sharing;
use super::statics::{ContactModel, StaticModel};
use crate::contact::hertz::ApproachLaw;
use crate::contact::mesh_kinematics::{Flank, PairPlacement};
use crate::dynamics::pmor::integrator::Integrator;
pub use crate::dynamics::pmor::linear::IntegratorStep;
use crate::dynamics::pmor::model::{
    FlankContact, FlankRows, Interpolation, PairInvariants, PmorBuildInfo, PmorGear, PmorModel, SampleInvariants,
};
use crate::dynamics::pmor::quasi_static::Condensation;
use crate::fe::assembly::{self, DofMap};
use crate::fe::clamped_gear::ClampedGear;
use crate::fe::cyclic_symmetry::{CyclicGear, FactoredCyclicGear};
use crate::fe::eigen;
use crate::fe::gear_mesh::{GearMesh, MeshSpec};
use crate::fe::hex8::Formulation;
use crate::gear::GearPair;
use faer::Mat;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The choices of the offline build.
#[derive(Debug, Clone, PartialEq)]
pub struct DynamicBuildOptions {
    /// Eigenmodes per gear (raised to the end of a cluster of the cyclic spectrum).
    pub modes: usize,
    /// Angular samples per mesh cycle n_θ.
    pub angles: usize,
    /// Torque levels on gear 1 of the static analyses (N·m).
    pub rom_torques_nm: Vec<f64>,
    /// Load-sharing shapes per sample and flank beside the static ones (`rom::sharing`: orders
    /// 1 … this).
    pub sharing_shapes: usize,
    pub depth_m: f64,
    pub p_en: f64,
    pub law: ApproachLaw,
    /// The contact law of the statics that make the shapes and of the FMU (PMOR-Hertz by
    /// default; the penalty one builds the standard PMOR reference on standard CMS gears).
    pub contact: FlankContact,
    pub interpolation: Interpolation,
    pub modal_damping_ratio: f64,
    pub shape_damping_ratio: f64,
    /// The time integrator of the FMU (its default step is a share of this one's limit).
    pub integrator: Integrator,
    /// Whether the FMU treats the contact shapes and the hub direction as quasi-static.
    pub condensation: Condensation,
    /// Whether to tabulate the lumped model's mesh law from this build's statics too
    /// (`rom::static_mesh_law`; no second reduction).
    pub lumped_mesh_law: bool,
    /// The memory the build may take (bytes); `None`: what the machine has available
    /// (`rom::build_memory::available_bytes`).
    pub memory_limit_bytes: Option<f64>,
}

impl Default for DynamicBuildOptions {
    fn default() -> Self {
        DynamicBuildOptions {
            modes: 20,
            // With the sharing shapes, example 3's DTE is the same at 20, 40 and 80 samples to
            // 0.03 % (BENCHMARKS, convergence); 40 would put the .fmu over 5 MB.
            angles: 20,
            rom_torques_nm: vec![250.0],
            // Without it example 3's DTE peak-to-peak follows the ROM torque (7 %); a second one
            // is linearly dependent for a spur pair (two pairs in the window at some angles).
            sharing_shapes: 1,
            depth_m: crate::rom::reductor::DEFAULT_CONTACT_DEPTH_M,
            p_en: crate::rom::svd::DEFAULT_P_EN,
            law: ApproachLaw::Weber,
            contact: FlankContact::Hertz,
            interpolation: Interpolation::CatmullRom,
            modal_damping_ratio: 0.01,
            shape_damping_ratio: 0.05,
            // The energy-conserving discrete gradient at velocity Verlet's default step: example
            // 3's DTE within 0.3 % of Verlet's, the undamped energy kept to 1e-4 of the vibration
            // energy where Verlet's shadow energy jumps at every contact event (BENCHMARKS,
            // "Integrators"); two quasi-static solves per step instead of one.
            integrator: Integrator::DiscreteGradient,
            // The step set by the body modes and the mesh, not by the shapes against the contact
            // or the hub: velocity Verlet's 20 µs instead of 1.7 µs on the Kurokawa spur pair,
            // example 3's DTE within 0.2 % of the full pair's (method §10a; `pmor_dynamics`,
            // `the_quasi_static_condensation_keeps_example_3s_dte_at_a_longer_step`).
            condensation: Condensation::QuasiStatic,
            lumped_mesh_law: false,
            memory_limit_bytes: None,
        }
    }
}

/// What the build measured, for the user and the tests.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DynamicBuildReport {
    /// Per gear: n_k kept, FE eigenfrequencies (Hz) of Φ.
    pub modes_hz: [Vec<f64>; 2],
    /// Per gear: the invariance residual of span Φ under the tooth rotation.
    pub invariance_residual: [f64; 2],
    /// Per gear: (Gx)ᵀM(Gx) against the exact inertia from the profile.
    pub polar_inertia_kgm2: [(f64, f64); 2],
    /// Per gear: the largest ‖S(pitch) − P·S(0)‖_M over the columns (unit modal mass each), from
    /// one extra sample one pitch on.
    pub closure_residual: [f64; 2],
    /// Per gear: max |ΦᵀM S| of the stored shapes (0 by construction up to round-off).
    pub residualization: [f64; 2],
    /// Per gear: the smallest ratio of the extreme eigenvalues of a sample's shape Gram matrix
    /// (1: orthogonal shapes; near 0: nearly parallel).
    pub shape_gram_ratio: [f64; 2],
    /// STE (m) of the static analyses, per torque, per sample.
    pub ste_m: Vec<Vec<f64>>,
    pub n_sv: [usize; 2],
    pub step: IntegratorStep,
    /// The lumped model's drive-flank law and its tooth-pair counts, where asked for.
    pub lumped_mesh_law: Option<super::static_mesh_law::StaticMeshLaw>,
    /// The peak memory estimated before the FE stage, and the schedule it chose.
    pub memory: BuildMemory,
    pub schedule: Schedule,
}

/// `f` applied to the reduced pair with the build's modal damping and integrator, no added
/// inertia and no mesh damper: what the build's linearizations start from.
fn with_build_dynamics<T>(
    model: &PmorModel,
    options: &DynamicBuildOptions,
    f: impl FnOnce(&mut crate::dynamics::pmor::PmorDynamics) -> T,
) -> T {
    let place = crate::contact::mesh_kinematics::PairPlacement::new(&model.pair);
    let mut dynamics = crate::dynamics::pmor::PmorDynamics::new(
        model,
        &place,
        model.damping(options.modal_damping_ratio, options.shape_damping_ratio),
        [0.0; 2],
    );
    dynamics.integrator = options.integrator;
    f(&mut dynamics)
}

/// The default step of a reduced pair with the build's damping and integrator
/// (`linear::default_step`).
fn integrator_step(model: &PmorModel, options: &DynamicBuildOptions) -> Result<IntegratorStep, String> {
    with_build_dynamics(model, options, |dynamics| {
        // The FMU starts with the spec's mesh damping ratio: its default step must hold with it.
        dynamics.mesh_damping_n_s_per_m = model.mesh_damper_n_s_per_m(
            model.pair.mesh_damping_ratio,
            [model.gears[0].polar_inertia_kgm2, model.gears[1].polar_inertia_kgm2],
        );
        crate::dynamics::pmor::linear::default_step(dynamics)
    })
}

/// The mesh damper's calibration (`linear::mesh_damper_gain`) with the build's modal damping:
/// (gain, the load on gear 1 it was found at).
///
/// One gain per pair, whatever the build's treatment of the stiff coordinates: the damper is a
/// physical element, and two FMUs of one spec (the default and `--dynamics full`) must carry the
/// same one. It is calibrated on the quasi-static condensation of the shapes and the hub with
/// every body mode keeping its inertia: its linearized mesh mode is the full pair's (frequency
/// within 0.5 %, and, since the condensation's damping sees the condensed coordinates' rates, ζ
/// within 1e-4 on the Kurokawa spur pair, 0.0417 against 0.0434 on the small helical one over a
/// mesh cycle), and clean, where the full pair's mixes with the stiff coordinates' at some
/// positions (ζ 0.034–0.051 there at one c; issue 38: its own calibration gave the small helical
/// pair a gain 10 % above the default build's). Where that condensation cannot be made (a model
/// it does not support), the build's own treatment is calibrated.
fn mesh_damper_gain(model: &PmorModel, options: &DynamicBuildOptions) -> Result<(f64, f64), String> {
    use crate::dynamics::pmor::linear;
    with_build_dynamics(model, options, |dynamics| {
        let mut condensed = dynamics.with_mesh_damper(dynamics.mesh_damping_n_s_per_m);
        condensed.set_quasi_static_cutoff(f64::INFINITY);
        linear::mesh_damper_gain(&condensed).or_else(|_| linear::mesh_damper_gain(dynamics))
    })
}

/// The reduced pair's mean tangent mesh stiffness at the reference mesh force, with the build's
/// damping (a static property: damping does not enter it).
fn mean_mesh_stiffness(model: &PmorModel, options: &DynamicBuildOptions) -> Result<f64, String> {
    use crate::dynamics::pmor::linear;
    with_build_dynamics(model, options, |dynamics| {
        linear::mean_mesh_stiffness(dynamics, linear::reference_mesh_force_n(&model.pair))
    })
}

/// G·f: the in-plane rotation generator ẑ× applied node by node.
fn generator(field: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; field.len()];
    for n in 0..field.len() / 3 {
        out[3 * n] = -field[3 * n + 1];
        out[3 * n + 1] = field[3 * n];
    }
    out
}

/// A faer matrix with the given columns.
fn from_columns(cols: &[Vec<f64>]) -> Mat<f64> {
    Mat::from_fn(cols[0].len(), cols.len(), |i, j| cols[j][i])
}

/// A·f for each field f: one block product, split over the threads (a field at a time, the
/// sparse product is sequential and was the largest cost of the shapes stage).
fn sparse_times_fields(a: &faer::sparse::SparseColMat<usize, f64>, fields: &[Vec<f64>]) -> Vec<Vec<f64>> {
    if fields.is_empty() {
        return Vec::new();
    }
    let af = assembly::symmetric_times_block(a, from_columns(fields).as_ref());
    (0..af.ncols()).map(|j| (0..af.nrows()).map(|i| af[(i, j)]).collect()).collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// How a gear's stiffness is factorized: by harmonics where its mesh is cyclic (every mesh
/// `fe::gear_mesh` makes), the whole gear otherwise.
enum Solver {
    Harmonics(CyclicGear),
    Whole(crate::fe::assembly::CholeskyAnalysis),
}

enum Factored {
    Harmonics(FactoredCyclicGear),
    Whole(crate::fe::assembly::Cholesky),
}

impl Factored {
    fn solver(&self) -> &dyn crate::fe::assembly::LinearSolve {
        match self {
            Factored::Harmonics(f) => f,
            Factored::Whole(f) => f,
        }
    }
}

/// One gear before its factorization: what the memory estimate is made from.
struct PreparedGear {
    model: ClampedGear,
    analysis: Solver,
    grid: FlankGrid,
    sizes: GearSizes,
}

/// Nodal fields the shapes stage holds at its fullest, for n_θ samples of n_t shapes and n_k
/// modes. The Gram products (`assembly::symmetric_gram`) hold their fields and one block of the
/// sparse product with its two transposes. While the stiffness Gram is formed: the cleaned
/// samples, the stored ones (n_θ + 5) and their free-DOF copy; while the mass Gram is formed:
/// the cleaned and stored samples and the fields [Gx | Φ | S]; while the raw samples are formed:
/// three copies of them (the product with the basis, expanded, turned); while cleaning: the raw
/// samples, two cleaned copies and one sample's product.
fn shape_fields(n_theta: usize, n_t: usize, n_k: usize) -> usize {
    let stored = (n_theta + 5) * n_t;
    let fields = 1 + n_k + stored;
    let block = 3 * assembly::GRAM_BLOCK;
    let stiffness_gram = n_theta * n_t + 2 * stored + block;
    let mass_gram = n_theta * n_t + stored + fields + block;
    let raw = 3 * (n_theta + 1) * n_t;
    let cleaning = (n_theta + 1) * n_t + 2 * n_theta * n_t + 5 * n_t;
    stiffness_gram.max(mass_gram).max(raw).max(cleaning)
}

/// One gear's FE side from its FE stage to the end of the build: the mesh and what the statics
/// and the shapes need.
struct GearFe {
    mesh: GearMesh,
    material: assembly::Material,
    dofs: DofMap,
    reduced: ReducedGear,
    /// Φ expanded to all DOFs.
    phi: Vec<Vec<f64>>,
    eigenvalues: Vec<f64>,
    n_sv: usize,
}

/// One gear's large arrays kept from its FE stage until its shapes are made, and freed then:
/// the other gear's shapes stage does not hold them.
struct GearFields {
    stiffness: faer::sparse::SparseColMat<usize, f64>,
    reconstructor: Reconstructor,
}

/// Builds the reduced pair. `progress(message)` reports the stages.
pub fn build_dynamic_model(
    pair: &GearPair,
    mesh: &MeshSpec,
    options: &DynamicBuildOptions,
    progress: impl Fn(String) + Sync,
) -> Result<(PmorModel, DynamicBuildReport), String> {
    // Generic only at the door: the body below is compiled once, here, not again in
    // every crate (each test, fmu-build) that passes a progress closure of its own.
    build_dynamic_model_dyn(pair, mesh, options, &progress)
}

fn build_dynamic_model_dyn(
    pair: &GearPair,
    mesh: &MeshSpec,
    options: &DynamicBuildOptions,
    progress: &(dyn Fn(String) + Sync),
) -> Result<(PmorModel, DynamicBuildReport), String> {
    if options.angles < 4 {
        return Err(format!("angles must be ≥ 4 per mesh cycle (got {})", options.angles));
    }
    if options.rom_torques_nm.is_empty() || options.rom_torques_nm.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
        return Err("rom_torques_nm must be one or more positive torques".into());
    }
    let place = PairPlacement::new(pair);
    // Each gear meshed, assembled, its factor analysed and its loadable flank found: every size
    // the memory estimate needs, before anything large is allocated.
    let prepare = |i: usize, gear: &crate::gear::Gear| -> Result<PreparedGear, String> {
        progress(format!("gear {}: FE model", i + 1));
        let model = ClampedGear::new(pair, gear, mesh, Formulation::IncompatibleModes);
        let analysis = match CyclicGear::new(&model)? {
            Some(cyclic) => Solver::Harmonics(cyclic),
            None => Solver::Whole(model.analyse()?),
        };
        let grid = FlankGrid::contact_flank_in_reach(&model.mesh, i, Flank::Drive, &place, 0)?;
        let solved_columns = match (options.contact, super::attachment::teeth_from_the_first(&model.mesh, &grid)) {
            (FlankContact::Hertz, Some(_)) => grid.len() / grid.teeth.len(),
            _ => grid.len(),
        };
        let n = model.dofs.n_free;
        let probed_modes = options.modes + 6;
        // The shapes stage's fields at its fullest, nodal fields each (`shape_fields` below).
        let (n_theta, n_t) = (options.angles, 2 * (options.rom_torques_nm.len() + options.sharing_shapes));
        let threads = rayon::current_num_threads();
        let (factor_nnz, factorization_scratch_bytes, sturm_factor_nnz, harmonic_matrix_nnz, krylov_entries) =
            match &analysis {
                Solver::Whole(a) => {
                    let k = a.factor_nnz();
                    (k, a.factorization_scratch_bytes(), k, 0, 3 * n * eigen::krylov_capacity(probed_modes, n))
                }
                // The harmonics' eigenproblems run one per thread, each with its Krylov space
                // and its real-form K_h and M_h; the whole modes' K and M products are formed
                // once all are done. The interior factor and the dense edge parts and Schur
                // factors are held throughout; the Sturm count adds an LDLᵀ of the interior.
                Solver::Harmonics(c) => {
                    let size = 2 * c.sector_dofs();
                    let krylov = threads * 3 * size * eigen::krylov_capacity(probed_modes, size);
                    (
                        c.factor_nnz() + c.dense_entries(),
                        c.factorization_scratch_bytes(),
                        c.factor_nnz(),
                        c.matrix_nnz() * (1 + 4 * threads),
                        krylov.max(4 * n * probed_modes),
                    )
                }
            };
        let sizes = GearSizes {
            free_dofs: n,
            all_dofs: model.dofs.free.len(),
            stiffness_nnz: model.stiffness.compute_nnz(),
            factor_nnz,
            factorization_scratch_bytes,
            sturm_factor_nnz,
            harmonic_matrix_nnz,
            elements: model.mesh.mesh.elements.len(),
            attachment_columns: grid.len(),
            solved_columns,
            krylov_entries,
            probed_modes,
            shape_fields: shape_fields(n_theta, n_t, probed_modes),
        };
        Ok(PreparedGear { model, analysis, grid, sizes })
    };
    let gear_fe = |i: usize, prepared: PreparedGear| -> Result<(GearFe, GearFields), String> {
        let PreparedGear { model, analysis, grid, sizes } = prepared;
        let solved_columns = sizes.solved_columns;
        let factor = match analysis {
            Solver::Harmonics(c) => Factored::Harmonics(c.factorize()?),
            Solver::Whole(a) => Factored::Whole(a.factorize(&model.stiffness)?),
        };
        // The mass over the free DOFs for the eigenmodes; the full one (the floating frame's
        // kinetic energy) is assembled again in the shapes stage rather than held through the
        // attachment stage, where the two gears' stages add up.
        let mass = assembly::mass(&model.mesh.mesh, &model.material, &model.dofs);
        let probe = options.modes + 6;
        let modes = match &factor {
            Factored::Harmonics(c) => {
                progress(format!("gear {}: eigenmodes by {} harmonics", i + 1, model.mesh.teeth / 2 + 1));
                c.lowest_modes(&model.stiffness, &mass, probe, 1e-10, 400)?
            }
            Factored::Whole(f) => {
                progress(format!("gear {}: eigenmodes", i + 1));
                eigen::lowest_modes_factored(&model.stiffness, &mass, f, probe, 1e-10, 400, |_, _| {})?
            }
        };
        if modes.sturm_count != modes.ritz_values_below_shift {
            return Err(format!("gear {}: the eigen solver missed a mode (Sturm count)", i + 1));
        }
        // End Φ at a gap of the spectrum: a cluster continues while the next eigenvalue is within
        // 1e-4 (relative) of the last kept one.
        let mut n_k = options.modes.max(1);
        while n_k < probe && modes.eigenvalues[n_k] <= modes.eigenvalues[n_k - 1] * (1.0 + 1e-4) {
            n_k += 1;
        }
        if n_k == probe {
            return Err(format!("gear {}: no spectral gap found after {} modes", i + 1, options.modes));
        }
        // The eigen stage's arrays (the Krylov space, the Sturm LDLᵀ) are freed before ψ, the
        // attachment stage's n_FE × n_c array, is allocated: the two never add up.
        drop(mass);
        let (reduced, reconstructor, n_sv) = match options.contact {
            FlankContact::Hertz => {
                progress(format!(
                    "gear {}: global attachment modes ({} flank nodes on {} teeth, {} solved)",
                    i + 1,
                    grid.len(),
                    grid.teeth.len(),
                    solved_columns
                ));
                let (reduced, reconstructor, report) =
                    pmor_hertz(&model, factor.solver(), grid, options.depth_m, options.p_en, |_| {})?;
                (reduced, reconstructor, report.n_sv)
            }
            FlankContact::Penalty { .. } => {
                progress(format!("gear {}: standard CMS attachment modes ({} flank nodes)", i + 1, grid.len()));
                let n = grid.len();
                let (reduced, reconstructor) = standard_cms(&model, factor.solver(), grid);
                (reduced, reconstructor, n)
            }
        };
        let phi: Vec<Vec<f64>> = (0..n_k)
            .map(|c| model.dofs.expand(&(0..model.dofs.n_free).map(|r| modes.vectors[(r, c)]).collect::<Vec<_>>()))
            .collect();
        // The end of this gear's own stages (the two gears run side by side: without it, the
        // last stage's cost could not be told from the other gear's).
        progress(format!("gear {}: reduced ({} DOFs)", i + 1, model.dofs.n_free));
        let ClampedGear { mesh, material, dofs, stiffness, .. } = model;
        Ok((
            GearFe { mesh, material, dofs, reduced, phi, eigenvalues: modes.eigenvalues[..n_k].to_vec(), n_sv },
            GearFields { stiffness, reconstructor },
        ))
    };
    let (prepared1, prepared2) = rayon::join(|| prepare(0, &pair.gear1), || prepare(1, &pair.gear2));
    let (prepared1, prepared2) = (prepared1?, prepared2?);
    let memory = BuildMemory { gears: [prepared1.sizes.memory(), prepared2.sizes.memory()] };
    let limit = options.memory_limit_bytes.or_else(super::build_memory::available_bytes);
    let schedule = match limit {
        Some(limit) => memory.schedule(limit)?,
        None => Schedule::SideBySide,
    };
    progress(format!(
        "estimated peak {:.1} GB ({}; {} GB available)",
        memory.peak(schedule) / 1e9,
        match schedule {
            Schedule::SideBySide => "gears side by side",
            Schedule::OneAfterTheOther => "gears one after the other: side by side would need more than is available",
        },
        limit.map_or("unknown".into(), |l| format!("{:.1}", l / 1e9))
    ));
    // The two gears' FE models, eigenmodes and attachment modes are independent: built side by
    // side, the sequential parts of one (assembly, the partial models' small factorizations)
    // overlap the other's parallel ones.
    let built = match schedule {
        Schedule::SideBySide => {
            let (fe1, fe2) = rayon::join(|| gear_fe(0, prepared1), || gear_fe(1, prepared2));
            [fe1?, fe2?]
        }
        Schedule::OneAfterTheOther => {
            let fe1 = gear_fe(0, prepared1)?;
            [fe1, gear_fe(1, prepared2)?]
        }
    };
    let (fe, mut kept): (Vec<GearFe>, Vec<Option<GearFields>>) = built.into_iter().map(|(g, f)| (g, Some(f))).unzip();

    // Static analyses over one mesh cycle (and one more sample, one pitch on, for the closure
    // check), for each torque.
    progress(format!("static contact: {} angles × {} torques", options.angles, options.rom_torques_nm.len()));
    let contact = match options.contact {
        FlankContact::Hertz => ContactModel::Hertz { law: options.law },
        FlankContact::Penalty { factor } => ContactModel::Penalty { factor },
    };
    let statics = StaticModel::new(pair, [&fe[0].reduced, &fe[1].reduced], contact)?;
    let pitch2 = 2.0 * std::f64::consts::PI / pair.gear2.teeth as f64;
    let n_theta = options.angles;
    let jobs: Vec<(usize, usize)> =
        (0..options.rom_torques_nm.len()).flat_map(|t| (0..=n_theta).map(move |s| (t, s))).collect();
    let cases: Vec<_> = jobs
        .par_iter()
        .map(|&(t, s)| statics.solve(pitch2 * s as f64 / n_theta as f64, options.rom_torques_nm[t]))
        .collect::<Result<Vec<_>, String>>()?;
    let case = |t: usize, s: usize| &cases[t * (n_theta + 1) + s];
    let lumped_mesh_law = if options.lumped_mesh_law {
        use super::static_mesh_law::{drive_law_from_statics, force_levels, FORCE_LEVELS, TABLE_ROWS};
        progress(format!("lumped mesh law: {TABLE_ROWS} roll positions × {FORCE_LEVELS} forces"));
        Some(drive_law_from_statics(pair, &statics, &force_levels(pair, FORCE_LEVELS), TABLE_ROWS, |_| {})?)
    } else {
        None
    };

    // The coast shapes: each gear's sample s loaded on its coast flanks is the drive statics of
    // the half-turned pose (`PairPlacement::half_turn_angles`), turned back onto the gear. Gear
    // i sits at its sample angle in that pose (gear 2: θ₂ = s·pitch₂/n_θ; gear 1: θ₁ =
    // s·pitch₁/n_θ less the static TE, as the drive samples sit at it plus the TE), so each gear
    // has its own analyses. The pose is wrapped into gear 2's reference pitch, where the
    // statics search, and its field turned on by the whole teeth it was wrapped by.
    progress(format!(
        "static contact, coast flanks: 2 × {} angles × {} torques",
        n_theta + 1,
        options.rom_torques_nm.len()
    ));
    let rb = [pair.gear1.base_radius_m, pair.gear2.base_radius_m];
    let pitch = [2.0 * std::f64::consts::PI / pair.gear1.teeth as f64, pitch2];
    let half_turned_theta2 = |i: usize, s: usize| -> f64 {
        let sample = pitch[i] * s as f64 / n_theta as f64;
        if i == 0 {
            rb[0] * place.half_turn_angles([sample, 0.0])[0] / rb[1]
        } else {
            place.half_turn_angles([0.0, sample])[1]
        }
    };
    // Gear i's sample s in the half-turned pose, wrapped into gear 2's reference pitch: (the
    // whole teeth it was wrapped by, θ₂ there).
    let half_turned_pose = |i: usize, s: usize| -> (i64, f64) {
        let theta2 = half_turned_theta2(i, s);
        let wraps = (theta2 / pitch2).floor();
        (wraps as i64, theta2 - wraps * pitch2)
    };
    let coast_jobs: Vec<(usize, usize, usize)> = (0..2)
        .flat_map(|i| (0..options.rom_torques_nm.len()).flat_map(move |t| (0..=n_theta).map(move |s| (i, t, s))))
        .collect();
    let coast_cases: Vec<(i64, super::statics::StaticCase)> = coast_jobs
        .par_iter()
        .map(|&(i, t, s)| {
            let (wraps, theta2) = half_turned_pose(i, s);
            Ok((wraps, statics.solve(theta2, options.rom_torques_nm[t])?))
        })
        .collect::<Result<Vec<_>, String>>()?;
    // A field of the half-turned pose, wrapped by `wraps` teeth, turned back onto gear i.
    // Gear 1's half-turned pose is one pitch behind the exact image (its tooth k is tooth 1 − k
    // here): one more tooth rotation.
    let turn_back = |i: usize, wraps: i64, field: &[f64], half_turn: &[usize]| -> Vec<f64> {
        let turned = fe[i].mesh.rotate_by_teeth(field, wraps + (i == 0) as i64);
        GearMesh::half_turn_field(half_turn, &turned)
    };
    // Gear i's raw shapes of sample s, as reduced coordinates and the whole teeth a coast
    // shape's field is turned back by (`None`: a drive shape, the field as it is): on the drive
    // flanks one per torque, then the load-sharing shapes (`rom::sharing`) at gear 2's sample
    // angle; then the same on the coast flanks, through the half turn of the coast statics.
    let raw_coordinates = |i: usize, s: usize| -> Vec<(Vec<f64>, Option<i64>)> {
        let n_torques = options.rom_torques_nm.len();
        let theta2 = pitch2 * s as f64 / n_theta as f64;
        let (wraps, coast_theta2) = half_turned_pose(i, s);
        let sharing = |theta2: f64, order: usize| sharing::sharing_load(&place, &fe[i].reduced, i, theta2, order);
        let orders = 1..=options.sharing_shapes;
        let drive = (0..n_torques).map(|t| (case(t, s).reduced[i].clone(), None));
        let drive_sharing = orders.clone().map(|m| (sharing(theta2, m), None));
        let coast = (0..n_torques).map(|t| {
            let (wraps, c) = &coast_cases[(i * n_torques + t) * (n_theta + 1) + s];
            (c.reduced[i].clone(), Some(*wraps))
        });
        let coast_sharing = orders.map(|m| (sharing(coast_theta2, m), Some(wraps)));
        drive.chain(drive_sharing).chain(coast).chain(coast_sharing).collect()
    };
    let ste_m: Vec<Vec<f64>> =
        (0..options.rom_torques_nm.len()).map(|t| (0..n_theta).map(|s| case(t, s).ste_m).collect()).collect();

    let mut gears = Vec::new();
    let mut report_modes = Vec::new();
    let mut invariance = [0.0; 2];
    let mut inertia = [(0.0, 0.0); 2];
    let mut closure = [0.0_f64; 2];
    let mut residualization = [0.0; 2];
    let mut gram_ratio = [1.0_f64; 2];
    for (i, g) in fe.iter().enumerate() {
        progress(format!("gear {}: shapes and invariants", i + 1));
        let gear = if i == 0 { &pair.gear1 } else { &pair.gear2 };
        let gm = &g.mesh;
        let GearFields { stiffness, reconstructor } = kept[i].take().expect("each gear's fields are used once");
        let mass_full = assembly::mass(&gm.mesh, &g.material, &DofMap::unclamped(gm.mesh.nodes.len()));
        let m_times_all = |fields: &[Vec<f64>]| sparse_times_fields(&mass_full, fields);
        let n_torques = options.rom_torques_nm.len();
        let per_flank = n_torques + options.sharing_shapes;
        let n_t = 2 * per_flank;
        // Raw shapes per sample (0..=n_θ) as full nodal fields: on the drive flanks one per
        // torque, then the sharing shapes; then the same on the coast flanks.
        let half_turn = gm.half_turn_about_x()?;
        // All samples' fields from one product with the reduction basis (it is read once, not
        // once per field), then the coast fields turned back onto the gear.
        let coordinates: Vec<(Vec<f64>, Option<i64>)> = (0..=n_theta).flat_map(|s| raw_coordinates(i, s)).collect();
        let q: Vec<&[f64]> = coordinates.iter().map(|(q, _)| q.as_slice()).collect();
        let displacements = reconstructor.displacements(&q);
        drop(reconstructor);
        let fields: Vec<Vec<f64>> = displacements
            .into_par_iter()
            .zip(coordinates.par_iter())
            .map(|(field, (_, wraps))| match wraps {
                None => field,
                Some(wraps) => turn_back(i, *wraps, &field, &half_turn),
            })
            .collect();
        let mut fields = fields.into_iter();
        let raw: Vec<Vec<Vec<f64>>> = (0..=n_theta).map(|_| fields.by_ref().take(n_t).collect()).collect();
        // Residual against Φ (Eq. 14), then each scaled to unit modal mass. The torque levels of
        // one sample are NOT orthogonalized against each other: their difference is a small,
        // ill-determined direction whose sign and orientation jump between samples, and an
        // interpolated pair of such columns can cancel (a singular mass matrix mid-interval —
        // seen as a spurious impulse before this was changed). Nearly parallel columns are only
        // ill-conditioned, and their coupled frequency is the physical Rayleigh quotient.
        let m_phi = m_times_all(&g.phi);
        // (field, M·field) of each field made residual and of unit modal mass.
        let clean = |fields: &[Vec<f64>]| -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
            let mut residual: Vec<Vec<f64>> = fields
                .par_iter()
                .map(|f| {
                    let mut v = f.clone();
                    for _pass in 0..2 {
                        for (p, mp) in g.phi.iter().zip(&m_phi) {
                            let a = dot(mp, &v);
                            v.iter_mut().zip(p).for_each(|(x, y)| *x -= a * y);
                        }
                    }
                    v
                })
                .collect();
            let mut m_residual = m_times_all(&residual);
            for (v, mv) in residual.iter_mut().zip(&mut m_residual) {
                let norm = dot(mv, v).sqrt();
                v.iter_mut().chain(mv.iter_mut()).for_each(|x| *x /= norm);
            }
            (residual, m_residual)
        };
        let (base, m_base): (Vec<Vec<Vec<f64>>>, Vec<Vec<Vec<f64>>>) = raw[..n_theta].iter().map(|f| clean(f)).unzip();
        // The shapes of one sample must span n_t directions. Several torque levels often do
        // not: the global contact shapes of PMOR-Hertz are nearly proportional to the load (the
        // nonlinear local part is the analytic Hertz law), so two levels are the same direction
        // to 1e-10 and the mass matrix is singular. Refuse that instead of integrating noise. (A
        // drive and a coast shape load opposite flanks; a sharing shape is never parallel to the
        // static one, `rom::sharing`.)
        for (s_idx, (sample, m_sample)) in base.iter().zip(&m_base).enumerate() {
            let gram = DMatrix::from_fn(n_t, n_t, |r, c| dot(&m_sample[r], &sample[c]));
            let eig = nalgebra::SymmetricEigen::new(gram).eigenvalues;
            let ratio = eig.min() / eig.max();
            gram_ratio[i] = gram_ratio[i].min(ratio);
            if ratio < 1e-6 {
                return Err(format!(
                    "gear {}: the shapes of angle sample {s_idx} (torque levels {:?} N·m, {} sharing shapes) are linearly dependent (Gram eigenvalue ratio {ratio:.1e} < 1e-6): torque levels add no direction where the contact pattern does not change, and the shapes per flank cannot outnumber the tooth pairs within the sharing window (two at some angles of a spur pair); use one torque level (--rom-torques-nm) and fewer sharing shapes (--sharing-shapes)",
                    i + 1,
                    options.rom_torques_nm,
                    options.sharing_shapes,
                ));
            }
        }
        // Closure check: the sample one pitch on against P·S₀, every column.
        drop(m_base);
        let (one_on, _) = clean(&raw[n_theta]);
        drop(raw);
        let differences: Vec<Vec<f64>> = (0..n_t)
            .map(|column| {
                let p_s0 = gm.rotate_by_teeth(&base[0][column], 1);
                one_on[column].iter().zip(&p_s0).map(|(a, b)| a - b).collect()
            })
            .collect();
        for (diff, m_diff) in differences.iter().zip(m_times_all(&differences)) {
            closure[i] = closure[i].max(dot(&m_diff, diff).sqrt());
        }
        // Stored samples s = −2 … n_θ + 2 with the periodic closure S_{s+n_θ} = P·S_s.
        let stored: Vec<Vec<Vec<f64>>> = (-2..=n_theta as i64 + 2)
            .map(|s| {
                let k = s.div_euclid(n_theta as i64);
                let r = s.rem_euclid(n_theta as i64) as usize;
                base[r].iter().map(|f| if k == 0 { f.clone() } else { gm.rotate_by_teeth(f, k) }).collect()
            })
            .collect();

        // Fields and their Gram products with the unclamped mass: [Gx | Φ | S_a] (the kinetic
        // energy's fields, `dynamics::pmor::equations`).
        let x: Vec<f64> = gm.mesh.nodes.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
        let n_k = g.phi.len();
        let n_a = stored.len();
        let gx = generator(&x);
        let fields: Vec<&Vec<f64>> = std::iter::once(&gx).chain(&g.phi).chain(stored.iter().flatten()).collect();
        let f = Mat::from_fn(gx.len(), fields.len(), |r, c| fields[c][r]);
        let gram = assembly::symmetric_gram(&mass_full, f.as_ref());
        drop(f);
        let sc = |a: usize, t: usize| 1 + n_k + a * n_t + t;
        let phic = |j: usize| 1 + j;
        // Stiffness products of the shapes (free DOFs; the bore does not move).
        let dofs = &g.dofs;
        // SᵀKS over the stored shapes (free DOFs: the bore does not move).
        let shapes: Vec<&Vec<f64>> = stored.iter().flatten().collect();
        let mut shape_free = Mat::<f64>::zeros(dofs.n_free, shapes.len());
        for (c, field) in shapes.iter().enumerate() {
            for (d, slot) in dofs.free.iter().enumerate() {
                if let Some(e) = slot {
                    shape_free[(*e, c)] = field[d];
                }
            }
        }
        let k_gram = assembly::symmetric_gram(&stiffness, shape_free.as_ref());
        drop((shape_free, stiffness));

        let sample: Vec<SampleInvariants> = (0..n_a)
            .map(|a| SampleInvariants {
                gx_s: DVector::from_fn(n_t, |t, _| gram[(0, sc(a, t))]),
                phi_s: DMatrix::from_fn(n_k, n_t, |j, t| gram[(phic(j), sc(a, t))]),
            })
            .collect();
        residualization[i] = sample.iter().map(|s| s.phi_s.amax()).fold(0.0, f64::max);
        let mut pairs = Vec::with_capacity(n_a * 7);
        for a in 0..n_a {
            for d in 0..7 {
                let b = a as i64 + d as i64 - 3;
                if b < 0 || b >= n_a as i64 {
                    pairs.push(None);
                    continue;
                }
                let b = b as usize;
                pairs.push(Some(PairInvariants {
                    s_s: DMatrix::from_fn(n_t, n_t, |r, c| gram[(sc(a, r), sc(b, c))]),
                    k_ss: DMatrix::from_fn(n_t, n_t, |r, c| {
                        let (ar, bc) = (a * n_t + r, b * n_t + c);
                        0.5 * (k_gram[(ar, bc)] + k_gram[(bc, ar)])
                    }),
                }));
            }
        }
        // The tooth rotation on Φ: R = ΦᵀM P⁻¹Φ and the part of P⁻¹Φ outside span Φ.
        let back: Vec<Vec<f64>> = g.phi.iter().map(|p| gm.rotate_by_teeth(p, -1)).collect();
        let pitch_map = DMatrix::from_fn(n_k, n_k, |r, c| dot(&m_phi[r], &back[c]));
        let outside: Vec<Vec<f64>> = (0..n_k)
            .map(|c| {
                let mut v = back[c].clone();
                for (r, p) in g.phi.iter().enumerate() {
                    v.iter_mut().zip(p).for_each(|(x, y)| *x -= pitch_map[(r, c)] * y);
                }
                v
            })
            .collect();
        invariance[i] = outside.iter().zip(m_times_all(&outside)).map(|(v, mv)| dot(&mv, v).sqrt()).fold(0.0, f64::max);
        // Flank rows for the online contact: the teeth that can mesh, with a margin of two pairs
        // on each side (an anchor may lag its angle by a step near a pitch boundary); three for
        // the coast flanks, whose reference pitch is the half turn of another interval of θ₂.
        let flank_rows = |flank: Flank, margin: i64| -> Result<FlankRows, String> {
            let grid = FlankGrid::contact_flank_in_reach(gm, i, flank, &place, margin)?;
            let rows = |field: &[f64], row: usize| field[3 * grid.nodes[row / 3].0 + row % 3];
            let phi = DMatrix::from_fn(3 * grid.len(), n_k, |r, c| rows(&g.phi[c], r));
            let shapes = stored.iter().map(|s| DMatrix::from_fn(3 * grid.len(), n_t, |r, c| rows(&s[c], r))).collect();
            Ok(FlankRows::new(grid, phi, shapes))
        };
        let flanks = [flank_rows(Flank::Drive, 2)?, flank_rows(Flank::Coast, 3)?];

        inertia[i] = (gram[(0, 0)], gear.inertia_kgm2);
        report_modes.push(g.eigenvalues.iter().map(|l| l.sqrt() / (2.0 * std::f64::consts::PI)).collect::<Vec<_>>());
        gears.push(PmorGear {
            teeth: gear.teeth,
            base_radius_m: gear.base_radius_m,
            samples: n_theta,
            eigenvalues: g.eigenvalues.clone(),
            shapes: n_t,
            pitch_map,
            invariance_residual: invariance[i],
            polar_inertia_kgm2: gram[(0, 0)],
            gx_phi: DVector::from_fn(n_k, |j, _| gram[(0, phic(j))]),
            phi_phi: DMatrix::from_fn(n_k, n_k, |r, c| gram[(phic(r), phic(c))]),
            sample,
            shape_damping_roots: (0..pairs.len() / 7)
                .map(|a| {
                    let p = pairs[a * 7 + 3].as_ref().expect("each stored sample pairs with itself");
                    crate::dynamics::pmor::equations::modal_damping_root(&p.s_s, &p.k_ss)
                })
                .collect(),
            pair: pairs,
            flanks,
        });
    }
    let gears: [PmorGear; 2] = gears.try_into().map_err(|_| "two gears")?;
    let penalty_layer_stiffness_n_per_m = match options.contact {
        FlankContact::Hertz => Vec::new(),
        FlankContact::Penalty { factor } => {
            let layers = &gears[0].flank(Flank::Drive).grid.layer_z_m;
            let stiffness = |l| crate::rom::statics::penalty_node_stiffness_n_per_m(pair, layers, l, factor);
            (0..layers.len()).map(stiffness).collect()
        }
    };
    let mut model = PmorModel {
        pair: pair.clone(),
        gears,
        interpolation: options.interpolation,
        modal_damping_ratio: options.modal_damping_ratio,
        shape_damping_ratio: options.shape_damping_ratio,
        mesh_stiffness_n_per_m: 0.0,
        mesh_damper_gain: 1.0,
        integrator: options.integrator,
        condensation: options.condensation,
        max_step_s: 0.0,
        stability_limit_s: 0.0,
        step_checked_torque_nm: 0.0,
        info: PmorBuildInfo {
            contact: options.contact,
            rom_torques_nm: options.rom_torques_nm.clone(),
            sharing_shapes: options.sharing_shapes,
            depth_m: options.depth_m,
            law: options.law,
            p_en: options.p_en,
            mesh: format!("{mesh:?}"),
            penalty_layer_stiffness_n_per_m,
        },
    };
    progress("the mean mesh stiffness (static equilibria over a pitch)".into());
    model.mesh_stiffness_n_per_m = mean_mesh_stiffness(&model, options)?;
    progress("calibrating the mesh damper on the linearized mesh mode".into());
    let (gain, gain_torque_nm) = mesh_damper_gain(&model, options)?;
    model.mesh_damper_gain = gain;
    progress(format!("mesh damper gain {gain:.3} (calibrated at T₁ = {gain_torque_nm:.4} N·m)"));
    progress("linearizing the pair for the integrator step".into());
    let step = integrator_step(&model, options)?;
    model.max_step_s = step.max_step_s;
    model.stability_limit_s = step.stability_limit_s;
    model.step_checked_torque_nm = step.torque_nm;
    let report = DynamicBuildReport {
        step,
        lumped_mesh_law,
        modes_hz: report_modes.try_into().map_err(|_| "two gears")?,
        invariance_residual: invariance,
        polar_inertia_kgm2: inertia,
        closure_residual: closure,
        residualization,
        shape_gram_ratio: gram_ratio,
        ste_m,
        n_sv: [fe[0].n_sv, fe[1].n_sv],
        memory,
        schedule,
    };
    Ok((model, report))
}
