//! One gear's finite element model with the bore clamped: the floating frame's attachment, in
//! which eigenmodes, attachment modes and tooth stiffness are all computed (design §4.2).

use super::assembly::{self, DofMap, Material};
use super::gear_mesh::{mesh_gear, GearMesh, MeshSpec};
use super::hex8::Formulation;
use crate::gear::{Gear, GearPair};
use faer::sparse::SparseColMat;

pub struct ClampedGear {
    pub mesh: GearMesh,
    pub material: Material,
    pub formulation: Formulation,
    /// Free DOFs: every DOF but the bore's.
    pub dofs: DofMap,
    pub stiffness: SparseColMat<usize, f64>,
}

impl ClampedGear {
    /// Meshes `gear`, clamps its bore and assembles K.
    pub fn new(pair: &GearPair, gear: &Gear, spec: &MeshSpec, formulation: Formulation) -> Self {
        let mesh = mesh_gear(pair, gear, spec);
        let mut clamped = vec![false; mesh.mesh.nodes.len()];
        for &b in &mesh.bore_nodes {
            clamped[b] = true;
        }
        let dofs = DofMap::new(mesh.mesh.nodes.len(), &clamped);
        let material = Material::of(pair);
        let stiffness = assembly::stiffness(&mesh.mesh, &material, formulation, &dofs);
        ClampedGear { mesh, material, formulation, dofs, stiffness }
    }

    /// The nested-dissection (METIS) ordering of the free DOFs.
    pub fn ordering(&self) -> Result<super::ordering::Ordering, String> {
        super::ordering::nested_dissection(&self.mesh.mesh, &self.dofs)
    }

    /// Cholesky factor of K with the nested-dissection ordering.
    pub fn factorize(&self) -> Result<super::assembly::Cholesky, String> {
        super::assembly::Cholesky::with_ordering(&self.stiffness, Some(&self.ordering()?))
    }

    /// The symbolic analysis of K with the nested-dissection ordering: the factor's size, before
    /// the numeric factorization (`CholeskyAnalysis::factorize`) allocates it.
    pub fn analyse(&self) -> Result<super::assembly::CholeskyAnalysis, String> {
        super::assembly::Cholesky::analyse(&self.stiffness, Some(&self.ordering()?))
    }

    /// The consistent mass matrix over the same free DOFs.
    pub fn mass(&self) -> SparseColMat<usize, f64> {
        assembly::mass(&self.mesh.mesh, &self.material, &self.dofs)
    }
}
