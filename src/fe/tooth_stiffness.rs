//! Single-tooth compliance by finite elements: the gear clamped at the bore, a line load normal
//! to one flank along the face (at the pitch circle, or at any radius of the meshed flank), and
//! the deflection along the load (the work conjugate: fᵀu/|F|²). It contains the local
//! deformation under the line load as far as the mesh resolves it (a line load is log-singular in
//! elasticity, so this part grows slowly with refinement; the analytic Hertz term of the
//! PMOR-Hertz method exists to replace it).

use super::assembly::relative_residual;
use super::clamped_gear::ClampedGear;
use super::gear_mesh::{GearMesh, MeshSpec};
use super::hex8::Formulation;
use crate::gear::{Gear, GearPair};

#[derive(Debug, Clone, Copy)]
pub struct ToothCompliance {
    pub dofs: usize,
    /// Deflection along the load per unit load times face width (m²/N); ×1e9 → mm·µm/N.
    pub compliance_per_width: f64,
    /// Radius the load acts at.
    pub load_radius_m: f64,
}

/// A uniform line load of `total_force` N along the face, normal to flank side +1 of tooth 0 at
/// the pitch circle (shared linearly between the two flank rows around it; trapezoid weights
/// across the face), as (node, force vector).
pub fn pitch_line_load(
    gm: &GearMesh,
    gear: &Gear,
    axial_slices: usize,
    total_force: f64,
) -> Result<Vec<(usize, [f64; 3])>, String> {
    line_load_at_radius(gm, axial_slices, gear.pitch_radius_m, total_force)
}

/// The same line load at any radius between the flank's lowest and highest node rows.
pub fn line_load_at_radius(
    gm: &GearMesh,
    axial_slices: usize,
    load_radius_m: f64,
    total_force: f64,
) -> Result<Vec<(usize, [f64; 3])>, String> {
    let radius = |node: usize| gm.mesh.nodes[node][0].hypot(gm.mesh.nodes[node][1]);
    let flank: Vec<_> = gm.flank_nodes.iter().filter(|f| f.tooth == 0 && f.side == 1).collect();
    let r_p = load_radius_m;
    let mut radii: Vec<f64> = flank.iter().map(|f| radius(f.node)).collect();
    radii.sort_by(f64::total_cmp);
    radii.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let above = radii.iter().position(|&r| r >= r_p).ok_or(format!("no flank row above radius {r_p} m"))?;
    if above == 0 {
        return Err(format!("no flank row below radius {r_p} m"));
    }
    let (r_lo, r_hi) = (radii[above - 1], radii[above]);
    let w_hi = (r_p - r_lo) / (r_hi - r_lo);
    let mut load = Vec::new();
    for node in &flank {
        let r = radius(node.node);
        let w_row = if (r - r_lo).abs() < 1e-9 {
            1.0 - w_hi
        } else if (r - r_hi).abs() < 1e-9 {
            w_hi
        } else {
            continue;
        };
        let w_axial = if node.slice == 0 || node.slice == axial_slices { 0.5 } else { 1.0 } / axial_slices as f64;
        // The load presses on the flank: against its outward normal.
        load.push((node.node, node.normal.map(|c| -total_force * w_row * w_axial * c)));
    }
    Ok(load)
}

pub fn single_tooth_compliance(
    pair: &GearPair,
    gear: &Gear,
    spec: &MeshSpec,
    formulation: Formulation,
) -> Result<ToothCompliance, String> {
    let along = tooth_compliance_along_profile(pair, gear, spec, formulation, &[gear.pitch_radius_m])?;
    Ok(along[0])
}

/// The single-tooth compliance with the line load at each of `load_radii_m` in turn: one
/// factorization, one solve per radius. How it grows from the pitch circle toward the tip is the
/// bending the potential-energy method predicts, and it is what makes a tooth pair softer at
/// the ends of the path of contact.
pub fn tooth_compliance_along_profile(
    pair: &GearPair,
    gear: &Gear,
    spec: &MeshSpec,
    formulation: Formulation,
    load_radii_m: &[f64],
) -> Result<Vec<ToothCompliance>, String> {
    let model = ClampedGear::new(pair, gear, spec, formulation);
    let (k, dofs) = (&model.stiffness, &model.dofs);
    let chol = model.factorize()?;
    let total_force = 1000.0;
    load_radii_m
        .iter()
        .map(|&radius| {
            let load = line_load_at_radius(&model.mesh, spec.axial_slices, radius, total_force)?;
            let f = dofs.load_vector(&load);
            let u = chol.solve(&f);
            let residual = relative_residual(k, &u, &f);
            if residual > 1e-8 {
                return Err(format!("Cholesky residual {residual:e} too large"));
            }
            let work: f64 = f.iter().zip(&u).map(|(a, b)| a * b).sum();
            Ok(ToothCompliance {
                dofs: dofs.n_free,
                compliance_per_width: work / (total_force * total_force) * pair.face_width_m,
                load_radius_m: radius,
            })
        })
        .collect()
}
