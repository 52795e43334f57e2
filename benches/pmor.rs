//! Cost of the PMOR-Hertz reduced pair, measured in release mode (`cargo bench --bench pmor`).
//!
//! Baselines, run in the same process: the full reduced pair (every coordinate with its
//! inertia, `Condensation::None`, the model before the quasi-static condensation) and the lumped
//! FMU's model (`dynamics::lumped`) on the same pair and the same loading. Reported: µs per
//! right-hand side of the full pair, per velocity Verlet step of each (one right-hand side
//! each; the condensed one with its contact evaluations per right-hand side), per RK4 step, and
//! the seed's example 3 (185 N·m haversine ramp 5 ms, viscous 20 N·m·s/rad on gear 2 fed back
//! from the port's speed, 25 ms, communication step 0.1 ms) as wall time and real-time factor,
//! each at its default max_step (0.6 of its integrator's limit from the linearization; lumped
//! 1 µs); the condensed pair also with RK4 (`--integrator rk4`), the integrator baseline, and
//! without the body-mode cut-off (every body mode dynamic), the step's baseline.
//!
//! The reduced pair is built here with the default options (about 15 s), so the figures belong
//! to the same model `fmu-build build` ships.

use gearfmu::contact::mesh_kinematics::PairPlacement;
use gearfmu::dynamics::lumped::{LumpedMesh, LumpedModel, LumpedState};
use gearfmu::dynamics::pmor::integrator::Integrator;
use gearfmu::dynamics::pmor::quasi_static::Condensation;
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
    let damping = model.damping(model.modal_damping_ratio, model.shape_damping_ratio);
    // Each treatment and integrator at its own default step (the build's rule).
    let at = |condensation: Condensation, integrator: Integrator| {
        let mut d = PmorDynamics::new(&model, &place, damping, [0.0; 2]);
        d.set_condensation(condensation);
        d.integrator = integrator;
        let step = linear::default_step(&d).unwrap().max_step_s;
        (d, step)
    };
    let (dynamics, verlet_max_step) = at(Condensation::QuasiStatic, Integrator::Verlet);
    let (rk4, rk4_max_step) = at(Condensation::QuasiStatic, Integrator::Rk4);
    let (full, full_max_step) = at(Condensation::None, Integrator::Verlet);
    // The condensation before the body-mode cut-off: the shapes and the hub quasi-static, every
    // body mode dynamic.
    let (every_mode, every_mode_max_step) = {
        let mut d = PmorDynamics::new(&model, &place, damping, [0.0; 2]);
        d.set_quasi_static_cutoff(f64::INFINITY);
        d.integrator = Integrator::Verlet;
        let step = linear::default_step(&d).unwrap().max_step_s;
        (d, step)
    };

    // Example 3 through the model's own sub-stepping, as the FMU runs it.
    let example_3 = |dynamics: &PmorDynamics, max_step: f64, runs: usize| {
        let mut walls = Vec::new();
        let mut last = None;
        for _ in 0..runs {
            let mut s = dynamics.start_state([0.0; 2], [0.0; 2], [0.0; 2]).unwrap();
            let t0 = Instant::now();
            for k in 0..(END_S / COMM_STEP_S).round() as usize {
                let t = k as f64 * COMM_STEP_S;
                let torques = [seed_torque(t), -20.0 * dynamics.port(1, &s).unwrap().1];
                dynamics.advance(&mut s, torques, COMM_STEP_S, max_step).unwrap();
            }
            walls.push(t0.elapsed().as_secs_f64());
            last = Some(s);
        }
        (median(walls), last.unwrap())
    };
    let counts_before = dynamics.condensed().unwrap().counts.get();
    let (pmor_wall, loaded) = example_3(&dynamics, verlet_max_step, 3);
    let counts_after = dynamics.condensed().unwrap().counts.get();
    let evaluations_per_solve = (counts_after.0 - counts_before.0) as f64 / (counts_after.1 - counts_before.1) as f64;
    let (rk4_wall, rk4_end) = example_3(&rk4, rk4_max_step, 3);
    let (full_wall, full_end) = example_3(&full, full_max_step, 3);
    let (every_mode_wall, every_mode_end) = example_3(&every_mode, every_mode_max_step, 3);

    // Per right-hand side of the full pair, and per step of each, at the loaded state example 3
    // ends in.
    let torques = [185.0, -20.0 * loaded.omega[1]];
    let n = 2000;
    let full_y = full.pack(&full_end);
    let full_rhs_us = median(
        (0..5)
            .map(|_| {
                let t0 = Instant::now();
                for _ in 0..n {
                    black_box(full.rhs(black_box(&full_y), full_end.anchor, torques).unwrap());
                }
                t0.elapsed().as_secs_f64() / n as f64 * 1e6
            })
            .collect(),
    );
    let step_us = |d: &PmorDynamics, start: &gearfmu::dynamics::pmor::PmorState, h: f64| {
        median(
            (0..5)
                .map(|_| {
                    let mut s = start.clone();
                    let t0 = Instant::now();
                    // Through `advance`, as the FMU steps (the condensed pair's time-stepping tolerance).
                    d.advance(&mut s, torques, n as f64 * h, h * (1.0 + 1e-9)).unwrap();
                    black_box(s);
                    t0.elapsed().as_secs_f64() / n as f64 * 1e6
                })
                .collect(),
        )
    };
    let verlet_step_us = step_us(&dynamics, &loaded, verlet_max_step);
    let rk4_step_us = step_us(&rk4, &rk4_end, rk4_max_step);
    let full_step_us = step_us(&full, &full_end, full_max_step);
    let every_mode_step_us = step_us(&every_mode, &every_mode_end, every_mode_max_step);

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

    println!(
        "full pair (every coordinate with its inertia): right-hand side {full_rhs_us:.2} µs; velocity Verlet step {full_step_us:.1} µs at its default {:.2} µs",
        full_max_step * 1e6
    );
    println!(
        "quasi-static shapes, hub and body modes above the cut-off (the default): velocity Verlet step {verlet_step_us:.1} µs at its default {:.2} µs ({evaluations_per_solve:.2} contact evaluations per right-hand side in example 3); RK4 step {rk4_step_us:.1} µs at {:.2} µs; lumped RK4 step {:.3} µs",
        verlet_max_step * 1e6,
        rk4_max_step * 1e6,
        lumped_step_us,
    );
    println!(
        "quasi-static shapes and hub, every body mode dynamic (no cut-off): velocity Verlet step {every_mode_step_us:.1} µs at its default {:.2} µs; example 3 {every_mode_wall:.3} s (ratio to the default {:.2}), end DTE {:.4} µm",
        every_mode_max_step * 1e6,
        every_mode_wall / pmor_wall,
        dte(&model, &every_mode_end) * 1e6
    );
    println!(
        "example 3 (25 ms, comm 0.1 ms), each at its default step: quasi-static {pmor_wall:.3} s wall ({:.2}× real time, {:.2} ms per doStep); full {full_wall:.3} s (ratio {:.2}); quasi-static RK4 {rk4_wall:.3} s (Verlet / RK4 {:.2}); lumped at 1 µs {:.2} ms (ratio {:.0})",
        pmor_wall / END_S,
        pmor_wall / (END_S / COMM_STEP_S) * 1e3,
        full_wall / pmor_wall,
        pmor_wall / rk4_wall,
        lumped_wall * 1e3,
        pmor_wall / lumped_wall
    );
    println!(
        "example 3 end: ω₂ = {:.4} rad/s (quasi-static, Verlet), {:.4} (RK4), {:.4} (full); DTE {:.4} / {:.4} / {:.4} µm",
        loaded.omega[1],
        rk4_end.omega[1],
        full_end.omega[1],
        dte(&model, &loaded) * 1e6,
        dte(&model, &rk4_end) * 1e6,
        dte(&model, &full_end) * 1e6
    );
}

fn dte(model: &gearfmu::dynamics::pmor::model::PmorModel, s: &gearfmu::dynamics::pmor::PmorState) -> f64 {
    model.gears[0].base_radius_m * s.theta[0] - model.gears[1].base_radius_m * s.theta[1]
}
