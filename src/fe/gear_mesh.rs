//! A structured hex8 mesh of a whole gear, every tooth meshed alike (a rotation by one pitch
//! maps nodes onto nodes, so tooth periodicity is exact).
//!
//! One tooth sector (|φ| ≤ π/z about the tooth axis) is meshed in polar coordinates:
//! - the rim/web block, bore → root circle: radial rows graded towards the root; its angular
//!   nodes blend from uniform at the bore to the tooth's root nodes at the root circle;
//! - the tooth block, root circle → tip: rows at radii dense near root and tip
//!   (sin² spacing), lateral nodes at φ = ζ·ψ(r), ζ ∈ [−1, 1], with ψ the real half-thickness
//!   angle (generated fillet, then involute). Where the fillets leave a bottom land on the root
//!   circle, one extra column on each side reaches the sector border.
//! The section is extruded in axial slices; helical gears turn each section by z·tan β/r
//! (right hand: counter-clockwise, seen from +z, as z grows). z sectors share their borders.

use super::mesh::Mesh;
pub use crate::gear::mesh_spec::{MeshSpec, ProfileGrading};
use crate::gear::{Gear, GearPair};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The fewest axial slices a helical pair of contact depth `depth_m` needs: a slice of length
/// Δz shifts the helical flank by Δz·tan β_b along the transverse contact normal, and the
/// partial models of depth h must reach past that, Δz·tan β_b < h; with the margin
/// `SLICE_DEPTH_MARGIN` (1.8, the Kurokawa helical spec's 8 slices). 1 for a spur pair.
pub fn axial_slices_for(pair: &GearPair, depth_m: f64) -> usize {
    let shift = pair.face_width_m * pair.base_helix_angle_rad.tan();
    (SLICE_DEPTH_MARGIN * shift / depth_m).ceil().max(1.0) as usize
}

/// Δz·tan β_b is kept below h / `SLICE_DEPTH_MARGIN` by `axial_slices_for`.
pub const SLICE_DEPTH_MARGIN: f64 = 1.8;

/// A flank node: which tooth, side and slice it belongs to, its outward unit normal and roll.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FlankNode {
    pub node: usize,
    pub tooth: usize,
    /// −1: flank on the clockwise side of the tooth axis; +1: counter-clockwise side.
    pub side: i8,
    pub slice: usize,
    pub normal: [f64; 3],
    /// Involute roll angle √((r/r_b)² − 1) (rad).
    pub roll_angle_rad: f64,
}

/// The mesh of one gear with its node sets.
#[derive(Debug, Clone)]
pub struct GearMesh {
    pub mesh: Mesh,
    pub bore_nodes: Vec<usize>,
    pub flank_nodes: Vec<FlankNode>,
    pub teeth: usize,
    /// Nodes per tooth sector and axial layer (the periodicity of the numbering).
    pub nodes_per_sector: usize,
}

impl GearMesh {
    /// The node that `node` becomes when the gear is turned on by `teeth` pitches (counter-
    /// clockwise seen from +z for positive `teeth`): the same layer and place in the sector
    /// `teeth` on. Node numbering is l·z·n_sector + k·n_sector + local.
    pub fn node_turned_by_teeth(&self, node: usize, teeth: i64) -> usize {
        let per_sector = self.nodes_per_sector;
        let per_layer = self.teeth * per_sector;
        let (l, rest) = (node / per_layer, node % per_layer);
        let (k, local) = (rest / per_sector, rest % per_sector);
        l * per_layer + ((k as i64 + teeth).rem_euclid(self.teeth as i64) as usize) * per_sector + local
    }

    /// The one-tooth rotation P of a nodal field (all nodes, 3 per node):
    /// (P f)(layer l, sector k) = R(−2π/z)·f(l, k + shift); `shift` = −1 gives P⁻¹ (with
    /// R(+2π/z)), which carries a field on tooth k onto tooth k + 1. The mesh is exactly cyclic,
    /// so P maps the response to a load onto the response to the turned load.
    pub fn rotate_by_teeth(&self, field: &[f64], shift: i64) -> Vec<f64> {
        let angle = -(shift as f64) * 2.0 * PI / self.teeth as f64;
        let (s, c) = angle.sin_cos();
        let mut out = vec![0.0; field.len()];
        for node in 0..field.len() / 3 {
            let from = self.node_turned_by_teeth(node, shift);
            let (fx, fy, fz) = (field[3 * from], field[3 * from + 1], field[3 * from + 2]);
            out[3 * node] = c * fx - s * fy;
            out[3 * node + 1] = s * fx + c * fy;
            out[3 * node + 2] = fz;
        }
        out
    }

    /// The node each node lands on under the half turn about the gear's x axis,
    /// (x, y, z) → (x, −y, −z). Every tooth is meshed symmetric about its axis and the face
    /// about its mid-plane, and a rotation keeps the hand of helix, so the mesh maps onto itself:
    /// tooth k onto tooth −k, side ±1 onto ∓1 (the coast flanks onto the drive flanks).
    /// `Err` if some node has no image (a mesh that is not symmetric).
    pub fn half_turn_about_x(&self) -> Result<Vec<usize>, String> {
        // Nodes are at least micrometres apart; positions are matched on a 10 nm grid, with
        // the neighbouring cells searched for images that round to the other side of a cell.
        const CELL_M: f64 = 1e-8;
        let key = |p: [f64; 3]| p.map(|v| (v / CELL_M).round() as i64);
        let mut cells: std::collections::HashMap<[i64; 3], Vec<usize>> = std::collections::HashMap::new();
        for (n, p) in self.mesh.nodes.iter().enumerate() {
            cells.entry(key(*p)).or_default().push(n);
        }
        let size = self.mesh.nodes.iter().flatten().fold(0.0_f64, |a, v| a.max(v.abs()));
        self.mesh
            .nodes
            .iter()
            .enumerate()
            .map(|(n, p)| {
                let image = [p[0], -p[1], -p[2]];
                let k = key(image);
                let mut best: Option<(f64, usize)> = None;
                for d in 0..27 {
                    let cell = [k[0] + d % 3 - 1, k[1] + (d / 3) % 3 - 1, k[2] + d / 9 - 1];
                    for &m in cells.get(&cell).into_iter().flatten() {
                        let q = self.mesh.nodes[m];
                        let dist =
                            ((q[0] - image[0]).powi(2) + (q[1] - image[1]).powi(2) + (q[2] - image[2]).powi(2)).sqrt();
                        if best.map_or(true, |b| dist < b.0) {
                            best = Some((dist, m));
                        }
                    }
                }
                match best {
                    Some((dist, m)) if dist <= 1e-12 * size.max(1.0) + 1e-12 => Ok(m),
                    _ => Err(format!(
                        "node {n} at {p:?} has no image under the half turn about x: the mesh is not symmetric"
                    )),
                }
            })
            .collect()
    }

    /// A nodal field (3 per node) carried by the half turn: the field at each node's image,
    /// turned, (u_x, u_y, u_z) → (u_x, −u_y, −u_z). `image` is [`GearMesh::half_turn_about_x`].
    pub fn half_turn_field(image: &[usize], field: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; field.len()];
        for (n, &m) in image.iter().enumerate() {
            out[3 * n] = field[3 * m];
            out[3 * n + 1] = -field[3 * m + 1];
            out[3 * n + 2] = -field[3 * m + 2];
        }
        out
    }
}

/// The transverse section of one sector: node positions (r, φ) and the index layout.
struct Sector {
    /// (r, φ) of the body nodes, row-major (rim rows × angular columns, the last column excluded:
    /// it is the next sector's first).
    body: Vec<(f64, f64)>,
    body_rows: usize,
    body_columns: usize,
    /// Offset of the tooth's root nodes in the body's top row (1 with a bottom land, else 0).
    land: usize,
    /// (r, φ) of the tooth nodes above the root circle, row-major.
    tooth: Vec<(f64, f64)>,
    tooth_rows: usize,
    lateral: usize,
}

fn sector(gear: &Gear, alpha_t: f64, spec: &MeshSpec) -> Sector {
    let z = gear.teeth as f64;
    let half_pitch = PI / z;
    let (r_root, psi_root) = gear.fillet.first().copied().unwrap_or((gear.root_radius_m, half_pitch));
    let psi = |r: f64| if r <= r_root { psi_root } else { gear.profile_half_thickness_angle(r, alpha_t) };
    let n_lat = spec.elements_across_tooth;
    let land = (half_pitch - psi_root > 1e-6) as usize;
    let columns = n_lat + 2 * land; // angular segments of the body
                                    // Angles of the body's top row: the tooth root nodes, plus the sector border if a land exists.
    let top: Vec<f64> = (0..=columns)
        .map(|j| {
            if land == 1 && j == 0 {
                -half_pitch
            } else if land == 1 && j == columns {
                half_pitch
            } else {
                let zeta = -1.0 + 2.0 * (j - land) as f64 / n_lat as f64;
                zeta * psi_root
            }
        })
        .collect();
    let n_rim = spec.elements_in_rim;
    let (r_bore, r_f) = (gear.bore_radius_m, r_root);
    let mut body = Vec::new();
    for i in 0..=n_rim {
        // Geometric grading: each row 1.3× thinner than the one below, towards the root.
        let g: f64 = 1.0 / 1.3;
        let s = if n_rim == 0 { 1.0 } else { (1.0 - g.powi(i as i32)) / (1.0 - g.powi(n_rim as i32)) };
        let r = r_bore + (r_f - r_bore) * s;
        for j in 0..columns {
            let uniform = -half_pitch + 2.0 * half_pitch * j as f64 / columns as f64;
            body.push((r, (1.0 - s) * uniform + s * top[j]));
        }
    }
    let n_prof = spec.elements_along_profile;
    let mut tooth = Vec::new();
    for k in 1..=n_prof {
        let t = k as f64 / n_prof as f64;
        let s = match spec.profile_grading {
            ProfileGrading::RootAndTip => (0.5 * PI * t).sin().powi(2),
            ProfileGrading::Uniform => t,
        };
        let r = r_f + (gear.tip_radius_m - r_f) * s;
        let half = psi(r);
        for j in 0..=n_lat {
            tooth.push((r, (-1.0 + 2.0 * j as f64 / n_lat as f64) * half));
        }
    }
    Sector { body, body_rows: n_rim + 1, body_columns: columns, land, tooth, tooth_rows: n_prof, lateral: n_lat + 1 }
}

/// Meshes one gear of the pair.
pub fn mesh_gear(pair: &GearPair, gear: &Gear, spec: &MeshSpec) -> GearMesh {
    let alpha_t = pair.transverse_pressure_angle_rad;
    let sec = sector(gear, alpha_t, spec);
    let z = gear.teeth as usize;
    let n_ax = spec.axial_slices;
    let per_sector = sec.body.len() + sec.tooth.len();
    let per_layer = z * per_sector;
    let b = pair.face_width_m;
    // The transverse profile turns with z by the lead: tan β / r rad per metre, in the sense of
    // the gear's hand of helix.
    let twist = |zc: f64| zc * gear.helix_hand.sign() * pair.helix_angle_rad.tan() / gear.pitch_radius_m;

    let body_id = |l: usize, k: usize, i: usize, j: usize| {
        let (k, j) = if j == sec.body_columns { ((k + 1) % z, 0) } else { (k, j) };
        l * per_layer + k * per_sector + i * sec.body_columns + j
    };
    let tooth_id = |l: usize, k: usize, row: usize, j: usize| {
        if row == 0 {
            body_id(l, k, sec.body_rows - 1, j + sec.land)
        } else {
            l * per_layer + k * per_sector + sec.body.len() + (row - 1) * sec.lateral + j
        }
    };

    let mut nodes = Vec::with_capacity(per_layer * (n_ax + 1));
    for l in 0..=n_ax {
        let zc = -0.5 * b + b * l as f64 / n_ax as f64;
        for k in 0..z {
            let turn = 2.0 * PI * k as f64 / z as f64 + twist(zc);
            for &(r, phi) in sec.body.iter().chain(&sec.tooth) {
                nodes.push([r * (phi + turn).cos(), r * (phi + turn).sin(), zc]);
            }
        }
    }

    // Hexahedra: counter-clockwise in the section (radius, then angle), lower layer first.
    let hexahedron = |l: usize, corner: &dyn Fn(usize, usize) -> usize| -> [usize; 8] {
        [0, 1, 2, 3]
            .map(|c| corner(l, c))
            .into_iter()
            .chain([0, 1, 2, 3].map(|c| corner(l + 1, c)))
            .collect::<Vec<_>>()
            .try_into()
            .unwrap()
    };
    let mut elements = Vec::new();
    for l in 0..n_ax {
        for k in 0..z {
            for i in 0..sec.body_rows - 1 {
                for j in 0..sec.body_columns {
                    let corner = |layer: usize, c: usize| match c {
                        0 => body_id(layer, k, i, j),
                        1 => body_id(layer, k, i + 1, j),
                        2 => body_id(layer, k, i + 1, j + 1),
                        _ => body_id(layer, k, i, j + 1),
                    };
                    elements.push(hexahedron(l, &corner));
                }
            }
            for row in 0..sec.tooth_rows {
                for j in 0..sec.lateral - 1 {
                    let corner = |layer: usize, c: usize| match c {
                        0 => tooth_id(layer, k, row, j),
                        1 => tooth_id(layer, k, row + 1, j),
                        2 => tooth_id(layer, k, row + 1, j + 1),
                        _ => tooth_id(layer, k, row, j + 1),
                    };
                    elements.push(hexahedron(l, &corner));
                }
            }
        }
    }

    let bore_nodes = (0..=n_ax)
        .flat_map(|l| (0..z).flat_map(move |k| (0..sec.body_columns).map(move |j| (l, k, j))))
        .map(|(l, k, j)| body_id(l, k, 0, j))
        .collect();

    // Flank nodes: the tooth's lateral borders on the involute (at or above the form circle).
    let r_form = gear.form_radius_m.max(gear.base_radius_m);
    let mut flank_nodes = Vec::new();
    for l in 0..=n_ax {
        for k in 0..z {
            for row in 1..=sec.tooth_rows {
                let (r, _) = sec.tooth[(row - 1) * sec.lateral];
                if r < r_form {
                    continue;
                }
                for (side, j) in [(-1i8, 0usize), (1, sec.lateral - 1)] {
                    let node = tooth_id(l, k, row, j);
                    flank_nodes.push(FlankNode {
                        node,
                        tooth: k,
                        side,
                        slice: l,
                        normal: flank_normal(pair, gear, alpha_t, r, side, nodes[node]),
                        roll_angle_rad: ((r / gear.base_radius_m).powi(2) - 1.0).max(0.0).sqrt(),
                    });
                }
            }
        }
    }
    GearMesh { mesh: Mesh { nodes, elements }, bore_nodes, flank_nodes, teeth: z, nodes_per_sector: per_sector }
}

/// Outward unit normal of the flank surface through `point` (radius r, side ±1): from the
/// tangents of the surface P(r, z) = Rot(turn(z))·(r cos ψ(r)·side…, z), by finite differences.
fn flank_normal(pair: &GearPair, gear: &Gear, alpha_t: f64, r: f64, side: i8, point: [f64; 3]) -> [f64; 3] {
    let s = side as f64;
    let phi_at = |rr: f64| s * gear.profile_half_thickness_angle(rr, alpha_t);
    let base_angle = point[1].atan2(point[0]) - phi_at(r);
    let twist_rate = gear.helix_hand.sign() * pair.helix_angle_rad.tan() / gear.pitch_radius_m;
    let surface = |rr: f64, dz: f64| {
        let a = base_angle + phi_at(rr) + twist_rate * dz;
        [rr * a.cos(), rr * a.sin(), point[2] + dz]
    };
    let h = 1e-7;
    let (p1, p0) = (surface(r + h, 0.0), surface(r - h, 0.0));
    let (q1, q0) = (surface(r, h), surface(r, -h));
    let t_r = [p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]];
    let t_z = [q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2]];
    let mut n =
        [t_r[1] * t_z[2] - t_r[2] * t_z[1], t_r[2] * t_z[0] - t_r[0] * t_z[2], t_r[0] * t_z[1] - t_r[1] * t_z[0]];
    let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    n = n.map(|v| v / norm);
    // Outward: away from the tooth axis, i.e. along +side·e_φ at the point.
    let a = point[1].atan2(point[0]);
    let e_phi = [-a.sin(), a.cos(), 0.0];
    if (n[0] * e_phi[0] + n[1] * e_phi[1]) * s < 0.0 {
        n = n.map(|v| -v);
    }
    n
}

/// The exact transverse area of the gear (bore excluded), by quadrature of the profile
/// (`Gear::section_moments`). Independent of the mesh.
pub fn section_area(pair: &GearPair, gear: &Gear) -> f64 {
    gear.section_moments(pair.transverse_pressure_angle_rad).0
}
