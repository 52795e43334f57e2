//! The loadable flank of a gear found on its FE mesh: the contact-side flank nodes of the teeth
//! that can mesh, as the structured grid of `contact::flank_grid` (the grid itself, and the
//! interpolation and Hertz load shares on it, are online code the FMU runs).

pub use crate::contact::flank_grid::{FlankGrid, Shares};
use crate::contact::mesh_kinematics::{Flank, PairPlacement};
use crate::fe::gear_mesh::GearMesh;

impl FlankGrid {
    /// The `flank` (drive or coast) of gear `gear` of a pair (0: gear 1, 1: gear 2) on `teeth`,
    /// placed as `contact::mesh_kinematics` places the pair: gear 1 keeps its axial coordinate;
    /// gear 2 is turned over, so its own z is the world's −z and its layers come in reverse
    /// order. The drive flanks are gear 1's side +1 and gear 2's side −1 (`Flank::side`).
    pub fn contact_flank(gm: &GearMesh, gear: usize, flank: Flank, teeth: &[usize]) -> Result<Self, String> {
        match gear {
            0 | 1 => Self::new(gm, flank.side(gear), teeth, gear == 1),
            _ => Err(format!("a gear pair has gears 0 and 1, not {gear}")),
        }
    }

    /// The `flank` of gear `gear` on the teeth of the tooth pairs that can touch in one pitch
    /// (`PairPlacement::pairs_in_reach`), plus `margin` pairs on each side; for the coast flanks
    /// the teeth the half turn maps them to (`PairPlacement::half_turn_teeth`).
    pub fn contact_flank_in_reach(
        gm: &GearMesh,
        gear: usize,
        flank: Flank,
        place: &PairPlacement,
        margin: i64,
    ) -> Result<Self, String> {
        let z = gm.teeth as i64;
        let reach = place.pairs_in_reach();
        let mut teeth: Vec<usize> = Vec::new();
        for j in *reach.start() - margin..=*reach.end() + margin {
            let t = j.rem_euclid(z) as usize;
            let t = match flank {
                Flank::Drive => t,
                Flank::Coast => place.half_turn_teeth([t, t])[gear],
            };
            if !teeth.contains(&t) {
                teeth.push(t);
            }
        }
        Self::contact_flank(gm, gear, flank, &teeth)
    }

    /// The flank nodes of `side` (+1 / −1) on `teeth`; `turned_over`: world z = −own z.
    fn new(gm: &GearMesh, side: i8, teeth: &[usize], turned_over: bool) -> Result<Self, String> {
        let radius = |n: usize| gm.mesh.nodes[n][0].hypot(gm.mesh.nodes[n][1]);
        let on_side: Vec<_> = gm.flank_nodes.iter().filter(|f| f.side == side && f.tooth == teeth[0]).collect();
        let mut rows: Vec<f64> = on_side.iter().map(|f| radius(f.node)).collect();
        rows.sort_by(f64::total_cmp);
        rows.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        let layers = on_side.iter().map(|f| f.slice).max().ok_or("the gear mesh has no flank nodes")? + 1;
        let mut layer_z = vec![0.0; layers];
        let mut nodes = vec![(usize::MAX, [0.0; 3]); teeth.len() * rows.len() * layers];
        for f in &gm.flank_nodes {
            let Some(t) = teeth.iter().position(|&t| t == f.tooth) else { continue };
            if f.side != side {
                continue;
            }
            let r = radius(f.node);
            let row = rows.iter().position(|&q| (q - r).abs() < 1e-9).ok_or("flank rows differ between teeth")?;
            let (layer, z_sign) = if turned_over { (layers - 1 - f.slice, -1.0) } else { (f.slice, 1.0) };
            layer_z[layer] = z_sign * gm.mesh.nodes[f.node][2];
            nodes[(t * rows.len() + row) * layers + layer] = (f.node, f.normal);
        }
        if nodes.iter().any(|n| n.0 == usize::MAX) {
            return Err("the flank grid has holes: not a structured gear mesh".into());
        }
        let node_xy = nodes.iter().map(|&(n, _)| [gm.mesh.nodes[n][0], gm.mesh.nodes[n][1]]).collect();
        Ok(FlankGrid { teeth: teeth.to_vec(), row_radius_m: rows, layer_z_m: layer_z, nodes, node_xy })
    }
}
