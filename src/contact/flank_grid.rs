//! The loadable flank of a gear: the FE flank nodes of the contact side of the teeth that can
//! mesh (found on the mesh by `rom::flank`), as a structured grid (profile rows × axial layers
//! per tooth), with the two operations the contact needs on it:
//! - interpolation of a nodal field at a contact point (bilinear over the flank face);
//! - the Hertz pressure of an axial section, a semi-ellipse of half-width β across the profile
//!   and uniform along the section, integrated against the same shape functions into nodal
//!   load shares (paper Sect. 4.3, Eqs. 21–22).

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

    /// The unit tangent of node k's flank in the transverse plane, e_z × n_k over its length,
    /// oriented along the flank the way a rotation that pushes the node out along its normal
    /// (into contact) carries it. Tooth friction acts along it (issue 42): flanks slide in
    /// transverse planes, so a helical flank's friction has no axial part, and e_z × n lies in
    /// the flank's tangent plane. The rotation's velocity there is ±e_z × x, so the pushing
    /// sense is the sign of (e_z × x)·n, and its tangential part (e_z × x)·(e_z × n) = x·n
    /// (transverse parts) is the radius of curvature ρ of an involute: the node's arm along the
    /// tangent.
    pub fn transverse_tangent(&self, k: usize) -> [f64; 3] {
        let ([x, y], n) = (self.node_xy[k], self.nodes[k].1);
        let transverse = (n[0] * n[0] + n[1] * n[1]).sqrt();
        let t = [-n[1] / transverse, n[0] / transverse, 0.0];
        let pushing = (x * n[1] - y * n[0]).signum(); // (e_z × x)·n
        let along = (-y * t[0] + x * t[1]).signum(); // (e_z × x)·t
        t.map(|c| pushing * along * c)
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
