//! The 8-node hexahedron: stiffness (plain full integration, or with Wilson–Taylor incompatible
//! modes) and consistent mass, by 2×2×2 Gauss quadrature.
//!
//! Incompatible modes. The plain trilinear element cannot bend without shearing (it locks on
//! thin teeth). Wilson's element adds, per displacement component, the bubbles 1−ξ², 1−η², 1−ζ²
//! (9 internal DOFs), condensed out statically: K = K_uu − K_uα K_αα⁻¹ K_αu. Taylor, Beresford &
//! Wilson (1976) evaluate the bubble derivatives with the Jacobian J₀ at the element center and
//! weight them by det J₀/det J, so that ∫ B_α dV = 0 on any shape and the patch test passes.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

pub type Mat24 = SMatrix<f64, 24, 24>;
type Mat6 = SMatrix<f64, 6, 6>;
type B24 = SMatrix<f64, 6, 24>;
type B9 = SMatrix<f64, 6, 9>;

/// Which stiffness formulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Formulation {
    /// Wilson–Taylor incompatible modes (the default: no shear locking in bending).
    IncompatibleModes,
    /// Plain trilinear, 2×2×2 Gauss (locks in bending; kept to show what locking costs).
    FullIntegration,
}

/// Natural coordinates of the nodes: bottom face (ζ = −1) counter-clockwise, then the top face.
pub const NODES: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

const GAUSS: f64 = 0.577_350_269_189_625_8; // 1/√3

fn gauss_points() -> impl Iterator<Item = [f64; 3]> {
    (0..8).map(|i| [NODES[i][0] * GAUSS, NODES[i][1] * GAUSS, NODES[i][2] * GAUSS])
}

/// Shape functions N_a(ξ) and their natural derivatives ∂N_a/∂ξ_j.
pub fn shape(xi: [f64; 3]) -> ([f64; 8], [[f64; 3]; 8]) {
    let mut n = [0.0; 8];
    let mut dn = [[0.0; 3]; 8];
    for a in 0..8 {
        let [p, q, r] = NODES[a];
        let (fx, fy, fz) = (1.0 + p * xi[0], 1.0 + q * xi[1], 1.0 + r * xi[2]);
        n[a] = 0.125 * fx * fy * fz;
        dn[a] = [0.125 * p * fy * fz, 0.125 * q * fx * fz, 0.125 * r * fx * fy];
    }
    (n, dn)
}

/// Jacobian J_ij = ∂x_j/∂ξ_i at ξ.
fn jacobian(coords: &[[f64; 3]; 8], dn: &[[f64; 3]; 8]) -> Matrix3<f64> {
    let mut j = Matrix3::zeros();
    for a in 0..8 {
        for i in 0..3 {
            for k in 0..3 {
                j[(i, k)] += dn[a][i] * coords[a][k];
            }
        }
    }
    j
}

/// Isotropic elasticity matrix in Voigt order (xx, yy, zz, xy, yz, zx), engineering shears.
pub fn elasticity(youngs_modulus_pa: f64, poisson_ratio: f64) -> Mat6 {
    let (e, nu) = (youngs_modulus_pa, poisson_ratio);
    let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e / (2.0 * (1.0 + nu));
    let mut d = Mat6::zeros();
    for i in 0..3 {
        for j in 0..3 {
            d[(i, j)] = lambda;
        }
        d[(i, i)] = lambda + 2.0 * mu;
        d[(i + 3, i + 3)] = mu;
    }
    d
}

/// Strain–displacement rows of one vector field with spatial gradient g.
fn strain_columns(g: &Vector3<f64>) -> SMatrix<f64, 6, 3> {
    SMatrix::<f64, 6, 3>::from_row_slice(&[
        g.x, 0.0, 0.0, //
        0.0, g.y, 0.0, //
        0.0, 0.0, g.z, //
        g.y, g.x, 0.0, //
        0.0, g.z, g.y, //
        g.z, 0.0, g.x,
    ])
}

/// Element stiffness (24×24, DOF order node-major: u_x, u_y, u_z of node 0, then node 1, …).
pub fn stiffness(coords: &[[f64; 3]; 8], d: &Mat6, formulation: Formulation) -> Mat24 {
    let mut k_uu = Mat24::zeros();
    let mut k_ua = SMatrix::<f64, 24, 9>::zeros();
    let mut k_aa = SMatrix::<f64, 9, 9>::zeros();
    let (_, dn0) = shape([0.0; 3]);
    let j0 = jacobian(coords, &dn0);
    let det0 = j0.determinant();
    let j0_inv = j0.try_inverse().expect("degenerate element (singular Jacobian at the center)");
    for xi in gauss_points() {
        let (_, dn) = shape(xi);
        let j = jacobian(coords, &dn);
        let det = j.determinant();
        assert!(det > 0.0, "element with non-positive Jacobian {det} (inverted or distorted)");
        let j_inv = j.try_inverse().unwrap();
        let mut b = B24::zeros();
        for a in 0..8 {
            let g = j_inv * Vector3::from(dn[a]);
            b.fixed_view_mut::<6, 3>(0, 3 * a).copy_from(&strain_columns(&g));
        }
        k_uu += b.transpose() * d * b * det;
        if formulation == Formulation::IncompatibleModes {
            let mut b_a = B9::zeros();
            for k in 0..3 {
                // ∂(1 − ξ_k²)/∂ξ = −2ξ_k e_k, mapped with J₀ and weighted by det J₀/det J.
                let mut dp = Vector3::zeros();
                dp[k] = -2.0 * xi[k];
                let g = j0_inv * dp * (det0 / det);
                b_a.fixed_view_mut::<6, 3>(0, 3 * k).copy_from(&strain_columns(&g));
            }
            k_ua += b.transpose() * d * b_a * det;
            k_aa += b_a.transpose() * d * b_a * det;
        }
    }
    if formulation == Formulation::IncompatibleModes {
        let chol = k_aa.cholesky().expect("incompatible-mode block is positive definite");
        k_uu -= k_ua * chol.solve(&k_ua.transpose());
    }
    // Symmetrize the round-off.
    (k_uu + k_uu.transpose()) * 0.5
}

/// Consistent mass matrix ρ∫NᵀN dV ⊗ I₃ (24×24).
pub fn mass(coords: &[[f64; 3]; 8], density: f64) -> Mat24 {
    let mut m = Mat24::zeros();
    for xi in gauss_points() {
        let (n, dn) = shape(xi);
        let det = jacobian(coords, &dn).determinant();
        for a in 0..8 {
            for b in 0..8 {
                let v = density * n[a] * n[b] * det;
                for c in 0..3 {
                    m[(3 * a + c, 3 * b + c)] += v;
                }
            }
        }
    }
    m
}

/// Volume by 2×2×2 Gauss (exact for trilinear geometry).
pub fn volume(coords: &[[f64; 3]; 8]) -> f64 {
    gauss_points().map(|xi| jacobian(coords, &shape(xi).1).determinant()).sum()
}

/// Displacement vector of the element from a global field (for tests and post-processing).
pub fn gather(u: &[f64], nodes: &[usize; 8]) -> SVector<f64, 24> {
    SVector::<f64, 24>::from_fn(|i, _| u[3 * nodes[i / 3] + i % 3])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn distorted() -> [[f64; 3]; 8] {
        let mut c = NODES.map(|p| [p[0] + 1.0, p[1] + 1.0, p[2] + 1.0]);
        c[6] = [2.3, 2.2, 2.4];
        c[1][1] -= 0.2;
        c[4][0] += 0.3;
        c
    }

    /// Rigid motions cost no energy: K·r = 0 for the three translations and three rotations.
    #[test]
    fn rigid_body_modes_are_zero_energy() {
        let c = distorted();
        let d = elasticity(2e11, 0.3);
        for f in [Formulation::IncompatibleModes, Formulation::FullIntegration] {
            let k = stiffness(&c, &d, f);
            for mode in 0..6 {
                let r = SVector::<f64, 24>::from_fn(|i, _| {
                    let (a, comp) = (i / 3, i % 3);
                    let x = Vector3::from(c[a]);
                    let v = if mode < 3 {
                        let mut t = Vector3::zeros();
                        t[mode] = 1.0;
                        t
                    } else {
                        let mut w = Vector3::zeros();
                        w[mode - 3] = 1.0;
                        w.cross(&x)
                    };
                    v[comp]
                });
                assert!((k * r).norm() < 1e-6 * k.norm(), "{f:?} mode {mode}");
            }
        }
    }

    #[test]
    fn mass_sums_to_density_times_volume() {
        let c = distorted();
        let m = mass(&c, 7700.0);
        let total: f64 =
            (0..24).step_by(3).flat_map(|i| (0..24).step_by(3).map(move |j| (i, j))).map(|(i, j)| m[(i, j)]).sum();
        assert!((total - 7700.0 * volume(&c)).abs() < 1e-9 * total);
    }
}
