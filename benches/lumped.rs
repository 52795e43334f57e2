//! Cost of the lumped model, measured in release mode (`cargo bench --bench lumped`).
//!
//! Baseline, run in the same process: the same RK4 on the same two inertias with a constant mesh
//! stiffness k̄ (the simplest lumped gear model: no tables, no backlash). Reported: ns per internal
//! RK4 step (ratio to the baseline; with tooth friction, μ 0.05, ratio to the frictionless step), ns per doStep through the exported C functions, and the
//! seed's 25 ms example (185 N·m haversine ramp, viscous 20 N·m·s/rad) as a real-time factor at
//! max_step 1 µs and 10 µs.

use fmi_sys::fmi2::*;
use gearfmu::dynamics::lumped::{LumpedMesh, LumpedModel, LumpedState};
use gearfmu::fmi2::exports::*;
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::interface::value_reference;
use gearfmu::model_file::{ModelFile, ModelKind};
use std::ffi::CString;
use std::hint::black_box;
use std::time::Instant;

fn median(mut samples: Vec<f64>) -> f64 {
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

/// The baseline: two inertias, a constant-stiffness spring-damper along the LOA.
fn baseline_step(s: &[f64; 4], torques: [f64; 2], h: f64, rb: [f64; 2], j: [f64; 2], k: f64, c: f64) -> [f64; 4] {
    let f = |s: &[f64; 4]| {
        let delta = rb[0] * s[0] - rb[1] * s[2];
        let delta_dot = rb[0] * s[1] - rb[1] * s[3];
        let force = k * delta + c * delta_dot;
        [s[1], (torques[0] - rb[0] * force) / j[0], s[3], (torques[1] + rb[1] * force) / j[1]]
    };
    let add = |a: &[f64; 4], b: &[f64; 4], t: f64| [a[0] + t * b[0], a[1] + t * b[1], a[2] + t * b[2], a[3] + t * b[3]];
    let k1 = f(s);
    let k2 = f(&add(s, &k1, 0.5 * h));
    let k3 = f(&add(s, &k2, 0.5 * h));
    let k4 = f(&add(s, &k3, h));
    let mut out = *s;
    for i in 0..4 {
        out[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    out
}

fn seed_torque(t: f64) -> f64 {
    185.0 * if t < 5e-3 { 0.5 * (1.0 - (std::f64::consts::PI * t / 5e-3).cos()) } else { 1.0 }
}

/// ns per fmi2DoStep (plus the two SetReal and one GetReal a master makes) through the exported
/// C functions, in-process, communication step 0.1 ms, max_step 10 µs.
fn per_do_step_through_c(pair: &GearPair, mesh: &LumpedMesh) -> f64 {
    let kind = ModelKind::Lumped(mesh.clone());
    let guid = ModelFile::compute_guid(gearfmu::interface::VARIABLES_TOML, &pair.name, &kind);
    let dir = std::env::temp_dir().join(format!("gearfmu-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = ModelFile { guid: guid.clone(), pair_name: pair.name.clone(), model: kind };
    std::fs::write(dir.join(gearfmu::model_file::FILE_NAME), file.to_bytes()).unwrap();
    let (name, guid, uri) = (
        CString::new("bench").unwrap(),
        CString::new(guid).unwrap(),
        CString::new(format!("file://{}", dir.display())).unwrap(),
    );
    let cb = fmi2CallbackFunctions {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::null_mut(),
    };
    // SAFETY: valid NUL-terminated strings and a callback table that outlives the instance.
    let c =
        unsafe { fmi2Instantiate(name.as_ptr(), fmi2Type_fmi2CoSimulation, guid.as_ptr(), uri.as_ptr(), &cb, 0, 0) };
    assert!(!c.is_null());
    let vr = |n: &str| value_reference(n).unwrap();
    let (tau, w2) = ([vr("tau_1"), vr("tau_2")], vr("w_2"));
    assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), fmi2Status_fmi2OK);
    assert_eq!(fmi2EnterInitializationMode(c), fmi2Status_fmi2OK);
    assert_eq!(fmi2ExitInitializationMode(c), fmi2Status_fmi2OK);
    let n = 2000;
    let comm = 1e-4;
    let mut omega = 0.0;
    let t0 = Instant::now();
    for k in 0..n {
        let t = k as f64 * comm;
        fmi2SetReal(c, tau.as_ptr(), 2, [seed_torque(t), -20.0 * omega].as_ptr());
        assert_eq!(fmi2DoStep(c, t, comm, 1), fmi2Status_fmi2OK);
        fmi2GetReal(c, &w2, 1, &mut omega);
    }
    let per_step = t0.elapsed().as_secs_f64() / n as f64;
    fmi2FreeInstance(c);
    per_step
}

fn main() {
    // `cargo bench` passes --bench; nothing else to parse.
    for name in ["kurokawa_spur.toml", "kurokawa_helical.toml"] {
        let spec = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(name);
        let pair = GearPair::from_spec(&PairSpec::load(&spec).unwrap()).unwrap();
        let mesh = LumpedMesh::from_pair(&pair).unwrap();
        let model = LumpedModel::with_defaults(&mesh);
        let steps = 200_000;
        let h = 1e-6;

        // The same with tooth friction (μ 0.05, v_ε as the FMU sets it at this step).
        let mut with_friction = gearfmu::dynamics::lumped::LumpedParameters {
            friction_coefficient: 0.05,
            ..gearfmu::dynamics::lumped::LumpedParameters::defaults(&mesh)
        };
        with_friction.sliding_regularization_m_per_s =
            gearfmu::dynamics::lumped::sliding_regularization_m_per_s(&mesh, &with_friction, h);
        let friction_model = LumpedModel::new(&mesh, with_friction);

        // Seconds per RK4 step of the seed example's drive.
        let per_step = |model: &LumpedModel| {
            let mut s = LumpedState::default();
            let t0 = Instant::now();
            for k in 0..steps {
                s = model.rk4_step(&s, [seed_torque(k as f64 * h), -20.0 * s.omega_2], h);
            }
            black_box(s);
            t0.elapsed().as_secs_f64() / steps as f64
        };

        let mut lumped = Vec::new();
        let mut friction = Vec::new();
        let mut base = Vec::new();
        for _ in 0..7 {
            friction.push(per_step(&friction_model));
            lumped.push(per_step(&model));

            let (rb, j) = (
                [mesh.base_radius_1_m, mesh.base_radius_2_m],
                [model.params.inertia_1_kgm2, model.params.inertia_2_kgm2],
            );
            let (k_mean, c) = (mesh.reference_stiffness(), model.damping_n_s_per_m);
            let mut b = [0.0; 4];
            let t0 = Instant::now();
            for k in 0..steps {
                b = baseline_step(&b, [seed_torque(k as f64 * h), -20.0 * b[3]], h, rb, j, k_mean, c);
            }
            black_box(b);
            base.push(t0.elapsed().as_secs_f64() / steps as f64);
        }
        let (lumped, friction, base) = (median(lumped), median(friction), median(base));
        println!(
            "{name}: internal RK4 step {:.1} ns; baseline (constant k̄) {:.1} ns; ratio {:.2}; with tooth friction (μ 0.05) {:.1} ns, {:.2} × the frictionless step",
            lumped * 1e9,
            base * 1e9,
            lumped / base,
            friction * 1e9,
            friction / lumped
        );

        println!(
            "{name}: per doStep through the C API (0.1 ms, max_step 10 µs = 10 RK4 sub-steps): {:.2} µs",
            per_do_step_through_c(&pair, &mesh) * 1e6
        );
        // The seed example through the model's sub-stepping, communication step 0.1 ms.
        for max_step in [1e-6, 1e-5] {
            let mut runs = Vec::new();
            for _ in 0..5 {
                let mut s = LumpedState::default();
                let comm = 1e-4;
                let t0 = Instant::now();
                for k in 0..250 {
                    let t = k as f64 * comm;
                    let torques = [seed_torque(t), -20.0 * s.omega_2];
                    model.advance(&mut s, torques, comm, max_step);
                }
                black_box(s);
                runs.push(t0.elapsed().as_secs_f64());
            }
            let wall = median(runs);
            println!(
                "{name}: seed example 25 ms at max_step {:.0} µs: wall {:.2} ms, real-time factor {:.1} (simulated/wall), per doStep {:.2} µs",
                max_step * 1e6,
                wall * 1e3,
                0.025 / wall,
                wall / 250.0 * 1e6
            );
        }
    }
}
