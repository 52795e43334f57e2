//! Global attachment responses (paper Sect. 2.2; design §4.3): the static response of the clamped
//! gear to a flank load ("total"), minus the response of a *partial model* — the same mesh cut by
//! the section perpendicular to the load at depth h below it, clamped on that section — so that
//! the local deformation under the load, which the analytic Hertz contact supplies instead, is
//! removed. (The paper's Eq. 10 prints a sum; the two fields share the same local part, so the
//! global field is their difference.)
//!
//! The partial model is the slab of elements whose nodes all lie within depth |d| ≤ h of the
//! loaded surface's tangent plane (d measured along the load) and within `LATERAL_REACH`·h of a
//! loaded node. The nodes it shares with the rest of the gear are clamped: its back face (the
//! section at depth h) and any face cut through material. Its far lateral edges, where the local
//! deformation has decayed, end on free surfaces or on such cuts alike.

use crate::fe::assembly::{self, Cholesky, DofMap, LinearSolve, Material};
use crate::fe::hex8::Formulation;
use crate::fe::mesh::Mesh;

/// How far (in multiples of h) the partial model reaches along the surface from the load.
pub const LATERAL_REACH: f64 = 5.0;

/// A load on flank nodes: (node, force vector in N).
pub type NodalLoad = [(usize, [f64; 3])];

/// Response (all DOFs, node-major) of the partial model to the load; zero outside it.
pub fn partial_response(
    mesh: &Mesh,
    material: &Material,
    formulation: Formulation,
    load: &NodalLoad,
    depth_m: f64,
) -> Result<Vec<f64>, String> {
    let partial = PartialResponse::solve(mesh, material, formulation, load, depth_m)?;
    let mut u = vec![0.0; mesh.dofs()];
    for (i, &n) in partial.nodes.iter().enumerate() {
        u[3 * n..3 * n + 3].copy_from_slice(&partial.displacement[3 * i..3 * i + 3]);
    }
    Ok(u)
}

/// Forces on some nodes of a gear: (gear node, force vector in N).
pub type NodalForces = Vec<(usize, [f64; 3])>;

/// The partial model's response on its own nodes only: a few hundred nodes of a gear of tens of
/// thousands, so that one response per loadable node fits in memory at the paper's resolution.
pub struct PartialResponse {
    /// Gear node numbers of the partial model.
    pub nodes: Vec<usize>,
    /// Displacement of those nodes (node-major, 3 per node; zero on the clamped section).
    pub displacement: Vec<f64>,
    /// The forces the clamped section exerts on the partial model's elements, K_sub·p on the
    /// section's nodes (gear node numbers): what holds the cut. The gear's whole stiffness
    /// times p is the load plus these, since the elements outside the cut see p = 0.
    pub section_reaction: NodalForces,
}

impl PartialResponse {
    /// The partial model at depth h with the standard lateral reach, `LATERAL_REACH`·h.
    pub fn solve(
        mesh: &Mesh,
        material: &Material,
        formulation: Formulation,
        load: &NodalLoad,
        depth_m: f64,
    ) -> Result<PartialResponse, String> {
        Self::solve_with_reach(mesh, material, formulation, load, depth_m, LATERAL_REACH * depth_m)
    }

    /// The partial model at depth h that reaches `reach_m` from the load (`f64::INFINITY`: the
    /// whole half-space within depth h, the slow reference the reach is checked against).
    pub fn solve_with_reach(
        mesh: &Mesh,
        material: &Material,
        formulation: Formulation,
        load: &NodalLoad,
        depth_m: f64,
        reach_m: f64,
    ) -> Result<PartialResponse, String> {
        // The load direction and a reference point on the loaded surface.
        let total: [f64; 3] = load.iter().fold([0.0; 3], |a, (_, f)| [a[0] + f[0], a[1] + f[1], a[2] + f[2]]);
        let norm = (total[0] * total[0] + total[1] * total[1] + total[2] * total[2]).sqrt();
        if norm == 0.0 {
            return Err("the load has no resultant: no direction to measure depth along".into());
        }
        let dir = total.map(|v| v / norm);
        // A node belongs to the slab if it lies no deeper than h below the loaded surface (depth
        // along the load, from the nearest loaded node) and within the lateral reach of a loaded
        // node: the local deformation has decayed beyond it, and the rest of the gear — other
        // teeth in front of the tangent plane included — only costs time.
        let within = |n: usize| {
            let p = mesh.nodes[n];
            let (mut depth, mut distance_sq) = (f64::INFINITY, f64::INFINITY);
            for &(m, _) in load {
                let q = mesh.nodes[m];
                let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
                depth = depth.min(d[0] * dir[0] + d[1] * dir[1] + d[2] * dir[2]);
                distance_sq = distance_sq.min(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            }
            let tolerance = 1e-9;
            depth <= depth_m + tolerance && distance_sq.sqrt() <= reach_m + tolerance
        };
        let node_within: Vec<bool> = (0..mesh.nodes.len()).map(within).collect();
        let inside: Vec<usize> =
            (0..mesh.elements.len()).filter(|&e| mesh.elements[e].iter().all(|&n| node_within[n])).collect();
        if inside.is_empty() {
            return Err(format!(
                "no element lies within the depth h = {:.2} mm of the load: h must reach past the flank elements; raise h or refine the mesh",
                depth_m * 1e3
            ));
        }
        // Sub-mesh of the partial model; nodes shared with outside elements are the clamped section.
        let mut in_partial = vec![false; mesh.nodes.len()];
        for &e in &inside {
            for &n in &mesh.elements[e] {
                in_partial[n] = true;
            }
        }
        let mut on_section = vec![false; mesh.nodes.len()];
        let mut is_inside = vec![false; mesh.elements.len()];
        for &e in &inside {
            is_inside[e] = true;
        }
        for (e, el) in mesh.elements.iter().enumerate() {
            if !is_inside[e] {
                for &n in el {
                    if in_partial[n] {
                        on_section[n] = true;
                    }
                }
            }
        }
        let local: Vec<usize> = (0..mesh.nodes.len()).filter(|&n| in_partial[n]).collect();
        let mut index = vec![usize::MAX; mesh.nodes.len()];
        for (i, &n) in local.iter().enumerate() {
            index[n] = i;
        }
        let sub = Mesh {
            nodes: local.iter().map(|&n| mesh.nodes[n]).collect(),
            elements: inside.iter().map(|&e| mesh.elements[e].map(|n| index[n])).collect(),
        };
        let clamped: Vec<bool> = local.iter().map(|&n| on_section[n]).collect();
        if !clamped.iter().any(|&c| c) {
            return Err("the partial model has no clamped section (h reaches through the whole body)".into());
        }
        for &(n, _) in load {
            if on_section[n] || !in_partial[n] {
                return Err(format!(
                    "loaded node {n} lies on the clamped section of its partial model: the depth h = {:.2} mm does not reach past the flank elements; raise h or refine the mesh",
                    depth_m * 1e3
                ));
            }
        }
        let dofs = DofMap::new(sub.nodes.len(), &clamped);
        let k_all = assembly::stiffness(&sub, material, formulation, &DofMap::unclamped(sub.nodes.len()));
        let k = dofs.restrict(&k_all);
        let local_load: Vec<(usize, [f64; 3])> = load.iter().map(|&(n, force)| (index[n], force)).collect();
        let displacement = dofs.expand(&Cholesky::new(&k)?.solve(&dofs.load_vector(&local_load)));
        let forces = assembly::mul(&k_all, &displacement);
        let section_reaction = (0..local.len())
            .filter(|&i| clamped[i])
            .map(|i| (local[i], [forces[3 * i], forces[3 * i + 1], forces[3 * i + 2]]))
            .collect();
        Ok(PartialResponse { nodes: local, displacement, section_reaction })
    }
}

/// Total and global responses (all DOFs) of the gear clamped by `dofs` (its factorized stiffness
/// `total_stiffness`) to a flank load: global = total − partial(h).
pub fn total_and_global_response(
    mesh: &Mesh,
    material: &Material,
    formulation: Formulation,
    dofs: &DofMap,
    total_stiffness: &dyn LinearSolve,
    load: &NodalLoad,
    depth_m: f64,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let total = dofs.expand(&total_stiffness.solve(&dofs.load_vector(load)));
    let partial = partial_response(mesh, material, formulation, load, depth_m)?;
    let global = total.iter().zip(&partial).map(|(t, p)| t - p).collect();
    Ok((total, global))
}

/// Global attachment modes ψ_glob (free DOFs × n_c) and the stiffness forces they carry.
///
/// Column j is the clamped gear's response u_j to a unit load f_j along a flank node's inward
/// normal, less its partial model's response p_j. The gear's stiffness times p_j is f_j plus the
/// reaction r_j of the partial model's clamped section (`PartialResponse::section_reaction`),
/// and K·u_j = f_j, so
///
///   K·ψ_j = −r_j:
///
/// the global mode is the gear's response to the forces that hold the cut at depth h, which is
/// why it is smooth at the flank. Its reduced stiffness ψᵢᵀKψⱼ = −ψᵢᵀr_j is then a sum over a
/// section's few hundred DOFs, not a product of the gear's stiffness with n_c fields (that
/// product and its dense Gram were most of the attachment stage's time).
pub struct GlobalAttachmentModes {
    /// ψ_glob over the free DOFs, a column per loaded node.
    pub psi: faer::Mat<f64>,
    /// r_j of each column: the section's reaction of its partial model.
    pub section_reactions: Vec<NodalForces>,
}

impl GlobalAttachmentModes {
    /// K_r = ψᵀKψ = −ψᵀR (n_c × n_c), symmetrized (the halves differ by the solvers' round-off).
    pub fn reduced_stiffness(&self, dofs: &DofMap) -> faer::Mat<f64> {
        use rayon::prelude::*;
        let n_c = self.psi.ncols();
        let columns: Vec<Vec<f64>> = self
            .section_reactions
            .par_iter()
            .map(|reaction| {
                (0..n_c)
                    .map(|i| {
                        let psi_i = self.psi.col(i);
                        -reaction
                            .iter()
                            .flat_map(|(node, force)| (0..3).map(move |c| (dofs.free[3 * node + c], force[c])))
                            .filter_map(|(slot, f)| slot.map(|d| psi_i[d] * f))
                            .sum::<f64>()
                    })
                    .collect()
            })
            .collect();
        faer::Mat::from_fn(n_c, n_c, |i, j| 0.5 * (columns[j][i] + columns[i][j]))
    }
}

/// Global attachment modes ψ_glob (free DOFs × nodes): for each loadable flank node, the response
/// to a unit load along its inward normal, minus that load's partial model at depth h. The total
/// responses are one block solve; the partial models run in parallel over nodes.
pub fn global_attachment_modes(
    mesh: &Mesh,
    material: &Material,
    formulation: Formulation,
    dofs: &DofMap,
    total_stiffness: &dyn LinearSolve,
    nodes: &[(usize, [f64; 3])],
    depth_m: f64,
    progress: impl Fn(usize) + Sync,
) -> Result<GlobalAttachmentModes, String> {
    // Generic only at the door: the body below is compiled once, here, not again in
    // every crate (each test, fmu-build) that passes a progress closure of its own.
    global_attachment_modes_dyn(mesh, material, formulation, dofs, total_stiffness, nodes, depth_m, &progress)
}

fn global_attachment_modes_dyn(
    mesh: &Mesh,
    material: &Material,
    formulation: Formulation,
    dofs: &DofMap,
    total_stiffness: &dyn LinearSolve,
    nodes: &[(usize, [f64; 3])],
    depth_m: f64,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<GlobalAttachmentModes, String> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let n_c = nodes.len();
    let mut psi = faer::Mat::zeros(dofs.n_free, n_c);
    for (j, &(node, normal)) in nodes.iter().enumerate() {
        for c in 0..3 {
            if let Some(i) = dofs.free[3 * node + c] {
                psi[(i, j)] = -normal[c];
            }
        }
    }
    total_stiffness.solve_block(&mut psi);
    let done = AtomicUsize::new(0);
    let partials: Vec<Result<PartialResponse, String>> = nodes
        .par_iter()
        .map(|&(node, normal)| {
            let r = PartialResponse::solve(mesh, material, formulation, &[(node, normal.map(|v| -v))], depth_m);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            r
        })
        .collect();
    let mut section_reactions = Vec::with_capacity(n_c);
    for (j, partial) in partials.into_iter().enumerate() {
        let partial = partial?;
        for (k, &n) in partial.nodes.iter().enumerate() {
            for c in 0..3 {
                if let Some(i) = dofs.free[3 * n + c] {
                    psi[(i, j)] -= partial.displacement[3 * k + c];
                }
            }
        }
        section_reactions.push(partial.section_reaction);
    }
    Ok(GlobalAttachmentModes { psi, section_reactions })
}

/// ψ_glob of a flank grid on several teeth of the gear mesh, solved for the first tooth's nodes
/// only. The mesh is exactly cyclic (`fe::gear_mesh`) and the grid alike on every tooth (tooth-
/// major, the same rows and layers), so the response to the unit normal load on a node of tooth
/// t₀ + d is the first tooth's response turned on by d teeth (`GearMesh::rotate_by_teeth`): one
/// block solve and one set of partial models instead of one per tooth. The partial model turns
/// with its load, since it is cut by depth and reach from the load alone. A grid that is not
/// such an image tooth by tooth (checked node by node and normal by normal) is solved whole.
pub fn global_attachment_modes_of_teeth(
    gear: &crate::fe::gear_mesh::GearMesh,
    material: &Material,
    formulation: Formulation,
    dofs: &DofMap,
    total_stiffness: &dyn LinearSolve,
    flank: &super::flank::FlankGrid,
    depth_m: f64,
    progress: impl Fn(usize) + Sync,
) -> Result<GlobalAttachmentModes, String> {
    // Generic only at the door: the body below is compiled once, here, not again in
    // every crate (each test, fmu-build) that passes a progress closure of its own.
    global_attachment_modes_of_teeth_dyn(gear, material, formulation, dofs, total_stiffness, flank, depth_m, &progress)
}

fn global_attachment_modes_of_teeth_dyn(
    gear: &crate::fe::gear_mesh::GearMesh,
    material: &Material,
    formulation: Formulation,
    dofs: &DofMap,
    total_stiffness: &dyn LinearSolve,
    flank: &super::flank::FlankGrid,
    depth_m: f64,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<GlobalAttachmentModes, String> {
    use rayon::prelude::*;
    let solve_whole = |progress| {
        global_attachment_modes(
            &gear.mesh,
            material,
            formulation,
            dofs,
            total_stiffness,
            &flank.nodes,
            depth_m,
            progress,
        )
    };
    let Some(turns) = teeth_from_the_first(gear, flank) else {
        return solve_whole(progress);
    };
    let per_tooth = flank.len() / flank.teeth.len();
    let first = global_attachment_modes(
        &gear.mesh,
        material,
        formulation,
        dofs,
        total_stiffness,
        &flank.nodes[..per_tooth],
        depth_m,
        progress,
    )?;
    // Column (t, j) is P^{-t} of the first tooth's column j (`GearMesh::rotate_by_teeth` by −t):
    // the value at node turned back by t teeth, its vector turned on by t pitches. The bore is
    // cyclic too, so a free DOF's source is free.
    let pitch = 2.0 * std::f64::consts::PI / gear.teeth as f64;
    let mut psi = faer::Mat::zeros(dofs.n_free, flank.len());
    psi.as_mut().par_col_chunks_mut(1).enumerate().for_each(|(column, mut out)| {
        let (t, j) = (turns[column / per_tooth], column % per_tooth);
        let (s, c) = (t as f64 * pitch).sin_cos();
        let source = first.psi.col(j);
        let value = |node: usize, k: usize| dofs.free[3 * node + k].map_or(0.0, |i| source[i]);
        for node in 0..dofs.free.len() / 3 {
            let from = gear.node_turned_by_teeth(node, -t);
            let (x, y, z) = (value(from, 0), value(from, 1), value(from, 2));
            for (k, v) in [c * x - s * y, s * x + c * y, z].into_iter().enumerate() {
                if let Some(i) = dofs.free[3 * node + k] {
                    out[(i, 0)] = v;
                }
            }
        }
    });
    // The reactions turn with their modes: the value at node m moves to node m turned on by t
    // teeth.
    let section_reactions = (0..flank.len())
        .map(|column| {
            let (t, j) = (turns[column / per_tooth], column % per_tooth);
            let (s, c) = (t as f64 * pitch).sin_cos();
            first.section_reactions[j]
                .iter()
                .map(|&(m, f)| (gear.node_turned_by_teeth(m, t), [c * f[0] - s * f[1], s * f[0] + c * f[1], f[2]]))
                .collect()
        })
        .collect();
    Ok(GlobalAttachmentModes { psi, section_reactions })
}

/// The teeth each tooth of a flank grid lies on from its first (mod z), where every tooth's nodes
/// and normals are the first tooth's turned on by that many teeth; `None` where they are not
/// (or the grid has one tooth): then nothing is gained by turning.
pub fn teeth_from_the_first(
    gear: &crate::fe::gear_mesh::GearMesh,
    flank: &super::flank::FlankGrid,
) -> Option<Vec<i64>> {
    let teeth = flank.teeth.len();
    if teeth < 2 || flank.len() % teeth != 0 {
        return None;
    }
    let per_tooth = flank.len() / teeth;
    let pitch = 2.0 * std::f64::consts::PI / gear.teeth as f64;
    let turns: Vec<i64> = flank.teeth.iter().map(|&t| t as i64 - flank.teeth[0] as i64).collect();
    let is_image = |slot: usize| {
        let (s, c) = (turns[slot] as f64 * pitch).sin_cos();
        (0..per_tooth).all(|j| {
            let ((node0, n0), (node, n)) = (flank.nodes[j], flank.nodes[slot * per_tooth + j]);
            let turned = [c * n0[0] - s * n0[1], s * n0[0] + c * n0[1], n0[2]];
            gear.node_turned_by_teeth(node0, turns[slot]) == node && (0..3).all(|k| (turned[k] - n[k]).abs() < 1e-9)
        })
    };
    (1..teeth).all(is_image).then_some(turns)
}
