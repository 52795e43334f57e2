//! The finite element model of a gear (design §4.2): hex8 elements, meshes, sparse assembly and
//! solvers. Offline only: nothing on the FMU's step path calls into this module.

pub mod assembly;
pub mod clamped_gear;
pub mod cyclic_symmetry;
pub mod dofs;
pub mod eigen;
pub mod gear_mesh;
pub mod hex8;
pub mod mesh;
pub mod ordering;
pub mod profile_png;
pub mod tooth_stiffness;
pub mod vtk;
