//! The gear by harmonics (`fe::cyclic_symmetry`) against the whole gear on the same mesh — the
//! independent reference is the whole gear's own Cholesky factor and block Lanczos, which know
//! nothing of the symmetry: static responses to loads on one tooth and on every tooth, and the
//! lowest eigenpairs with their Sturm count, for a spur and a helical gear (odd and even z).

use faer::Mat;
use gearfmu::fe::assembly::{self, Cholesky, LinearSolve};
use gearfmu::fe::clamped_gear::ClampedGear;
use gearfmu::fe::cyclic_symmetry::CyclicGear;
use gearfmu::fe::eigen;
use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::fe::hex8::Formulation;
use gearfmu::gear::{GearPair, PairSpec};

/// Both gears of an example on a coarse mesh; `pinion_teeth` replaces gear 1's count (the
/// examples' are all odd: an even one has the single harmonic z/2 too).
fn coarse_gears(example: &str, pinion_teeth: Option<i64>) -> Vec<ClampedGear> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(example);
    let mut spec = PairSpec::load(&path).unwrap();
    if let Some(z) = pinion_teeth {
        spec.gear1.teeth = z;
    }
    let p = GearPair::from_spec(&spec).unwrap();
    let spec = MeshSpec {
        elements_across_tooth: 4,
        elements_along_profile: 6,
        elements_in_rim: 3,
        axial_slices: 3,
        ..Default::default()
    };
    [&p.gear1, &p.gear2].map(|g| ClampedGear::new(&p, g, &spec, Formulation::IncompatibleModes)).into()
}

fn largest(m: &Mat<f64>) -> f64 {
    let mut a = 0.0f64;
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            a = a.max(m[(i, j)].abs());
        }
    }
    a
}

fn check(model: &ClampedGear) {
    let z = model.mesh.teeth;
    let n = model.dofs.n_free;
    let cyclic = CyclicGear::new(model).unwrap().expect("the gear mesh is cyclic");
    assert_eq!(cyclic.harmonics(), z / 2 + 1);
    assert_eq!(cyclic.sector_dofs() * z, n);
    let cyclic = cyclic.factorize().unwrap();
    let whole = Cholesky::new(&model.stiffness).unwrap();

    // Static responses: a load on every flank node of tooth 3 alone, and pseudo-random loads on
    // every DOF (every sector loaded, every harmonic excited).
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut random = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut loads = Mat::<f64>::zeros(n, 3);
    for f in model.mesh.flank_nodes.iter().filter(|f| f.tooth == 3) {
        for c in 0..3 {
            if let Some(i) = model.dofs.free[3 * f.node + c] {
                loads[(i, 0)] = -f.normal[c];
            }
        }
    }
    for j in 1..3 {
        for i in 0..n {
            loads[(i, j)] = random();
        }
    }
    let (mut by_harmonics, mut reference) = (loads.clone(), loads.clone());
    LinearSolve::solve_block(&cyclic, &mut by_harmonics);
    whole.solve_block(&mut reference);
    let difference = largest(&(&by_harmonics - &reference)) / largest(&reference);
    println!("z = {z}: static responses by harmonics against the whole factor: {difference:.1e} of the largest");
    assert!(difference < 1e-9, "static responses differ by {difference:.1e}");

    // Eigenpairs: the lowest 26 (the build's default probe) by harmonics and by the whole gear.
    let mass = model.mass();
    let count = 26;
    let modes = cyclic.lowest_modes(&model.stiffness, &mass, count, 1e-10, 400).unwrap();
    let reference = eigen::lowest_modes(&model.stiffness, &mass, count, 1e-10, 400, |_, _| {}).unwrap();
    for (j, (a, b)) in modes.eigenvalues.iter().zip(&reference.eigenvalues).enumerate() {
        assert!(((a - b) / b).abs() < 1e-8, "mode {j}: λ {a} by harmonics, {b} whole");
    }
    assert_eq!(modes.sturm_count, modes.ritz_values_below_shift, "a mode missed by the harmonics");
    assert_eq!(modes.sturm_count, reference.sturm_count, "Sturm counts of the two solvers");
    // The expanded modes are mass-orthonormal in the whole gear's M.
    let mx = assembly::symmetric_times_block(&mass, modes.vectors.as_ref());
    let gram = modes.vectors.transpose() * &mx;
    let off = largest(&(&gram - Mat::<f64>::identity(count, count)));
    assert!(off < 1e-8, "Φᵀ M Φ differs from I by {off:.1e}");
    println!(
        "z = {z}: {} modes, λ within 1e-8, Sturm {} = {}, largest residual {:.1e}",
        count,
        modes.sturm_count,
        reference.sturm_count,
        modes.residuals.iter().cloned().fold(0.0, f64::max)
    );
}

#[test]
fn spur_gears_by_harmonics_equal_the_whole_gear() {
    for model in coarse_gears("kurokawa_spur.toml", None) {
        check(&model);
    }
}

#[test]
fn helical_gears_with_an_even_tooth_count_by_harmonics_equal_the_whole_gear() {
    for model in coarse_gears("kurokawa_helical.toml", Some(22)) {
        check(&model);
    }
}
