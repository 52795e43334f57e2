//! `fmu-build inspect`: a pair's geometry, ISO 6336-1 stiffness and lumped mesh law, printed
//! and optionally dumped as JSON.

use anyhow::{bail, Result};
use gearfmu::closed_forms::iso6336;
use gearfmu::dynamics::lumped::{mesh_damping_coefficient, mesh_natural_frequency_hz, LumpedMesh, LumpedParameters};
use gearfmu::gear::sig;
use gearfmu::gear::GearPair;
use gearfmu::model_file::ModelKind;
use std::path::{Path, PathBuf};

use crate::cli::{pair_and_mesh, MeshLawChoice, Resolution};

use crate::build_command::lumped_mesh;

pub(crate) fn inspect(
    spec: &Path,
    json: Option<PathBuf>,
    law: MeshLawChoice,
    from_fmu: Option<&Path>,
    resolution: Resolution,
) -> Result<()> {
    let (pair, mesh_spec) = pair_and_mesh(spec, resolution)?;
    let iso = iso6336::mesh_stiffness_c_gamma_alpha(&pair);
    let iso_total = iso6336::to_newton_per_metre(iso, pair.face_width_m);
    println!("pair {}: z {}/{}", pair.name, pair.gear1.teeth, pair.gear2.teeth);
    println!("  base radii        {:.4} / {:.4} mm", pair.gear1.base_radius_m * 1e3, pair.gear2.base_radius_m * 1e3);
    println!(
        "  center distance   {:.4} mm, operating pressure angle {:.4}°",
        pair.center_distance_m * 1e3,
        pair.operating_pressure_angle_rad.to_degrees()
    );
    println!("  base pitch        {:.4} mm", pair.base_pitch_m * 1e3);
    println!("  contact ratios    ε_α {:.4}, ε_β {:.4}", pair.transverse_contact_ratio, pair.overlap_ratio);
    println!("  inertias          {:.5} / {:.5} kg·m²", pair.gear1.inertia_kgm2, pair.gear2.inertia_kgm2);
    println!(
        "  torque on gear 1  operating {} N·m; rated {} N·m (nominal root stress at a third of the yield strength), yield {} N·m",
        sig(pair.operating_torque_nm),
        sig(gearfmu::closed_forms::rating::rated_torque_nm(&pair)),
        sig(gearfmu::closed_forms::rating::yield_torque_nm(&pair))
    );
    println!("  ISO 6336-1 c_γα·b {iso_total:.4e} N/m");
    // The sliding loss estimate a drivetrain engineer starts from (the lumped FMU's friction is
    // checked against it, `tests/lumped_friction.rs`).
    use gearfmu::closed_forms::gear_loss::{addendum_contact_ratios, gear_loss_factor, gear_loss_factor_uniform_load};
    let h_v = gear_loss_factor(&pair);
    match &h_v {
        Ok(h_v) => {
            let [e1, e2] = addendum_contact_ratios(&pair);
            println!(
                "  ISO/TR 14179-2 gear loss factor H_V {h_v:.4}: mesh efficiency 1 − μ·H_V = {:.2} % at μ = 0.05 (addendum contact ratios ε₁ {e1:.4}, ε₂ {e2:.4})",
                100.0 * (1.0 - 0.05 * h_v)
            );
            println!(
                "  the same with the load spread evenly over the path (a helical pair's limit at ε_β ≥ 1): H_V,u {:.4}",
                gear_loss_factor_uniform_load(&pair)
            )
        }
        Err(why) => println!("  gear loss factor H_V: not given: {why}"),
    }
    // The geometry is printed; the mesh law takes its FE statics now (with `--mesh-law fe`).
    let mesh = match from_fmu {
        Some(fmu) => lumped_mesh_of_fmu(fmu, &pair)?,
        None => lumped_mesh(&pair, &mesh_spec, law, None)?,
    };
    let params = LumpedParameters::defaults(&mesh);
    for specific_load in [50.0, 100.0, 200.0, 400.0] {
        let force = specific_load * 1e3 * pair.face_width_m;
        let secant = mesh.drive.mean_secant_stiffness(force);
        println!(
            "  at {specific_load:>3} N/mm: mean secant stiffness {secant:.4e} N/m ({:.3} × ISO), mean tangent {:.4e} N/m, mesh natural frequency {:.1} Hz",
            secant / iso_total,
            mesh.drive.mean_tangent_stiffness(force),
            mesh_natural_frequency_hz(&mesh, &params, force)
        );
    }
    if let Some(path) = json {
        let k = mesh.drive.force_levels_n.len();
        let rows = |law: &gearfmu::dynamics::mesh_law::MeshLaw| -> Vec<Vec<f64>> {
            law.deflection_m.chunks(k).map(|r| r.to_vec()).collect()
        };
        let n = mesh.drive.rows();
        let value = serde_json::json!({
            "base_radius_1_m": mesh.base_radius_1_m,
            "base_radius_2_m": mesh.base_radius_2_m,
            "teeth_1": mesh.teeth_1,
            "teeth_2": mesh.teeth_2,
            "inertia_1_kgm2": params.inertia_1_kgm2,
            "inertia_2_kgm2": params.inertia_2_kgm2,
            "base_pitch_m": mesh.base_pitch_m,
            "backlash_m": mesh.backlash_m,
            "mesh_damping_n_s_per_m": mesh_damping_coefficient(&mesh, &params),
            "roll_offset_m": mesh.roll_offset_m,
            "roll_m": (0..n).map(|i| mesh.base_pitch_m * i as f64 / n as f64).collect::<Vec<_>>(),
            "force_levels_n": mesh.drive.force_levels_n,
            "drive_deflection_m": rows(&mesh.drive),
            "coast_deflection_m": rows(&mesh.coast),
            "reference_force_n": mesh.reference_force_n,
            "reference_stiffness_n_per_m": mesh.reference_stiffness(),
            "mesh_natural_frequency_hz": mesh_natural_frequency_hz(&mesh, &params, mesh.reference_force_n),
            "iso6336_c_gamma_alpha_n_per_m": iso_total,
            "operating_torque_nm": pair.operating_torque_nm,
            "operating_pressure_angle_rad": pair.operating_pressure_angle_rad,
            "base_helix_angle_rad": pair.base_helix_angle_rad,
            "overlap_ratio": pair.overlap_ratio,
            "path_start_m": pair.path_start_m,
            "path_end_m": pair.path_end_m,
            "pitch_point_m": pair.pitch_point_m(),
            "face_width_m": pair.face_width_m,
            "gear_loss_factor_iso": h_v.as_ref().ok(),
            "gear_loss_factor_uniform_load": gear_loss_factor_uniform_load(&pair),
            "mesh_law": match mesh.law_source {
                gearfmu::dynamics::lumped::MeshLawSource::Analytic => "analytic",
                gearfmu::dynamics::lumped::MeshLawSource::FeStatics => "fe",
            },
        });
        std::fs::write(&path, serde_json::to_string_pretty(&value)?)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// The lumped mesh law a built lumped FMU carries (its `resources/` model file), checked to be
/// of the spec's pair: its teeth, base radii and base pitch must be the spec's.
fn lumped_mesh_of_fmu(fmu: &Path, pair: &GearPair) -> Result<LumpedMesh> {
    let ModelKind::Lumped(mesh) = crate::fmu_archive::read_model_file(fmu)?.model else {
        bail!("{} is not a lumped FMU (build it with --model lumped or --lumped-fmu)", fmu.display());
    };
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
    if mesh.teeth_1 != pair.gear1.teeth
        || mesh.teeth_2 != pair.gear2.teeth
        || !same(mesh.base_radius_1_m, pair.gear1.base_radius_m)
        || !same(mesh.base_radius_2_m, pair.gear2.base_radius_m)
        || !same(mesh.base_pitch_m, pair.base_pitch_m)
    {
        bail!("{} was not built from this spec (pair {}): its teeth or base radii differ", fmu.display(), pair.name);
    }
    Ok(mesh)
}
