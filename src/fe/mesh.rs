//! A hexahedral mesh: node coordinates and 8-node connectivity, plus a structured box mesher
//! for the closed-form checks (beams, patches).

/// Nodes (m) and hex8 elements (node indices in the order of `hex8::NODES`).
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    pub nodes: Vec<[f64; 3]>,
    pub elements: Vec<[usize; 8]>,
}

impl Mesh {
    pub fn element_coords(&self, e: usize) -> [[f64; 3]; 8] {
        self.elements[e].map(|n| self.nodes[n])
    }

    pub fn dofs(&self) -> usize {
        3 * self.nodes.len()
    }

    /// Total volume (m³).
    pub fn volume(&self) -> f64 {
        (0..self.elements.len()).map(|e| super::hex8::volume(&self.element_coords(e))).sum()
    }
}

/// A box [0, lx]×[0, ly]×[0, lz] cut into nx×ny×nz hexahedra. Node (i, j, k) has index
/// i + (nx+1)(j + (ny+1)k).
pub fn box_mesh(size_m: [f64; 3], cells: [usize; 3]) -> Mesh {
    let [nx, ny, nz] = cells;
    let id = |i: usize, j: usize, k: usize| i + (nx + 1) * (j + (ny + 1) * k);
    let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                nodes.push([
                    size_m[0] * i as f64 / nx as f64,
                    size_m[1] * j as f64 / ny as f64,
                    size_m[2] * k as f64 / nz as f64,
                ]);
            }
        }
    }
    let mut elements = Vec::with_capacity(nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                elements.push([
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ]);
            }
        }
    }
    Mesh { nodes, elements }
}

/// Rigid-body motion `mode` (0–2: translations along x, y, z; 3–5: rotations about x, y, z
/// through the origin) evaluated at the nodes, as a DOF vector (node-major).
pub fn rigid_body_mode(nodes: &[[f64; 3]], mode: usize) -> Vec<f64> {
    (0..3 * nodes.len())
        .map(|i| {
            let (p, c) = (nodes[i / 3], i % 3);
            match mode {
                0..=2 => (c == mode) as u8 as f64,
                3 => [0.0, -p[2], p[1]][c],
                4 => [p[2], 0.0, -p[0]][c],
                _ => [-p[1], p[0], 0.0][c],
            }
        })
        .collect()
}
