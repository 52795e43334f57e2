//! The gear-pair specification: what an engineer writes in a TOML file.
//!
//! Units live in the key names (`module_mm`, `pressure_angle_deg`, …). The file is converted
//! once, here, into SI (`PairSpec::load` → [`crate::gear::GearPair`]); nothing downstream sees mm.

pub use super::spec_error::SpecError;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Hand of helix; irrelevant for spur gears (helix angle 0). The spec gives gear 1's hand; an
/// external pair meshes only with opposite hands, so gear 2 has the other one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HelixHand {
    Left,
    Right,
}

impl HelixHand {
    /// +1 for a right hand: like a right-hand screw, the tooth trace turns counter-clockwise
    /// about +z (the gear's axis in its own frame) as z grows; −1 for a left hand.
    pub fn sign(self) -> f64 {
        match self {
            HelixHand::Right => 1.0,
            HelixHand::Left => -1.0,
        }
    }

    pub fn opposite(self) -> Self {
        match self {
            HelixHand::Right => HelixHand::Left,
            HelixHand::Left => HelixHand::Right,
        }
    }
}

/// One gear of the pair (gear 1 = pinion/driver, gear 2 = wheel/driven).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GearSpec {
    pub teeth: i64,
    #[serde(default)]
    pub profile_shift: f64,
    pub bore_radius_mm: f64,
    /// Overrides the polar moment of inertia computed from geometry and density.
    #[serde(default)]
    pub inertia_kgm2: Option<f64>,
    /// Accept a gear whose root the rack cutter undercuts (refused by default).
    #[serde(default)]
    pub allow_undercut: bool,
    /// Radius of the rounded edge between flank and tip, the body that touches the mating
    /// flank in tip (corner) contact. Default 0.1 × m_n: a deburred edge (the paper gives none,
    /// and a sharp corner is no Hertz contact). Must lie in (0, half the tip land].
    #[serde(default)]
    pub tip_edge_radius_mm: Option<f64>,
    /// Flank modifications (ISO 21771-1): tip and root relief, crowning, helix slope, end relief.
    #[serde(default)]
    pub modification: Option<super::modification::ModificationSpec>,
}

/// Basic rack (ISO 53 style), shared by both gears.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RackSpec {
    pub module_mm: f64,
    pub pressure_angle_deg: f64,
    #[serde(default)]
    pub helix_angle_deg: f64,
    #[serde(default = "default_hand")]
    pub helix_hand: HelixHand,
    #[serde(default = "one")]
    pub addendum_coefficient: f64,
    #[serde(default = "default_dedendum")]
    pub dedendum_coefficient: f64,
    #[serde(default = "default_tip_radius")]
    pub cutter_tip_radius_coefficient: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    pub youngs_modulus_gpa: f64,
    pub poisson_ratio: f64,
    pub density_kg_m3: f64,
    /// Yield strength, the bound of the tooth-root stress guard: a static case whose nominal
    /// root stress (Lewis) exceeds it is refused. Default 1000 MPa, the order of a quenched and
    /// tempered gear steel (the paper gives none): set your material's value.
    #[serde(default = "default_yield_strength")]
    pub yield_strength_mpa: f64,
}

fn default_yield_strength() -> f64 {
    1000.0
}

/// How the two gears are mounted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MountingSpec {
    pub face_width_mm: f64,
    /// Operating center distance; default: the zero-backlash distance of the two profiles.
    #[serde(default)]
    pub center_distance_mm: Option<f64>,
    /// Normal backlash from tooth thinning, added to any backlash the center distance makes.
    #[serde(default)]
    pub backlash_mm: f64,
    /// Mesh damping as a fraction of critical damping of the mesh mode.
    #[serde(default = "default_damping")]
    pub mesh_damping_ratio: f64,
    /// Shaft misalignment in the plane of action across the face width (µm): the +z face end
    /// closes by it against the −z end.
    #[serde(default)]
    pub misalignment_um: f64,
}

/// How the lumped model treats the contact of the flanks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HertzContact {
    /// Nonlinear Hertz line contact, Weber's approach referred to the tooth half-thickness:
    /// the mesh stiffness grows with load.
    #[default]
    Weber,
    /// Yang & Lin's linearized contact stiffness πEL/(4(1−ν²)): load-independent.
    Linearized,
}

/// Options of the lumped model.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LumpedSpec {
    #[serde(default)]
    pub hertz_contact: HertzContact,
}

/// Tooth friction (issue 42): the sliding flanks' Coulomb friction on every loaded contact.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionSpec {
    /// The coefficient μ of the tangential force μ·F_n that opposes the flanks' sliding, the
    /// same at every contact (a constant law). Default 0: a frictionless mesh, as the paper's.
    #[serde(default)]
    pub coefficient: f64,
    /// The law μ follows: `constant` (default: `coefficient`) or `iso-tr-14179-2` (μ_mz from
    /// the load, the speed, the oil and the roughness: `dynamics::lubricated_friction`).
    #[serde(default)]
    pub law: FrictionLawSpec,
    /// ISO/TR 14179-2's inputs: the oil's dynamic viscosity at its running temperature (mPa·s),
    /// the flanks' mean roughness Ra = (Ra₁ + Ra₂)/2 (µm), and the lubricant factor X_L
    /// (default 1.0, mineral oil).
    #[serde(default)]
    pub oil_viscosity_mpa_s: Option<f64>,
    #[serde(default)]
    pub roughness_ra_um: Option<f64>,
    #[serde(default)]
    pub lubricant_factor: Option<f64>,
}

/// The friction law a spec chooses (`[friction] law`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FrictionLawSpec {
    #[default]
    Constant,
    #[serde(rename = "iso-tr-14179-2")]
    IsoTr14179_2,
}

/// The operating point the pair is designed for: what the offline build sizes its model on.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OperatingSpec {
    /// The design torque on gear 1 (N·m). Default: the pair's rated torque
    /// ([`crate::closed_forms::rating::rated_torque_nm`], from the tooth-root stress and the yield
    /// strength). The PMOR-Hertz build takes its static contact shapes at this torque, checks its
    /// step up to `STEP_LOAD_FACTOR` × it, and `fmu-build linearize` and the sweeps default to it.
    #[serde(default)]
    pub torque_nm: Option<f64>,
}

/// The whole pair spec as written in the TOML file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairSpec {
    pub name: String,
    pub rack: RackSpec,
    pub material: MaterialSpec,
    pub mounting: MountingSpec,
    pub gear1: GearSpec,
    pub gear2: GearSpec,
    #[serde(default)]
    pub lumped: LumpedSpec,
    #[serde(default)]
    pub operating: OperatingSpec,
    #[serde(default)]
    pub friction: FrictionSpec,
    /// Finite element mesh resolution (defaults: the coarse test mesh).
    #[serde(default)]
    pub mesh: super::mesh_spec::MeshSpec,
}

fn one() -> f64 {
    1.0
}
fn default_dedendum() -> f64 {
    1.25
}
fn default_tip_radius() -> f64 {
    0.38
}
fn default_hand() -> HelixHand {
    HelixHand::Right
}
fn default_damping() -> f64 {
    0.05
}

impl PairSpec {
    pub fn from_toml(text: &str) -> Result<Self, SpecError> {
        toml::from_str(text).map_err(|e| SpecError::Parse(e.to_string()))
    }

    pub fn load(path: &Path) -> Result<Self, SpecError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| SpecError::Io { path: path.display().to_string(), source })?;
        Self::from_toml(&text)
    }
}
