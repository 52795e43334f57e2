//! Study (issue 38): the linearized mesh mode of a PMOR-Hertz .fmu under each treatment of the stiff
//! coordinates — the default quasi-static condensation (shapes, hub and body modes above 3 × the
//! mesh mode), the same with every body mode dynamic, and the full model (every coordinate with its
//! inertia): which of the condensation's approximations moves the mesh mode.
//!
//!     cargo run --release --example mesh_mode_condensation -- out/KurokawaSpur.fmu [T1_Nm] [positions]
#[path = "common/fmu_model.rs"]
mod fmu_model;
use gearfmu::dynamics::pmor::{linear, quasi_static::Condensation};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or("usage: mesh_mode_condensation FMU [T1] [positions]")?;
    let model = fmu_model::pmor_model(path)?;
    let torque: f64 = args.get(2).map_or(Ok(model.pair.operating_torque_nm), |t| t.parse()).map_err(|_| "T1")?;
    let positions: usize = args.get(3).map_or(Ok(4), |t| t.parse()).map_err(|_| "positions")?;
    let place = gearfmu::contact::mesh_kinematics::PairPlacement::new(&model.pair);
    let damping = model.damping(model.modal_damping_ratio, model.shape_damping_ratio);
    let cases: [(&str, Option<Condensation>, Option<f64>); 4] = [
        ("quasi-static, default body cut-off", Some(Condensation::QuasiStatic), None),
        ("quasi-static, cut-off 6 × mesh mode", Some(Condensation::QuasiStatic), Some(2.0)),
        ("quasi-static, every body mode dynamic", Some(Condensation::QuasiStatic), Some(f64::INFINITY)),
        ("full (every coordinate with inertia)", Some(Condensation::None), None),
    ];
    let default_cutoff = gearfmu::dynamics::pmor::quasi_static::body_cutoff_hz(&model);
    for (label, condensation, cutoff) in cases {
        let mut d = gearfmu::dynamics::pmor::PmorDynamics::new(&model, &place, damping, [0.0; 2]);
        d.set_condensation(condensation.unwrap());
        if let Some(c) = cutoff {
            d.set_quasi_static_cutoff(if c.is_finite() { c * default_cutoff } else { c });
        }
        let mut text = Vec::new();
        for j in 0..positions {
            let theta2 = (j as f64 + 0.5) / positions as f64 * model.gears[1].pitch_rad();
            let m = linear::mesh_mode(&d, theta2, torque)?;
            text.push(format!("{:.0} Hz", m.frequency_hz));
        }
        println!("{label:40} {}", text.join("  "));
    }
    Ok(())
}
