//! Set-ups several FE test files share.

use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::gear::{GearPair, PairSpec};

/// The Kurokawa spur pair of `examples/kurokawa_spur.toml`.
pub fn kurokawa_spur() -> GearPair {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
    GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap()
}

/// A mesh finer than the default in-plane: 6 across the tooth, 12 along the profile, 6 in the
/// rim. (The line-load FE/PEM ratio at the pitch point happens to be ≈ 1 on it; that ratio grows
/// with refinement and is no evidence, see fe_tooth.)
pub fn medium_mesh(axial_slices: usize) -> MeshSpec {
    MeshSpec {
        elements_across_tooth: 6,
        elements_along_profile: 12,
        elements_in_rim: 6,
        axial_slices,
        ..Default::default()
    }
}
