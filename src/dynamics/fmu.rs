//! The gear pair behind the FMI layer: maps the interface's variables (by name, from
//! `modelDescription/variables.toml`) to the physics, and steps the model with RK4 sub-steps no
//! longer than `max_step`. Everything that changes lives in [`GearPairState`], so an FMU state
//! is a copy of it.

use super::lumped::{LumpedMesh, LumpedModel, LumpedParameters, LumpedState};
use crate::fmi2::{Model, Phase};
use crate::interface;
use crate::model_file::{ModelFile, ModelKind};
use serde::{Deserialize, Serialize};
use std::path::Path;

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
}

impl Var {
    pub const ALL: [Var; 19] = [
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
    pub mech: LumpedState,
}

pub struct GearPairFmu {
    pub mesh: LumpedMesh,
    /// (value reference, variable), from variables.toml.
    lookup: Vec<(u32, Var)>,
}

impl GearPairFmu {
    pub fn from_model_file(file: ModelFile) -> Result<Self, String> {
        let ModelKind::Lumped(mesh) = file.model;
        let mut lookup = Vec::new();
        for v in interface::variables() {
            let var = Var::ALL
                .into_iter()
                .find(|x| x.name() == v.name)
                .ok_or_else(|| format!("interface variable {} has no physics in this binary", v.name))?;
            lookup.push((v.value_reference, var));
        }
        Ok(GearPairFmu { mesh, lookup })
    }

    fn var(&self, vr: u32) -> Result<Var, String> {
        self.lookup
            .iter()
            .find(|(r, _)| *r == vr)
            .map(|(_, v)| *v)
            .ok_or_else(|| format!("unknown value reference {vr}"))
    }

    pub fn lumped(&self, state: &GearPairState) -> LumpedModel<'_> {
        LumpedModel::new(&self.mesh, state.params)
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
        let file = ModelFile::read(resources)?;
        if file.guid != guid {
            return Err(format!("GUID {guid} does not match the FMU's model data ({})", file.guid));
        }
        Self::from_model_file(file)
    }

    fn initial_state(&self) -> GearPairState {
        let start = LumpedState::default();
        GearPairState {
            torques_nm: [0.0; 2],
            start,
            max_step_s: 1e-5,
            params: LumpedParameters::defaults(&self.mesh),
            mech: start,
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
            Var::MaxStep => s.max_step_s = positive("max_step", value)?,
            Var::Inertia1 => s.params.inertia_1_kgm2 = positive("inertia_1", value)?,
            Var::Inertia2 => s.params.inertia_2_kgm2 = positive("inertia_2", value)?,
            Var::MeshDampingRatio => {
                if !(0.0..1.0).contains(&value) {
                    return Err(format!("mesh_damping_ratio must be in [0, 1), got {value}"));
                }
                s.params.mesh_damping_ratio = value
            }
            other => return Err(format!("{} is an output and cannot be set", other.name())),
        }
        // Until initialization ends the mechanical state follows the start values.
        if matches!(phase, Phase::Instantiated | Phase::InitializationMode) {
            s.mech = s.start;
        }
        Ok(())
    }

    fn get_real(&self, s: &GearPairState, vr: u32) -> Result<f64, String> {
        let model = self.lumped(s);
        let mesh = model.mesh_state(&s.mech);
        Ok(match self.var(vr)? {
            Var::Tau1 => s.torques_nm[0],
            Var::Tau2 => s.torques_nm[1],
            Var::Phi1 => s.mech.theta_1,
            Var::Phi2 => s.mech.theta_2,
            Var::W1 => s.mech.omega_1,
            Var::W2 => s.mech.omega_2,
            Var::Dte => mesh.transmission_error_m,
            Var::DteAngle => mesh.transmission_error_m / self.mesh.base_radius_2_m,
            Var::MeshForce => mesh.force_n,
            Var::MeshStiffness => mesh.stiffness_n_per_m,
            Var::Phi1Start => s.start.theta_1,
            Var::Phi2Start => s.start.theta_2,
            Var::W1Start => s.start.omega_1,
            Var::W2Start => s.start.omega_2,
            Var::MaxStep => s.max_step_s,
            Var::Inertia1 => s.params.inertia_1_kgm2,
            Var::Inertia2 => s.params.inertia_2_kgm2,
            Var::MeshDampingRatio => s.params.mesh_damping_ratio,
            Var::ContactPairs => return Err(format!("value reference {vr} (contact_pairs) is an Integer, not a Real")),
        })
    }

    fn get_integer(&self, s: &GearPairState, vr: u32) -> Result<i32, String> {
        match self.var(vr)? {
            Var::ContactPairs => Ok(self.lumped(s).mesh_state(&s.mech).pairs_in_contact as i32),
            other => Err(format!("value reference {vr} ({}) is not an Integer", other.name())),
        }
    }

    fn exit_initialization(&self, s: &mut GearPairState) -> Result<(), String> {
        s.mech = s.start;
        Ok(())
    }

    fn do_step(&self, s: &mut GearPairState, h: f64) -> Result<(), String> {
        let model = self.lumped(s);
        model.advance(&mut s.mech, s.torques_nm, h, s.max_step_s);
        let m = &s.mech;
        if [m.theta_1, m.omega_1, m.theta_2, m.omega_2].iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(format!("the state became non-finite: the integrator is unstable at max_step = {} s", s.max_step_s))
        }
    }
}
