//! The pair's contact loads by the model's contact law: PMOR-Hertz's Hertz sections
//! (`contact`), or the node-to-surface penalty of the standard PMOR reference (`penalty`). The
//! one place that chooses, so that neither law's file needs the other's.

use super::contact::{section_contact_loads, ContactLoads, GearPose, Loading};
use super::equations::Stencil;
use super::model::{FlankContact, PmorModel};
use super::penalty::penalty_contact_loads;
use crate::contact::mesh_kinematics::{Flank, PairPlacement};
use crate::dynamics::mesh_friction::SlidingFriction;

/// Contact loads of the pair on both flanks; `restage` maps a gear's angle to its stencil (for
/// the penalty law's differences).
/// The mesh damper: a viscous coefficient c (N·s/m) shared by the loaded sections in proportion
/// to their Hertz tangent stiffness, each acting on its approach velocity α̇ = J·q̇ from the
/// gears' rotation and body modes (θ̇, η̇_Φ) and never pulling: F_d = max(c_s·α̇, −F_s), so the
/// section's force stays ≥ 0 and the damper's power F_d·α̇ ≥ 0. The contact shapes' velocities
/// η̇_Ψ are left out on purpose: they are the stiff coordinates (the shapes against the Hertz
/// contact near 100 kHz), and a damper on them makes those modes overdamped with a real
/// eigenvalue near −c/m_shape ≈ −2·10⁶ s⁻¹ — an explicit step of 0.5 µs.
/// Tooth friction, where given, on the loaded sections' sliding (`contact::apply_tooth_friction`).
pub fn contact_loads(
    model: &PmorModel,
    place: &PairPlacement,
    poses: [&GearPose; 2],
    restage: &dyn Fn(usize, f64) -> Result<Stencil, String>,
    loading: Loading,
    damper_n_s_per_m: f64,
    friction: Option<SlidingFriction>,
    collect_rows: bool,
) -> Result<ContactLoads, String> {
    if let FlankContact::Penalty { .. } = model.info.contact {
        if friction.is_some() {
            return Err("the standard PMOR reference (penalty contact) is the paper's frictionless model".into());
        }
        return penalty_contact_loads(model, place, poses, restage, damper_n_s_per_m, collect_rows);
    }
    section_contact_loads(model, place, poses, loading, damper_n_s_per_m, friction, collect_rows, &Flank::BOTH)
}
