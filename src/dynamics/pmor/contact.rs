//! Contact of the reduced pair: the statics' contact search (`contact::mesh_kinematics`), Hertz
//! law (`contact::hertz`) and pressure band (`rom::flank`), on the deformed flanks
//! u = P^k·V(ϑ)η of the teeth near the line of action.
//!
//! Per tooth pair j and axial section the penetration is α = α₀(θ₁, θ₂) + Σᵢ nᵢᵀuᵢ at the
//! contact point of the rigid search (the deformation enters along the flank normals, as in the
//! statics); the force P(α) inverts the load–approach relation; its generalized forces are
//! P·Vᵀ(band shares) on η (the Hertz pressure band, as in the statics) and −∂W/∂θᵢ on the
//! angles, W = P·α − W*(P) the contact potential that the energy balance counts.
//!
//! ∂W/∂θᵢ at fixed η = P·∂α/∂θᵢ + ∂W/∂R·∂R/∂θᵢ. For conjugate contact it is exact and cheap:
//! the contact point sits on the line of action at u = u_C + r_b2·θ₂ (+ the helix's axial
//! shift), so α₀ = cos β_b·(r_b1θ₁ − r_b2θ₂) + const, both flank radii and the radii of
//! curvature move with θ₂ alone, and each gear's nᵀu changes through the point sliding along
//! the flank (the bilinear shares and the interpolated normal) and through the shapes turning
//! with the gear (Ψ'(ϑ)). At a tip corner the geometry has no such closed form and ∂α/∂θ is a
//! central difference of the same search at fixed η.
//!
//! A tooth on gear i at pitch anchor kᵢ (θᵢ = kᵢ·pitch + ϑᵢ) carries the field of reference tooth
//! t + kᵢ: the one-tooth rotation P moves content of tooth t + 1 onto tooth t.
//!
//! Both flanks are searched. The coast flanks touch across the backlash (TE < −j): their
//! contact is the drive contact of the half-turned pose (`PairPlacement::flank_contact`), read
//! on the coast flank's own rows of Φ and of the shapes (the reduced basis carries shapes loaded
//! on each flank), with the same law and band; its angle forces follow the half turn's reversed
//! angles.

use super::equations::Stencil;
use super::model::{NodeDirection, PmorModel};
use crate::contact::mesh_kinematics::{line_of_action_point_m, ContactKind, Flank, PairPlacement, SectionContact};
use crate::dynamics::mesh_friction::SlidingFriction;

/// Angle step of the central differences ∂α/∂θ at tip corners (rad).
const ANGLE_STEP: f64 = 1e-7;

/// The kinematic state of one gear that the contact reads.
pub struct GearPose<'a> {
    pub theta: f64,
    pub anchor: i64,
    pub stencil: Stencil,
    pub eta: &'a [f64],
    /// (θ̇, η̇): what the mesh damper reads (empty where no damper acts).
    pub velocity: &'a [f64],
}

/// What the contact puts on the pair.
#[derive(Debug, Clone, Default)]
pub struct ContactLoads {
    /// Generalized forces on (θᵢ, ηᵢ), per gear.
    pub force: [Vec<f64>; 2],
    /// Total normal force (N): positive on the drive flanks, negative on the coast flanks.
    pub normal_force_n: f64,
    pub pairs_in_contact: u32,
    /// Contact potential Σ W (J).
    pub potential_j: f64,
    /// Σ dP/dα (N/m), the Hertz tangent stiffness of the loaded sections in parallel.
    pub tangent_stiffness_n_per_m: f64,
    /// Force per tooth pair (N, negative on the coast flanks), with its pair index j in the pose
    /// where its flanks drive (`PairPlacement::flank_contact`).
    pub pair_forces: Vec<(i64, f64)>,
    /// The mesh damper's part of `force` with the sign of Dq̇, per gear over (θ, η), its force
    /// (N, signed as `normal_force_n`) and its power Σ F_d·α̇ ≥ 0 (W).
    pub damping_force: [Vec<f64>; 2],
    pub damper_force_n: f64,
    pub damper_power_w: f64,
    /// Tooth friction (`apply_tooth_friction`; zero without it): the friction forces' sum
    /// (N, each signed as its sliding) and their power Σ f·v ≥ 0 (W). Its generalized forces (on
    /// the angles and the elastic coordinates) are part of `force` and `damping_force`, as the
    /// damper's are.
    pub friction_force_n: f64,
    pub friction_power_w: f64,
    /// The loaded sections' rows, where asked for (the mesh damper, the quasi-static
    /// condensation's Newton): empty otherwise.
    pub sections: Vec<SectionRows>,
}

/// One loaded section: its elastic force, its Hertz tangent stiffness and the row through
/// which its force enters each gear's coordinates — what the mesh damper reads (on θ and η_Φ)
/// and what the quasi-static condensation's tangent stiffness Σ k_s·r rᵀ is made of.
#[derive(Debug, Clone)]
pub struct SectionRows {
    pub flank_sign: f64,
    /// The contact point u (m from T₁) on its flank's transverse line of action
    /// (`mesh_kinematics::line_of_action_point_m`): tooth friction's arms are u and T₁T₂ − u.
    pub point_m: f64,
    pub force_n: f64,
    pub stiffness_n_per_m: f64,
    /// Per gear over (θ, η_Φ, η_Ψ): ∂α/∂θ, then the band's rows of the basis along the flank
    /// normal (the generalized force on η is −force·row).
    pub rows: [Vec<f64>; 2],
    /// Where tooth friction is on (empty otherwise), per gear over (θ, η_Φ, η_Ψ): the rows of
    /// the deformed flanks' sliding v = s₁·q̇₁ + s₂·q̇₂ (m/s, positive where gear 1's flank runs
    /// ahead of gear 2's), `sliding_rows`. Friction f acts on gear i's coordinates as −f·sᵢ.
    pub sliding_rows: [Vec<f64>; 2],
}

/// The rows of a section's sliding (`SectionRows::sliding_rows`), per gear: on η the band's rows
/// along the flank's transverse tangent t, with the flank's sign; on θ the rigid arm of
/// `mesh_friction` (u on gear 1, −(T₁T₂ − u) on gear 2: the sliding ω₁u − ω₂(T₁T₂ − u)) and the
/// same band's tᵀ∂u/∂ϑ, the shapes' turning with the gear (the material's rate is V·η̇ + θ̇·V_ϑ·η:
/// as the load rolls on, the deformation moves through both). Why the flank's sign: a turn of
/// gear i in its mesh sense moves its flank point along τᵢ at speed ρᵢ, and the tangent
/// (`FlankGrid::transverse_tangent`) is oriented with the turn that pushes the flank into
/// contact. On the drive flanks gear 1's mesh sense pushes (∂α/∂θ₁ > 0) and gear 2's retreats
/// (∂α/∂θ₂ < 0), so τ₁ = t₁ and τ₂ = −t₂; gear 1's material runs along τ₁ by t₁ᵀu̇₁, gear 2's
/// by −t₂ᵀu̇₂, and the sliding, their difference, takes +t₁ᵀu̇₁ + t₂ᵀu̇₂. The coast flanks turn
/// both signs. The two τ are one direction in the world: at the pitch point the flanks roll.
#[allow(clippy::too_many_arguments)]
fn add_sliding_rows(
    g: &super::model::PmorGear,
    i: usize,
    flank: Flank,
    pose: &GearPose,
    loa_m: f64,
    point_m: f64,
    band: &[(usize, f64)],
    rows: &mut [f64],
) {
    let sign = flank.sign();
    let mut turning = 0.0;
    for &(k, w) in band {
        g.add_directed_basis_row(flank, &pose.stencil, k, NodeDirection::Tangent, sign * w, &mut rows[1..]);
        turning += sign * w * g.directed_turning(flank, &pose.stencil, k, NodeDirection::Tangent, pose.eta);
    }
    let arm = if i == 0 { point_m } else { -(loa_m - point_m) };
    rows[0] = arm + turning;
}

/// Gear i's elastic approach at a contact point: nᵀũ, with n the flank normal and ũ the
/// displacement interpolated there, and its derivatives along the flank radius and in the
/// gear's angle at fixed η.
struct ElasticApproach {
    value_m: f64,
    per_radius: f64,
    per_angle_m: f64,
    /// The reference tooth the point lies on, its shares and normal (for the loads).
    tooth: usize,
    shares: [(usize, f64); 4],
    normal: [f64; 3],
}

/// A section contact on one flank: the search's result in the pose where that flank drives
/// (`PairPlacement::flank_contact`), with the FE teeth and the axial section of this pose.
struct Located {
    c: SectionContact,
    teeth: [usize; 2],
    section: usize,
}

impl Located {
    /// The same contact in another axial section (a spur pair's search does not depend on z).
    /// Only the modifications' axial part (crowning, slope, end relief, misalignment) changes
    /// with z; a deviation is a profile part plus an axial part (`FlankModification::deviation_m`),
    /// so the change is the same for every candidate and the choice among them stands.
    fn in_section(
        &self,
        place: &PairPlacement,
        flank: Flank,
        search_section: usize,
        z: f64,
        sections: usize,
    ) -> Located {
        let mut c = self.c;
        if place.is_modified() {
            c.rigid_penetration_m += place.modification_m(c.radius_m, c.z_m) - place.modification_m(c.radius_m, z);
        }
        c.section = search_section;
        c.z_m = z;
        let section = match flank {
            Flank::Drive => search_section,
            Flank::Coast => sections - 1 - search_section,
        };
        Located { c, teeth: self.teeth, section }
    }
}

/// The contact of tooth pair j on `flank`, searched in section `search_section` (mid-plane
/// `z`) of the pose where that flank drives.
fn locate(
    place: &PairPlacement,
    flank: Flank,
    theta: [f64; 2],
    j: i64,
    search_section: usize,
    z: f64,
    sections: usize,
) -> Option<Located> {
    let c = place.flank_contact(flank, theta, j, search_section, z)?;
    Some(match flank {
        Flank::Drive => Located { c, teeth: c.teeth, section: search_section },
        Flank::Coast => Located { c, teeth: place.half_turn_teeth(c.teeth), section: sections - 1 - search_section },
    })
}

/// The displacements u and ∂u/∂ϑ of the flank nodes one contact evaluation has read, for one
/// gear and flank at one pose: neighbouring axial sections share a layer of nodes and the tip
/// corners' differences read the same nodes again, so most reads repeat. Found by the node's
/// hash (open addressing): a list searched end to end took a tenth of a helical pair's
/// evaluation, whose sections read a hundred nodes and more.
struct NodeDisplacements {
    /// Per hash slot, 1 + the node's place in `read` (0: empty).
    slots: [u32; NODE_SLOTS],
    read: Vec<(usize, [f64; 3], [f64; 3])>,
}

/// Hash slots of `NodeDisplacements`: a power of two, four times the most nodes an evaluation
/// reads of one gear (beyond three quarters full, a node is read without being kept).
const NODE_SLOTS: usize = 1024;

impl NodeDisplacements {
    fn new() -> Self {
        NodeDisplacements { slots: [0; NODE_SLOTS], read: Vec::with_capacity(64) }
    }

    fn get(&mut self, g: &super::model::PmorGear, flank: Flank, pose: &GearPose, node: usize) -> ([f64; 3], [f64; 3]) {
        // Fibonacci hashing: the top bits of node·2⁶⁴/φ.
        let mut slot = (node as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (64 - NODE_SLOTS.trailing_zeros());
        loop {
            match self.slots[slot as usize] {
                0 => break,
                kept => {
                    let (k, u, du) = self.read[kept as usize - 1];
                    if k == node {
                        return (u, du);
                    }
                    slot = (slot + 1) % NODE_SLOTS as u64;
                }
            }
        }
        let (u, du) = g.node_displacement(flank, &pose.stencil, node, pose.eta);
        if 4 * self.read.len() < 3 * NODE_SLOTS {
            self.read.push((node, u, du));
            self.slots[slot as usize] = self.read.len() as u32;
        }
        (u, du)
    }
}

/// Gear i's elastic approach at `at`, its nodes read through `nodes` (the pose's own). With the
/// gear turned by `turn` (rad) from its pose at fixed η, each node's displacement is taken as
/// u + turn·∂u/∂ϑ: the tip corners' central differences turn by 10⁻⁷ rad, where the term left
/// out, ½turn²·∂²u/∂ϑ², cancels in the difference.
fn elastic_approach(
    model: &PmorModel,
    i: usize,
    flank: Flank,
    pose: &GearPose,
    at: &Located,
    nodes: &mut NodeDisplacements,
    turn: f64,
) -> Result<ElasticApproach, String> {
    let g = &model.gears[i];
    let grid = &g.flank(flank).grid;
    let z = g.teeth as i64;
    let tooth = (at.teeth[i] as i64 + pose.anchor).rem_euclid(z) as usize;
    let (shares, slopes) = grid.point_stencil(tooth, at.c.radius_m[i], at.section).ok_or_else(|| {
        format!("contact on reference tooth {tooth} of gear {} ({flank:?} flank): outside the stored flank rows", i + 1)
    })?;
    // n = m/|m| with m = Σ w·nₖ; dn/dr = (m' − n(n·m'))/|m|.
    let (mut m, mut dm) = ([0.0; 3], [0.0; 3]);
    let (mut u, mut du_dr, mut du_dtheta) = ([0.0; 3], [0.0; 3], [0.0; 3]);
    for (&(k, w), &(_, dw)) in shares.iter().zip(&slopes) {
        let n_k = grid.nodes[k].1;
        let (u_k, du_k) = nodes.get(g, flank, pose, k);
        let u_k = [0, 1, 2].map(|c| u_k[c] + turn * du_k[c]);
        for c in 0..3 {
            m[c] += w * n_k[c];
            dm[c] += dw * n_k[c];
            u[c] += w * u_k[c];
            du_dr[c] += dw * u_k[c];
            du_dtheta[c] += w * du_k[c];
        }
    }
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let norm = dot(m, m).sqrt();
    let n = m.map(|v| v / norm);
    let n_dm = dot(n, dm);
    let dn = [0, 1, 2].map(|c| (dm[c] - n[c] * n_dm) / norm);
    Ok(ElasticApproach {
        value_m: dot(n, u),
        per_radius: dot(dn, u) + dot(n, du_dr),
        per_angle_m: dot(n, du_dtheta),
        tooth,
        shares,
        normal: n,
    })
}

/// The penetration and the transverse effective radius of curvature of pair j on `flank`,
/// search section s, with gear `turned.0` turned by `turned.1` (rad) from its pose at fixed η
/// (the tip corners' central differences; the nodes read through `nodes`, the poses' own).
#[allow(clippy::too_many_arguments)]
fn penetration_at(
    model: &PmorModel,
    place: &PairPlacement,
    flank: Flank,
    poses: [&GearPose; 2],
    turned: (usize, f64),
    j: i64,
    section: usize,
    z_mid: f64,
    nodes: &mut [NodeDisplacements; 2],
) -> Result<Option<(f64, f64)>, String> {
    let sections = model.gears[0].flank(flank).grid.layer_z_m.len() - 1;
    let mut theta = [poses[0].theta, poses[1].theta];
    theta[turned.0] += turned.1;
    let Some(at) = locate(place, flank, theta, j, section, z_mid, sections) else {
        return Ok(None);
    };
    let mut alpha = at.c.rigid_penetration_m;
    for (i, nodes) in nodes.iter_mut().enumerate() {
        let turn = if i == turned.0 { turned.1 } else { 0.0 };
        alpha += elastic_approach(model, i, flank, poses[i], &at, nodes, turn)?.value_m;
    }
    Ok(Some((alpha, transverse_radius(&at.c))))
}

fn transverse_radius(c: &SectionContact) -> f64 {
    c.curvature_radius_m[0] * c.curvature_radius_m[1] / (c.curvature_radius_m[0] + c.curvature_radius_m[1])
}

/// ∂α/∂θᵢ and ∂R/∂θᵢ (R transverse) of a conjugate contact at fixed η, in closed form. Each
/// gear's contact point is its own crossing of the line of action (`section_contact`): gear 1's
/// at u₁ from T₁ follows θ₁ alone (du₁/dθ₁ = r_b1), gear 2's at v = L − u from T₂ follows θ₂
/// alone (dv/dθ₂ = −r_b2); their radii and radii of curvature (R₁ = u₁, R₂ = v) travel with
/// them, and so do the flank modifications there (`conjugate_modification_slopes`: without
/// them a tip relief's ramp would be a force the energy balance does not book). The search
/// pose turns as ±θ (`Flank::sign`: the half turn reverses the angles): the rigid approach and
/// the points' travel follow it, the shapes' turning (∂/∂ϑ at a fixed point) follows the gear
/// itself.
fn conjugate_slopes(
    model: &PmorModel,
    place: &PairPlacement,
    flank: Flank,
    c: &SectionContact,
    e: &[ElasticApproach; 2],
) -> ([f64; 2], [f64; 2]) {
    let rb = [model.pair.gear1.base_radius_m, model.pair.gear2.base_radius_m];
    let sign = flank.sign();
    let [u1, v] = c.curvature_radius_m;
    let radius_slope = [u1 * rb[0] / c.radius_m[0], -v * rb[1] / c.radius_m[1]];
    let relief = place.conjugate_modification_slopes(c.radius_m);
    let alpha = [
        sign * (c.arm_ratio * rb[0] + relief[0] + e[0].per_radius * radius_slope[0]) + e[0].per_angle_m,
        sign * (-c.arm_ratio * rb[1] + relief[1] + e[1].per_radius * radius_slope[1]) + e[1].per_angle_m,
    ];
    // R = u₁v/(u₁ + v): ∂R/∂u₁ = v²/(u₁ + v)², ∂R/∂v = u₁²/(u₁ + v)².
    let sum2 = (u1 + v).powi(2);
    (alpha, [sign * rb[0] * v * v / sum2, -sign * rb[1] * u1 * u1 / sum2])
}

/// Where the contact force enters the elastic coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Loading {
    /// The Hertz pressure band integrated over the flank (the statics' loads; the default).
    HertzBand,
    /// A point load at the contact point: exactly the gradient of the penetration, so the contact
    /// force derives from the potential W(α) — the energy test's control case.
    Point,
}

/// The Hertz sections' contact loads on the given flanks (`contact_law::contact_loads`).
#[allow(clippy::too_many_arguments)]
pub fn section_contact_loads(
    model: &PmorModel,
    place: &PairPlacement,
    poses: [&GearPose; 2],
    loading: Loading,
    damper_n_s_per_m: f64,
    friction: Option<SlidingFriction>,
    collect_rows: bool,
    flanks: &[Flank],
) -> Result<ContactLoads, String> {
    let p = &model.pair;
    let n_e = [poses[0].eta.len(), poses[1].eta.len()];
    let mut out = ContactLoads {
        force: [vec![0.0; 1 + n_e[0]], vec![0.0; 1 + n_e[1]]],
        damping_force: [vec![0.0; 1 + n_e[0]], vec![0.0; 1 + n_e[1]]],
        ..Default::default()
    };
    let damped = damper_n_s_per_m > 0.0;
    let collect = damped || collect_rows || friction.is_some();
    let mut sections_loaded: Vec<SectionRows> = Vec::new();
    let layers = &model.gears[0].flank(Flank::Drive).grid.layer_z_m;
    let sections = layers.len() - 1;
    let base = [p.gear1.base_radius_m, p.gear2.base_radius_m];
    let loa = p.loa_length_m();
    let info = &model.info;
    let theta = [poses[0].theta, poses[1].theta];
    let spur = p.base_helix_angle_rad == 0.0;
    let mut band_row = [vec![0.0; n_e[0]], vec![0.0; n_e[1]]];
    for &flank in flanks {
        let searched = place.searched_angles(flank, theta);
        let reach: f64 =
            (0..2).map(|i| model.gears[i].flank_displacement_bound(flank, &poses[i].stencil, poses[i].eta)).sum();
        if !place.flank_can_close(flank, theta, reach) {
            continue; // backed off beyond the deformation's reach (the coast flanks, mostly)
        }
        // The flank nodes read at the poses (the tip corners' differences read them too).
        let mut nodes = [NodeDisplacements::new(), NodeDisplacements::new()];
        for j in place.candidate_pairs(searched[1]) {
            let mut pair_force = 0.0;
            // A spur pair's sections differ only in z, which its contact search does not read
            // (no helix, no twist): one search serves them all.
            let spur_search = spur.then(|| locate(place, flank, theta, j, 0, 0.5 * (layers[0] + layers[1]), sections));
            for s in 0..sections {
                let z_mid = 0.5 * (layers[s] + layers[s + 1]);
                let found = match &spur_search {
                    Some(first) => first.as_ref().map(|at| at.in_section(place, flank, s, z_mid, sections)),
                    None => locate(place, flank, theta, j, s, z_mid, sections),
                };
                let Some(at) = found else { continue };
                let c = &at.c;
                if c.rigid_penetration_m + reach <= 0.0 {
                    continue; // a gap the deformation cannot close (most of the coast flanks)
                }
                let e = [
                    elastic_approach(model, 0, flank, poses[0], &at, &mut nodes[0], 0.0)?,
                    elastic_approach(model, 1, flank, poses[1], &at, &mut nodes[1], 0.0)?,
                ];
                let alpha = c.rigid_penetration_m + e[0].value_m + e[1].value_m;
                if alpha <= 0.0 {
                    continue;
                }
                let law = c.line_contact(p, layers[s + 1] - layers[s], info.depth_m, info.law);
                let force = law.force(alpha)?;
                if force <= 0.0 {
                    continue;
                }
                law.check_half_width(force)
                    .map_err(|m| format!("tooth pair {j}, section {}, {flank:?} flanks: {m}", at.section))?;
                // Generalized forces on η: the Hertz band, pushing into each tooth.
                let beta = law.half_width(force);
                let mut section = collect.then(|| SectionRows {
                    flank_sign: flank.sign(),
                    point_m: line_of_action_point_m(p, c.kind, c.radius_m),
                    force_n: force,
                    stiffness_n_per_m: 1.0 / law.compliance(force),
                    rows: [0, 1].map(|i| vec![0.0; 1 + n_e[i]]),
                    sliding_rows: [0, 1].map(|i| if friction.is_some() { vec![0.0; 1 + n_e[i]] } else { Vec::new() }),
                });
                for i in 0..2 {
                    let g = &model.gears[i];
                    let grid = &g.flank(flank).grid;
                    let (band, normal) = match loading {
                        Loading::HertzBand => (
                            grid.band_shares(e[i].tooth, c.radius_m[i], beta, base[i], at.section)
                                .ok_or("band outside the stored flank")?,
                            None,
                        ),
                        Loading::Point => (e[i].shares.to_vec(), Some(e[i].normal)),
                    };
                    // The band's row Σ w·V_kᵀn_k, then its force.
                    let row = &mut band_row[i];
                    row.fill(0.0);
                    for &(k, w) in &band {
                        match normal {
                            Some(n) => g.add_basis_row(flank, &poses[i].stencil, k, n.map(|c| w * c), row),
                            None => {
                                g.add_directed_basis_row(flank, &poses[i].stencil, k, NodeDirection::Normal, w, row)
                            }
                        }
                    }
                    for (f, r) in out.force[i][1..].iter_mut().zip(row.iter()) {
                        *f -= force * r;
                    }
                    if let Some(section) = section.as_mut() {
                        section.rows[i][1..].copy_from_slice(row);
                        if friction.is_some() {
                            let (point, sliding) = (section.point_m, &mut section.sliding_rows[i]);
                            add_sliding_rows(g, i, flank, poses[i], loa, point, &band, sliding);
                        }
                    }
                }
                // Generalized forces on the angles: −∂W/∂θᵢ at fixed η, W(α(θ), R(θ)): the force
                // along the penetration's change, plus the potential's change with the radii of
                // curvature as the contact point travels (the law's geometry).
                // ∂W/∂R for the transverse R (the law's R is R/cos β_b).
                let dw_dr = law.potential_radius_derivative(force) * law.effective_radius() / transverse_radius(c);
                let (alpha_slope, radius_slope) = match c.kind {
                    ContactKind::Conjugate => conjugate_slopes(model, place, flank, c, &e),
                    ContactKind::TipOfGear1 | ContactKind::TipOfGear2 => {
                        let mut slopes = ([0.0; 2], [0.0; 2]);
                        for i in 0..2 {
                            let up =
                                penetration_at(model, place, flank, poses, (i, ANGLE_STEP), j, s, z_mid, &mut nodes)?;
                            let down =
                                penetration_at(model, place, flank, poses, (i, -ANGLE_STEP), j, s, z_mid, &mut nodes)?;
                            // A difference that leaves the corner's reach contributes nothing.
                            let (Some(up), Some(down)) = (up, down) else { continue };
                            slopes.0[i] = (up.0 - down.0) / (2.0 * ANGLE_STEP);
                            slopes.1[i] = (up.1 - down.1) / (2.0 * ANGLE_STEP);
                        }
                        slopes
                    }
                };
                for i in 0..2 {
                    out.force[i][0] -= force * alpha_slope[i] + dw_dr * radius_slope[i];
                }
                if let Some(mut section) = section {
                    for i in 0..2 {
                        section.rows[i][0] = alpha_slope[i];
                    }
                    sections_loaded.push(section);
                }
                out.normal_force_n += flank.sign() * force;
                out.potential_j += force * alpha - law.complementary_energy(force);
                out.tangent_stiffness_n_per_m += 1.0 / law.compliance(force);
                pair_force += force;
            }
            if pair_force > 0.0 {
                out.pairs_in_contact += 1;
                out.pair_forces.push((j, flank.sign() * pair_force));
            }
        }
    }
    if damped {
        apply_mesh_damper(model, poses, &sections_loaded, damper_n_s_per_m, &mut out);
    }
    if let Some(law) = friction {
        apply_tooth_friction(poses, &sections_loaded, law, &mut out);
    }
    out.normal_force_n += out.damper_force_n;
    if collect_rows {
        out.sections = sections_loaded;
    }
    Ok(out)
}

/// The mesh damper on the loaded sections (see `contact_loads`): c shared in proportion to each
/// section's tangent stiffness, on its approach rate from θ̇ and η̇_Φ (the rows' first 1 + n_k
/// entries), never pulling.
pub(super) fn apply_mesh_damper(
    model: &PmorModel,
    poses: [&GearPose; 2],
    sections: &[SectionRows],
    damper_n_s_per_m: f64,
    out: &mut ContactLoads,
) {
    let slow = [1 + model.gears[0].modes(), 1 + model.gears[1].modes()];
    let total_stiffness: f64 = sections.iter().map(|s| s.stiffness_n_per_m).sum();
    for section in sections {
        let approach_rate: f64 = (0..2)
            .map(|i| section.rows[i][..slow[i]].iter().zip(poses[i].velocity).map(|(r, v)| r * v).sum::<f64>())
            .sum();
        let damper = section_damper_force_n(section, damper_n_s_per_m, total_stiffness, approach_rate);
        for i in 0..2 {
            for (k, r) in section.rows[i][..slow[i]].iter().enumerate() {
                out.force[i][k] -= damper * r;
                out.damping_force[i][k] += damper * r;
            }
        }
        out.damper_force_n += section.flank_sign * damper;
        out.damper_power_w += damper * approach_rate;
    }
}

/// Tooth friction on the loaded sections (`dynamics::mesh_friction`): on each, f = μF_s·v/√(v² + v_ε²)
/// at the deformed flanks' sliding v = s₁·q̇₁ + s₂·q̇₂ (`SectionRows::sliding_rows`: the floating
/// frames' rotation, ω₁u − ω₂(T₁T₂ − u), and the flank nodes' elastic rates along the flank), F_s
/// the section's elastic force, acting on gear i's coordinates as −f·sᵢ: on the angles the
/// torques −f·u and +f·(T₁T₂ − u), on η the teeth bent along the flank. The rates are what the
/// pose carries (every coordinate's on the full pair, the slow motion's on the condensed one,
/// whose fast rates `quasi_static::damp_the_fast_motion` adds). Its forces are booked with the
/// damping forces (the sign of Dq̇), so the integrator counts their work as dissipation: f·v ≥ 0.
pub(super) fn apply_tooth_friction(
    poses: [&GearPose; 2],
    sections: &[SectionRows],
    law: SlidingFriction,
    out: &mut ContactLoads,
) {
    for section in sections {
        let sliding: f64 = (0..2)
            .map(|i| section.sliding_rows[i].iter().zip(poses[i].velocity).map(|(s, v)| s * v).sum::<f64>())
            .sum();
        let f = law.force_n(section.force_n, sliding);
        for i in 0..2 {
            for (k, s) in section.sliding_rows[i].iter().enumerate() {
                out.force[i][k] -= f * s;
                out.damping_force[i][k] += f * s;
            }
        }
        out.friction_force_n += f;
        out.friction_power_w += f * sliding;
    }
}

/// Section s's mesh damper force at approach rate α̇: its share of c in proportion to its
/// stiffness, c_s = c·k_s/Σk, on α̇, bounded below by minus its elastic force so that it never
/// pulls (F_d = max(c_s·α̇, −F_s)).
pub(super) fn section_damper_force_n(
    section: &SectionRows,
    damper_n_s_per_m: f64,
    total_stiffness_n_per_m: f64,
    approach_rate_m_per_s: f64,
) -> f64 {
    let c = damper_n_s_per_m * section.stiffness_n_per_m / total_stiffness_n_per_m;
    (c * approach_rate_m_per_s).max(-section.force_n)
}
