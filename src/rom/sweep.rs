//! Sweeps of static contact analyses over gear 2's angle × torque (paper Sect. 6.1): the pair is
//! reduced once (both gears, the contact-side flanks of every tooth that can mesh in one pitch),
//! then the cases run in parallel.

use super::flank::FlankGrid;
use super::reductor::{pmor_hertz, standard_cms, standard_cms_with_flank_tangents, CompressionReport, ReducedGear};
use super::statics::{ContactModel, StaticCase, StaticModel};
use crate::contact::mesh_kinematics::{Flank, PairPlacement};
use crate::fe::clamped_gear::ClampedGear;
use crate::fe::gear_mesh::MeshSpec;
use crate::fe::hex8::Formulation;
use crate::gear::GearPair;
use rayon::prelude::*;

/// Which reduction and contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Global attachment modes at depth h, SVD to share p_en, Hertz sections.
    PmorHertz { depth_m: f64, p_en: f64, law: crate::contact::hertz::ApproachLaw },
    /// Attachment modes of every loadable node, node-to-surface penalty (factor × ISO c_γα).
    Penalty { factor: f64 },
}

/// Both gears reduced for one method.
pub struct ReducedPair {
    pub pair: GearPair,
    pub gears: [ReducedGear; 2],
    pub method: Method,
    /// What the SVD kept per gear (PMOR-Hertz only).
    pub compression: Option<[CompressionReport; 2]>,
}

impl ReducedPair {
    /// Meshes, clamps and reduces both gears; `progress(gear, nodes done)` reports the partial
    /// models of the global attachment modes.
    pub fn build(
        pair: &GearPair,
        mesh: &MeshSpec,
        method: Method,
        progress: impl Fn(usize, usize) + Sync,
    ) -> Result<Self, String> {
        // Generic only at the door: the body below is compiled once, here, not again in
        // every crate (each test, fmu-build) that passes a progress closure of its own.
        Self::build_dyn(pair, mesh, method, false, &progress)
    }

    /// As [`ReducedPair::build`], for statics with tooth friction
    /// (`sweep_with_friction`): the penalty baseline's gears take a second attachment mode per
    /// node, along its flank tangent (`reductor::standard_cms_with_flank_tangents`, twice the
    /// solves), so that friction's load lies in their basis. PMOR-Hertz's basis is the same
    /// either way: friction's load is projected on it, as in the dynamics.
    pub fn build_for_friction(
        pair: &GearPair,
        mesh: &MeshSpec,
        method: Method,
        progress: impl Fn(usize, usize) + Sync,
    ) -> Result<Self, String> {
        Self::build_dyn(pair, mesh, method, true, &progress)
    }

    fn build_dyn(
        pair: &GearPair,
        mesh: &MeshSpec,
        method: Method,
        friction: bool,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Self, String> {
        let place = PairPlacement::new(pair);
        let mut gears = Vec::new();
        let mut reports = Vec::new();
        for (i, gear) in [&pair.gear1, &pair.gear2].into_iter().enumerate() {
            let model = ClampedGear::new(pair, gear, mesh, Formulation::IncompatibleModes);
            let factor = crate::fe::cyclic_symmetry::static_solver(&model)?;
            let grid = FlankGrid::contact_flank_in_reach(&model.mesh, i, Flank::Drive, &place, 0)?;
            match method {
                Method::PmorHertz { depth_m, p_en, .. } => {
                    let (reduced, _, report) =
                        pmor_hertz(&model, factor.as_ref(), grid, depth_m, p_en, |n| progress(i, n))?;
                    gears.push(reduced);
                    reports.push(report);
                }
                Method::Penalty { .. } if friction => {
                    gears.push(standard_cms_with_flank_tangents(&model, factor.as_ref(), grid).0)
                }
                Method::Penalty { .. } => gears.push(standard_cms(&model, factor.as_ref(), grid).0),
            }
        }
        let gears: [ReducedGear; 2] = gears.try_into().map_err(|_| "two gears")?;
        let compression = reports.try_into().ok();
        Ok(ReducedPair { pair: pair.clone(), gears, method, compression })
    }

    pub fn static_model(&self) -> Result<StaticModel<'_>, String> {
        let contact = match self.method {
            Method::PmorHertz { law, .. } => ContactModel::Hertz { law },
            Method::Penalty { factor } => ContactModel::Penalty { factor },
        };
        StaticModel::new(&self.pair, [&self.gears[0], &self.gears[1]], contact)
    }

    /// Cases at `angles` positions of gear 2 spread over `pitches` angular pitches (starting at
    /// the reference position, half a step in), for each torque; parallel over cases. Positions
    /// beyond the first pitch use the tooth periodicity of the mesh (exact).
    pub fn sweep(&self, torques_nm: &[f64], angles: usize, pitches: f64) -> Vec<Result<StaticCase, String>> {
        self.sweep_with_friction(torques_nm, angles, pitches, 0.0)
    }

    /// [`ReducedPair::sweep`] with tooth friction of Coulomb coefficient μ at every contact
    /// (`StaticModel::with_friction`); a penalty pair must come from `build_for_friction`.
    pub fn sweep_with_friction(
        &self,
        torques_nm: &[f64],
        angles: usize,
        pitches: f64,
        friction_coefficient: f64,
    ) -> Vec<Result<StaticCase, String>> {
        let model = match self.static_model().and_then(|m| m.with_friction(friction_coefficient)) {
            Ok(model) => model,
            Err(e) => return vec![Err(e); torques_nm.len() * angles],
        };
        let pitch = 2.0 * std::f64::consts::PI / self.pair.gear2.teeth as f64;
        let jobs: Vec<(f64, f64)> = torques_nm
            .iter()
            .flat_map(|&t| (0..angles).map(move |k| (t, pitches * pitch * (k as f64 + 0.5) / angles as f64)))
            .collect();
        jobs.par_iter()
            .map(|&(torque, theta2)| {
                let periods = (theta2 / pitch).floor();
                let mut case = model.solve(theta2 - periods * pitch, torque)?;
                let (rb1, rb2) = (self.pair.gear1.base_radius_m, self.pair.gear2.base_radius_m);
                case.theta_rad = [(rb2 * theta2 + case.ste_m) / rb1, theta2];
                Ok(case)
            })
            .collect()
    }
}
