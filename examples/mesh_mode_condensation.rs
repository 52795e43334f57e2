//! Study (issue 38): the linearized mesh mode of a PMOR-Hertz .fmu under each treatment of the stiff
//! coordinates — the default quasi-static condensation (shapes, hub and body modes above 6 × the
//! mesh mode under the discrete gradient), the same at 3 ×, with every body mode dynamic, and the full model (every coordinate with its
//! inertia): which of the condensation's approximations moves the mesh mode.
//!
//!     cargo run --release --example mesh_mode_condensation -- out/KurokawaSpur.fmu [T1_Nm] [positions] [mesh damping ratio]
#[path = "common/fmu_model.rs"]
mod fmu_model;
use gearfmu::dynamics::pmor::{linear, quasi_static::Condensation};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or("usage: mesh_mode_condensation FMU [T1] [positions] [zeta]")?;
    let model = fmu_model::pmor_model(path)?;
    let torque: f64 = args.get(2).map_or(Ok(model.pair.operating_torque_nm), |t| t.parse()).map_err(|_| "T1")?;
    let positions: usize = args.get(3).map_or(Ok(4), |t| t.parse()).map_err(|_| "positions")?;
    // The mesh damper's ratio (default none: the bodies' and shapes' damping alone).
    let zeta: f64 = args.get(4).map_or(Ok(0.0), |t| t.parse()).map_err(|_| "zeta")?;
    let inertia = [model.gears[0].polar_inertia_kgm2, model.gears[1].polar_inertia_kgm2];
    let place = gearfmu::contact::mesh_kinematics::PairPlacement::new(&model.pair);
    let damping = model.damping(model.modal_damping_ratio, model.shape_damping_ratio);
    // Cut-offs as multiples of the mesh mode's 2-DOF estimate (`None`: the model's own).
    let cases: [(&str, Condensation, Option<f64>); 4] = [
        ("quasi-static, the default body cut-off", Condensation::QuasiStatic, None),
        ("quasi-static, cut-off 3 × mesh mode", Condensation::QuasiStatic, Some(3.0)),
        ("quasi-static, every body mode dynamic", Condensation::QuasiStatic, Some(f64::INFINITY)),
        ("full (every coordinate with inertia)", Condensation::None, None),
    ];
    let mesh_mode_hz = gearfmu::dynamics::pmor::quasi_static::mesh_mode_estimate_hz(&model);
    // Each build calibrates its own gain on its own treatment: every row here takes this FMU's.
    println!("mesh damper gain g = {:.3} (this FMU's build), mesh damping ratio {zeta}", model.mesh_damper_gain);
    for (label, condensation, cutoff) in cases {
        let mut d = gearfmu::dynamics::pmor::PmorDynamics::new(&model, &place, damping, [0.0; 2]);
        d.set_condensation(condensation);
        d.mesh_damping_n_s_per_m = model.mesh_damper_n_s_per_m(zeta, inertia);
        if let Some(factor) = cutoff {
            d.set_quasi_static_cutoff(factor * mesh_mode_hz);
        }
        let mut text = Vec::new();
        for j in 0..positions {
            let theta2 = (j as f64 + 0.5) / positions as f64 * model.gears[1].pitch_rad();
            let m = linear::mesh_mode(&d, theta2, torque)?;
            text.push(format!("{:.0} Hz ζ {:.4}", m.frequency_hz, m.damping_ratio));
        }
        println!("{label:40} {}", text.join("  "));
    }
    Ok(())
}
