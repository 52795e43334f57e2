//! A PNG of a gear's transverse section: the mesh (black) drawn over the exact profile (red,
//! generated fillet + involute, from `gear`), the whole gear on the left and one tooth on the
//! right. Lines are rasterized here (Bresenham); the `png` crate encodes.

use super::gear_mesh::GearMesh;
use crate::gear::{Gear, GearPair};
use std::f64::consts::PI;
use std::path::Path;

struct Canvas {
    width: usize,
    height: usize,
    rgb: Vec<u8>,
}

/// A view: world window (x_min, y_min, size) drawn into the pixel square at (left, top, side).
#[derive(Clone, Copy)]
struct View {
    x_min: f64,
    y_min: f64,
    size: f64,
    left: usize,
    top: usize,
    side: usize,
}

impl View {
    fn pixel(&self, p: [f64; 2]) -> (i64, i64) {
        let s = self.side as f64 / self.size;
        let x = self.left as f64 + (p[0] - self.x_min) * s;
        let y = self.top as f64 + self.side as f64 - (p[1] - self.y_min) * s;
        (x.round() as i64, y.round() as i64)
    }
}

impl Canvas {
    fn new(width: usize, height: usize) -> Self {
        Canvas { width, height, rgb: vec![255; width * height * 3] }
    }

    fn put(&mut self, x: i64, y: i64, color: [u8; 3], view: &View) {
        let inside = x >= view.left as i64
            && y >= view.top as i64
            && x < (view.left + view.side) as i64
            && y < (view.top + view.side) as i64;
        if inside && (x as usize) < self.width && (y as usize) < self.height {
            let i = 3 * (y as usize * self.width + x as usize);
            self.rgb[i..i + 3].copy_from_slice(&color);
        }
    }

    fn line(&mut self, a: [f64; 2], b: [f64; 2], color: [u8; 3], view: &View) {
        let ((mut x0, mut y0), (x1, y1)) = (view.pixel(a), view.pixel(b));
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
        let mut err = dx + dy;
        for _ in 0..=(dx - dy).max(0) + 1 {
            self.put(x0, y0, color, view);
            if x0 == x1 && y0 == y1 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x0 += sx;
            }
            if e2 <= dx {
                err += dx;
                y0 += sy;
            }
        }
    }
}

/// The exact outline of tooth k as polylines (both flanks, root to tip) in the transverse plane
/// at axial position z (helical teeth turn by z·tan β/r).
fn exact_flanks(pair: &GearPair, gear: &Gear, tooth: usize, z: f64) -> Vec<Vec<[f64; 2]>> {
    let alpha_t = pair.transverse_pressure_angle_rad;
    let axis = 2.0 * PI * tooth as f64 / gear.teeth as f64 + z * pair.helix_angle_rad.tan() / gear.pitch_radius_m;
    let r_root = gear.fillet.first().map_or(gear.root_radius_m, |f| f.0);
    [-1.0, 1.0]
        .iter()
        .map(|side| {
            (0..=200)
                .map(|i| {
                    let r = r_root + (gear.tip_radius_m - r_root) * i as f64 / 200.0;
                    let a = axis + side * gear.profile_half_thickness_angle(r.max(r_root + 1e-9), alpha_t);
                    [r * a.cos(), r * a.sin()]
                })
                .collect()
        })
        .collect()
}

pub fn write_profile_png(path: &Path, pair: &GearPair, gear: &Gear, gm: &GearMesh) -> Result<(), String> {
    let side = 700;
    let mut canvas = Canvas::new(2 * side + 30, side + 20);
    let r = gear.tip_radius_m * 1.05;
    let whole = View { x_min: -r, y_min: -r, size: 2.0 * r, left: 10, top: 10, side };
    let h = (gear.tip_radius_m - gear.bore_radius_m) * 0.6;
    let zoom =
        View { x_min: gear.tip_radius_m - 1.1 * h, y_min: -0.5 * h, size: 1.2 * h, left: side + 20, top: 10, side };
    let z_min = gm.mesh.nodes.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
    for view in [whole, zoom] {
        for e in &gm.mesh.elements {
            let face: Vec<[f64; 3]> = e[..4].iter().map(|&n| gm.mesh.nodes[n]).collect();
            if face.iter().any(|p| (p[2] - z_min).abs() > 1e-12) {
                continue;
            }
            for i in 0..4 {
                let (a, b) = (face[i], face[(i + 1) % 4]);
                canvas.line([a[0], a[1]], [b[0], b[1]], [0, 0, 0], &view);
            }
        }
        for tooth in 0..gear.teeth as usize {
            for flank in exact_flanks(pair, gear, tooth, z_min) {
                for w in flank.windows(2) {
                    canvas.line(w[0], w[1], [220, 30, 30], &view);
                }
            }
        }
    }
    let file = std::fs::File::create(path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), canvas.width as u32, canvas.height as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(&canvas.rgb).map_err(|e| e.to_string())?;
    Ok(())
}
