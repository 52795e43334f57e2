//! The loadable flank of a gear: the FE flank nodes of the contact side of the teeth that can
//! mesh, as a structured grid (profile rows × axial layers per tooth), with the two operations
//! the contact needs on it:
//! - interpolation of a nodal field at a contact point (bilinear over the flank face);
//! - the Hertz pressure of an axial section, a semi-ellipse of half-width β across the profile
//!   and uniform along the section, integrated against the same shape functions into nodal
//!   load shares (paper Sect. 4.3, Eqs. 21–22).

use crate::contact::mesh_kinematics::{Flank, PairPlacement};
use crate::fe::gear_mesh::GearMesh;

/// The contact-side flank nodes of some teeth of one gear.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FlankGrid {
    /// Teeth on the grid (FE tooth indices).
    pub teeth: Vec<usize>,
    /// Radii of the flank rows (same on every tooth), ascending.
    pub row_radius_m: Vec<f64>,
    /// Axial positions of the node layers in the pair's world frame, ascending.
    pub layer_z_m: Vec<f64>,
    /// Loadable nodes: (FE node, outward unit normal), tooth-major, then row, then layer.
    pub nodes: Vec<(usize, [f64; 3])>,
    /// Their transverse position (x, y) in the gear's frame.
    pub node_xy: Vec<[f64; 2]>,
}

/// Shares of a unit quantity over loadable nodes: (index into `FlankGrid::nodes`, weight).
pub type Shares = Vec<(usize, f64)>;

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

    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    fn index(&self, tooth_slot: usize, row: usize, layer: usize) -> usize {
        (tooth_slot * self.row_radius_m.len() + row) * self.layer_z_m.len() + layer
    }

    fn tooth_slot(&self, tooth: usize) -> Option<usize> {
        self.teeth.iter().position(|&t| t == tooth)
    }

    /// Row interval and linear weight of a radius (clamped to the flank's extent).
    fn row_of(&self, r: f64) -> (usize, f64) {
        let rows = &self.row_radius_m;
        let i = rows.partition_point(|&q| q <= r).clamp(1, rows.len() - 1) - 1;
        let t = ((r - rows[i]) / (rows[i + 1] - rows[i])).clamp(0.0, 1.0);
        (i, t)
    }

    /// Shares of the point (radius r, mid-plane of axial section `section`) of `tooth`'s flank.
    pub fn point_shares(&self, tooth: usize, r: f64, section: usize) -> Option<Shares> {
        self.point_shares_and_slopes(tooth, r, section).map(|(shares, _)| shares)
    }

    /// [`FlankGrid::point_shares`] and their d/dr: the same nodes, the profile weights' slopes
    /// ∓1/Δr (zero where the radius is clamped to the flank's extent, as the shares are constant
    /// there).
    pub fn point_shares_and_slopes(&self, tooth: usize, r: f64, section: usize) -> Option<(Shares, Shares)> {
        self.point_stencil(tooth, r, section).map(|(shares, slopes)| (shares.to_vec(), slopes.to_vec()))
    }

    /// [`FlankGrid::point_shares_and_slopes`] without allocation: the four nodes, as arrays (the
    /// dynamics' contact reads them at every loaded section at every right-hand side).
    pub fn point_stencil(
        &self,
        tooth: usize,
        r: f64,
        section: usize,
    ) -> Option<([(usize, f64); 4], [(usize, f64); 4])> {
        let slot = self.tooth_slot(tooth)?;
        let rows = &self.row_radius_m;
        let (row, t) = self.row_of(r);
        let inside = r > rows[0] && r < rows[rows.len() - 1];
        let slope = if inside { 1.0 / (rows[row + 1] - rows[row]) } else { 0.0 };
        let (mut shares, mut slopes) = ([(0, 0.0); 4], [(0, 0.0); 4]);
        for (n, (dr, wr, sr)) in [(0, 1.0 - t, -slope), (1, t, slope)].into_iter().enumerate() {
            for dl in 0..2 {
                let node = self.index(slot, row + dr, section + dl);
                shares[2 * n + dl] = (node, 0.5 * wr);
                slopes[2 * n + dl] = (node, 0.5 * sr);
            }
        }
        Some((shares, slopes))
    }

    /// Shares of the point at radius r on node layer `layer` of `tooth`'s flank.
    pub fn layer_shares(&self, tooth: usize, r: f64, layer: usize) -> Option<Shares> {
        let slot = self.tooth_slot(tooth)?;
        let (row, t) = self.row_of(r);
        Some(vec![(self.index(slot, row, layer), 1.0 - t), (self.index(slot, row + 1, layer), t)])
    }

    /// Shares of a Hertz pressure band of half-width β (m, along the profile) centred at radius
    /// r in axial section `section`. Gauss–Chebyshev quadrature of the second kind integrates the
    /// semi-ellipse √(1 − s²/β²) against the piecewise-linear profile shape functions.
    pub fn band_shares(
        &self,
        tooth: usize,
        r: f64,
        half_width_m: f64,
        base_radius_m: f64,
        section: usize,
    ) -> Option<Shares> {
        const POINTS: usize = 8;
        let slot = self.tooth_slot(tooth)?;
        // Along an involute ds = (r/r_b)·dr: the band's half-width in radius.
        let dr = half_width_m * base_radius_m / r;
        // Profile weights per row, accumulated over the quadrature points (row_of is monotone,
        // so the rows of the band's two ends bound them): one share per node.
        let first = self.row_of(r - dr).0;
        let span = self.row_of(r + dr).0 + 2 - first;
        // On the stack where the band spans few rows (always, on the shipped meshes): the
        // dynamics calls this for every loaded section and gear at every contact evaluation.
        let (mut stack, mut heap) = ([0.0; 32], Vec::new());
        let row_weight: &mut [f64] = if span <= stack.len() {
            &mut stack[..span]
        } else {
            heap.resize(span, 0.0);
            &mut heap
        };
        // The nodes sin²(kπ/(P+1)) and abscissae cos(kπ/(P+1)), once per process: the contact
        // calls this for every loaded section and gear at every right-hand side.
        static QUADRATURE: std::sync::OnceLock<[(f64, f64); POINTS]> = std::sync::OnceLock::new();
        let quadrature = QUADRATURE.get_or_init(|| {
            std::array::from_fn(|i| {
                let angle = std::f64::consts::PI * (i + 1) as f64 / (POINTS + 1) as f64;
                (angle.sin().powi(2), angle.cos())
            })
        });
        let mut total = 0.0;
        for &(w, abscissa) in quadrature {
            total += w;
            let (row, t) = self.row_of(r + dr * abscissa);
            row_weight[row - first] += w * (1.0 - t);
            row_weight[row + 1 - first] += w * t;
        }
        let mut out: Shares = Vec::with_capacity(2 * span);
        for (d, &w) in row_weight.iter().enumerate() {
            for dl in 0..2 {
                out.push((self.index(slot, first + d, section + dl), 0.5 * w / total));
            }
        }
        Some(out)
    }

    /// Unit normal at a point, interpolated from the shares.
    pub fn normal(&self, shares: &Shares) -> [f64; 3] {
        let mut n = [0.0; 3];
        for &(k, w) in shares {
            for c in 0..3 {
                n[c] += w * self.nodes[k].1[c];
            }
        }
        let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        n.map(|v| v / norm)
    }
}
