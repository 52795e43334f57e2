//! Study (issue 39): where a PMOR-Hertz doStep's time goes at operating speed. Runs issue 38's
//! brake case (synchronous start, constant T₁, a viscous brake on gear 2 fed back from the port's
//! speed each communication step) on the model of a .fmu, in process, through
//! `PmorDynamics::advance` as the FMU calls it, and reports per doStep: wall time, internal steps,
//! quasi-static solves and contact evaluations, and the wall time per evaluation.
//!
//!     cargo run --release --example step_cost -- out/KurokawaSpur.fmu [mesh_Hz] [comm_step_s] [T1_Nm]
use gearfmu::dynamics::pmor::PmorDynamics;
use gearfmu::model_file::{ModelFile, ModelKind};
use std::time::Instant;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or("usage: step_cost FMU [mesh_Hz] [comm_step_s] [T1_Nm]")?;
    let arg = |k: usize, default: f64| args.get(k).map_or(Ok(default), |t| t.parse::<f64>()).map_err(|e| e.to_string());
    let (mesh_hz, h, torque) = (arg(2, 1500.0)?, arg(3, 2e-5)?, arg(4, 185.0)?);
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut archive = zip::ZipArchive::new(file).map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(&mut archive.by_name("resources/model.bin").map_err(|e| e.to_string())?, &mut bytes)
        .map_err(|e| e.to_string())?;
    let ModelKind::PmorHertz(model) = ModelFile::from_bytes(&bytes)?.model else { return Err("not PMOR-Hertz".into()) };
    let place = gearfmu::contact::mesh_kinematics::PairPlacement::new(&model.pair);
    let damping = model.damping(model.modal_damping_ratio, model.shape_damping_ratio);
    let (z1, z2) = (model.pair.gear1.teeth as f64, model.pair.gear2.teeth as f64);
    let omega_2 = 2.0 * std::f64::consts::PI * mesh_hz / z2;
    let brake = torque * z2 / (z1 * omega_2);
    let mut dynamics = PmorDynamics::new(&model, &place, damping, [0.0; 2]);
    let inertia = [model.gears[0].polar_inertia_kgm2, model.gears[1].polar_inertia_kgm2];
    dynamics.mesh_damping_n_s_per_m = model.mesh_damper_n_s_per_m(model.pair.mesh_damping_ratio, inertia);
    let mut s = dynamics.start_state([0.0; 2], [omega_2 * z2 / z1, omega_2], [torque, -torque * z2 / z1])?;
    let steps = (0.02 / h).round() as usize;
    let counts = |d: &PmorDynamics| d.condensed().map_or((0, 0), |q| q.counts.get());
    let before = counts(&dynamics);
    let t0 = Instant::now();
    for _ in 0..steps {
        let w2 = dynamics.port(1, &s)?.1;
        dynamics.advance(&mut s, [torque, -brake * w2], h, model.max_step_s)?;
    }
    let wall = t0.elapsed().as_secs_f64();
    let after = counts(&dynamics);
    let (evaluations, solves) = ((after.0 - before.0) as f64, (after.1 - before.1) as f64);
    let bound = dynamics.angular_step_bound_s(&s).min(model.max_step_s);
    let substeps = (h / bound - 1e-9).ceil();
    println!(
        "{mesh_hz} Hz, h = {h:e} s: {:.0} µs per doStep ({:.1} × real time), {substeps} steps per doStep, \
         {:.2} solves and {:.2} contact evaluations per doStep, {:.1} µs per evaluation; ω₂ {:.4} of its target",
        wall / steps as f64 * 1e6,
        wall / (steps as f64 * h),
        solves / steps as f64,
        evaluations / steps as f64,
        wall / evaluations * 1e6,
        s.omega[1] / omega_2
    );
    Ok(())
}
