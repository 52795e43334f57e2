//! The gear pair behind the FMI layer: maps the interface's variables (by name, from
//! `modelDescription/variables.toml`) to the physics of the model kind the FMU carries (the
//! lumped model or the PMOR-Hertz reduced pair), and steps it with sub-steps no longer than `max_step`
//! (RK4; the PMOR-Hertz model's own integrator). Everything that changes lives in [`GearPairState`], so an FMU state is a copy of it.

use super::shared_model::SharedByContent;
use crate::contact::mesh_kinematics::PairPlacement;
use crate::dynamics::lubricated_friction::PitchPointGeometry;
use crate::dynamics::lumped::{LumpedMesh, LumpedModel, LumpedParameters, LumpedState, ShaftForce};
use crate::dynamics::mesh_friction::SlidingFriction;
use crate::dynamics::pmor::model::PmorModel;
use crate::dynamics::pmor::quasi_static::{Condensation, GearSplit};
use crate::dynamics::pmor::{PmorDynamics, PmorOutputs, PmorState};
use crate::fmi2::{Model, Phase};
use crate::gear::sig;
use crate::interface;
use crate::model_file::{ModelFile, ModelKind};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Arc;

/// The interface variables, named as in variables.toml.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Var {
    Tau1,
    Tau2,
    Phi1,
    Phi2,
    W1,
    W2,
    Dte,
    DteAngle,
    MeshForce,
    MeshStiffness,
    ContactPairs,
    Phi1Start,
    Phi2Start,
    W1Start,
    W2Start,
    MaxStep,
    Inertia1,
    Inertia2,
    MeshDampingRatio,
    StartAtEquilibrium,
    FrictionCoefficient,
    ForceTangential,
    ForceRadial,
    ForceAxial,
    MeshPowerLoss,
    MeshEfficiency,
    MeshEnergyLoss,
    FrictionRegularization,
    OilViscosity,
    FlankRoughnessRa,
    LubricantFactor,
    FrictionCoefficientApplied,
}

impl Var {
    pub const ALL: [Var; 32] = [
        Var::Tau1,
        Var::Tau2,
        Var::Phi1,
        Var::Phi2,
        Var::W1,
        Var::W2,
        Var::Dte,
        Var::DteAngle,
        Var::MeshForce,
        Var::MeshStiffness,
        Var::ContactPairs,
        Var::Phi1Start,
        Var::Phi2Start,
        Var::W1Start,
        Var::W2Start,
        Var::MaxStep,
        Var::Inertia1,
        Var::Inertia2,
        Var::MeshDampingRatio,
        Var::StartAtEquilibrium,
        Var::FrictionCoefficient,
        Var::ForceTangential,
        Var::ForceRadial,
        Var::ForceAxial,
        Var::MeshPowerLoss,
        Var::MeshEfficiency,
        Var::MeshEnergyLoss,
        Var::FrictionRegularization,
        Var::OilViscosity,
        Var::FlankRoughnessRa,
        Var::LubricantFactor,
        Var::FrictionCoefficientApplied,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Var::Tau1 => "tau_1",
            Var::Tau2 => "tau_2",
            Var::Phi1 => "phi_1",
            Var::Phi2 => "phi_2",
            Var::W1 => "w_1",
            Var::W2 => "w_2",
            Var::Dte => "dte",
            Var::DteAngle => "dte_angle",
            Var::MeshForce => "mesh_force",
            Var::MeshStiffness => "mesh_stiffness",
            Var::ContactPairs => "contact_pairs",
            Var::Phi1Start => "phi_1_start",
            Var::Phi2Start => "phi_2_start",
            Var::W1Start => "w_1_start",
            Var::W2Start => "w_2_start",
            Var::MaxStep => "max_step",
            Var::Inertia1 => "inertia_1",
            Var::Inertia2 => "inertia_2",
            Var::MeshDampingRatio => "mesh_damping_ratio",
            Var::StartAtEquilibrium => "start_at_equilibrium",
            Var::FrictionCoefficient => "friction_coefficient",
            Var::ForceTangential => "force_tangential",
            Var::ForceRadial => "force_radial",
            Var::ForceAxial => "force_axial",
            Var::MeshPowerLoss => "mesh_power_loss",
            Var::MeshEfficiency => "mesh_efficiency",
            Var::MeshEnergyLoss => "mesh_energy_loss",
            Var::FrictionRegularization => "friction_regularization",
            Var::OilViscosity => "oil_viscosity",
            Var::FlankRoughnessRa => "flank_roughness_ra",
            Var::LubricantFactor => "lubricant_factor",
            Var::FrictionCoefficientApplied => "friction_coefficient_applied",
        }
    }

    fn is_parameter(self) -> bool {
        matches!(
            self,
            Var::Phi1Start
                | Var::Phi2Start
                | Var::W1Start
                | Var::W2Start
                | Var::MaxStep
                | Var::Inertia1
                | Var::Inertia2
                | Var::MeshDampingRatio
                | Var::StartAtEquilibrium
                | Var::FrictionCoefficient
                | Var::OilViscosity
                | Var::FlankRoughnessRa
                | Var::LubricantFactor
        )
    }
}

/// Everything of an instance that changes: inputs, parameters, the mechanical state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GearPairState {
    pub torques_nm: [f64; 2],
    pub start: LumpedState,
    pub max_step_s: f64,
    pub params: LumpedParameters,
    /// The lumped model's state; for the PMOR-Hertz model it carries the start values only.
    pub mech: LumpedState,
    /// The PMOR-Hertz state (after initialization).
    pub pmor: Option<PmorState>,
    /// The validity rules already reported ([`Validity`]): each is logged once per instance.
    #[serde(default)]
    pub warned: [bool; 2],
    /// Warnings of the last step, for the FMI layer to log (`Model::take_warnings`).
    #[serde(default)]
    pub pending_warnings: Vec<String>,
    /// The pair's stored energy at its start state (J), found once at ExitInitializationMode
    /// for the energy balance every doStep checks.
    #[serde(default)]
    pub start_energy_j: f64,
    /// Whether the master set max_step. If not, the default follows the instance's own
    /// stability limit at ExitInitializationMode (a raised mesh damping ratio shortens it).
    #[serde(default)]
    pub max_step_set: bool,
    /// Start from the static equilibrium under τ₁ (`start_at_equilibrium`).
    #[serde(default)]
    pub start_at_equilibrium: bool,
    /// PMOR-Hertz: the contact outputs and stored energy at `pmor`, evaluated once where the state
    /// was made (ExitInitializationMode, doStep) and read by every GetReal/GetInteger and the
    /// next doStep's settling (issue 39: a master that reads every output each step, as
    /// libcosim's observer does, cost three contact evaluations per step). A function of `pmor`
    /// alone, so an FMU state carries it as it carries `pmor`.
    #[serde(default)]
    pub pmor_outputs: Option<PmorPortOutputs>,
    /// The μ the dynamics apply: the `friction_coefficient` parameter, or under ISO/TR 14179-2's
    /// law its μ_mz, evaluated at initialization and at the start of every doStep.
    #[serde(default)]
    pub friction_coefficient_applied: f64,
    /// ISO/TR 14179-2's law was held below its speed floor, and that was logged (once).
    #[serde(default)]
    pub warned_friction_law: bool,
}

impl GearPairState {
    /// The parameters the dynamics run with: the instance's, with the μ applied now.
    pub fn dynamics_params(&self) -> LumpedParameters {
        let mut p = self.params;
        if p.lubricated_flanks().is_some() {
            p.friction_coefficient = self.friction_coefficient_applied;
        }
        p
    }
}

/// The shaft force and the friction losses of a state, as the FMU answers them.
struct MeshLosses {
    shaft: ShaftForce,
    power_loss_w: f64,
    efficiency: f64,
    energy_loss_j: f64,
}

/// The PMOR-Hertz pair's shaft force and losses from its contact outputs (NaN where none are
/// kept and none were asked for), the bores' speeds and the friction's work so far. The
/// normal force F_n acts along the line of action in the normal plane (F_bt = F_n·cos β_b; a tip
/// corner's force is taken along it too); the friction along the flanks' tangent. The power into
/// the mesh is what the gears put in, Σ max(0, −(contact torque on bore i)·θ̇ᵢ).
fn pmor_losses(
    pair: &crate::gear::GearPair,
    contact: Option<&PmorPortOutputs>,
    bore_speeds: [f64; 2],
    friction_j: f64,
) -> MeshLosses {
    let Some(o) = contact else {
        let nan = f64::NAN;
        return MeshLosses {
            shaft: ShaftForce { tangential_n: nan, radial_n: nan, axial_n: nan },
            power_loss_w: nan,
            efficiency: nan,
            energy_loss_j: friction_j,
        };
    };
    let cos_bb = pair.base_helix_angle_rad.cos();
    let input: f64 = (0..2).map(|i| (-o.mesh_torque_nm[i] * bore_speeds[i]).max(0.0)).sum();
    MeshLosses {
        shaft: ShaftForce::of(
            o.mesh_force_n * cos_bb,
            o.friction_force_n,
            pair.operating_pressure_angle_rad,
            pair.base_helix_angle_rad.tan(),
        ),
        power_loss_w: o.friction_power_w,
        efficiency: if input > 0.0 { 1.0 - o.friction_power_w / input } else { 1.0 },
        energy_loss_j: friction_j,
    }
}

/// The contact outputs of a PMOR-Hertz state, kept beside it (`GearPairState::pmor_outputs`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PmorPortOutputs {
    pub mesh_force_n: f64,
    pub mesh_stiffness_n_per_m: f64,
    pub contact_pairs: u32,
    /// Elastic and contact energy (J): what the next settling's energy booking starts from.
    pub stored_j: f64,
    /// Tooth friction's force sum (N, signed as the sliding) and power (W), and the contact's
    /// torque on each bore (N·m, damper and friction included): the shaft force and losses.
    #[serde(default)]
    pub friction_force_n: f64,
    #[serde(default)]
    pub friction_power_w: f64,
    #[serde(default)]
    pub mesh_torque_nm: [f64; 2],
}

impl PmorPortOutputs {
    fn of(out: &PmorOutputs) -> Self {
        PmorPortOutputs {
            mesh_force_n: out.contact.normal_force_n,
            mesh_stiffness_n_per_m: out.contact.tangent_stiffness_n_per_m,
            contact_pairs: out.contact.pairs_in_contact,
            stored_j: out.elastic_j + out.contact_j,
            friction_force_n: out.contact.friction_force_n,
            friction_power_w: out.contact.friction_power_w,
            mesh_torque_nm: [
                out.contact.force[0].first().copied().unwrap_or(0.0),
                out.contact.force[1].first().copied().unwrap_or(0.0),
            ],
        }
    }
}

/// What a run may not silently leave (issue 25): the same rules for both models, checked on the
/// mesh force at the end of every doStep and logged once each as fmi2Warning.
#[derive(Debug, Clone, Copy)]
pub struct Validity {
    /// [0] The mesh force at which one pair, loaded at its tip, bends its root past the yield
    /// strength (`closed_forms::rating::yield_mesh_force_n`): the linear-elastic teeth end there.
    pub yield_mesh_force_n: f64,
    /// [1] The mesh force of the largest load the model was built and its step checked for
    /// (PMOR-Hertz: `PmorModel::linearization_torque_nm` / r_b1; the lumped law has no such bound:
    /// infinite).
    pub range_mesh_force_n: f64,
    /// That load as a torque on gear 1 (N·m), for the message.
    pub range_torque_nm: f64,
}

impl Validity {
    /// The warnings the mesh force `force_n` raises that `warned` has not yet given; marks them.
    pub fn check(&self, force_n: f64, warned: &mut [bool; 2]) -> Vec<String> {
        let mut out = Vec::new();
        let f = force_n.abs();
        if f > self.yield_mesh_force_n && !warned[0] {
            warned[0] = true;
            out.push(format!(
                "mesh force {} N is beyond {} N, where one tooth pair loaded at its tip bends its root past the \
                 material's yield strength (nominal root stress, Lewis): the linear-elastic gear model does not \
                 hold there; results past this point are outside the model's validity",
                sig(f),
                sig(self.yield_mesh_force_n)
            ));
        }
        if f > self.range_mesh_force_n && !warned[1] {
            warned[1] = true;
            // The force as a torque on gear 1 (the range's own ratio is r_b1).
            let torque_now = f * self.range_torque_nm / self.range_mesh_force_n;
            let advice = if f > self.yield_mesh_force_n {
                "it is past the yield torque too (above): no model of this pair holds there; lower the load".to_string()
            } else {
                format!(
                    "rebuild with [operating] torque_nm = {} (or fmu-build build --rom-torques-nm {})",
                    sig(torque_now),
                    sig(torque_now)
                )
            };
            out.push(format!(
                "mesh force {} N (T₁ ≈ {} N·m) is beyond {} N (T₁ = {} N·m), the largest load this model was \
                 built and its step checked for: {advice}",
                sig(f),
                sig(torque_now),
                sig(self.range_mesh_force_n),
                sig(self.range_torque_nm),
            ));
        }
        out
    }
}

/// The physics an FMU carries.
pub enum Physics {
    Lumped(LumpedMesh),
    PmorHertz { model: Box<PmorModel>, place: PairPlacement },
}

/// The model of an FMU, shared by all its instances in one process: the data is immutable, so
/// a second instance of the same model file costs only its state (see [`super::shared_model`]).
pub struct GearPairFmu(Arc<LoadedPair>);

impl std::ops::Deref for GearPairFmu {
    type Target = LoadedPair;
    fn deref(&self) -> &LoadedPair {
        &self.0
    }
}

/// One model file, loaded and checked.
pub struct LoadedPair {
    /// The GUID the model file carries; instantiate compares it with the master's.
    guid: String,
    pub physics: Physics,
    /// Lumped: the mesh law's largest tangent stiffness (N/m), which sets RK4's stability limit
    /// (0 for PMOR-Hertz, whose limit comes from its linearization): frictionless, and at any
    /// friction share up to `gear::MAX_FRICTION_COEFFICIENT` (an instance with friction).
    stiffest_mesh_n_per_m: [f64; 2],
    /// (value reference, variable), from variables.toml.
    lookup: Vec<(u32, Var)>,
    /// PMOR-Hertz: the integrator's stability limit (s) for parameters other than the build's (inertias,
    /// mesh damping ratio, as bits), linearized once per set (`check_stability`).
    stability_limits: std::sync::Mutex<Vec<([u64; 3], f64)>>,
    pub validity: Validity,
    /// The pitch point ISO/TR 14179-2's friction law reads (`lubricated_friction`).
    pitch_point: PitchPointGeometry,
    /// PMOR-Hertz, condensed: each gear's split into slow and quasi-static coordinates at the FE
    /// inertias (an eigen-decomposition per gear), made once rather than per call.
    default_splits: Option<Arc<[GearSplit; 2]>>,
    /// The same for inertias above the FE values (a gear on a shaft, `inertia_i`), made once per
    /// set (the added inertias, as bits) and kept (issue 39: made per doStep and per GetReal of an
    /// angle or speed before).
    splits_by_inertia: std::sync::Mutex<Vec<([u64; 2], Arc<[GearSplit; 2]>)>>,
}

/// Stability limits kept per PMOR-Hertz model for parameter sets other than the build's.
const STABILITY_LIMITS_KEPT: usize = 16;

/// Sets of splits kept per PMOR-Hertz model for inertias above the FE values.
const SPLITS_KEPT: usize = 16;

/// The lumped model's (s).
pub const LUMPED_DEFAULT_MAX_STEP_S: f64 = 1e-5;

impl GearPairFmu {
    pub fn from_model_file(file: ModelFile) -> Result<Self, String> {
        Ok(GearPairFmu(Arc::new(LoadedPair::from_model_file(file)?)))
    }

    /// The pair of a model file's bytes, shared with the live instances of the same bytes
    /// (`shared_model`), for the master's GUID.
    pub fn from_bytes(bytes: Vec<u8>, guid: &str) -> Result<Self, String> {
        static LOADED: SharedByContent<LoadedPair> = SharedByContent::new();
        let pair = LOADED.get_or_load(bytes, |bytes| LoadedPair::from_model_file(ModelFile::from_bytes(bytes)?))?;
        check_guid(&pair.guid, guid)?;
        Ok(GearPairFmu(pair))
    }
}

/// The GUID the master passed against the model file's.
pub fn check_guid(file: &str, master: &str) -> Result<(), String> {
    if file == master {
        Ok(())
    } else {
        Err(format!("GUID {master} does not match the FMU's model data ({file})"))
    }
}

impl LoadedPair {
    fn from_model_file(file: ModelFile) -> Result<Self, String> {
        let physics = match file.model {
            ModelKind::Lumped(mesh) => {
                check_lumped_mesh(&mesh)?;
                Physics::Lumped(mesh)
            }
            ModelKind::PmorHertz(model) => {
                let place = PairPlacement::new(&model.pair);
                Physics::PmorHertz { model, place }
            }
            ModelKind::Element(e) => {
                return Err(format!("the model file holds a drivetrain {}, not a gear pair", e.kind()))
            }
        };
        let mut lookup = Vec::new();
        for v in interface::variables() {
            let var = Var::ALL
                .into_iter()
                .find(|x| x.name() == v.name)
                .ok_or_else(|| format!("interface variable {} has no physics in this binary", v.name))?;
            lookup.push((v.value_reference, var));
        }
        let stiffest_mesh_n_per_m = match &physics {
            Physics::Lumped(mesh) => [0.0, crate::gear::MAX_FRICTION_COEFFICIENT]
                .map(|max_lambda| crate::dynamics::lumped::stiffest_tangent_stiffness(mesh, max_lambda)),
            Physics::PmorHertz { .. } => [0.0; 2],
        };
        let validity = match &physics {
            Physics::Lumped(mesh) => Validity {
                yield_mesh_force_n: mesh.yield_mesh_force_n,
                range_mesh_force_n: f64::INFINITY,
                range_torque_nm: f64::INFINITY,
            },
            Physics::PmorHertz { model, .. } => {
                let range_torque_nm = model.linearization_torque_nm();
                // Forged model data may make these NaN: a NaN bound never warns, and nothing panics.
                Validity {
                    yield_mesh_force_n: crate::closed_forms::rating::yield_mesh_force_n(&model.pair),
                    range_mesh_force_n: range_torque_nm / model.gears[0].base_radius_m,
                    range_torque_nm,
                }
            }
        };
        let default_splits = match &physics {
            Physics::PmorHertz { model, .. } if model.condensation == Condensation::QuasiStatic => {
                let cutoff_hz = crate::dynamics::pmor::quasi_static::body_cutoff_hz(model);
                Some(Arc::new([
                    GearSplit::new(&model.gears[0], 0.0, cutoff_hz)?,
                    GearSplit::new(&model.gears[1], 0.0, cutoff_hz)?,
                ]))
            }
            _ => None,
        };
        let pitch_point = match &physics {
            Physics::Lumped(mesh) => mesh.pitch_point,
            Physics::PmorHertz { model, .. } => PitchPointGeometry::of_pair(&model.pair),
        };
        Ok(LoadedPair {
            guid: file.guid,
            pitch_point,
            physics,
            stiffest_mesh_n_per_m,
            lookup,
            stability_limits: Default::default(),
            validity,
            default_splits,
            splits_by_inertia: Default::default(),
        })
    }
}

impl GearPairFmu {
    fn var(&self, vr: u32) -> Result<Var, String> {
        self.lookup
            .iter()
            .find(|(r, _)| *r == vr)
            .map(|(_, v)| *v)
            .ok_or_else(|| format!("unknown value reference {vr}"))
    }

    /// The lumped mesh, if this FMU carries the lumped model.
    pub fn lumped_mesh(&self) -> Option<&LumpedMesh> {
        match &self.physics {
            Physics::Lumped(mesh) => Some(mesh),
            Physics::PmorHertz { .. } => None,
        }
    }

    /// Base radii and the default parameters of the model kind.
    fn base_radii(&self) -> [f64; 2] {
        match &self.physics {
            Physics::Lumped(m) => [m.base_radius_1_m, m.base_radius_2_m],
            Physics::PmorHertz { model, .. } => [model.gears[0].base_radius_m, model.gears[1].base_radius_m],
        }
    }

    /// The PMOR-Hertz dynamics with an instance's parameters: the FE inertia of each gear plus
    /// the rigid inertia the instance adds at its bore (inertia_i above the FE value), the
    /// build's modal damping, and the mesh damper from mesh_damping_ratio, defined as the lumped
    /// model's: c = 2ζ√(k̄·m_e), k̄ the pair's mean mesh stiffness, m_e = 1/(r_b1²/J₁ + r_b2²/J₂).
    pub fn pmor<'a>(&'a self, model: &'a PmorModel, place: &'a PairPlacement, s: &GearPairState) -> PmorDynamics<'a> {
        let p = &s.dynamics_params();
        let added = Self::added_inertia(model, s);
        let damping = model.damping(model.modal_damping_ratio, model.shape_damping_ratio);
        let mut dynamics = match self.splits(model, added) {
            Some(splits) => PmorDynamics::with_splits(model, place, damping, added, &splits),
            None => PmorDynamics::new(model, place, damping, added),
        };
        dynamics.mesh_damping_n_s_per_m =
            model.mesh_damper_n_s_per_m(p.mesh_damping_ratio, [p.inertia_1_kgm2, p.inertia_2_kgm2]);
        if p.friction_coefficient > 0.0 {
            dynamics.friction = Some(SlidingFriction {
                coefficient: p.friction_coefficient,
                regularization_m_per_s: p.sliding_regularization_m_per_s,
            });
        }
        dynamics
    }

    /// The condensed pair's splits with rigid inertia `added` at the bores (kg·m²): the build's
    /// at none, else from the kept sets or made and kept (at most `SPLITS_KEPT` sets). `None` where
    /// the model is not condensed or a split cannot be made (`PmorDynamics::new` then says why).
    fn splits(&self, model: &PmorModel, added: [f64; 2]) -> Option<Arc<[GearSplit; 2]>> {
        let default = self.default_splits.as_ref()?;
        if added == [0.0; 2] {
            return Some(default.clone());
        }
        let key = added.map(f64::to_bits);
        let mut kept = self.splits_by_inertia.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, splits)) = kept.iter().find(|(k, _)| *k == key) {
            return Some(splits.clone());
        }
        let cutoff_hz = crate::dynamics::pmor::quasi_static::body_cutoff_hz(model);
        let splits = Arc::new([
            GearSplit::new(&model.gears[0], added[0], cutoff_hz).ok()?,
            GearSplit::new(&model.gears[1], added[1], cutoff_hz).ok()?,
        ]);
        if kept.len() >= SPLITS_KEPT {
            kept.remove(0);
        }
        kept.push((key, splits.clone()));
        Some(splits)
    }

    /// The rigid inertia an instance adds at each bore (kg·m²): inertia_i above the FE value.
    fn added_inertia(model: &PmorModel, s: &GearPairState) -> [f64; 2] {
        let fe = [model.gears[0].polar_inertia_kgm2, model.gears[1].polar_inertia_kgm2];
        [s.params.inertia_1_kgm2 - fe[0], s.params.inertia_2_kgm2 - fe[1]]
    }

    fn pmor_outputs(&self, s: &GearPairState) -> Result<Option<(PmorOutputs, PmorState)>, String> {
        let Physics::PmorHertz { model, place } = &self.physics else { return Ok(None) };
        let state = match &s.pmor {
            Some(p) => p.clone(),
            None => model.initial_state([s.mech.theta_1, s.mech.theta_2], [s.mech.omega_1, s.mech.omega_2]),
        };
        Ok(Some((self.pmor(model, place, s).outputs(&state)?, state)))
    }
}

impl GearPairFmu {
    /// The stability contract: max_step must lie within the integrator's stability limit of the
    /// stiffest dynamics the model retains (lumped, RK4: the mesh mode at the law's largest
    /// tangent stiffness with these inertias and this damping; PMOR-Hertz, its model's
    /// integrator: the pair linearized at 4 × its ROM torque, computed offline for the model's
    /// own inertias — larger ones only lower it).
    fn check_stability(&self, s: &GearPairState) -> Result<(), String> {
        let (limit, integrator, what) = match &self.physics {
            Physics::Lumped(mesh) => (
                crate::dynamics::lumped::rk4_stability_limit_s(
                    mesh,
                    &s.params,
                    self.stiffest_mesh_n_per_m
                        [usize::from(s.params.friction_coefficient > 0.0 || s.params.lubricated_flanks().is_some())],
                ),
                "RK4",
                "the stiffest mesh mode",
            ),
            // The discrete gradient is unconditionally stable; its step rule is velocity
            // Verlet's limit (the accuracy its DTE was measured at), checked as Verlet's.
            Physics::PmorHertz { model, place } => (
                self.pmor_stability_limit(model, place, s)?,
                match model.integrator {
                    crate::dynamics::pmor::integrator::Integrator::DiscreteGradient => {
                        "the discrete gradient's step rule, velocity Verlet"
                    }
                    other => other.name(),
                },
                "the pair linearized at 4 × its ROM torque",
            ),
        };
        if s.max_step_s <= limit {
            Ok(())
        } else {
            Err(format!(
                "max_step = {:e} s exceeds {integrator}'s stability limit {limit:.4e} s on {what} (inertias {:e} / {:e} kg·m², mesh damping ratio {}): lower max_step",
                s.max_step_s, s.params.inertia_1_kgm2, s.params.inertia_2_kgm2, s.params.mesh_damping_ratio
            ))
        }
    }

    /// The stability limit of the PMOR-Hertz pair with an instance's parameters: the build's
    /// (stored in the model file) when they are the build's own, else the same linearization
    /// with the instance's inertias and shape damping (about 0.3 s, once per parameter set):
    /// a raised damping ratio puts real eigenvalues beyond the default step's reach.
    fn pmor_stability_limit(&self, model: &PmorModel, place: &PairPlacement, s: &GearPairState) -> Result<f64, String> {
        let p = &s.params;
        let fe = [model.gears[0].polar_inertia_kgm2, model.gears[1].polar_inertia_kgm2];
        if p.mesh_damping_ratio == model.pair.mesh_damping_ratio
            && p.inertia_1_kgm2 == fe[0]
            && p.inertia_2_kgm2 == fe[1]
        {
            return Ok(model.stability_limit_s);
        }
        let key = [p.inertia_1_kgm2.to_bits(), p.inertia_2_kgm2.to_bits(), p.mesh_damping_ratio.to_bits()];
        // The cache is shared by the FMU's instances (a poisoned lock still holds whole entries).
        let cache = || self.stability_limits.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some(&(_, limit)) = cache().iter().find(|(k, _)| *k == key) {
            return Ok(limit);
        }
        // Linearized without the lock, so other instances are not held up meanwhile.
        let limit = crate::dynamics::pmor::linear::default_step(&self.pmor(model, place, s))
            .map_err(|e| format!("the stability limit with these parameters could not be found: {e}"))?
            .stability_limit_s;
        let mut cache = cache();
        // Bounded: a master that tries ever new parameters must not grow the FMU's memory.
        if cache.len() == STABILITY_LIMITS_KEPT {
            cache.remove(0);
        }
        cache.push((key, limit));
        Ok(limit)
    }

    /// An inertia parameter: positive; for the PMOR-Hertz model not below the FE gear's own
    /// (the excess is rigid inertia at the bore: the hub and shaft share).
    fn inertia(&self, name: &str, gear: usize, value: f64) -> Result<f64, String> {
        let value = positive(name, value)?;
        if let Physics::PmorHertz { model, .. } = &self.physics {
            let fe = model.gears[gear].polar_inertia_kgm2;
            if value < fe * (1.0 - 1e-12) {
                return Err(format!(
                    "{name} = {value} kg·m² is below the FE gear's own inertia {fe} kg·m²: the PMOR-Hertz model takes the gear's inertia from its mesh and adds only the excess (hub, shaft) at the bore"
                ));
            }
        }
        Ok(value)
    }

    fn max_substeps(&self) -> f64 {
        match &self.physics {
            Physics::Lumped(_) => MAX_SUBSTEPS_LUMPED,
            Physics::PmorHertz { .. } => MAX_SUBSTEPS_PMOR,
        }
    }

    /// μ: in [0, 0.3] (`gear::MAX_FRICTION_COEFFICIENT`). The PMOR-Hertz model carries friction
    /// with its default integrator and condensation only (its friction work is tallied there),
    /// and refuses it otherwise rather than ignore it.
    fn friction_coefficient(&self, value: f64) -> Result<f64, String> {
        let max = crate::gear::MAX_FRICTION_COEFFICIENT;
        if !(0.0..=max).contains(&value) {
            return Err(format!("friction_coefficient must be in [0, {max}], got {value}"));
        }
        if value != 0.0 {
            self.carries_friction(&format!("friction_coefficient = {value}"))?;
        }
        Ok(value)
    }

    /// Refuses friction (`what` says which setting asks for it) where the PMOR-Hertz model does
    /// not carry it: only its default integrator and condensation tally friction's work.
    fn carries_friction(&self, what: &str) -> Result<(), String> {
        if let Physics::PmorHertz { model, .. } = &self.physics {
            use crate::dynamics::pmor::{integrator::Integrator, model::FlankContact};
            let condensed = self.default_splits.is_some();
            if model.info.contact != FlankContact::Hertz
                || model.integrator != Integrator::DiscreteGradient
                || !condensed
            {
                return Err(format!(
                    "{what}: tooth friction is carried by the PMOR-Hertz model with its default \
                     discrete-gradient integrator and quasi-static condensation only (this FMU: {}, {}); the penalty \
                     reference is the paper's frictionless model",
                    model.integrator.name(),
                    if condensed { "condensed" } else { "every coordinate dynamic" }
                ));
            }
        }
        Ok(())
    }

    /// ISO/TR 14179-2's law, where an oil viscosity above 0 switches it on: its inputs within
    /// their ranges (named by their FMU variables), friction_coefficient left at 0, a model that
    /// carries friction, and μ_mz within [0, 0.3] up to the yield force at the speed floor.
    /// Returns the largest μ the law gives: what the friction's regularization is sized on.
    fn friction_law(&self, p: &LumpedParameters) -> Result<f64, String> {
        let Some(flanks) = p.lubricated_flanks() else {
            return Ok(p.friction_coefficient);
        };
        if let Err((field, rule)) = flanks.check() {
            let name = LAW_INPUTS.iter().find(|(_, f)| *f == field).map_or(field, |(v, _)| v.name());
            return Err(format!("oil_viscosity > 0 switches on ISO/TR 14179-2's friction law: {name} {rule}"));
        }
        if p.friction_coefficient != 0.0 {
            return Err(format!(
                "friction_coefficient = {} and oil_viscosity = {} mPa·s: set one of them (a constant μ, or ISO/TR \
                 14179-2's law), and leave the other at 0",
                p.friction_coefficient, flanks.oil_viscosity_mpa_s
            ));
        }
        self.carries_friction(&format!("oil_viscosity = {} mPa·s", flanks.oil_viscosity_mpa_s))?;
        // The largest transverse force the models answer for: the yield force.
        let largest = flanks.largest_coefficient(&self.pitch_point, self.validity.yield_mesh_force_n);
        let max = crate::gear::MAX_FRICTION_COEFFICIENT;
        if !(largest <= max) {
            return Err(format!(
                "ISO/TR 14179-2's law gives μ = {} with these inputs under the yield force at its speed floor: above \
                 {max}, dry steel's; check oil_viscosity, flank_roughness_ra and lubricant_factor",
                sig(largest)
            ));
        }
        Ok(largest)
    }

    /// μ under ISO/TR 14179-2's law at a state: transverse mesh force `force_n` (N), gear 1 at
    /// ω₁; logs once where the speed is below the law's floor. Without the law, the parameter.
    fn applied_friction(&self, s: &mut GearPairState, force_n: f64, omega_1: f64) {
        let Some(flanks) = s.params.lubricated_flanks() else {
            s.friction_coefficient_applied = s.params.friction_coefficient;
            return;
        };
        let pitch = &self.pitch_point;
        let mu = flanks.mean_coefficient(pitch, force_n, omega_1);
        if mu.held_at_low_speed && !s.warned_friction_law && force_n != 0.0 {
            s.warned_friction_law = true;
            s.pending_warnings.push(format!(
                "the sum velocity at the pitch point is {} m/s, below {} m/s where ISO/TR 14179-2's friction law is \
                 held (it describes running gears; below, boundary lubrication): μ = {} there",
                sig(pitch.sum_velocity_m_per_s(omega_1)),
                crate::dynamics::lubricated_friction::MIN_SUM_VELOCITY_M_PER_S,
                sig(mu.coefficient)
            ));
        }
        s.friction_coefficient_applied = mu.coefficient;
    }

    fn mesh_damping_ratio(value: f64) -> Result<f64, String> {
        if (0.0..1.0).contains(&value) {
            Ok(value)
        } else {
            Err(format!("mesh_damping_ratio must be in [0, 1), got {value}"))
        }
    }
}

/// The most integrator sub-steps one fmi2DoStep may take, per model kind: at most about 10 s of work per call
/// on the development machine (2 cores shared, load ≈ 3), measured through the FMU (fmpy,
/// `fmi2DoStep` with h = 10⁴·max_step, Kurokawa spur pair, 185 N·m against its static load,
/// five calls each: `scripts/substep_cost.py`):
/// - lumped: 0.22 µs per sub-step (0.217–0.236) → 4·10⁷ sub-steps ≈ 9 s (h ≤ 400 s at the
///   default max_step 1e-5 s);
/// - PMOR-Hertz: velocity Verlet, the default, 34 µs per sub-step (34.1–34.6) when the bound was
///   set, 17.3–17.6 µs since issue 24 → 10⁵ sub-steps ≈ 1.8–3.4 s (h ≤ 0.17 s at the spur
///   model's max_step 1.7e-6 s); RK4 (`--integrator rk4`)
///   141 µs (139–142, with the load-sharing shapes; 104 µs before them, which set the bound)
///   → 14 s (h ≤ 0.28 s at 2.8e-6 s).
///
/// A longer communication step is refused before any work, naming h, max_step and the bound.
pub const MAX_SUBSTEPS_LUMPED: f64 = 4e7;
pub const MAX_SUBSTEPS_PMOR: f64 = 1e5;

/// The lumped model data as read from a model file: the shape and ranges `LumpedMesh::from_pair`
/// produces, so that a damaged (or hand-made) file is refused at instantiate with a message
/// instead of failing inside a call.
fn check_lumped_mesh(m: &LumpedMesh) -> Result<(), String> {
    let positive = [
        m.base_radius_1_m,
        m.base_radius_2_m,
        m.inertia_1_kgm2,
        m.inertia_2_kgm2,
        m.base_pitch_m,
        m.reference_force_n,
        m.reference_stiffness_n_per_m,
    ];
    if m.teeth_1 == 0 || m.teeth_2 == 0 || !positive.iter().all(|x| x.is_normal() && *x > 0.0) {
        return Err(
            "the lumped model data holds a zero tooth count or a non-positive radius, inertia, pitch or reference"
                .into(),
        );
    }
    if ![m.backlash_m, m.roll_offset_m].iter().all(|x| x.is_finite()) || m.backlash_m < 0.0 {
        return Err("the lumped model data holds a non-finite roll offset or a negative backlash".into());
    }
    if !(0.0..1.0).contains(&m.mesh_damping_ratio) {
        return Err(format!("the lumped model data's mesh damping ratio {} is not in [0, 1)", m.mesh_damping_ratio));
    }
    m.drive.check("drive")?;
    m.coast.check("coast")?;
    if m.drive_pairs.len() != m.drive.deflection_m.len() || m.coast_pairs.len() != m.coast.deflection_m.len() {
        return Err(format!(
            "the lumped model data has {}/{} contact-pair counts for {}/{} law entries",
            m.drive_pairs.len(),
            m.coast_pairs.len(),
            m.drive.deflection_m.len(),
            m.coast.deflection_m.len()
        ));
    }
    Ok(())
}

/// max_step: finite, > 0 and normal (a subnormal step is a hang, not a setting).
fn max_step(value: f64) -> Result<f64, String> {
    if value.is_finite() && value > 0.0 && value.is_normal() {
        Ok(value)
    } else {
        Err(format!("max_step must be a finite, positive, normal number of seconds, got {value:e}"))
    }
}

fn finite(name: &str, values: &[f64]) -> Result<(), String> {
    match values.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(format!("{name} holds a non-finite value {x}")),
        None => Ok(()),
    }
}

fn positive(name: &str, value: f64) -> Result<f64, String> {
    if value > 0.0 {
        Ok(value)
    } else {
        Err(format!("{name} must be > 0, got {value}"))
    }
}

impl Model for GearPairFmu {
    type State = GearPairState;

    fn load(resources: &Path, guid: &str) -> Result<Self, String> {
        GearPairFmu::from_bytes(ModelFile::read_bytes(resources)?, guid)
    }

    fn initial_state(&self) -> GearPairState {
        let start = LumpedState::default();
        let (max_step_s, params) = match &self.physics {
            Physics::Lumped(mesh) => (LUMPED_DEFAULT_MAX_STEP_S, LumpedParameters::defaults(mesh)),
            Physics::PmorHertz { model, .. } => (
                model.max_step_s,
                LumpedParameters {
                    inertia_1_kgm2: model.gears[0].polar_inertia_kgm2,
                    inertia_2_kgm2: model.gears[1].polar_inertia_kgm2,
                    // The spec's mounting.mesh_damping_ratio, as the lumped FMU's (the build's
                    // step limit was found with it).
                    mesh_damping_ratio: model.pair.mesh_damping_ratio,
                    friction_coefficient: model.pair.friction_coefficient,
                    sliding_regularization_m_per_s: crate::dynamics::mesh_friction::MIN_SLIDING_REGULARIZATION_M_PER_S,
                    lubrication: model.pair.lubricated_flanks.unwrap_or_default(),
                    // The PMOR-Hertz model's friction acts on its own flanks: unused there.
                    rolling_sense: 1.0,
                },
            ),
        };
        GearPairState {
            torques_nm: [0.0; 2],
            start,
            max_step_s,
            params,
            mech: start,
            pmor: None,
            warned: [false; 2],
            pending_warnings: Vec::new(),
            start_energy_j: 0.0,
            max_step_set: false,
            start_at_equilibrium: false,
            pmor_outputs: None,
            friction_coefficient_applied: params.friction_coefficient,
            warned_friction_law: false,
        }
    }

    fn set_real(&self, s: &mut GearPairState, vr: u32, value: f64, phase: Phase) -> Result<(), String> {
        let var = self.var(vr)?;
        if var.is_parameter() && !matches!(phase, Phase::Instantiated | Phase::InitializationMode) {
            return Err(format!("{} is a fixed parameter: it can be set only before initialization ends", var.name()));
        }
        match var {
            Var::Tau1 => s.torques_nm[0] = value,
            Var::Tau2 => s.torques_nm[1] = value,
            Var::Phi1Start => s.start.theta_1 = value,
            Var::Phi2Start => s.start.theta_2 = value,
            Var::W1Start => s.start.omega_1 = value,
            Var::W2Start => s.start.omega_2 = value,
            Var::MaxStep => {
                s.max_step_s = max_step(value)?;
                s.max_step_set = true;
            }
            Var::Inertia1 => s.params.inertia_1_kgm2 = self.inertia("inertia_1", 0, value)?,
            Var::Inertia2 => s.params.inertia_2_kgm2 = self.inertia("inertia_2", 1, value)?,
            Var::MeshDampingRatio => s.params.mesh_damping_ratio = Self::mesh_damping_ratio(value)?,
            Var::FrictionCoefficient => s.params.friction_coefficient = self.friction_coefficient(value)?,
            Var::OilViscosity => s.params.lubrication.oil_viscosity_mpa_s = lubrication_input(var, value)?,
            Var::FlankRoughnessRa => s.params.lubrication.roughness_ra_um = lubrication_input(var, value)?,
            Var::LubricantFactor => s.params.lubrication.lubricant_factor = lubrication_input(var, value)?,
            Var::StartAtEquilibrium => {
                return Err(format!("value reference {vr} (start_at_equilibrium) is a Boolean, not a Real"))
            }
            other => return Err(format!("{} is an output and cannot be set", other.name())),
        }
        // Until initialization ends the mechanical state follows the start values.
        if matches!(phase, Phase::Instantiated | Phase::InitializationMode) {
            s.mech = s.start;
            s.pmor = None;
            s.pmor_outputs = None;
        }
        Ok(())
    }

    fn get_real(&self, s: &GearPairState, vr: u32) -> Result<f64, String> {
        let var = self.var(vr)?;
        let rb = self.base_radii();
        // The mechanical outputs of the model kind: the ports' angles and speeds, the bores'
        // angles (the DTE is bore to bore), force, stiffness.
        let bores_and_ports = |bore: [f64; 2], port: [(f64, f64); 2]| (bore, port.map(|p| p.0), port.map(|p| p.1));
        let ((bore, theta, omega), force, stiffness, losses) = match &self.physics {
            Physics::Lumped(mesh) => {
                let model = LumpedModel::new(mesh, s.dynamics_params());
                let m = model.mesh_state(&s.mech);
                let theta = [s.mech.theta_1, s.mech.theta_2];
                let omega = [s.mech.omega_1, s.mech.omega_2];
                // Friction (the bulk of an evaluation on a helical pair) only for what reads it.
                let reads_friction =
                    matches!(var, Var::ForceTangential | Var::ForceRadial | Var::MeshPowerLoss | Var::MeshEfficiency);
                let friction = if reads_friction { model.friction(&m, &s.mech) } else { Default::default() };
                let losses = MeshLosses {
                    shaft: model.shaft_force(&m, &friction),
                    power_loss_w: friction.power_w,
                    efficiency: model.mesh_efficiency(&m, &friction, &s.mech),
                    energy_loss_j: s.mech.friction_dissipated_j,
                };
                ((theta, theta, omega), m.force_n, m.stiffness_n_per_m, losses)
            }
            Physics::PmorHertz { model, place } => {
                let needs_contact = matches!(
                    var,
                    Var::MeshForce
                        | Var::MeshStiffness
                        | Var::ForceTangential
                        | Var::ForceRadial
                        | Var::ForceAxial
                        | Var::MeshPowerLoss
                        | Var::MeshEfficiency
                );
                let ports = |p: &PmorState| -> Result<_, String> {
                    // Condensed, the ports are the splits' mean axes: no dynamics to set up.
                    if let Some(sp) = self.splits(model, Self::added_inertia(model, s)) {
                        let port = |i: usize| sp[i].mean_axis_port(&p.eta[i], &p.eta_dot[i], p.theta[i], p.omega[i]);
                        return Ok(bores_and_ports(p.theta, [port(0), port(1)]));
                    }
                    let dynamics = self.pmor(model, place, s);
                    Ok(bores_and_ports(p.theta, [dynamics.port(0, p)?, dynamics.port(1, p)?]))
                };
                // The contact outputs where kept (or asked for), the bores' speeds and the
                // friction's work so far.
                let (ports_and_speeds, contact, bore_speeds, friction_j) = match (&s.pmor, &s.pmor_outputs) {
                    (Some(p), Some(o)) => (ports(p)?, Some(*o), p.omega, p.friction_dissipated_j),
                    (Some(p), None) if !needs_contact => (ports(p)?, None, p.omega, p.friction_dissipated_j),
                    // Before initialization the pair sits at its start values with η = 0 (port
                    // = bore): angles and speeds need no contact evaluation, which a start angle
                    // pressing the flanks beyond Hertz's range would refuse (found by fuzzing: a
                    // GetReal of tau_1 failed on it).
                    (None, _) if !needs_contact => {
                        let theta = [s.mech.theta_1, s.mech.theta_2];
                        let omega = [s.mech.omega_1, s.mech.omega_2];
                        ((theta, theta, omega), None, omega, 0.0)
                    }
                    _ => {
                        let (out, p) = self.pmor_outputs(s)?.expect("PMOR-Hertz physics");
                        (ports(&p)?, Some(PmorPortOutputs::of(&out)), p.omega, p.friction_dissipated_j)
                    }
                };
                let losses = pmor_losses(&model.pair, contact.as_ref(), bore_speeds, friction_j);
                let (force, stiffness) =
                    contact.map_or((f64::NAN, f64::NAN), |o| (o.mesh_force_n, o.mesh_stiffness_n_per_m));
                (ports_and_speeds, force, stiffness, losses)
            }
        };
        let te = rb[0] * bore[0] - rb[1] * bore[1];
        Ok(match var {
            Var::Tau1 => s.torques_nm[0],
            Var::Tau2 => s.torques_nm[1],
            Var::Phi1 => theta[0],
            Var::Phi2 => theta[1],
            Var::W1 => omega[0],
            Var::W2 => omega[1],
            Var::Dte => te,
            Var::DteAngle => te / rb[1],
            Var::MeshForce => force,
            Var::MeshStiffness => stiffness,
            Var::FrictionCoefficient => s.params.friction_coefficient,
            Var::ForceTangential => losses.shaft.tangential_n,
            Var::ForceRadial => losses.shaft.radial_n,
            Var::ForceAxial => losses.shaft.axial_n,
            Var::MeshPowerLoss => losses.power_loss_w,
            Var::MeshEfficiency => losses.efficiency,
            Var::MeshEnergyLoss => losses.energy_loss_j,
            Var::FrictionRegularization => s.params.sliding_regularization_m_per_s,
            Var::FrictionCoefficientApplied => s.dynamics_params().friction_coefficient,
            Var::OilViscosity => s.params.lubrication.oil_viscosity_mpa_s,
            Var::FlankRoughnessRa => s.params.lubrication.roughness_ra_um,
            Var::LubricantFactor => s.params.lubrication.lubricant_factor,
            Var::Phi1Start => s.start.theta_1,
            Var::Phi2Start => s.start.theta_2,
            Var::W1Start => s.start.omega_1,
            Var::W2Start => s.start.omega_2,
            Var::MaxStep => s.max_step_s,
            Var::Inertia1 => s.params.inertia_1_kgm2,
            Var::Inertia2 => s.params.inertia_2_kgm2,
            Var::MeshDampingRatio => s.params.mesh_damping_ratio,
            Var::ContactPairs => return Err(format!("value reference {vr} (contact_pairs) is an Integer, not a Real")),
            Var::StartAtEquilibrium => {
                return Err(format!("value reference {vr} (start_at_equilibrium) is a Boolean, not a Real"))
            }
        })
    }

    fn get_integer(&self, s: &GearPairState, vr: u32) -> Result<i32, String> {
        match self.var(vr)? {
            Var::ContactPairs => match &self.physics {
                Physics::Lumped(mesh) => {
                    Ok(LumpedModel::new(mesh, s.dynamics_params()).pairs_in_contact(&s.mech) as i32)
                }
                Physics::PmorHertz { .. } => match (&s.pmor, &s.pmor_outputs) {
                    (Some(_), Some(o)) => Ok(o.contact_pairs as i32),
                    _ => Ok(self.pmor_outputs(s)?.expect("PMOR-Hertz physics").0.contact.pairs_in_contact as i32),
                },
            },
            other => Err(format!("value reference {vr} ({}) is not an Integer", other.name())),
        }
    }

    fn get_boolean(&self, s: &GearPairState, vr: u32) -> Result<bool, String> {
        match self.var(vr)? {
            Var::StartAtEquilibrium => Ok(s.start_at_equilibrium),
            other => Err(format!("value reference {vr} ({}) is not a Boolean", other.name())),
        }
    }

    fn set_boolean(&self, s: &mut GearPairState, vr: u32, value: bool, phase: Phase) -> Result<(), String> {
        match self.var(vr)? {
            Var::StartAtEquilibrium if matches!(phase, Phase::Instantiated | Phase::InitializationMode) => {
                s.start_at_equilibrium = value;
                Ok(())
            }
            Var::StartAtEquilibrium => {
                Err("start_at_equilibrium is a fixed parameter: it can be set only before initialization ends".into())
            }
            other => Err(format!("value reference {vr} ({}) is not a Boolean", other.name())),
        }
    }

    fn exit_initialization(&self, s: &mut GearPairState) -> Result<(), String> {
        if let (Physics::PmorHertz { model, place }, false) = (&self.physics, s.max_step_set) {
            // The default step is the build's share of its limit; with the instance's own
            // parameters (a raised mesh damper) the same share of the instance's limit, if shorter.
            let limit = self.pmor_stability_limit(model, place, s)?;
            let own = (crate::dynamics::pmor::linear::STEP_SAFETY * limit * 1e7).floor() / 1e7;
            if !(own > 0.0) {
                return Err(format!(
                    "with these parameters (inertias {:e} / {:e} kg·m², mesh damping ratio {}) the integrator's stability limit is {limit:e} s: below 0.2 µs, no step is practical; lower mesh_damping_ratio",
                    s.params.inertia_1_kgm2, s.params.inertia_2_kgm2, s.params.mesh_damping_ratio
                ));
            }
            s.max_step_s = s.max_step_s.min(own);
        }
        self.check_stability(s)?;
        s.mech = s.start;
        // The largest μ the instance applies (ISO/TR 14179-2's law varies it): what friction's
        // regularization is sized on.
        let largest_mu = self.friction_law(&s.params)?;
        s.friction_coefficient_applied = s.params.friction_coefficient;
        if let Physics::PmorHertz { model, .. } = &self.physics {
            // Friction's regularization: the narrowest band the discrete gradient's fixed point on
            // friction contracts in at this step, under the yield force.
            let p = &s.params;
            s.params.sliding_regularization_m_per_s = crate::dynamics::mesh_friction::regularization_for_pair_m_per_s(
                &model.pair,
                largest_mu,
                [p.inertia_1_kgm2, p.inertia_2_kgm2],
                s.max_step_s,
                1.0,
            );
        }
        if let Physics::Lumped(mesh) = &self.physics {
            // Friction's regularization: the narrowest band RK4 stays stable in at this step.
            let sized = LumpedParameters { friction_coefficient: largest_mu, ..s.params };
            s.params.sliding_regularization_m_per_s =
                crate::dynamics::lumped::sliding_regularization_m_per_s(mesh, &sized, s.max_step_s);
            // At rest friction is nil, and so is its elastic share: the equilibrium does not
            // depend on μ.
            if s.start_at_equilibrium {
                s.params.rolling_sense = 0.0;
                let model = LumpedModel::new(mesh, s.dynamics_params());
                s.mech = lumped_equilibrium(&model, s.start, s.torques_nm[0])?;
            }
            let model = LumpedModel::new(mesh, s.dynamics_params());
            let force = model.mesh_state(&s.mech).force_n;
            self.applied_friction(s, force, s.mech.omega_1);
            s.params.rolling_sense = model.rolling_sense(&s.mech);
            let model = LumpedModel::new(mesh, s.dynamics_params());
            s.start_energy_j = model.kinetic_energy(&s.mech) + model.mesh_state(&s.mech).potential_j;
        }
        if let Physics::PmorHertz { model, place } = &self.physics {
            let dynamics = self.pmor(model, place, s);
            let start = if s.start_at_equilibrium {
                pmor_equilibrium(&dynamics, s)?
            } else {
                dynamics.start_state(
                    [s.start.theta_1, s.start.theta_2],
                    [s.start.omega_1, s.start.omega_2],
                    s.torques_nm,
                )?
            };
            // The start must be a state the model can evaluate (e.g. no coast-flank contact).
            let mut out = dynamics.outputs(&start)?;
            if s.params.lubricated_flanks().is_some() {
                // The law's μ at the start state, and the start's outputs with it.
                let transverse = out.contact.normal_force_n * model.pair.base_helix_angle_rad.cos();
                self.applied_friction(s, transverse, start.omega[0]);
                out = self.pmor(model, place, s).outputs(&start)?;
            }
            s.start_energy_j = out.total_energy_j();
            s.pmor = Some(start);
            s.pmor_outputs = Some(PmorPortOutputs::of(&out));
        }
        // Finite start values can still hold an energy beyond f64 (a speed of 1e300 rad/s): refused
        // here, so no state with a non-finite energy reference is ever stored.
        finite("the start energy (from the start values)", &[s.start_energy_j])?;
        Ok(())
    }

    fn check_step(&self, s: &GearPairState, h: f64) -> Result<(), String> {
        // The bound is about 10 s of work.
        crate::dynamics::check_substep_bound(h, max_step(s.max_step_s)?, self.max_substeps())
    }

    fn check_state(&self, s: &GearPairState, initialized: bool) -> Result<(), String> {
        // The parameters, with the rules of set_real.
        max_step(s.max_step_s)?;
        self.inertia("inertia_1", 0, s.params.inertia_1_kgm2)?;
        self.inertia("inertia_2", 1, s.params.inertia_2_kgm2)?;
        Self::mesh_damping_ratio(s.params.mesh_damping_ratio)?;
        self.friction_coefficient(s.params.friction_coefficient)?;
        // ISO/TR 14179-2's inputs are complete once initialization ends (set in any order before).
        if initialized {
            let largest_mu = self.friction_law(&s.params)?;
            if !(0.0..=largest_mu).contains(&s.friction_coefficient_applied) {
                return Err(format!(
                    "the applied friction coefficient {} is outside [0, {}], the law's range",
                    s.friction_coefficient_applied, largest_mu
                ));
            }
        }
        if !(s.params.rolling_sense.abs() <= 1.0) {
            return Err(format!("the rolling sense {} is outside [−1, 1]", s.params.rolling_sense));
        }
        let eps = s.params.sliding_regularization_m_per_s;
        if !(eps.is_finite() && eps >= crate::dynamics::mesh_friction::MIN_SLIDING_REGULARIZATION_M_PER_S) {
            return Err(format!("the friction's regularization speed {eps} m/s is not a finite speed ≥ 1 mm/s"));
        }
        // After initialization, the stability contract of exit_initialization holds too.
        if initialized {
            self.check_stability(s)?;
        }
        // Inputs, start values and the mechanical state: finite (set_reals refuses the rest).
        finite("tau_1/tau_2", &s.torques_nm)?;
        let l = |m: &LumpedState| {
            [
                m.theta_1,
                m.omega_1,
                m.theta_2,
                m.omega_2,
                m.input_work_j,
                m.dissipated_j,
                m.friction_dissipated_j,
                m.friction_elastic_work_j,
            ]
        };
        finite("the start values", &l(&s.start))?;
        finite("the lumped state", &l(&s.mech))?;
        finite("the start energy", &[s.start_energy_j])?;
        match (&self.physics, &s.pmor) {
            (Physics::Lumped(_), Some(_)) => Err("a PMOR-Hertz state cannot be restored into the lumped model".into()),
            (Physics::Lumped(_), None) | (Physics::PmorHertz { .. }, None) => Ok(()),
            (Physics::PmorHertz { model, .. }, Some(p)) => {
                for i in 0..2 {
                    let n = model.gears[i].elastic_size();
                    if p.eta[i].len() != n || p.eta_dot[i].len() != n {
                        return Err(format!(
                            "gear {}'s elastic state has {}/{} coordinates; this model has {n}",
                            i + 1,
                            p.eta[i].len(),
                            p.eta_dot[i].len()
                        ));
                    }
                    finite("the PMOR-Hertz elastic state", &p.eta[i])?;
                    finite("the PMOR-Hertz elastic state", &p.eta_dot[i])?;
                }
                finite("the PMOR-Hertz rigid state", &[p.theta, p.omega].concat())?;
                finite("the PMOR-Hertz state's torques", &p.torques_nm)?;
                if let Some(o) = &s.pmor_outputs {
                    finite(
                        "the PMOR-Hertz contact outputs",
                        &[
                            o.mesh_force_n,
                            o.mesh_stiffness_n_per_m,
                            o.stored_j,
                            o.friction_force_n,
                            o.friction_power_w,
                            o.mesh_torque_nm[0],
                            o.mesh_torque_nm[1],
                        ],
                    )?;
                }
                finite(
                    "the PMOR-Hertz energy terms",
                    &[p.input_work_j, p.dissipated_j, p.friction_dissipated_j, s.start_energy_j],
                )
            }
        }
    }

    fn do_step(&self, s: &mut GearPairState, h: f64) -> Result<(), String> {
        // The FMI layer checks before calling; checked again so no caller can start unbounded work.
        self.check_step(s, h)?;
        let mesh = match &self.physics {
            Physics::Lumped(mesh) => mesh,
            Physics::PmorHertz { model, place } => {
                let mut state = s.pmor.clone().ok_or("the PMOR-Hertz state is not initialized")?;
                if let (Some(_), Some(o)) = (s.params.lubricated_flanks(), s.pmor_outputs) {
                    // ISO/TR 14179-2's μ at the step's start, held over the step.
                    let transverse = o.mesh_force_n * model.pair.base_helix_angle_rad.cos();
                    self.applied_friction(s, transverse, state.omega[0]);
                }
                let dynamics = self.pmor(model, place, s);
                let stored_j = s.pmor_outputs.map(|o| o.stored_j);
                let end = match dynamics.advance_knowing(&mut state, s.torques_nm, h, s.max_step_s, stored_j)? {
                    Some(end) => end,
                    None => dynamics.outputs(&state)?,
                };
                // The work integrals start at zero (`PmorModel::initial_state`).
                energy_balance([s.start_energy_j, end.total_energy_j()], [state.input_work_j, state.dissipated_j])?;
                s.pmor = Some(state);
                s.pmor_outputs = Some(PmorPortOutputs::of(&end));
                // The rules' forces are along the transverse line of action (the lumped model's);
                // the sections' force is normal to the flanks: F_bt = F_n·cos β_b.
                let transverse = end.contact.normal_force_n * model.pair.base_helix_angle_rad.cos();
                let warnings = self.validity.check(transverse, &mut s.warned);
                s.pending_warnings.extend(warnings);
                return Ok(());
            }
        };
        // ISO/TR 14179-2's μ and the rolling sense at the step's start, held over the step; what
        // their change does to friction's elastic share, and so to the stored energy, is booked.
        let held = LumpedModel::new(mesh, s.dynamics_params());
        if s.params.lubricated_flanks().is_some() {
            let force = held.mesh_state(&s.mech).force_n;
            self.applied_friction(s, force, s.mech.omega_1);
        }
        s.params.rolling_sense = held.rolling_sense(&s.mech);
        let model = LumpedModel::new(mesh, s.dynamics_params());
        // Only a law that reads λ stores energy that depends on it (the FE-fed law with the share).
        if model.friction_share() != held.friction_share() && mesh.drive.has_friction_share() {
            s.mech.friction_elastic_work_j +=
                model.mesh_state(&s.mech).potential_j - held.mesh_state(&s.mech).potential_j;
        }
        let mut next = s.mech;
        model.advance(&mut next, s.torques_nm, h, s.max_step_s);
        let m = &next;
        if ![m.theta_1, m.omega_1, m.theta_2, m.omega_2].iter().all(|x| x.is_finite()) {
            return Err(format!(
                "the state became non-finite: the integrator is unstable at max_step = {} s",
                s.max_step_s
            ));
        }
        let stored = |x: &LumpedState| model.kinetic_energy(x) + model.mesh_state(x).potential_j;
        // The work integrals start at zero at ExitInitializationMode, where E₀ was stored.
        energy_balance(
            [s.start_energy_j, stored(&next)],
            [next.input_work_j + next.friction_elastic_work_j, next.dissipated_j + next.friction_dissipated_j],
        )?;
        s.mech = next;
        let warnings = self.validity.check(model.mesh_state(&next).force_n, &mut s.warned);
        s.pending_warnings.extend(warnings);
        Ok(())
    }

    fn take_warnings(&self, s: &mut GearPairState) -> Vec<String> {
        std::mem::take(&mut s.pending_warnings)
    }
}

/// ISO/TR 14179-2's inputs: each FMU parameter and its field in `gear::lubrication`.
const LAW_INPUTS: [(Var, &str); 3] = [
    (Var::OilViscosity, "oil_viscosity_mpa_s"),
    (Var::FlankRoughnessRa, "roughness_ra_um"),
    (Var::LubricantFactor, "lubricant_factor"),
];

/// An input of ISO/TR 14179-2's law as an FMU parameter: within its range
/// (`gear::lubrication::FIELD_RANGES`), or 0 (oil_viscosity: the law off; the others: not set).
fn lubrication_input(var: Var, value: f64) -> Result<f64, String> {
    let field = LAW_INPUTS.iter().find(|(v, _)| *v == var).map_or("", |(_, f)| f);
    if value == 0.0 {
        return Ok(0.0);
    }
    crate::gear::lubrication::field_rule(field, value)
        .map(|()| value)
        .map_err(|rule| format!("{} {rule} (or 0: oil_viscosity = 0 is the constant friction_coefficient)", var.name()))
}

/// How much energy a step may create, E + D − W − E₀ > 0, as a share of the energy in play
/// (E₀, |W|, D and the present E, summed), before it is called divergent. The bound is one-sided,
/// as the physics is: the stored energy may not exceed the start's plus the work put in minus
/// what was dissipated. An unstable RK4 step creates energy geometrically, so the step where
/// divergence starts is an error instead of an OK with garbage. The other sign is the
/// integrator's own loss: RK4 at the lumped default step loses up to ~10 % of the energy in play
/// across coast-flank impacts (the soak in `tests/fmi_c_api.rs`), which is an accuracy matter,
/// not a divergence.
pub const ENERGY_BALANCE_SLACK: f64 = 0.1;

/// `Err` naming the terms when stored energy [E₀, E] exceeds the start's plus the integrals
/// [W (input work), D (dissipated)] since the start by more than `ENERGY_BALANCE_SLACK`.
fn energy_balance(stored_j: [f64; 2], integrals_j: [f64; 2]) -> Result<(), String> {
    let [start, now] = stored_j;
    let [work, dissipated] = integrals_j;
    let residual = now + dissipated - work - start;
    let scale = start.abs() + now.abs() + work.abs() + dissipated.abs();
    if residual.is_finite() && residual <= ENERGY_BALANCE_SLACK * scale + 1e-12 {
        Ok(())
    } else {
        Err(format!(
            "the energy balance broke: stored {now:.6e} J exceeds {start:.6e} J at the start + {work:.6e} J of input work − {dissipated:.6e} J dissipated (residual {residual:.3e} J, over {ENERGY_BALANCE_SLACK} of the energy in play): the integration diverges; lower max_step"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::Validity;

    /// The validity rules speak once each, and the range rule's advice follows the load: a
    /// rebuild at the load run (its torque, F·r_b1) below the yield torque, none above it.
    /// Figures: a pair with r_b1 = 0.05 m, range 1000 N·m (20 kN), yield 2000 N·m (40 kN).
    #[test]
    fn each_rule_is_logged_once_with_the_advice_the_load_allows() {
        let v = Validity { yield_mesh_force_n: 40e3, range_mesh_force_n: 20e3, range_torque_nm: 1000.0 };
        let mut warned = [false; 2];
        assert!(v.check(19e3, &mut warned).is_empty());
        let past_range = v.check(-26e3, &mut warned); // a coast-flank force counts by its size
        assert_eq!(past_range.len(), 1, "{past_range:?}");
        assert!(past_range[0].contains("[operating] torque_nm = 1300"), "{}", past_range[0]);
        assert!(v.check(30e3, &mut warned).is_empty(), "said twice");
        let past_yield = v.check(50e3, &mut warned);
        assert_eq!(past_yield.len(), 1, "{past_yield:?}");
        assert!(past_yield[0].contains("yield strength") && past_yield[0].contains("40000 N"), "{}", past_yield[0]);
        // Past both at once, on a fresh instance: the range rule advises no rebuild.
        let mut fresh = [false; 2];
        let both = v.check(50e3, &mut fresh);
        assert_eq!(both.len(), 2);
        assert!(both[1].contains("lower the load") && !both[1].contains("rebuild"), "{}", both[1]);
    }
}

/// The reduced pair at rest in its static equilibrium under τ₁ with gear 2 held at its start
/// angle (`linear::static_equilibrium`: the mesh, the bodies and the shapes deflected, gear 2's
/// reaction torque found), then given the start speeds (`start_at_equilibrium`). Its
/// quasi-static coordinates are in equilibrium with τ₁ and that reaction; the first doStep
/// moves them to the master's τ₂ and books the work.
fn pmor_equilibrium(dynamics: &PmorDynamics, s: &GearPairState) -> Result<PmorState, String> {
    let model = dynamics.model;
    let torque_1 = s.torques_nm[0];
    // As `linear::stability_limit_under_load`: a tenth of the STE of 10 N/(mm·µm), from the
    // light side, inside the contact law's range.
    let light = torque_1 / model.pair.gear1.base_radius_m / (1e11 * model.pair.face_width_m);
    // A reversed torque rests on the coast flanks, across the backlash.
    let guess = if torque_1 < 0.0 { -model.pair.backlash_loa_m + light } else { light };
    let (mut state, reaction) =
        crate::dynamics::pmor::linear::static_equilibrium(dynamics, s.start.theta_2, torque_1, guess)
            .map_err(|e| format!("start_at_equilibrium: {e}"))?;
    state.omega = [s.start.omega_1, s.start.omega_2];
    state.torques_nm = [torque_1, reaction];
    Ok(state)
}

/// The lumped pair at rest in its static equilibrium under τ₁ with gear 2 held at its start
/// angle: θ₁ such that τ₁ = r_b1·(F − F_roll) (the mesh law's force and its roll force), by
/// Newton on the law's tangent stiffness from the tabulated static deflection; then given the
/// start speeds. τ₁ = 0 leaves the flanks just touching.
fn lumped_equilibrium(model: &LumpedModel, start: LumpedState, torque_1: f64) -> Result<LumpedState, String> {
    let m = model.mesh;
    let (r1, r2) = (m.base_radius_1_m, m.base_radius_2_m);
    let force = torque_1 / r1;
    let mut s = LumpedState { omega_1: 0.0, omega_2: 0.0, ..start };
    let roll = |s: &LumpedState| r1 * s.theta_1 + m.roll_offset_m;
    let set_delta = |s: &mut LumpedState, delta: f64| s.theta_1 = (r2 * s.theta_2 + delta) / r1;
    // The tabulated deflection at the start's roll position: a start within the law's accuracy.
    let delta = if force > 0.0 {
        m.drive.static_deflection(force, roll(&s))
    } else if force < 0.0 {
        -(m.backlash_m + m.coast.static_deflection(-force, roll(&s)))
    } else {
        0.0
    };
    set_delta(&mut s, delta);
    if force != 0.0 {
        let mut converged = false;
        for _ in 0..50 {
            let mesh = model.mesh_state(&s);
            let residual = torque_1 - r1 * (mesh.elastic_force_n - mesh.roll_force_n);
            if residual.abs() <= 1e-10 * torque_1.abs() {
                converged = true;
                break;
            }
            if !(mesh.stiffness_n_per_m > 0.0) {
                return Err(format!(
                    "start_at_equilibrium: the mesh carries no load at δ = {:e} m",
                    mesh.transmission_error_m
                ));
            }
            // d(residual)/dδ = −r_b1·k (the roll force's slope left out: Newton's matrix only).
            set_delta(&mut s, mesh.transmission_error_m + residual / (r1 * mesh.stiffness_n_per_m));
        }
        if !converged {
            return Err(format!("start_at_equilibrium: no static equilibrium found under τ₁ = {torque_1} N·m"));
        }
    }
    s.omega_1 = start.omega_1;
    s.omega_2 = start.omega_2;
    Ok(s)
}
