//! The finite elements against closed forms: a Timoshenko cantilever, the patch test, rigid-body
//! modes and mass.

use gearfmu::fe::assembly::{self, relative_residual, Cholesky, DofMap, Material};
use gearfmu::fe::hex8::Formulation;
use gearfmu::fe::mesh::{box_mesh, Mesh};

const STEEL: Material = Material { youngs_modulus_pa: 2e11, poisson_ratio: 0.3, density_kg_m3: 7700.0 };

/// How the root of the cantilever is held.
#[derive(Clone, Copy, PartialEq)]
enum Root {
    /// As beam theory assumes: the root section stays plane and normal to the axis (u_x = 0 on
    /// the face), its centroidal line carries the shear (u_y = 0 on y = h/2), one point fixes
    /// u_z; the section may still contract (Poisson).
    BeamTheory,
    /// Every DOF of the root face fixed: also stops the Poisson contraction there, a local
    /// stiffening that beam theory does not have.
    FullyClamped,
}

/// Tip deflection of a cantilever (length L along x, square h×h), held at x = 0, under a
/// transverse tip force P spread as the consistent load of a uniform shear traction on the end face.
fn cantilever_tip_deflection(
    length: f64,
    h: f64,
    cells: [usize; 3],
    formulation: Formulation,
    force: f64,
    root: Root,
) -> f64 {
    let mesh = box_mesh([length, h, h], cells);
    let mid = |v: f64| (v - 0.5 * h).abs() < 1e-12;
    let mut free = vec![None; mesh.dofs()];
    let mut n_free = 0;
    for (node, p) in mesh.nodes.iter().enumerate() {
        for c in 0..3 {
            let held = p[0] == 0.0
                && match (root, c) {
                    (Root::FullyClamped, _) | (Root::BeamTheory, 0) => true,
                    (Root::BeamTheory, 1) => mid(p[1]),
                    (Root::BeamTheory, _) => mid(p[1]) && mid(p[2]),
                };
            if !held {
                free[3 * node + c] = Some(n_free);
                n_free += 1;
            }
        }
    }
    let dofs = DofMap { free, n_free };
    let k = assembly::stiffness(&mesh, &STEEL, formulation, &dofs);
    // Consistent nodal forces of a uniform traction on the bilinear end face: each face cell
    // gives a quarter of its share to each of its four corners.
    let [_, ny, nz] = cells;
    let mut f = vec![0.0; dofs.n_free];
    let share = force / (ny * nz) as f64 / 4.0;
    let tip = |j: usize, k: usize| cells[0] + (cells[0] + 1) * (j + (ny + 1) * k);
    for j in 0..ny {
        for kk in 0..nz {
            for (a, b) in [(j, kk), (j + 1, kk), (j, kk + 1), (j + 1, kk + 1)] {
                f[dofs.free[3 * tip(a, b) + 1].unwrap()] += share;
            }
        }
    }
    let chol = Cholesky::new(&k).unwrap();
    let u = chol.solve(&f);
    assert!(relative_residual(&k, &u, &f) < 1e-10);
    let u = dofs.expand(&u);
    let tip_nodes: Vec<usize> = (0..=ny).flat_map(|j| (0..=nz).map(move |k| tip(j, k))).collect();
    tip_nodes.iter().map(|&n| u[3 * n + 1]).sum::<f64>() / tip_nodes.len() as f64
}

/// Timoshenko: δ = PL³/(3EI) + PL/(κGA), κ = 10(1+ν)/(12+11ν) for a rectangle (Cowper 1966).
#[test]
fn cantilever_tip_deflection_within_1_percent_of_timoshenko() {
    let (length, h, force): (f64, f64, f64) = (0.1, 0.01, 100.0);
    let (e, nu) = (STEEL.youngs_modulus_pa, STEEL.poisson_ratio);
    let (inertia, area, g) = (h.powi(4) / 12.0, h * h, e / (2.0 * (1.0 + nu)));
    let kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
    let timoshenko = force * length.powi(3) / (3.0 * e * inertia) + force * length / (kappa * g * area);
    let run = |formulation, root| cantilever_tip_deflection(length, h, [20, 2, 2], formulation, force, root);
    let im = run(Formulation::IncompatibleModes, Root::BeamTheory);
    let plain = run(Formulation::FullIntegration, Root::BeamTheory);
    let clamped = run(Formulation::IncompatibleModes, Root::FullyClamped);
    let error = |d: f64| (d - timoshenko) / timoshenko;
    let (e_im, e_plain) = (error(im), error(plain));
    println!(
        "L/h = 10, 20×2×2 elements: Timoshenko {:.5e} m; incompatible modes {:.5e} m ({:+.2} %); plain hex8 {:.5e} m ({:+.1} %, shear locking); incompatible modes with the root face fully clamped {:+.2} %",
        timoshenko, im, 100.0 * e_im, plain, 100.0 * e_plain, 100.0 * error(clamped)
    );
    assert!(e_im.abs() < 0.01, "incompatible modes: {e_im}");
    // The figure is reported; the assertion only says that the plain element locks (is clearly
    // stiffer than the beam), which is what the incompatible modes are there to cure.
    assert!(e_plain < -0.05, "the plain hex8 should lock in bending, got {e_plain}");
}

/// Patch test: on a patch of distorted elements, boundary displacements from a linear field must
/// give that field exactly at the interior node (constant strain reproduced exactly).
#[test]
fn patch_test_is_passed_exactly_by_the_incompatible_mode_element() {
    let mut mesh: Mesh = box_mesh([1.0, 1.0, 1.0], [2, 2, 2]);
    let center = 1 + 3 * (1 + 3 * 1);
    mesh.nodes[center] = [0.43, 0.58, 0.47];
    let linear =
        |p: [f64; 3]| [1e-3 * (p[0] + 2.0 * p[1] - p[2]), 1e-3 * (0.5 * p[0] - p[2]), 1e-3 * (p[1] + 3.0 * p[2])];
    let clamped: Vec<bool> = (0..mesh.nodes.len()).map(|n| n != center).collect();
    let dofs = DofMap::new(mesh.nodes.len(), &clamped);
    let all = DofMap::unclamped(mesh.nodes.len());
    for formulation in [Formulation::IncompatibleModes, Formulation::FullIntegration] {
        let k_all = assembly::stiffness(&mesh, &STEEL, formulation, &all);
        // f = −K_fc u_c for the free (center) DOFs; K_ff u_f = f.
        let mut u_full = vec![0.0; mesh.dofs()];
        for (n, p) in mesh.nodes.iter().enumerate() {
            if n != center {
                u_full[3 * n..3 * n + 3].copy_from_slice(&linear(*p));
            }
        }
        let kf = assembly::mul(&k_all, &u_full);
        let f: Vec<f64> = (0..3).map(|c| -kf[3 * center + c]).collect();
        let k = assembly::stiffness(&mesh, &STEEL, formulation, &dofs);
        let u = Cholesky::new(&k).unwrap().solve(&f);
        let exact = linear(mesh.nodes[center]);
        let error = (0..3).map(|c| (u[c] - exact[c]).abs()).fold(0.0, f64::max) / 1e-3;
        println!("{formulation:?}: interior node error {error:.2e} (relative to the field's scale)");
        assert!(error < 1e-10, "{formulation:?} fails the patch test: {error}");
    }
}

/// The unclamped K has the six rigid-body motions in its null space (closed form: K·r = 0).
#[test]
fn free_box_has_six_rigid_body_modes() {
    let mut mesh = box_mesh([0.05, 0.02, 0.03], [5, 2, 3]);
    for (i, p) in mesh.nodes.iter_mut().enumerate() {
        p[0] += 1e-3 * ((i * 7919) % 13) as f64 / 13.0; // a little distortion
    }
    let dofs = DofMap::unclamped(mesh.nodes.len());
    let k = assembly::stiffness(&mesh, &STEEL, Formulation::IncompatibleModes, &dofs);
    for mode in 0..6 {
        let r = gearfmu::fe::mesh::rigid_body_mode(&mesh.nodes, mode);
        let kr = assembly::mul(&k, &r);
        let norm_kr = kr.iter().map(|v| v * v).sum::<f64>().sqrt();
        let norm_k_r =
            k.as_ref().val().iter().map(|v| v.abs()).fold(0.0, f64::max) * r.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(norm_kr < 1e-10 * norm_k_r, "mode {mode}: ‖Kr‖ = {norm_kr:e}");
    }
}

#[test]
fn assembled_mass_is_density_times_volume() {
    let mesh = box_mesh([0.05, 0.02, 0.03], [5, 2, 3]);
    let dofs = DofMap::unclamped(mesh.nodes.len());
    let m = assembly::mass(&mesh, &STEEL, &dofs);
    // uᵀMu for a unit translation in x is the total mass.
    let ux: Vec<f64> = (0..dofs.n_free).map(|i| (i % 3 == 0) as u8 as f64).collect();
    let total: f64 = assembly::mul(&m, &ux).iter().zip(&ux).map(|(a, b)| a * b).sum();
    let exact = STEEL.density_kg_m3 * 0.05 * 0.02 * 0.03;
    assert!((total - exact).abs() < 1e-12 * exact, "{total} vs {exact}");
}

/// Clamped–free beam (L/h = 20, square section): the two lowest bending modes in each plane
/// against Euler–Bernoulli, ω_n = (β_nL)²√(EI/(ρAL⁴)), β₁L = 1.8751, β₂L = 4.6941 (slender
/// enough that Timoshenko's shear and rotary-inertia corrections stay below ~1 %). The Sturm
/// count must find exactly the modes returned below σ.
#[test]
fn clamped_free_beam_frequencies_within_2_percent_of_euler_bernoulli() {
    let (length, h): (f64, f64) = (0.2, 0.01);
    let mesh = box_mesh([length, h, h], [40, 2, 2]);
    let clamped: Vec<bool> = mesh.nodes.iter().map(|p| p[0] == 0.0).collect();
    let dofs = DofMap::new(mesh.nodes.len(), &clamped);
    let k = assembly::stiffness(&mesh, &STEEL, Formulation::IncompatibleModes, &dofs);
    let m = assembly::mass(&mesh, &STEEL, &dofs);
    let modes = gearfmu::fe::eigen::lowest_modes(&k, &m, 4, 1e-10, 200, |_, _| {}).unwrap();
    let f = modes.frequencies_hz();
    let base = (STEEL.youngs_modulus_pa * h * h / (12.0 * STEEL.density_kg_m3 * length.powi(4))).sqrt()
        / (2.0 * std::f64::consts::PI);
    let expected =
        [1.8751f64.powi(2) * base, 1.8751f64.powi(2) * base, 4.6941f64.powi(2) * base, 4.6941f64.powi(2) * base];
    for i in 0..4 {
        let error = (f[i] - expected[i]) / expected[i];
        println!(
            "mode {}: {:.2} Hz, Euler–Bernoulli {:.2} Hz ({:+.2} %), residual {:.1e}",
            i + 1,
            f[i],
            expected[i],
            100.0 * error,
            modes.residuals[i]
        );
        assert!(error.abs() < 0.02, "mode {}: {error}", i + 1);
        assert!(modes.residuals[i] < 1e-6);
    }
    println!(
        "{} iterations; Sturm count below the shift: {} (Ritz values below it: {})",
        modes.iterations, modes.sturm_count, modes.ritz_values_below_shift
    );
    assert_eq!(modes.sturm_count, modes.ritz_values_below_shift, "no mode may be missed below the shift");
    assert!(modes.sturm_count >= 4);
}
