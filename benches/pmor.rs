//! Cost of the PMOR-Hertz reduced pair, measured in release mode (`cargo bench --bench pmor`).
//!
//! Baseline, run in the same process: the lumped FMU's model (`dynamics::lumped`) on the same
//! pair and the same loading. Reported: µs per right-hand side, per velocity Verlet step and per
//! RK4 step of the reduced pair (ratio to the lumped RK4 step), and the seed's example 3 (185 N·m
//! haversine ramp 5 ms, viscous 20 N·m·s/rad on gear 2, 25 ms, communication step 0.1 ms) as
//! wall time and real-time factor for both models at their default max_step (PMOR-Hertz: the
//! model's own, 0.6 of its integrator's limit from the linearization; lumped 1 µs); the reduced
//! pair also with RK4 at 0.6 of RK4's limit (`--integrator rk4`), the integrator baseline.
//!
//! The reduced pair is built here with the default options (about 15 s), so the figures belong
//! to the same model `fmu-build build` ships.

use gearfmu::contact::mesh_kinematics::PairPlacement;
use gearfmu::dynamics::lumped::{LumpedMesh, LumpedModel, LumpedState};
use gearfmu::dynamics::pmor::integrator::Integrator;
use gearfmu::dynamics::pmor::{linear, PmorDynamics};
use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::rom::dynamic_reductor::{build_dynamic_model, DynamicBuildOptions};
use std::hint::black_box;
use std::time::Instant;

fn median(mut samples: Vec<f64>) -> f64 {
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

fn seed_torque(t: f64) -> f64 {
    185.0 * if t < 5e-3 { 0.5 * (1.0 - (std::f64::consts::PI * t / 5e-3).cos()) } else { 1.0 }
}

const COMM_STEP_S: f64 = 1e-4;
const END_S: f64 = 25e-3;

fn main() {
    let spec = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
    let pair = GearPair::from_spec(&PairSpec::load(&spec).unwrap()).unwrap();
    let built = Instant::now();
    let (model, _) = build_dynamic_model(&pair, &MeshSpec::default(), &DynamicBuildOptions::default(), |_| {}).unwrap();
    println!("offline build (default options): {:.1} s", built.elapsed().as_secs_f64());
    let place = PairPlacement::new(&model.pair);
    let dynamics = PmorDynamics::new(
        &model,
        &place,
        model.damping(model.modal_damping_ratio, model.shape_damping_ratio),
        [0.0; 2],
    );
    // The integrators side by side, each at its own default step (the build's rule).
    let at = |integrator: Integrator| {
        let mut d = PmorDynamics::new(&model, &place, dynamics.damping, [0.0; 2]);
        d.integrator = integrator;
        let step = linear::default_step(&d).unwrap().max_step_s;
        (d, step)
    };
    let ((dynamics, verlet_max_step), (rk4, rk4_max_step)) = (at(Integrator::Verlet), at(Integrator::Rk4));

    // Example 3 through the model's own sub-stepping, as the FMU runs it.
    let example_3 = |dynamics: &PmorDynamics, max_step: f64, runs: usize| {
        let mut walls = Vec::new();
        let mut last = None;
        for _ in 0..runs {
            let mut s = model.initial_state([0.0; 2], [0.0; 2]);
            let t0 = Instant::now();
            for k in 0..(END_S / COMM_STEP_S).round() as usize {
                let t = k as f64 * COMM_STEP_S;
                let torques = [seed_torque(t), -20.0 * s.omega[1]];
                dynamics.advance(&mut s, torques, COMM_STEP_S, max_step).unwrap();
            }
            walls.push(t0.elapsed().as_secs_f64());
            last = Some(s);
        }
        (median(walls), last.unwrap())
    };
    let (pmor_wall, loaded) = example_3(&dynamics, verlet_max_step, 3);
    let (rk4_wall, rk4_end) = example_3(&rk4, rk4_max_step, 3);

    // Per right-hand side and per RK4 step, at the loaded state example 3 ends in.
    let y = dynamics.pack(&loaded);
    let torques = [185.0, -20.0 * loaded.omega[1]];
    let n = 2000;
    let rhs_us = median(
        (0..5)
            .map(|_| {
                let t0 = Instant::now();
                for _ in 0..n {
                    black_box(dynamics.rhs(black_box(&y), loaded.anchor, torques).unwrap());
                }
                t0.elapsed().as_secs_f64() / n as f64 * 1e6
            })
            .collect(),
    );
    let step_us = |integrator: Integrator| {
        median(
            (0..5)
                .map(|_| {
                    let mut s = loaded.clone();
                    let t0 = Instant::now();
                    match integrator {
                        Integrator::Rk4 => (0..n).for_each(|_| rk4.rk4_step(&mut s, torques, rk4_max_step).unwrap()),
                        Integrator::Verlet => {
                            let h = verlet_max_step;
                            dynamics.verlet_advance(&mut s, torques, n as f64 * h, h * (1.0 + 1e-9)).unwrap()
                        }
                    }
                    black_box(s);
                    t0.elapsed().as_secs_f64() / n as f64 * 1e6
                })
                .collect(),
        )
    };
    let (verlet_step_us, rk4_step_us) = (step_us(Integrator::Verlet), step_us(Integrator::Rk4));

    // The lumped model, same process, same loading.
    let mesh = LumpedMesh::from_pair(&pair).unwrap();
    let lumped = LumpedModel::with_defaults(&mesh);
    let lumped_step_us = median(
        (0..5)
            .map(|_| {
                let mut s = LumpedState::default();
                let steps = 200_000;
                let t0 = Instant::now();
                for k in 0..steps {
                    s = lumped.rk4_step(&s, [seed_torque(k as f64 * 1e-6), -20.0 * s.omega_2], 1e-6);
                }
                black_box(s);
                t0.elapsed().as_secs_f64() / steps as f64 * 1e6
            })
            .collect(),
    );
    let lumped_wall = median(
        (0..5)
            .map(|_| {
                let mut s = LumpedState::default();
                let t0 = Instant::now();
                for k in 0..(END_S / COMM_STEP_S).round() as usize {
                    let t = k as f64 * COMM_STEP_S;
                    let torques = [seed_torque(t), -20.0 * s.omega_2];
                    lumped.advance(&mut s, torques, COMM_STEP_S, 1e-6);
                }
                black_box(s);
                t0.elapsed().as_secs_f64()
            })
            .collect(),
    );

    println!("PMOR-Hertz right-hand side: {rhs_us:.2} µs (state size {})", y.len());
    println!(
        "PMOR-Hertz velocity Verlet step: {verlet_step_us:.1} µs; RK4 step: {rk4_step_us:.1} µs; lumped RK4 step: {:.3} µs; ratios {:.0} / {:.0}",
        lumped_step_us,
        verlet_step_us / lumped_step_us,
        rk4_step_us / lumped_step_us
    );
    println!(
        "example 3 (25 ms, comm 0.1 ms): PMOR-Hertz, velocity Verlet at {:.1} µs {:.3} s wall ({:.1}× slower than real time, {:.2} ms per doStep); lumped at 1 µs {:.2} ms wall; ratio {:.0}",
        verlet_max_step * 1e6,
        pmor_wall,
        pmor_wall / END_S,
        pmor_wall / (END_S / COMM_STEP_S) * 1e3,
        lumped_wall * 1e3,
        pmor_wall / lumped_wall
    );
    println!(
        "example 3 with RK4 at {:.1} µs: {rk4_wall:.3} s wall; velocity Verlet / RK4 wall-time ratio {:.2}",
        rk4_max_step * 1e6,
        pmor_wall / rk4_wall
    );
    println!("example 3 end: ω₂ = {:.4} rad/s (velocity Verlet), {:.4} rad/s (RK4)", loaded.omega[1], rk4_end.omega[1]);
}
