//! The lumped gear-pair model: two rigid gears on the line of action, coupled by a mesh whose
//! stiffness varies with the roll position, with backlash, contact loss and back-flank contact.
//!
//! Mesh deflection δ = TE = r_b1·θ₁ − r_b2·θ₂ (design §3), roll position ξ = r_b1·θ₁ + ξ₀.
//! The mesh is a load-dependent force law F(δ, ξ) (`mesh_law`) on the drive flank (δ > δ₀(ξ),
//! the no-load TE: zero unless the flanks are modified) and its mirror on the coast flank
//! (δ < −j − δ₀, j the backlash); in between the flanks do not touch.
//! The law derives from a potential V(δ, ξ) and the generalized forces are −∂V/∂θ, so the model
//! conserves energy exactly: besides the mesh force F = ∂V/∂δ it carries the torque r_b1·(−∂V/∂ξ)
//! that the roll-dependent stiffness exerts on the driver (−r_b1·½K′δ² for a linear law). A tooth
//! pair entering contact is a steep but continuous change of the law over one table interval; its
//! work is this torque. Damping c·δ̇ acts only while a flank is in contact; a flank never pulls.

use super::lubricated_friction::{LubricatedFlanks, PitchPointGeometry};
use super::mesh_friction::{
    friction_reach_per_kg, regularization_for_step_m_per_s, ContactFriction, ContactSpread, SlidingFriction,
    MIN_SLIDING_REGULARIZATION_M_PER_S,
};
use super::mesh_law::{MeshForce, MeshLaw};
use crate::gear::GearPair;
use serde::{Deserialize, Serialize};

/// Everything the lumped model needs at run time: plain data, written into the FMU resources.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LumpedMesh {
    pub teeth_1: u32,
    pub teeth_2: u32,
    pub base_radius_1_m: f64,
    pub base_radius_2_m: f64,
    pub inertia_1_kgm2: f64,
    pub inertia_2_kgm2: f64,
    pub base_pitch_m: f64,
    /// Backlash along the LOA: the gap between the coast flanks when the drive flanks touch.
    pub backlash_m: f64,
    pub mesh_damping_ratio: f64,
    /// Roll position at θ₁ = 0: a tooth pair then touches at the pitch point (the reference mesh
    /// position where both angles are zero).
    pub roll_offset_m: f64,
    /// Where the drive flank's law comes from.
    pub law_source: MeshLawSource,
    /// Load-dependent force laws of the drive and the coast flanks.
    pub drive: MeshLaw,
    pub coast: MeshLaw,
    /// Tooth pairs in contact at ξᵢ = i·p_b/N under each force level, laid out as the law's
    /// deflections (row-major, N rows of K+1): under load the contact extends beyond the rigid
    /// geometry's, so the double-contact zone widens with the force.
    pub drive_pairs: Vec<u32>,
    pub coast_pairs: Vec<u32>,
    /// The mesh force at which the reference stiffness (damping, natural frequency) is taken:
    /// 200 N/mm of face width, mid-range of Kurokawa's loads and within ISO 6336-1's ≥ 100 N/mm.
    pub reference_force_n: f64,
    /// Mean tangent stiffness of the drive flank at the reference force (N/m), computed once
    /// offline: damping and the predicted natural frequency use it, the step path must not
    /// recompute it (an O(N) mean).
    pub reference_stiffness_n_per_m: f64,
    /// Where the load is carried along the line of action, per row and force level of each
    /// flank's law: what tooth friction acts on (`mesh_friction`).
    pub drive_spread: ContactSpread,
    pub coast_spread: ContactSpread,
    /// The tooth friction coefficient of the spec (the FMU parameter's start value).
    pub friction_coefficient: f64,
    /// ISO/TR 14179-2's law of the spec, if it chose one, and the pitch point it reads.
    pub lubricated_flanks: Option<LubricatedFlanks>,
    pub pitch_point: PitchPointGeometry,
    /// T₁T₂ (m), cos β_b, and the operating transverse pressure angle (rad): the friction's arms
    /// and the shaft force's directions.
    pub loa_m: f64,
    pub cos_base_helix: f64,
    /// The path of contact A…E (m from T₁).
    pub path_start_m: f64,
    pub path_end_m: f64,
    pub operating_pressure_angle_rad: f64,
    /// The mesh force (N, along the line of action) at which one pair carrying it at the tip
    /// bends its root past the yield strength (`closed_forms::rating::yield_mesh_force_n`): beyond it the
    /// FMU logs a warning, once (the same rule as the PMOR-Hertz FMU's).
    pub yield_mesh_force_n: f64,
}

/// The origin of a lumped mesh law.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MeshLawSource {
    /// Potential-energy teeth and Weber's contact on the geometry alone
    /// (`closed_forms::mesh_stiffness`, `LumpedMesh::from_pair`): the
    /// no-FE estimate.
    Analytic,
    /// The loaded transmission error of the PMOR-Hertz FE statics (`rom::static_mesh_law`).
    FeStatics,
}

impl LumpedMesh {
    /// The lumped mesh around a drive-flank law (rows at ξᵢ = i·p_b/N) and the tooth pairs in
    /// contact per row and force level; the coast flank mirrors it.
    pub fn from_drive_law(
        pair: &GearPair,
        law_source: MeshLawSource,
        drive: MeshLaw,
        drive_pairs: Vec<u32>,
        drive_spread: ContactSpread,
    ) -> LumpedMesh {
        let levels = drive.force_levels_n.clone();
        let n = drive.rows();
        let roll_offset = pair.pitch_point_m() - pair.path_start_m;
        // Coast flank: the mirror image of the drive flank about the reference position (symmetric
        // teeth). The phase between drive and coast contact, set by tooth thickness, is neglected.
        // A modification mirrors with it: the spec gives each gear one for both its flanks (a
        // helix slope or a misalignment, odd in z, is mirrored in roll only).
        let offset_index = (roll_offset / pair.base_pitch_m * n as f64).round() as usize;
        let mirror = |i: usize| (2 * offset_index + 2 * n - i) % n;
        let k = levels.len();
        let mirrored = |table: &[f64]| -> Vec<f64> {
            (0..n).flat_map(|i| table[mirror(i) * k..(mirror(i) + 1) * k].to_vec()).collect()
        };
        let mut coast = MeshLaw::new(pair.base_pitch_m, levels, mirrored(&drive.deflection_m));
        if drive.has_friction_share() {
            // The mirror turns the speeds round, and friction with them: the coast law is read at
            // −λ (`LumpedModel::friction_share`), so its rows are the drive's, mirrored.
            coast = coast
                .with_friction_share(mirrored(&drive.friction_deflection_m), crate::gear::MAX_FRICTION_COEFFICIENT)
                .expect("the drive law's share, mirrored, passes the drive law's own check");
        }
        let coast_pairs = (0..n).flat_map(|i| drive_pairs[mirror(i) * k..(mirror(i) + 1) * k].to_vec()).collect();
        let coast_spread = drive_spread.with_rows_from(mirror);
        let reference_force = 200.0e3 * pair.face_width_m;
        let reference_stiffness = drive.mean_tangent_stiffness(reference_force);
        LumpedMesh {
            teeth_1: pair.gear1.teeth,
            teeth_2: pair.gear2.teeth,
            base_radius_1_m: pair.gear1.base_radius_m,
            base_radius_2_m: pair.gear2.base_radius_m,
            inertia_1_kgm2: pair.gear1.inertia_kgm2,
            inertia_2_kgm2: pair.gear2.inertia_kgm2,
            base_pitch_m: pair.base_pitch_m,
            backlash_m: pair.backlash_loa_m,
            mesh_damping_ratio: pair.mesh_damping_ratio,
            roll_offset_m: roll_offset,
            law_source,
            drive,
            coast,
            drive_pairs,
            coast_pairs,
            drive_spread,
            coast_spread,
            friction_coefficient: pair.friction_coefficient,
            lubricated_flanks: pair.lubricated_flanks,
            pitch_point: PitchPointGeometry::of_pair(pair),
            loa_m: pair.loa_length_m(),
            path_start_m: pair.path_start_m,
            path_end_m: pair.path_end_m,
            cos_base_helix: pair.base_helix_angle_rad.cos(),
            operating_pressure_angle_rad: pair.operating_pressure_angle_rad,
            reference_force_n: reference_force,
            reference_stiffness_n_per_m: reference_stiffness,
            yield_mesh_force_n: crate::closed_forms::rating::yield_mesh_force_n(pair),
        }
    }

    /// Tooth pairs in contact on the drive flank, row by row, under force level k.
    pub fn drive_pairs_under(&self, k: usize) -> Vec<u32> {
        let levels = self.drive.force_levels_n.len();
        self.drive_pairs.chunks(levels).map(|row| row[k]).collect()
    }

    /// Mean tangent stiffness of the drive flank at the reference force (N/m).
    pub fn reference_stiffness(&self) -> f64 {
        self.reference_stiffness_n_per_m
    }
}

/// Run-time parameters of a lumped model instance (FMU parameters may override the defaults).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LumpedParameters {
    pub inertia_1_kgm2: f64,
    pub inertia_2_kgm2: f64,
    pub mesh_damping_ratio: f64,
    /// Tooth friction coefficient μ (0: frictionless).
    #[serde(default)]
    pub friction_coefficient: f64,
    /// Friction's regularization v_ε (m/s, `mesh_friction`): set from the step at
    /// initialization (`sliding_regularization_m_per_s`).
    #[serde(default = "min_sliding_regularization")]
    pub sliding_regularization_m_per_s: f64,
    /// ISO/TR 14179-2's inputs (`lubricated_friction`); an oil viscosity of 0 leaves μ the
    /// constant `friction_coefficient`.
    #[serde(default)]
    pub lubrication: LubricatedFlanks,
    /// The sense the pair rolls in, in [−1, 1] (`LumpedModel::rolling_sense`): +1 forward, as
    /// the statics that tabulated friction's elastic share; −1 reversed; near 0 at rest, where
    /// the regularized friction vanishes. The share is λ = μ × this (`mesh_law`). Held over a
    /// step, as μ is; the FMU sets it at each step's start and books what its change does to
    /// the stored energy (`LumpedState::friction_elastic_work_j`).
    #[serde(default = "forward")]
    pub rolling_sense: f64,
}

fn forward() -> f64 {
    1.0
}

impl LumpedParameters {
    /// ISO/TR 14179-2's law, where the parameters switch it on (an oil viscosity above 0).
    pub fn lubricated_flanks(&self) -> Option<LubricatedFlanks> {
        (self.lubrication.oil_viscosity_mpa_s > 0.0).then_some(self.lubrication)
    }
}

fn min_sliding_regularization() -> f64 {
    MIN_SLIDING_REGULARIZATION_M_PER_S
}

/// Friction's regularization v_ε for an RK4 step h (m/s): `regularization_for_step_m_per_s` at
/// h·λ = 2, with F_n the yield force (the largest the model answers for, `yield_mesh_force_n`).
/// A pair held by friction creeps no faster than this v_ε.
pub fn sliding_regularization_m_per_s(mesh: &LumpedMesh, p: &LumpedParameters, step_s: f64) -> f64 {
    let reach =
        friction_reach_per_kg(mesh.loa_m, [mesh.path_start_m, mesh.path_end_m], [p.inertia_1_kgm2, p.inertia_2_kgm2]);
    let normal = mesh.yield_mesh_force_n / mesh.cos_base_helix;
    regularization_for_step_m_per_s(p.friction_coefficient, normal, reach, step_s, 2.0)
}

/// Equivalent mass of the mesh mode along the LOA: 1/m_e = r_b1²/J₁ + r_b2²/J₂.
pub fn equivalent_mesh_mass(mesh: &LumpedMesh, p: &LumpedParameters) -> f64 {
    1.0 / (mesh.base_radius_1_m.powi(2) / p.inertia_1_kgm2 + mesh.base_radius_2_m.powi(2) / p.inertia_2_kgm2)
}

/// Natural frequency (Hz) of small vibrations of the mesh mode about a mean mesh force F:
/// √(k̄_t/m_e)/2π with k̄_t the mean tangent stiffness at F.
pub fn mesh_natural_frequency_hz(mesh: &LumpedMesh, p: &LumpedParameters, force_n: f64) -> f64 {
    (mesh.drive.mean_tangent_stiffness(force_n) / equivalent_mesh_mass(mesh, p)).sqrt() / (2.0 * std::f64::consts::PI)
}

/// Mesh damping coefficient c = 2ζ√(k̄·m_e) (N·s/m), k̄ the reference stiffness.
pub fn mesh_damping_coefficient(mesh: &LumpedMesh, p: &LumpedParameters) -> f64 {
    2.0 * p.mesh_damping_ratio * (mesh.reference_stiffness() * equivalent_mesh_mass(mesh, p)).sqrt()
}

/// The mesh law's largest tangent stiffness on either flank (N/m), at friction shares within
/// ±`max_lambda` (0: frictionless). It scans every entry of both tables, so the FMU computes it
/// once per model file, not at each check of a step.
pub fn stiffest_tangent_stiffness(mesh: &LumpedMesh, max_lambda: f64) -> f64 {
    mesh.drive.max_tangent_stiffness(max_lambda).max(mesh.coast.max_tangent_stiffness(max_lambda))
}

/// RK4's stability limit (s) on the stiffest mesh mode: the equivalent mesh mass on the mesh law's
/// largest tangent stiffness (`stiffest_tangent_stiffness`), with the mesh damping.
pub fn rk4_stability_limit_s(mesh: &LumpedMesh, p: &LumpedParameters, stiffest_n_per_m: f64) -> f64 {
    let lambdas = crate::dynamics::rk4_stability::oscillator_eigenvalues(
        equivalent_mesh_mass(mesh, p),
        mesh_damping_coefficient(mesh, p),
        stiffest_n_per_m,
    );
    crate::dynamics::rk4_stability::largest_stable_step(&lambdas, 1.0)
}

/// The state of the two rigid gears, plus the work integrals that the energy balance needs.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct LumpedState {
    pub theta_1: f64,
    pub omega_1: f64,
    pub theta_2: f64,
    pub omega_2: f64,
    /// ∫(τ₁ω₁ + τ₂ω₂)dt: work of the shaft torques.
    pub input_work_j: f64,
    /// ∫(F − F_elastic)·δ̇ dt: work dissipated by mesh damping.
    pub dissipated_j: f64,
    /// ∫Σ f·v dt: work dissipated by tooth friction (never decreasing).
    #[serde(default)]
    pub friction_dissipated_j: f64,
    /// The work that changes of friction's elastic share λ did on the mesh (J): the stored
    /// energy's change at fixed state each time λ changed (a new μ, a new rolling sense), which
    /// the law's potential does not book. Zero while λ is held.
    #[serde(default)]
    pub friction_elastic_work_j: f64,
}

/// What the mesh does at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MeshState {
    /// δ = r_b1θ₁ − r_b2θ₂ (m).
    pub transmission_error_m: f64,
    /// Normal force along the LOA (N), negative on the coast flank.
    pub force_n: f64,
    /// Elastic part of the force (N).
    pub elastic_force_n: f64,
    /// −∂V/∂ξ: force of the varying stiffness on the roll coordinate (N).
    pub roll_force_n: f64,
    /// Stiffness of the flank in contact (0 if none).
    pub stiffness_n_per_m: f64,
    /// Elastic energy V (J).
    pub potential_j: f64,
}

/// The force the mesh puts on gear 2's shaft (N), contact and friction together, in the pair's
/// frame at the pitch point; gear 1's is its opposite. Tangential: along the pitch circles'
/// common tangent, positive in gear 2's mesh sense (driving it). Radial: along the centre line,
/// positive pushing the gears apart. Axial: F_bt·tan β_b, positive on the drive flanks (its sense
/// along the axis follows the helix hand; zero for spur gears).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ShaftForce {
    pub tangential_n: f64,
    pub radial_n: f64,
    pub axial_n: f64,
}

impl ShaftForce {
    /// From the transverse normal force along the line of action F_bt (negative on the coast
    /// flank) and the friction force sum Σf (signed as the sliding): the normal force acts along
    /// the line of action, at α_wt to the tangent; friction along the flanks' common tangent,
    /// perpendicular to it (`mesh_friction`; on the coast flank, the mirror image).
    pub fn of(transverse_force_n: f64, friction_n: f64, pressure_angle_rad: f64, tan_base_helix: f64) -> Self {
        let (sin, cos) = pressure_angle_rad.sin_cos();
        let flank = if transverse_force_n < 0.0 { -1.0 } else { 1.0 };
        ShaftForce {
            tangential_n: transverse_force_n * cos + friction_n * sin,
            radial_n: transverse_force_n.abs() * sin - flank * friction_n * cos,
            axial_n: transverse_force_n * tan_base_helix,
        }
    }
}

/// The entry of a per-row-and-level table (`LumpedMesh::drive_pairs`) at the row nearest ξ and
/// the force level nearest F.
fn nearest(law: &MeshLaw, table: &[u32], force_n: f64, xi: f64) -> u32 {
    let (n, levels) = (law.rows(), &law.force_levels_n);
    let i = (xi.rem_euclid(law.base_pitch_m) / law.base_pitch_m * n as f64).round() as usize % n;
    let above = levels.partition_point(|&f| f < force_n).min(levels.len() - 1);
    let k = if above > 0 && force_n - levels[above - 1] < levels[above] - force_n { above - 1 } else { above };
    table[i * levels.len() + k]
}

impl LumpedParameters {
    /// The defaults carried by the mesh data (inertias from geometry, damping from the spec).
    pub fn defaults(mesh: &LumpedMesh) -> Self {
        LumpedParameters {
            inertia_1_kgm2: mesh.inertia_1_kgm2,
            inertia_2_kgm2: mesh.inertia_2_kgm2,
            mesh_damping_ratio: mesh.mesh_damping_ratio,
            friction_coefficient: mesh.friction_coefficient,
            sliding_regularization_m_per_s: MIN_SLIDING_REGULARIZATION_M_PER_S,
            lubrication: mesh.lubricated_flanks.unwrap_or_default(),
            rolling_sense: forward(),
        }
    }
}

/// The lumped model at run time: a view of the mesh data with the instance's parameters and
/// the damping coefficient they imply. Building one costs nothing (the tables are borrowed).
#[derive(Debug, Clone, Copy)]
pub struct LumpedModel<'a> {
    pub mesh: &'a LumpedMesh,
    pub params: LumpedParameters,
    pub damping_n_s_per_m: f64,
}

impl<'a> LumpedModel<'a> {
    pub fn new(mesh: &'a LumpedMesh, params: LumpedParameters) -> Self {
        let damping = mesh_damping_coefficient(mesh, &params);
        LumpedModel { mesh, params, damping_n_s_per_m: damping }
    }

    pub fn with_defaults(mesh: &'a LumpedMesh) -> Self {
        Self::new(mesh, LumpedParameters::defaults(mesh))
    }

    /// Friction's elastic share λ = μ × the rolling sense (`mesh_law`), on the drive flank; the
    /// coast flank, the pair mirrored with its speeds reversed, takes −λ.
    pub fn friction_share(&self) -> f64 {
        self.params.friction_coefficient * self.params.rolling_sense
    }

    /// The sense the pair rolls in at a state, regularized as friction is: the sliding at the
    /// recess end of the path, v = ω₁ρ₁(E) − ω₂ρ₂(E), as v/√(v² + v_ε²). There it is largest and
    /// positive when the pair turns forward.
    pub fn rolling_sense(&self, s: &LumpedState) -> f64 {
        let m = self.mesh;
        let v = s.omega_1 * m.path_end_m - s.omega_2 * (m.loa_m - m.path_end_m);
        let eps = self.params.sliding_regularization_m_per_s;
        v / (v * v + eps * eps).sqrt()
    }

    /// The mesh force law at a state (see the module comment).
    pub fn mesh_state(&self, s: &LumpedState) -> MeshState {
        let m = self.mesh;
        let delta = m.base_radius_1_m * s.theta_1 - m.base_radius_2_m * s.theta_2;
        let delta_dot = m.base_radius_1_m * s.omega_1 - m.base_radius_2_m * s.omega_2;
        let xi = m.base_radius_1_m * s.theta_1 + m.roll_offset_m;
        let c = self.damping_n_s_per_m;
        let mut out = MeshState { transmission_error_m: delta, ..Default::default() };
        // Each flank's law is zero until its no-load transmission error (zero for unmodified
        // flanks, a relief's opening where they are modified), and so is its damper.
        let lambda = self.friction_share();
        let drive = m.drive.evaluate_with_friction(delta, xi, lambda);
        let coast = if drive.force_n > 0.0 {
            MeshForce::default()
        } else {
            m.coast.evaluate_with_friction(-(delta + m.backlash_m), xi, -lambda)
        };
        if drive.force_n > 0.0 {
            let law = drive;
            out.elastic_force_n = law.force_n;
            out.force_n = (law.force_n + c * delta_dot).max(0.0);
            out.roll_force_n = law.roll_force_n;
            out.stiffness_n_per_m = law.stiffness_n_per_m;
            out.potential_j = law.potential_j;
        } else if coast.force_n > 0.0 {
            // The coast law is written for a positive closure −(δ + j); its force pushes back.
            let law = coast;
            out.elastic_force_n = -law.force_n;
            out.force_n = (-law.force_n + c * delta_dot).min(0.0);
            out.roll_force_n = law.roll_force_n;
            out.stiffness_n_per_m = law.stiffness_n_per_m;
            out.potential_j = law.potential_j;
        }
        out
    }

    /// Tooth friction on the loaded contacts of `mesh` (the mesh state at `s`; zero without
    /// friction or contact). Apart from `mesh_state`, so that what reads only the mesh force or
    /// the energy does not pay for it.
    pub fn friction(&self, mesh: &MeshState, s: &LumpedState) -> ContactFriction {
        let m = self.mesh;
        let mu = self.params.friction_coefficient;
        if mu == 0.0 || mesh.force_n == 0.0 {
            return ContactFriction::default();
        }
        // The drive flank's contacts travel from T₁ towards T₂ as ξ grows, the coast flank's
        // (its mirror image) the other way.
        let (spread, table, travel) =
            if mesh.force_n > 0.0 { (&m.drive_spread, &m.drive, 1.0) } else { (&m.coast_spread, &m.coast, -1.0) };
        let transverse = mesh.force_n.abs();
        let law =
            SlidingFriction { coefficient: mu, regularization_m_per_s: self.params.sliding_regularization_m_per_s };
        spread.friction(
            law,
            table,
            m.loa_m,
            transverse,
            transverse / m.cos_base_helix,
            m.base_radius_1_m * s.theta_1 + m.roll_offset_m,
            travel,
            [s.omega_1, s.omega_2],
        )
    }

    /// The instantaneous mesh efficiency 1 − P_loss/P_in, P_in the power the gears put into the
    /// mesh, Σ max(0, −(mesh torque on gear i)·ωᵢ); 1 where none enters (at rest). In a
    /// transient (a load reversal, an impact) the mesh can pay friction from its stored energy,
    /// and the value then falls below 0: the mean over whole mesh cycles is the efficiency.
    pub fn mesh_efficiency(&self, mesh: &MeshState, friction: &ContactFriction, s: &LumpedState) -> f64 {
        let m = self.mesh;
        let into_1 = (m.base_radius_1_m * (mesh.force_n - mesh.roll_force_n) - friction.torque_nm[0]) * s.omega_1;
        let into_2 = -(m.base_radius_2_m * mesh.force_n + friction.torque_nm[1]) * s.omega_2;
        let input = into_1.max(0.0) + into_2.max(0.0);
        if input > 0.0 {
            1.0 - friction.power_w / input
        } else {
            1.0
        }
    }

    /// The force the mesh puts on gear 2's shaft at a state ([`ShaftForce`]; gear 1's is its opposite).
    pub fn shaft_force(&self, mesh: &MeshState, friction: &ContactFriction) -> ShaftForce {
        let m = self.mesh;
        let tan_bb = (1.0 - m.cos_base_helix * m.cos_base_helix).sqrt() / m.cos_base_helix;
        ShaftForce::of(mesh.force_n, friction.force_n, m.operating_pressure_angle_rad, tan_bb)
    }

    /// Tooth pairs in contact at a state (an output only: the step path does not read it), from
    /// the table at the nearest roll position and force level of the flank that touches.
    pub fn pairs_in_contact(&self, s: &LumpedState) -> u32 {
        let m = self.mesh;
        let mesh = self.mesh_state(s);
        let xi = m.base_radius_1_m * s.theta_1 + m.roll_offset_m;
        if mesh.elastic_force_n > 0.0 {
            nearest(&m.drive, &m.drive_pairs, mesh.elastic_force_n, xi)
        } else if mesh.elastic_force_n < 0.0 {
            nearest(&m.coast, &m.coast_pairs, -mesh.elastic_force_n, xi)
        } else {
            0
        }
    }

    /// Time derivative of the state under shaft torques τ₁, τ₂ (N·m).
    pub fn derivative(&self, s: &LumpedState, torques: [f64; 2]) -> LumpedState {
        let m = self.mesh;
        let mesh = self.mesh_state(s);
        let friction = self.friction(&mesh, s);
        let delta_dot = m.base_radius_1_m * s.omega_1 - m.base_radius_2_m * s.omega_2;
        let torque_1 = torques[0] - m.base_radius_1_m * mesh.force_n
            + m.base_radius_1_m * mesh.roll_force_n
            + friction.torque_nm[0];
        let torque_2 = torques[1] + m.base_radius_2_m * mesh.force_n + friction.torque_nm[1];
        LumpedState {
            theta_1: s.omega_1,
            omega_1: torque_1 / self.params.inertia_1_kgm2,
            theta_2: s.omega_2,
            omega_2: torque_2 / self.params.inertia_2_kgm2,
            input_work_j: torques[0] * s.omega_1 + torques[1] * s.omega_2,
            dissipated_j: (mesh.force_n - mesh.elastic_force_n) * delta_dot,
            friction_dissipated_j: friction.power_w,
            friction_elastic_work_j: 0.0,
        }
    }

    /// Kinetic energy of both gears (J).
    pub fn kinetic_energy(&self, s: &LumpedState) -> f64 {
        0.5 * self.params.inertia_1_kgm2 * s.omega_1.powi(2) + 0.5 * self.params.inertia_2_kgm2 * s.omega_2.powi(2)
    }

    /// One classical Runge–Kutta step of length h with the torques held.
    pub fn rk4_step(&self, s: &LumpedState, torques: [f64; 2], h: f64) -> LumpedState {
        let k1 = self.derivative(s, torques);
        let k2 = self.derivative(&axpy(s, 0.5 * h, &k1), torques);
        let k3 = self.derivative(&axpy(s, 0.5 * h, &k2), torques);
        let k4 = self.derivative(&axpy(s, h, &k3), torques);
        let sum = LumpedState {
            theta_1: k1.theta_1 + 2.0 * k2.theta_1 + 2.0 * k3.theta_1 + k4.theta_1,
            omega_1: k1.omega_1 + 2.0 * k2.omega_1 + 2.0 * k3.omega_1 + k4.omega_1,
            theta_2: k1.theta_2 + 2.0 * k2.theta_2 + 2.0 * k3.theta_2 + k4.theta_2,
            omega_2: k1.omega_2 + 2.0 * k2.omega_2 + 2.0 * k3.omega_2 + k4.omega_2,
            input_work_j: k1.input_work_j + 2.0 * k2.input_work_j + 2.0 * k3.input_work_j + k4.input_work_j,
            dissipated_j: k1.dissipated_j + 2.0 * k2.dissipated_j + 2.0 * k3.dissipated_j + k4.dissipated_j,
            friction_dissipated_j: k1.friction_dissipated_j
                + 2.0 * k2.friction_dissipated_j
                + 2.0 * k3.friction_dissipated_j
                + k4.friction_dissipated_j,
            friction_elastic_work_j: 0.0,
        };
        axpy(s, h / 6.0, &sum)
    }

    /// Advances the state over `duration` in equal RK4 sub-steps no longer than `max_step`.
    pub fn advance(&self, s: &mut LumpedState, torques: [f64; 2], duration: f64, max_step: f64) {
        let n = super::substep_count(duration, max_step);
        let h = duration / n as f64;
        for _ in 0..n {
            *s = self.rk4_step(s, torques, h);
        }
    }
}

fn axpy(s: &LumpedState, a: f64, d: &LumpedState) -> LumpedState {
    LumpedState {
        theta_1: s.theta_1 + a * d.theta_1,
        omega_1: s.omega_1 + a * d.omega_1,
        theta_2: s.theta_2 + a * d.theta_2,
        omega_2: s.omega_2 + a * d.omega_2,
        input_work_j: s.input_work_j + a * d.input_work_j,
        dissipated_j: s.dissipated_j + a * d.dissipated_j,
        friction_dissipated_j: s.friction_dissipated_j + a * d.friction_dissipated_j,
        friction_elastic_work_j: s.friction_elastic_work_j + a * d.friction_elastic_work_j,
    }
}
