//! `fmu-build build`: a spec reduced (PMOR-Hertz, the standard PMOR reference, or the lumped
//! pair's mesh law from the FE statics) and written as an FMU.

use anyhow::Result;
use gearfmu::contact::hertz::ApproachLaw;
use gearfmu::dynamics::lumped::LumpedMesh;
use gearfmu::dynamics::pmor::model::FlankContact;
use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::gear::{sig, GearPair};
use gearfmu::model_file::ModelKind;
use gearfmu::rom::sweep::{Method, ReducedPair};
use std::path::{Path, PathBuf};

use crate::cli::{
    contact_depth_or_default, pair_and_mesh_or, DynamicsChoice, IntegratorChoice, InterpolationChoice, MeshLawChoice,
    ModelChoice, Resolution, RomOptions,
};

use crate::fmu_archive::{check_output_folder, library_bytes, write_fmu};
use crate::progress::spinner;

pub(crate) fn build(
    spec: &Path,
    output: &Path,
    model: ModelChoice,
    mesh_law: Option<MeshLawChoice>,
    lumped_fmu: Option<&Path>,
    library: Option<PathBuf>,
    rom: &RomOptions,
    resolution: Resolution,
) -> Result<()> {
    check_output_folder(output)?;
    if let Some(path) = lumped_fmu {
        check_output_folder(path)?;
    }
    if !matches!(model, ModelChoice::Lumped) && mesh_law.is_some() {
        anyhow::bail!("--mesh-law chooses the lumped model's mesh law: give it with --model lumped");
    }
    if matches!(model, ModelChoice::PmorPenalty) {
        // The reference is the paper's model: its gears keep their local deformation (no depth,
        // no SVD) and it is RK4 on every coordinate. An option it would ignore is refused.
        let ignored: Vec<&str> = [
            ("--integrator", rom.integrator.is_some()),
            ("--dynamics", rom.dynamics.is_some()),
            ("--depth-mm", rom.depth_mm.is_some()),
            ("--p-en", rom.p_en.is_some()),
        ]
        .into_iter()
        .filter_map(|(name, given)| given.then_some(name))
        .collect();
        if !ignored.is_empty() {
            anyhow::bail!(
                "{} do not apply to --model pmor-penalty: the standard PMOR reference keeps each gear's local deformation (standard CMS: no contact depth, no SVD) and integrates every coordinate by RK4, as the paper ran it",
                ignored.join(", ")
            );
        }
    }
    if !matches!(model, ModelChoice::PmorHertz) && lumped_fmu.is_some() {
        anyhow::bail!("--lumped-fmu writes the lumped FMU beside a PMOR-Hertz build: give it with --model pmor-hertz");
    }
    let mesh_law = mesh_law.unwrap_or(MeshLawChoice::Fe);
    // The FE models' accuracy rests on the mesh: where the spec's [mesh] is silent it takes the
    // mesh measured to meet the DTE's accuracy (as every command does); the analytic law meshes
    // nothing.
    let meshes = !matches!(model, ModelChoice::Lumped) || mesh_law == MeshLawChoice::Fe;
    let fallback = match model {
        ModelChoice::PmorPenalty => Some(MeshSpec::penalty_reference_default()),
        _ => meshes.then(MeshSpec::dynamic_default),
    };
    let (pair, mesh_spec) = pair_and_mesh_or(spec, resolution, fallback, rom.depth_mm)?;
    let modified = gearfmu::contact::mesh_kinematics::PairPlacement::new(&pair).is_modified();
    if modified && matches!(model, ModelChoice::Lumped) && mesh_law == MeshLawChoice::Analytic {
        anyhow::bail!(
            "{}: the analytic mesh law knows nothing of flank modifications or misalignment; the FE law \
             (`--mesh-law fe`, the default) carries them from the statics",
            spec.display()
        );
    }
    // Tooth friction: the lumped model, and the PMOR-Hertz model with its default integrator and
    // condensation (where its friction work is tallied); the penalty reference is the paper's
    // frictionless model.
    let frictionless_only = match model {
        ModelChoice::Lumped => None,
        ModelChoice::PmorPenalty => Some("the standard PMOR reference is the paper's frictionless model"),
        ModelChoice::PmorHertz => match (rom.integrator, rom.dynamics) {
            (Some(IntegratorChoice::Verlet | IntegratorChoice::Rk4), _) => {
                Some("the PMOR-Hertz model carries friction with its default integrator only (--integrator discrete-gradient)")
            }
            (_, Some(DynamicsChoice::Full)) => {
                Some("the PMOR-Hertz model carries friction with its quasi-static dynamics only (--dynamics quasi-static)")
            }
            _ => None,
        },
    };
    if let (Some(why), true) = (frictionless_only, pair.friction_coefficient != 0.0) {
        anyhow::bail!("{}: friction.coefficient = {}: {why}; set it to 0", spec.display(), pair.friction_coefficient);
    }
    if let (Some(why), true) = (frictionless_only, pair.lubricated_flanks.is_some()) {
        anyhow::bail!("{}: friction.law = \"iso-tr-14179-2\": {why}; leave the law out", spec.display());
    }
    let so = library_bytes(library)?;
    match model {
        ModelChoice::Lumped => {
            write_fmu(output, &pair, ModelKind::Lumped(lumped_mesh(&pair, &mesh_spec, mesh_law, rom.depth_mm)?), &so)
        }
        ModelChoice::PmorPenalty => {
            let factor = gearfmu::rom::statics::DEFAULT_PENALTY_FACTOR;
            let (rom_model, _) = build_rom(&pair, &mesh_spec, rom, false, FlankContact::Penalty { factor })?;
            write_fmu(output, &pair, ModelKind::PmorHertz(Box::new(rom_model)), &so)
        }
        ModelChoice::PmorHertz => {
            let (rom_model, lumped) = build_rom(&pair, &mesh_spec, rom, lumped_fmu.is_some(), FlankContact::Hertz)?;
            write_fmu(output, &pair, ModelKind::PmorHertz(Box::new(rom_model)), &so)?;
            match (lumped_fmu, lumped) {
                (Some(path), Some(mesh)) => write_fmu(path, &pair, ModelKind::Lumped(mesh), &so),
                _ => Ok(()),
            }
        }
    }
}

/// The lumped model's mesh: from the FE statics (the reduction `ste` makes, then a table of
/// static cases over roll × force; progress and cost reported) or from the geometry alone.
pub(crate) fn lumped_mesh(
    pair: &GearPair,
    mesh: &MeshSpec,
    law: MeshLawChoice,
    depth_mm: Option<f64>,
) -> Result<LumpedMesh> {
    use gearfmu::rom::static_mesh_law::{drive_law_from_statics, force_levels, FORCE_LEVELS, TABLE_ROWS};
    if law == MeshLawChoice::Analytic {
        return LumpedMesh::from_pair(pair).map_err(anyhow::Error::msg);
    }
    let started = std::time::Instant::now();
    let depth_m = contact_depth_or_default(pair, depth_mm);
    let method = Method::PmorHertz { depth_m, p_en: gearfmu::rom::svd::DEFAULT_P_EN, law: ApproachLaw::Weber };
    let bar = spinner("mesh law from the FE statics: reducing both gears".into());
    let reduced = ReducedPair::build(pair, mesh, method, |gear, done| {
        bar.set_message(format!("mesh law from the FE statics: gear {}, {done} partial models", gear + 1))
    })
    .map_err(anyhow::Error::msg)?;
    let reduction_s = started.elapsed().as_secs_f64();
    let levels = force_levels(pair, FORCE_LEVELS);
    let statics = reduced.static_model().map_err(anyhow::Error::msg)?;
    let table = drive_law_from_statics(pair, &statics, &levels, TABLE_ROWS, |done| {
        bar.set_message(format!("mesh law from the FE statics: roll position {done} of {TABLE_ROWS}"))
    })
    .map_err(anyhow::Error::msg)?;
    bar.finish_and_clear();
    // The mesh's mean deflection at the operating torque: the table's STE less its no-load row.
    let force = pair.operating_torque_nm / pair.gear1.base_radius_m;
    let rows = table.law.rows();
    let deflection = (0..rows)
        .map(|i| {
            let roll = pair.base_pitch_m * i as f64 / rows as f64;
            table.law.static_deflection(force, roll) - table.law.static_deflection(0.0, roll)
        })
        .sum::<f64>()
        / rows as f64;
    check_loaded_contact_ratio(pair, deflection, pair.operating_torque_nm)?;
    let kept = &table.law.force_levels_n;
    println!(
        "lumped mesh law from the PMOR-Hertz statics ({} elements across/along/rim): reduction {reduction_s:.1} s, \
         {TABLE_ROWS} roll positions × {} forces up to {:.4e} N in {:.1} s",
        format_args!("{}/{}/{}", mesh.elements_across_tooth, mesh.elements_along_profile, mesh.elements_in_rim),
        kept.len() - 1,
        kept[kept.len() - 1],
        started.elapsed().as_secs_f64() - reduction_s
    );
    Ok(lumped_from_table(pair, table))
}

/// A modified pair's loaded contact ratio at a torque (`PairPlacement::loaded_contact_ratio`),
/// printed; below 1 the build is refused: over part of each mesh cycle the load would ride on a
/// relief deeper than the mesh deflects, a transmission error no model here is validated for.
pub(crate) fn check_loaded_contact_ratio(pair: &GearPair, deflection_m: f64, torque_nm: f64) -> Result<()> {
    let place = gearfmu::contact::mesh_kinematics::PairPlacement::new(pair);
    if !place.is_modified() {
        return Ok(());
    }
    let ratio = place.loaded_contact_ratio(deflection_m);
    println!(
        "flank modifications: loaded contact ratio {ratio:.3} at {} N·m (ε_α {:.3}; the path where the profile \
         modifications' gap is within the mean mesh deflection, {:.2} µm)",
        sig(torque_nm),
        pair.transverse_contact_ratio,
        deflection_m * 1e6
    );
    if ratio < 1.0 {
        anyhow::bail!(
            "flank modifications: the loaded contact ratio falls to {ratio:.3} (< 1) at {} N·m: the reliefs are deeper \
             over more of the path than the mesh deflects under that load ({:.2} µm), so over part of each mesh cycle \
             no tooth pair carries the load within its deflection; shorten or lessen the reliefs",
            sig(torque_nm),
            deflection_m * 1e6
        );
    }
    Ok(())
}

/// The lumped mesh around an FE-fed table; says where the statics ended it, if they did.
pub(crate) fn lumped_from_table(pair: &GearPair, table: gearfmu::rom::static_mesh_law::StaticMeshLaw) -> LumpedMesh {
    if let Some(why) = &table.capped {
        println!("note: {why}; beyond it the law continues with its last slope");
    }
    if let Some(why) = &table.friction_share_missing {
        println!("warning: {why}");
    }
    LumpedMesh::from_drive_law(
        pair,
        gearfmu::dynamics::lumped::MeshLawSource::FeStatics,
        table.law,
        table.pairs,
        table.spread,
    )
}

/// The offline PMOR-Hertz build: FE models, eigenmodes, static contact shapes, invariants.
pub(crate) fn build_rom(
    pair: &GearPair,
    mesh: &MeshSpec,
    rom: &RomOptions,
    lumped_mesh_law: bool,
    contact: FlankContact,
) -> Result<(gearfmu::dynamics::pmor::model::PmorModel, Option<LumpedMesh>)> {
    use gearfmu::dynamics::pmor::integrator::Integrator;
    use gearfmu::dynamics::pmor::model::Interpolation;
    use gearfmu::dynamics::pmor::quasi_static::Condensation;
    use gearfmu::rom::build_cache::build_dynamic_model_reusing;
    use gearfmu::rom::dynamic_reductor::DynamicBuildOptions;
    let rom_torques_nm = rom.rom_torques_nm.clone().unwrap_or_else(|| vec![pair.operating_torque_nm]);
    let yield_torque = gearfmu::closed_forms::rating::yield_torque_nm(pair);
    if let Some(t) = rom_torques_nm.iter().find(|t| **t > yield_torque) {
        anyhow::bail!(
            "--rom-torques-nm {}: beyond the pair's yield torque {} N·m (one pair at the tip bends its root past \
             material.yield_strength_mpa); give a torque below it",
            sig(*t),
            sig(yield_torque)
        );
    }
    let depth_m = contact_depth_or_default(pair, rom.depth_mm);
    // Every spec value reaches the FMU or the build says why not.
    for (i, gear) in [&pair.gear1, &pair.gear2].into_iter().enumerate() {
        if gear.inertia_overridden {
            println!(
                "note: gear{}.inertia_kgm2 = {} kg·m² is not the PMOR-Hertz gear's inertia, which comes from its FE mass; \
                 the FMU's inertia_{} parameter adds what exceeds the FE value at the bore (hub, shaft share)",
                i + 1,
                sig(gear.inertia_kgm2),
                i + 1
            );
        }
    }
    println!(
        "PMOR-Hertz build of {}: static shapes at T₁ = {} N·m ({}), contact depth h = {} mm, step to be checked at up to {} N·m (4 × the ROM torque, at most the yield torque)",
        pair.name,
        rom_torques_nm.iter().map(|t| sig(*t)).collect::<Vec<_>>().join(", "),
        if rom.rom_torques_nm.is_some() { "--rom-torques-nm" } else { "the spec's operating torque" },
        sig(depth_m * 1e3),
        sig(gearfmu::dynamics::pmor::model::step_load_ceiling_of(pair, &rom_torques_nm))
    );
    if matches!(rom.integrator, Some(IntegratorChoice::DiscreteGradient))
        && matches!(rom.dynamics, Some(DynamicsChoice::Full))
    {
        anyhow::bail!(
            "--integrator discrete-gradient needs --dynamics quasi-static: its step is implicit in the slow coordinates only, whose mass is constant"
        );
    }
    let options = DynamicBuildOptions {
        modes: rom.modes,
        angles: rom.angles,
        rom_torques_nm,
        sharing_shapes: rom.sharing_shapes,
        depth_m,
        p_en: rom.p_en.unwrap_or(gearfmu::rom::svd::DEFAULT_P_EN),
        interpolation: match rom.interpolation {
            InterpolationChoice::CatmullRom => Interpolation::CatmullRom,
            InterpolationChoice::Linear => Interpolation::Linear,
        },
        // The energy-conserving step where the dynamics are quasi-static (the default), velocity
        // Verlet on the full pair (the discrete gradient needs the constant slow mass).
        integrator: match rom.integrator.unwrap_or(match rom.dynamics {
            Some(DynamicsChoice::Full) => IntegratorChoice::Verlet,
            _ => IntegratorChoice::DiscreteGradient,
        }) {
            IntegratorChoice::Verlet => Integrator::Verlet,
            IntegratorChoice::Rk4 => Integrator::Rk4,
            IntegratorChoice::DiscreteGradient => Integrator::DiscreteGradient,
        },
        condensation: match rom.dynamics.unwrap_or(DynamicsChoice::QuasiStatic) {
            DynamicsChoice::QuasiStatic => Condensation::QuasiStatic,
            DynamicsChoice::Full => Condensation::None,
        },
        lumped_mesh_law,
        contact,
        memory_limit_bytes: rom.memory_limit_gb.map(|gb| gb * 1e9),
        ..Default::default()
    };
    // The reference model: what the paper ran (RK4, every coordinate dynamic).
    let options = match contact {
        FlankContact::Hertz => options,
        FlankContact::Penalty { .. } => {
            DynamicBuildOptions { integrator: Integrator::Rk4, condensation: Condensation::None, ..options }
        }
    };
    let started = std::time::Instant::now();
    let bar = spinner("PMOR-Hertz build".into());
    // Each stage's start, for the report of where the offline time goes.
    let stages = std::sync::Mutex::new(Vec::<(String, std::time::Instant)>::new());
    // Through the build cache where GEARFMU_BUILD_CACHE names one (a hit: one stage, "reused").
    let (model, report) = build_dynamic_model_reusing(pair, mesh, &options, |m| {
        stages.lock().unwrap().push((m.clone(), std::time::Instant::now()));
        bar.stage(m)
    })
    .map_err(anyhow::Error::msg)?;
    bar.finish_and_clear();
    // The statics the shapes were taken from, at the first ROM torque, over a mesh cycle.
    let pitch2 = 2.0 * std::f64::consts::PI / pair.gear2.teeth as f64;
    let samples = report.ste_m[0].len() - 1; // the last closes the cycle
    let cases: Vec<(f64, f64)> =
        (0..samples).map(|s| (pitch2 * s as f64 / samples as f64, report.ste_m[0][s])).collect();
    let place = gearfmu::contact::mesh_kinematics::PairPlacement::new(pair);
    let layers = &model.gears[0].flank(gearfmu::contact::mesh_kinematics::Flank::Drive).grid.layer_z_m;
    let deflection = gearfmu::rom::statics::mean_mesh_deflection_m(&place, layers, &cases);
    check_loaded_contact_ratio(pair, deflection, options.rom_torques_nm[0])?;
    if let FlankContact::Penalty { factor } = contact {
        let k = gearfmu::rom::statics::penalty_node_stiffness_n_per_m(pair, layers, 1, factor);
        println!(
            "standard PMOR reference: node-to-surface penalty {} × ISO 6336-1 c_γα per node share, both passes: {:.3e} N/mm per interior node and pass ({:.3e} N/mm per node, the paper's Table 9 unit)",
            sig(factor),
            k * 1e-3,
            2.0 * k * 1e-3
        );
    }
    // Start times, not durations: the two gears' first stages run side by side.
    let stages = stages.into_inner().unwrap();
    let timings: Vec<String> =
        stages.iter().map(|(name, at)| format!("{:.1} s {name}", (*at - started).as_secs_f64())).collect();
    println!("build stages (start times): {}; done {:.1} s", timings.join(", "), started.elapsed().as_secs_f64());
    for i in 0..2 {
        let g = &model.gears[i];
        let hz = &report.modes_hz[i];
        println!(
            "gear {}: {} eigenmodes ({:.0} … {:.0} Hz) + {} shapes × {} angles; span Φ invariance residual {:.1e}; shape closure residual {:.1e}; smallest shape Gram ratio {:.1e}; polar inertia {:.6e} kg·m² (exact {:.6e}); SVD kept {}",
            i + 1,
            g.modes(),
            hz[0],
            hz[hz.len() - 1],
            g.shapes,
            g.samples,
            report.invariance_residual[i],
            report.closure_residual[i],
            report.shape_gram_ratio[i],
            report.polar_inertia_kgm2[i].0,
            report.polar_inertia_kgm2[i].1,
            report.n_sv[i],
        );
    }
    let f = &report.step.natural_frequencies_hz;
    let step_rule = match report.step.integrator {
        gearfmu::dynamics::pmor::integrator::Integrator::DiscreteGradient => {
            "discrete gradient (unconditionally stable; its step is 0.6 of velocity Verlet's limit)"
        }
        other => other.name(),
    };
    println!(
        "linearized at {:.0} N·m: lowest natural frequencies {:.0}, {:.0}, {:.0} … highest {:.0} Hz; {} limit {:.2} µs, default max_step {:.1} µs",
        report.step.torque_nm,
        f[1],
        f[2],
        f[3],
        f[f.len() - 1],
        step_rule,
        report.step.stability_limit_s * 1e6,
        report.step.max_step_s * 1e6
    );
    println!("offline build {:.1} s", started.elapsed().as_secs_f64());
    // The lumped FMU's law from the same statics: where the stage log above says it took its time.
    let lumped = report.lumped_mesh_law.map(|table| lumped_from_table(pair, table));
    Ok((model, lumped))
}
