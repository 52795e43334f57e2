//! The lumped model against independent references: closed-form kinematics, ISO 6336-1 mesh
//! stiffness, the mesh natural frequency from k̄ and the inertias, and the energy balance.

use gearfmu::dynamics::iso6336;
use gearfmu::dynamics::lumped::{mesh_natural_frequency_hz, LumpedMesh, LumpedModel, LumpedState};
use gearfmu::gear::{GearPair, PairSpec};
use std::path::Path;

fn pair(name: &str) -> GearPair {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(name);
    GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap()
}

#[test]
fn print_figures() {
    for name in ["kurokawa_spur.toml", "kurokawa_helical.toml"] {
        let p = pair(name);
        let mesh = LumpedMesh::from_pair(&p);
        let model = LumpedModel::with_defaults(&mesh);
        let iso = iso6336::to_newton_per_metre(iso6336::mesh_stiffness_c_gamma_alpha(&p), p.face_width_m);
        println!(
            "{name}: eps_a {:.4} eps_b {:.4} pb {:.4} mm  J1 {:.5} J2 {:.5} kmean {:.4e} iso {:.4e} ratio {:.3} fn {:.1} Hz backlash {:.1} um  min/max k {:.3e} {:.3e}",
            p.transverse_contact_ratio, p.overlap_ratio, p.base_pitch_m*1e3, p.gear1.inertia_kgm2, p.gear2.inertia_kgm2,
            mesh.mean_drive_stiffness(), iso, mesh.mean_drive_stiffness()/iso, mesh_natural_frequency_hz(&mesh, &model.params), p.backlash_loa_m*1e6,
            mesh.drive_stiffness_n_per_m.iter().cloned().fold(f64::MAX, f64::min), mesh.drive_stiffness_n_per_m.iter().cloned().fold(0.0, f64::max)
        );
        let _ = LumpedState::default();
    }
}
