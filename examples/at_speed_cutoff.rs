//! Study (issue 38): the steady response through the mesh resonance under another body-mode
//! cut-off than the shipped one, in process — the brake case of `gearfmu.at_speed` (synchronous
//! start, constant T₁, a viscous brake on gear 2 fed back from its speed at each step's start,
//! c = T₁z₂/(z₁ω₂*)), its DTE RMS about the mean over the last 5 ms, for each cut-off factor
//! (× the mesh mode's 2-DOF estimate; `inf`: every body mode dynamic). Which approximation a
//! departure from the full model comes from: the cut-off, or what it leaves.
//!
//!     cargo run --release --example at_speed_cutoff -- out/KurokawaSpur.fmu 4800 0 6,12,inf [t_end_ms] [T1_Nm] [max_step_s]
#[path = "common/fmu_model.rs"]
mod fmu_model;
use gearfmu::dynamics::pmor::{quasi_static, PmorDynamics};

const STEP_S: f64 = 1e-5;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: at_speed_cutoff FMU MESH_HZ[,MESH_HZ…] ZETA FACTOR[,FACTOR…] [t_end_ms] [T1_Nm] [max_step_s]";
    let model = fmu_model::pmor_model(args.get(1).ok_or(usage)?)?;
    let list = |i: usize| -> Result<Vec<f64>, String> {
        args.get(i).ok_or(usage)?.split(',').map(|x| x.parse::<f64>().map_err(|_| format!("{x}: {usage}"))).collect()
    };
    let (mesh_hz, zeta, factors) = (list(2)?, list(3)?[0], list(4)?);
    let t_end_s = args.get(5).map_or(Ok(40.0), |t| t.parse::<f64>()).map_err(|_| usage)? * 1e-3;
    let torque_1 = args.get(6).map_or(Ok(model.pair.operating_torque_nm), |t| t.parse::<f64>()).map_err(|_| usage)?;
    let (z1, z2) = (model.gears[0].teeth as f64, model.gears[1].teeth as f64);
    let max_step = args.get(7).map_or(Ok(model.max_step_s), |t| t.parse::<f64>()).map_err(|_| usage)?;
    let rb = [model.gears[0].base_radius_m, model.gears[1].base_radius_m];
    let place = gearfmu::contact::mesh_kinematics::PairPlacement::new(&model.pair);
    let damping = model.damping(model.modal_damping_ratio, model.shape_damping_ratio);
    let inertia = [model.gears[0].polar_inertia_kgm2, model.gears[1].polar_inertia_kgm2];
    let mesh_mode_hz = quasi_static::mesh_mode_estimate_hz(&model);
    println!("T₁ {torque_1} N·m, mesh damping ratio {zeta}, max_step {max_step:e} s, {STEP_S:e} s calls, {:.0} ms; DTE RMS (µm) over the last 5 ms", t_end_s * 1e3);
    for &f in &mesh_hz {
        let omega_2 = 2.0 * std::f64::consts::PI * f / z2;
        let omega = [omega_2 * z2 / z1, omega_2];
        let brake = torque_1 * z2 / (z1 * omega_2);
        let mut row = format!("{f:7.0} Hz");
        for &factor in &factors {
            let mut d = PmorDynamics::new(&model, &place, damping, [0.0; 2]);
            d.mesh_damping_n_s_per_m = model.mesh_damper_n_s_per_m(zeta, inertia);
            d.set_quasi_static_cutoff(factor * mesh_mode_hz);
            let mut s = d.start_state([0.0; 2], omega, [0.0; 2])?;
            let steps = (t_end_s / STEP_S).round() as usize;
            let tail = (5e-3 / STEP_S).round() as usize;
            let mut dte = Vec::with_capacity(tail);
            for k in 0..steps {
                let (_, w_2) = d.port(1, &s)?;
                d.advance(&mut s, [torque_1, -brake * w_2], STEP_S, max_step)?;
                if k + tail >= steps {
                    dte.push(rb[0] * s.theta[0] - rb[1] * s.theta[1]);
                }
            }
            let mean = dte.iter().sum::<f64>() / dte.len() as f64;
            let rms = (dte.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / dte.len() as f64).sqrt();
            row += &format!("   {factor} ×: {:.3}", rms * 1e6);
        }
        println!("{row}");
    }
    Ok(())
}
