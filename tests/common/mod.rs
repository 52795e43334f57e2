//! Set-ups several FE test files share.

use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::gear::{GearPair, PairSpec};

/// The Kurokawa spur pair of `examples/kurokawa_spur.toml`.
#[allow(dead_code)]
pub fn kurokawa_spur() -> GearPair {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
    GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap()
}

/// A mesh finer than the default in-plane: 6 across the tooth, 12 along the profile, 6 in the
/// rim. (The line-load FE/PEM ratio at the pitch point happens to be ≈ 1 on it; that ratio grows
/// with refinement and is no evidence, see fe_tooth.)
#[allow(dead_code)]
pub fn medium_mesh(axial_slices: usize) -> MeshSpec {
    MeshSpec {
        elements_across_tooth: 6,
        elements_along_profile: 12,
        elements_in_rim: 6,
        axial_slices,
        ..Default::default()
    }
}

/// Both gears of `p` reduced by PMOR-Hertz on the default (coarse) mesh, h = 3 mm, p_en = 99.9 %.
#[allow(dead_code)]
pub fn reduce_pmor_hertz(p: &GearPair) -> [gearfmu::rom::reductor::ReducedGear; 2] {
    use gearfmu::contact::mesh_kinematics::{Flank, PairPlacement};
    use gearfmu::fe::clamped_gear::ClampedGear;
    use gearfmu::fe::hex8::Formulation;
    use gearfmu::rom::flank::FlankGrid;
    let place = PairPlacement::new(p);
    let spec = MeshSpec::default();
    let mut hertz = Vec::new();
    for (i, gear) in [&p.gear1, &p.gear2].into_iter().enumerate() {
        let model = ClampedGear::new(p, gear, &spec, Formulation::IncompatibleModes);
        let factor = model.factorize().unwrap();
        let z = gear.teeth as i64;
        let teeth: Vec<usize> = place.pairs_in_reach().map(|j| j.rem_euclid(z) as usize).collect();
        let grid = FlankGrid::contact_flank(&model.mesh, i, Flank::Drive, &teeth).unwrap();
        let (reduced, _, report) =
            gearfmu::rom::reductor::pmor_hertz(&model, &factor, grid, 3e-3, 0.999, |_| {}).unwrap();
        println!("gear {}: n_c {} → n_sv {} (retained {:.4})", i + 1, report.n_c, report.n_sv, report.retained);
        hertz.push(reduced);
    }
    hertz.try_into().unwrap()
}
