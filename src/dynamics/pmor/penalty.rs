//! Node-to-surface penalty contact between the deformed flanks: the contact law of the standard
//! PMOR (paper Sects. 4.1 and 5.2), the reference model PMOR-Hertz is compared with
//! (`--model pmor-penalty`, `FlankContact::Penalty`).
//!
//! Both passes, as the statics' baseline (`rom::statics`): each flank node k of one gear (the
//! slave) against the other gear's flank (the master). Its penetration is
//!
//!   α = α₀(θ₁, θ₂) + n_kᵀu_slave(k) + n_mᵀu_master(m),
//!
//! α₀ the rigid node's distance inside the master's involute flank (normal to the flanks, less
//! the modifications' opening), u = V(ϑ)η the deformed flanks in the floating frames, m the point
//! of the master's node layer at the node's radius, n_m the interpolated normal there. Its force is
//! k·α for α > 0, k the node's share of the statics' penalty stiffness
//! (`rom::statics::penalty_node_stiffness_n_per_m`, evaluated by the build into `PmorBuildInfo`), and its potential ½kα². The generalized
//! forces are the potential's gradient: on η exactly (α is linear in η), on the angles by
//! central differences of the same α at fixed η (the node, the master point and the shapes all
//! move with the angles; the tip corners' contact does this too, `contact`).
//!
//! The geometry is read in each gear's reduced angle ϑᵢ = θᵢ − kᵢ·pitchᵢ: a whole pitch is a
//! symmetry of a rigid gear, and there the teeth carry the labels of the stored rows (the field
//! of reference tooth t + kᵢ, as in `contact`). The master's tooth is the one whose flank is
//! nearest to the node.
//!
//! Drive flanks only: the reference model is for the paper's loaded runs. Where a coast flank
//! could close, the right-hand side is an error, not a silent miss.

use super::contact::{ContactLoads, GearPose, SectionRows};
use super::equations::Stencil;
use super::model::{NodeDirection, PmorModel};
use crate::contact::flank_grid::Shares;
use crate::contact::mesh_kinematics::{Flank, PairPlacement};

/// Angle step of the central differences ∂α/∂θᵢ (rad).
const ANGLE_STEP: f64 = 1e-7;

/// One gear's kinematics at a (possibly shifted) angle: its reduced angle and its stencil.
#[derive(Clone, Copy)]
struct Placed<'a> {
    reduced_angle: f64,
    stencil: Stencil,
    eta: &'a [f64],
}

/// A node's contact with the master flank at one pose.
struct NodePenetration {
    alpha_m: f64,
    master_shares: Shares,
    master_normal: [f64; 3],
}

/// Where a rigid slave node sits against the master: its radius in the master's frame, its
/// signed distance from the nearest master flank (m) and that flank's tooth.
#[derive(Clone, Copy)]
struct RigidNode {
    radius_m: f64,
    distance_m: f64,
    tooth: usize,
}

/// The last node's rigid placement, by its transverse position: on a spur pair the node layers
/// of one flank row share their (x, y) and the placement does not depend on z (no helix), so a
/// row's layers are placed once — the trigonometry is most of this contact's cost.
type RigidMemo = Option<([f64; 2], Option<RigidNode>)>;

/// The rigid placement of a slave node at (x, y) in axial plane z, or `None` where it does not
/// face the master's active flank.
fn rigid_node(place: &PairPlacement, slave: usize, x: [f64; 2], z: f64, at: [&Placed; 2]) -> Option<RigidNode> {
    let pair = &place.pair;
    let master = 1 - slave;
    let w = place.to_world(slave, at[slave].reduced_angle, x);
    let own = place.to_own(master, at[master].reduced_angle, w);
    let r = own[0].hypot(own[1]);
    let g = if master == 0 { &pair.gear1 } else { &pair.gear2 };
    if !(g.form_radius_m.max(g.base_radius_m)..=g.tip_radius_m).contains(&r) {
        return None;
    }
    Some(RigidNode {
        radius_m: r,
        distance_m: place.distance_from_flank(master, 0, z, own),
        tooth: place.nearest_flank_tooth(master, z, own),
    })
}

/// The penetration of slave gear `slave`'s flank node k (in its drive flank rows) into the other
/// gear's flank; `None` where the node does not face the master's active flank. `reach_m`: the
/// most the deformation can close (a rigid gap beyond it is skipped before the elastic part).
fn node_penetration(
    model: &PmorModel,
    place: &PairPlacement,
    slave: usize,
    k: usize,
    at: [&Placed; 2],
    reach_m: f64,
    memo: &mut RigidMemo,
) -> Result<Option<NodePenetration>, String> {
    let pair = &model.pair;
    let master = 1 - slave;
    let rows = [model.gears[0].flank(Flank::Drive), model.gears[1].flank(Flank::Drive)];
    let grid = &rows[slave].grid;
    let layers = &grid.layer_z_m;
    let layer = k % layers.len();
    let z = layers[layer];
    let x = grid.node_xy[k];
    let rigid = match memo {
        Some((last, rigid)) if *last == x && pair.base_helix_angle_rad == 0.0 => *rigid,
        _ => {
            let rigid = rigid_node(place, slave, x, z, at);
            *memo = Some((x, rigid));
            rigid
        }
    };
    let Some(RigidNode { radius_m: r, distance_m, tooth }) = rigid else { return Ok(None) };
    let slave_radius = x[0].hypot(x[1]);
    let radii = if slave == 0 { [slave_radius, r] } else { [r, slave_radius] };
    let cos_bb = pair.base_helix_angle_rad.cos();
    let alpha0 = -cos_bb * distance_m - place.modification_m(radii, z);
    if alpha0 + reach_m <= 0.0 {
        return Ok(None);
    }
    let Some(master_shares) = rows[master].grid.layer_shares(tooth, r, layer) else {
        return Err(format!(
            "gear {}'s flank node {k} meets tooth {tooth} of gear {}, which has no stored flank rows",
            slave + 1,
            master + 1
        ));
    };
    let master_normal = rows[master].grid.normal(&master_shares);
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let gears = &model.gears;
    let (u_slave, _) = gears[slave].node_displacement(Flank::Drive, &at[slave].stencil, k, at[slave].eta);
    let mut alpha = alpha0 + dot(grid.nodes[k].1, u_slave);
    for &(node, share) in &master_shares {
        let (u, _) = gears[master].node_displacement(Flank::Drive, &at[master].stencil, node, at[master].eta);
        alpha += share * dot(master_normal, u);
    }
    Ok(Some(NodePenetration { alpha_m: alpha, master_shares, master_normal }))
}

/// The teeth (slots of the drive flank grid) of gear `slave` that can face the other gear's
/// flanks: a tooth whose first flank node lies farther from the master's axis than the master's
/// tip radius plus the slave's whole tooth height is out of the mesh.
fn teeth_near_mesh(model: &PmorModel, place: &PairPlacement, slave: usize, at: [&Placed; 2]) -> Vec<usize> {
    let pair = &model.pair;
    let master = 1 - slave;
    let grid = &model.gears[slave].flank(Flank::Drive).grid;
    let per_tooth = grid.row_radius_m.len() * grid.layer_z_m.len();
    let (g_slave, g_master) = if slave == 0 { (&pair.gear1, &pair.gear2) } else { (&pair.gear2, &pair.gear1) };
    let reach = g_master.tip_radius_m + (g_slave.tip_radius_m - g_slave.root_radius_m);
    (0..grid.teeth.len())
        .filter(|&slot| {
            let w = place.to_world(slave, at[slave].reduced_angle, grid.node_xy[slot * per_tooth]);
            let own = place.to_own(master, at[master].reduced_angle, w);
            own[0].hypot(own[1]) <= reach
        })
        .collect()
}

/// The contact loads of the pair under node-to-surface penalty contact (the layout of
/// `contact_law::contact_loads`, which chooses it; it shares `contact`'s mesh damper: a loaded
/// node is a section).
#[allow(clippy::too_many_arguments)]
pub fn penalty_contact_loads(
    model: &PmorModel,
    place: &PairPlacement,
    poses: [&GearPose; 2],
    restage: &dyn Fn(usize, f64) -> Result<Stencil, String>,
    damper_n_s_per_m: f64,
    collect_rows: bool,
) -> Result<ContactLoads, String> {
    let n_e = [poses[0].eta.len(), poses[1].eta.len()];
    let mut out = ContactLoads {
        force: [vec![0.0; 1 + n_e[0]], vec![0.0; 1 + n_e[1]]],
        damping_force: [vec![0.0; 1 + n_e[0]], vec![0.0; 1 + n_e[1]]],
        ..Default::default()
    };
    let theta = [poses[0].theta, poses[1].theta];
    let coast_reach: f64 =
        (0..2).map(|i| model.gears[i].flank_displacement_bound(Flank::Coast, &poses[i].stencil, poses[i].eta)).sum();
    // The bound is loose (the CMS shapes carry the local deformation): where it cannot rule the
    // coast flanks out, their Hertz sections on the deformed flanks decide (a detector only).
    let coast_closes = place.flank_can_close(Flank::Coast, theta, coast_reach)
        && super::contact::section_contact_loads(
            model,
            place,
            poses,
            super::contact::Loading::Point,
            0.0,
            None,
            false,
            &[Flank::Coast],
        )
        .map_or(true, |c| c.normal_force_n != 0.0);
    if coast_closes {
        return Err(format!(
            "the coast flanks can close at θ = ({}, {}) rad (a load reversal or rattle): the penalty reference model carries drive-flank contact only",
            crate::gear::sig(theta[0]),
            crate::gear::sig(theta[1])
        ));
    }
    let reach: f64 =
        (0..2).map(|i| model.gears[i].flank_displacement_bound(Flank::Drive, &poses[i].stencil, poses[i].eta)).sum();
    let reduced = |i: usize, theta: f64| theta - poses[i].anchor as f64 * model.gears[i].pitch_rad();
    let placed =
        [0, 1].map(|i| Placed { reduced_angle: reduced(i, theta[i]), stencil: poses[i].stencil, eta: poses[i].eta });
    // Each gear turned by ±ANGLE_STEP (the differences' poses), staged once per right-hand side.
    let mut shifted = Vec::with_capacity(4);
    for i in 0..2 {
        for sign in [1.0, -1.0] {
            let angle = theta[i] + sign * ANGLE_STEP;
            shifted.push(Placed { reduced_angle: reduced(i, angle), stencil: restage(i, angle)?, eta: poses[i].eta });
        }
    }
    let damped = damper_n_s_per_m > 0.0;
    let collect = damped || collect_rows;
    let layers = &model.gears[0].flank(Flank::Drive).grid.layer_z_m;
    // The node stiffness depends on the layer only (the build's, from the ISO 6336-1 c_γα).
    let layer_stiffness = &model.info.penalty_layer_stiffness_n_per_m;
    let mut sections: Vec<SectionRows> = Vec::new();
    let mut pair_forces: Vec<(i64, f64)> = Vec::new();
    let mut tmp = [vec![0.0; n_e[0]], vec![0.0; n_e[1]]];
    for slave in 0..2 {
        let master = 1 - slave;
        let grid = &model.gears[slave].flank(Flank::Drive).grid;
        let per_tooth = grid.row_radius_m.len() * layers.len();
        for slot in teeth_near_mesh(model, place, slave, [&placed[0], &placed[1]]) {
            // One memo for the pose and one for each of the differences' four.
            let mut memo: RigidMemo = None;
            let mut shifted_memo: [RigidMemo; 4] = [None; 4];
            for k in slot * per_tooth..(slot + 1) * per_tooth {
                let at = [&placed[0], &placed[1]];
                let Some(hit) = node_penetration(model, place, slave, k, at, reach, &mut memo)? else {
                    continue;
                };
                if hit.alpha_m <= 0.0 {
                    continue;
                }
                let stiffness = layer_stiffness[k % layers.len()];
                let force = stiffness * hit.alpha_m;
                // ∂α/∂θᵢ at fixed η: central differences of the same node's penetration.
                let mut alpha_slope = [0.0; 2];
                for i in 0..2 {
                    let mut value = [0.0; 2];
                    for (d, v) in value.iter_mut().enumerate() {
                        let at = if i == 0 { [&shifted[d], &placed[1]] } else { [&placed[0], &shifted[2 + d]] };
                        // Moved off the master's flank within 1e-7 rad: the contact's edge; the
                        // one-sided value stands in as no penetration.
                        let memo = &mut shifted_memo[2 * i + d];
                        *v = node_penetration(model, place, slave, k, at, f64::INFINITY, memo)?
                            .map_or(0.0, |p| p.alpha_m);
                    }
                    alpha_slope[i] = (value[0] - value[1]) / (2.0 * ANGLE_STEP);
                }
                let mut section = collect.then(|| SectionRows {
                    flank_sign: 1.0,
                    // The penalty reference is frictionless: no arm is read.
                    point_m: f64::NAN,
                    force_n: force,
                    stiffness_n_per_m: stiffness,
                    rows: [0, 1].map(|i| vec![0.0; 1 + n_e[i]]),
                    sliding_rows: [Vec::new(), Vec::new()],
                });
                // Generalized forces on η: −F·∂α/∂η, the slave node along its own normal, the
                // master point along the interpolated one.
                tmp.iter_mut().for_each(|t| t.fill(0.0));
                let mut load = |i: usize, node: usize, share: f64, normal: Option<[f64; 3]>| {
                    let g = &model.gears[i];
                    match normal {
                        Some(n) => {
                            g.add_basis_row(Flank::Drive, &poses[i].stencil, node, n.map(|c| share * c), &mut tmp[i])
                        }
                        None => g.add_directed_basis_row(
                            Flank::Drive,
                            &poses[i].stencil,
                            node,
                            NodeDirection::Normal,
                            share,
                            &mut tmp[i],
                        ),
                    }
                };
                load(slave, k, 1.0, None);
                for &(node, share) in &hit.master_shares {
                    load(master, node, share, Some(hit.master_normal));
                }
                for i in 0..2 {
                    for (f, t) in out.force[i][1..].iter_mut().zip(&tmp[i]) {
                        *f -= force * t;
                    }
                    if let Some(section) = section.as_mut() {
                        section.rows[i][1..].copy_from_slice(&tmp[i]);
                    }
                }
                for i in 0..2 {
                    out.force[i][0] -= force * alpha_slope[i];
                }
                if let Some(mut section) = section {
                    for i in 0..2 {
                        section.rows[i][0] = alpha_slope[i];
                    }
                    sections.push(section);
                }
                out.normal_force_n += force;
                out.potential_j += 0.5 * stiffness * hit.alpha_m * hit.alpha_m;
                out.tangent_stiffness_n_per_m += stiffness;
                // The tooth pair by gear 2's tooth in its reduced pose.
                let tooth2 = if slave == 1 { grid.teeth[slot] } else { hit_tooth(model, &hit) };
                match pair_forces.iter_mut().find(|(j, _)| *j == tooth2 as i64) {
                    Some(entry) => entry.1 += force,
                    None => pair_forces.push((tooth2 as i64, force)),
                }
            }
        }
    }
    if damped {
        super::contact::apply_mesh_damper(model, poses, &sections, damper_n_s_per_m, &mut out);
    }
    out.normal_force_n += out.damper_force_n;
    pair_forces.sort_by_key(|&(j, _)| j);
    out.pairs_in_contact = pair_forces.len() as u32;
    out.pair_forces = pair_forces;
    if collect_rows {
        out.sections = sections;
    }
    Ok(out)
}

/// Gear 2's tooth of a gear-1 node's contact: the master's tooth, read off its shares' first node.
fn hit_tooth(model: &PmorModel, hit: &NodePenetration) -> usize {
    let grid = &model.gears[1].flank(Flank::Drive).grid;
    let per_tooth = grid.row_radius_m.len() * grid.layer_z_m.len();
    grid.teeth[hit.master_shares[0].0 / per_tooth]
}
