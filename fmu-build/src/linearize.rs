//! `fmu-build linearize`: a built FMU's pair linearized about its static equilibria: natural
//! frequencies and the explicit step's stability limit.

use anyhow::Result;
use gearfmu::model_file::{ModelFile, ModelKind};
use std::path::Path;

pub(crate) fn linearize_command(
    fmu: &Path,
    torque_nm: Option<f64>,
    mesh_damping_ratio: Option<f64>,
    positions: usize,
    count: usize,
) -> Result<()> {
    use gearfmu::dynamics::pmor::linear;
    let ModelKind::PmorHertz(model) = crate::fmu_archive::read_model_file(fmu)?.model else {
        anyhow::bail!(
            "{} carries the lumped model: its linearized mesh frequency is sqrt(k (r_b1²/J1 + r_b2²/J2))/2π with k its mesh_stiffness output (`inspect`)",
            fmu.display()
        );
    };
    // The instance's dynamics, as the FMU builds it (mesh damper included).
    let file =
        ModelFile { guid: String::new(), pair_name: model.pair.name.clone(), model: ModelKind::PmorHertz(model) };
    let fmu_model = gearfmu::fmu::gear_pair::GearPairFmu::from_model_file(file).map_err(anyhow::Error::msg)?;
    let gearfmu::fmu::gear_pair::Physics::PmorHertz { model, place } = &fmu_model.physics else { unreachable!() };
    let mut state = gearfmu::fmi2::Model::initial_state(&fmu_model);
    let torque_nm = torque_nm.unwrap_or(model.pair.operating_torque_nm);
    let zeta = mesh_damping_ratio.unwrap_or(state.params.mesh_damping_ratio);
    state.params.mesh_damping_ratio = zeta;
    let dynamics = fmu_model.pmor(model, place, &state);
    let guess = torque_nm / model.pair.gear1.base_radius_m / (1e11 * model.pair.face_width_m);
    println!(
        "{}: linearized at T1 = {torque_nm} N·m; modal damping {} on the eigenmodes, {} on the shapes; mesh damper ζ = {zeta} (c = {:.1} N·s/m on k̄ = {:.4e} N/m)",
        model.pair.name, model.modal_damping_ratio, model.shape_damping_ratio, dynamics.mesh_damping_n_s_per_m, model.mesh_stiffness_n_per_m
    );
    let mesh_mass_kg = model.mesh_mass_kg([state.params.inertia_1_kgm2, state.params.inertia_2_kgm2]);
    println!(
        "rigid gears on the mean mesh stiffness (the 2-DOF estimate): √(k̄/m_e)/2π = {:.0} Hz (m_e = {mesh_mass_kg:.4} kg)",
        (model.mesh_stiffness_n_per_m / mesh_mass_kg).sqrt() / (2.0 * std::f64::consts::PI)
    );
    println!("position (pitch of gear 2) | mesh mode (its share of a load step's DTE) | lowest modes: |λ|/2π (Hz), ζ = −Re λ/|λ|");
    let mut omega_squared = 0.0;
    for j in 0..positions {
        let share = (j as f64 + 0.5) / positions as f64;
        let theta2 = share * model.gears[1].pitch_rad();
        let mesh = linear::mesh_mode(&dynamics, theta2, torque_nm).map_err(anyhow::Error::msg)?;
        omega_squared += mesh.frequency_hz.powi(2) / positions as f64;
        let (state, torque2) =
            linear::static_equilibrium(&dynamics, theta2, torque_nm, guess).map_err(anyhow::Error::msg)?;
        let lin = linear::linearize(&dynamics, &state, [torque_nm, torque2]).map_err(anyhow::Error::msg)?;
        // Oscillating modes, one of each conjugate pair; the rigid rotation (λ ≈ 0) left out.
        let mut modes: Vec<(f64, f64)> = lin
            .flow_eigenvalues()
            .into_iter()
            .filter(|l| l.im > 0.0 && l.norm() > 2.0 * std::f64::consts::PI)
            .map(|l| (l.norm() / (2.0 * std::f64::consts::PI), -l.re / l.norm()))
            .collect();
        modes.sort_by(|a, b| a.0.total_cmp(&b.0));
        let text: Vec<String> = modes.iter().take(count).map(|(f, z)| format!("{f:.0} Hz ζ {z:.4}")).collect();
        println!(
            "{share:.3} | {:.0} Hz ζ {:.4} ({:.0} %) | {}",
            mesh.frequency_hz,
            mesh.damping_ratio,
            100.0 * mesh.dte_share,
            text.join(", ")
        );
    }
    // The mesh stiffness varies over the pitch; its mean (over positions) is the mean of ω².
    println!("mesh mode on the mean mesh stiffness, √(mean ω²)/2π over the positions: {:.0} Hz", omega_squared.sqrt());
    Ok(())
}
