//! The condensed static solver (active set on the contact forces, `rom::statics::condensed`)
//! against the dense reference (Newton on every reduced coordinate, `rom::statics::dense`): the
//! same equations solved two ways must give the same answer to solver tolerance. The dense
//! solver stops at a relative force residual of 1e-9, the condensed one when its Newton steps
//! fall below 1e-11 of the forces; both run the same contact searches. Agreement is asked to
//! 1e-8 (STE, force per tooth pair over the mesh force) and 1e-7 for the reduced coordinates,
//! whose smallest components are the least determined.
//! Both reductions, both of Table 4's loads, a mesh cycle of positions, and the helical pair.

use gearfmu::contact::hertz::ApproachLaw;
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::rom::statics::Solver;
use gearfmu::rom::sweep::{Method, ReducedPair};
use std::time::Instant;

fn pair(file: &str) -> (GearPair, PairSpec) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(file);
    let spec = PairSpec::load(&path).unwrap();
    (GearPair::from_spec(&spec).unwrap(), spec)
}

/// Solves `angles` positions over one pitch at each torque both ways and compares the STE, the
/// force of every tooth pair and the reduced coordinates (the global contact shapes of the
/// dynamics). Returns the per-case times (dense, condensed) in seconds.
fn compare(reduced: &ReducedPair, torques_nm: &[f64], angles: usize) -> (f64, f64) {
    compare_with_friction(reduced, torques_nm, angles, 0.0)
}

/// `compare` with tooth friction of coefficient μ (`StaticModel::with_friction`).
fn compare_with_friction(reduced: &ReducedPair, torques_nm: &[f64], angles: usize, mu: f64) -> (f64, f64) {
    let model = reduced.static_model().unwrap().with_friction(mu).unwrap();
    let pitch = 2.0 * std::f64::consts::PI / reduced.pair.gear2.teeth as f64;
    let (mut dense_s, mut condensed_s, mut cases) = (0.0, 0.0, 0);
    let mut worst = [0.0_f64; 3];
    for &torque in torques_nm {
        for k in 0..angles {
            let theta2 = pitch * (k as f64 + 0.5) / angles as f64;
            let start = Instant::now();
            let dense = model.solve_with(theta2, torque, Solver::Dense).unwrap();
            dense_s += start.elapsed().as_secs_f64();
            let start = Instant::now();
            let condensed = model.solve_with(theta2, torque, Solver::Condensed).unwrap();
            condensed_s += start.elapsed().as_secs_f64();
            cases += 1;
            let ste = (condensed.ste_m / dense.ste_m - 1.0).abs();
            let (a, b) = (dense.force_per_pair(), condensed.force_per_pair());
            let of = |v: &[(i64, f64)], j: i64| v.iter().find(|p| p.0 == j).map_or(0.0, |p| p.1);
            let force = a.iter().chain(b.iter()).map(|&(j, _)| (of(&a, j) - of(&b, j)).abs()).fold(0.0, f64::max)
                / dense.mesh_force_n;
            let norm = |q: &[f64]| q.iter().map(|v| v * v).sum::<f64>().sqrt();
            let shape = (0..2)
                .map(|i| {
                    let diff: Vec<f64> =
                        dense.reduced[i].iter().zip(&condensed.reduced[i]).map(|(x, y)| x - y).collect();
                    norm(&diff) / norm(&dense.reduced[i])
                })
                .fold(0.0, f64::max);
            worst = [worst[0].max(ste), worst[1].max(force), worst[2].max(shape)];
            assert!(ste <= 1e-8, "θ₂ = {theta2}, T = {torque}: STE {} vs {} m", condensed.ste_m, dense.ste_m);
            assert!(force <= 1e-8, "θ₂ = {theta2}, T = {torque}: forces per pair {b:?} vs {a:?}");
            assert!(shape <= 1e-7, "θ₂ = {theta2}, T = {torque}: reduced coordinates differ by {shape:.2e}");
            assert_eq!(dense.pairs_in_contact, condensed.pairs_in_contact, "θ₂ = {theta2}, T = {torque}");
        }
    }
    println!(
        "{cases} cases: worst relative difference STE {:.1e}, pair force {:.1e}, reduced coordinates {:.1e}; \
         per case dense {:.4} s, condensed {:.4} s",
        worst[0],
        worst[1],
        worst[2],
        dense_s / cases as f64,
        condensed_s / cases as f64
    );
    (dense_s / cases as f64, condensed_s / cases as f64)
}

#[test]
fn condensed_equals_dense_for_the_penalty_baseline_spur() {
    let (p, spec) = pair("kurokawa_spur.toml");
    let reduced = ReducedPair::build(&p, &spec.mesh, Method::Penalty { factor: 100.0 }, |_, _| {}).unwrap();
    compare(&reduced, &[20.79, 370.251], 12);
}

#[test]
fn condensed_equals_dense_for_pmor_hertz_spur() {
    let (p, spec) = pair("kurokawa_spur.toml");
    let method = Method::PmorHertz { depth_m: 3e-3, p_en: gearfmu::rom::svd::DEFAULT_P_EN, law: ApproachLaw::Weber };
    let reduced = ReducedPair::build(&p, &spec.mesh, method, |_, _| {}).unwrap();
    compare(&reduced, &[20.79, 370.251], 12);
}

/// The helical pair on its spec's mesh (8 axial slices), Table 7's lightest and heaviest torque:
/// more contact elements per pair, and contact lines that end on the tip and the face edges.
#[test]
fn condensed_equals_dense_for_both_methods_helical() {
    let (p, spec) = pair("kurokawa_helical.toml");
    let method = Method::PmorHertz { depth_m: 3e-3, p_en: gearfmu::rom::svd::DEFAULT_P_EN, law: ApproachLaw::Weber };
    for method in [method, Method::Penalty { factor: 100.0 }] {
        let reduced = ReducedPair::build(&p, &spec.mesh, method, |_, _| {}).unwrap();
        compare(&reduced, &[21.07, 1835.462], 4);
    }
}

/// With tooth friction (μ = 0.05, issue 42) the condensed matrix is no longer symmetric: the
/// torque row takes the friction arms, the responses the tangential loads. Both methods on the
/// spur pair, the penalty baseline's gears with their flank-tangent attachment modes.
#[test]
fn condensed_equals_dense_with_tooth_friction_spur() {
    let (p, spec) = pair("kurokawa_spur.toml");
    let method = Method::PmorHertz { depth_m: 3e-3, p_en: gearfmu::rom::svd::DEFAULT_P_EN, law: ApproachLaw::Weber };
    for method in [method, Method::Penalty { factor: 100.0 }] {
        let reduced = ReducedPair::build_for_friction(&p, &spec.mesh, method, |_, _| {}).unwrap();
        compare_with_friction(&reduced, &[370.251], 12, 0.05);
    }
}
