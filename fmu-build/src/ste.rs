//! `fmu-build ste`: the static transmission error over a mesh cycle by PMOR-Hertz or the
//! penalty baseline, printed, as CSV and as a plot.

use anyhow::{Context, Result};
use gearfmu::closed_forms::iso6336;
use gearfmu::contact::hertz::ApproachLaw;
use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::gear::{sig, GearPair};
use gearfmu::rom::sweep::{Method, ReducedPair};
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::cli::{contact_depth_or_default, pair_and_mesh_or, Resolution, StaticMethod};

use crate::progress::spinner;

/// The positions of a sweep, and its tooth friction.
pub(crate) struct SweepOptions {
    pub(crate) angles: usize,
    pub(crate) pitches: f64,
    /// Coulomb's μ (0: frictionless).
    pub(crate) friction: f64,
}

/// Reduces the pair, runs the sweep (progress on stderr), prints a summary per torque and writes
/// the CSV.
pub(crate) fn ste_command(
    pair: &GearPair,
    mesh_spec: &MeshSpec,
    torques: &[f64],
    sweep_options: SweepOptions,
    method: Method,
    out: StePlots,
) -> Result<()> {
    let SweepOptions { angles, pitches, friction } = sweep_options;
    let started = std::time::Instant::now();
    let bar = spinner("reducing both gears".into());
    let progress = |gear: usize, done: usize| bar.set_message(format!("gear {}: {done} partial models", gear + 1));
    let reduced = if friction > 0.0 {
        ReducedPair::build_for_friction(pair, mesh_spec, method, progress)
    } else {
        ReducedPair::build(pair, mesh_spec, method, progress)
    }
    .map_err(anyhow::Error::msg)?;
    let offline = started.elapsed().as_secs_f64();
    if let Some(reports) = &reduced.compression {
        for (i, r) in reports.iter().enumerate() {
            println!("gear {}: {} loadable nodes → n_sv {} (retained {:.4})", i + 1, r.n_c, r.n_sv, r.retained);
        }
    }
    bar.set_message(format!("{} static cases", angles * torques.len()));
    let sweep_start = std::time::Instant::now();
    let cases: Vec<_> = reduced
        .sweep_with_friction(torques, angles, pitches, friction)
        .into_iter()
        .collect::<Result<_, _>>()
        .map_err(anyhow::Error::msg)?;
    let sweep = sweep_start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let name = match method {
        Method::PmorHertz { .. } => "pmor-hertz",
        Method::Penalty { .. } => "penalty",
    };
    let b_mm = pair.face_width_m * 1e3;
    let layers = &reduced.gears[0].flank.layer_z_m;
    let penalty = matches!(method, Method::Penalty { .. });
    for &t in torques {
        let at_t: Vec<_> = cases.iter().filter(|c| c.torque_nm == t).collect();
        let ste: Vec<f64> = cases.iter().filter(|c| c.torque_nm == t).map(|c| c.ste_m * 1e6).collect();
        let mean = ste.iter().sum::<f64>() / ste.len() as f64;
        let (lo, hi) = ste.iter().fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        // Mean mesh stiffness as ISO 6336-1 counts it: the transverse force along the line of
        // action per face width over the mean transverse deflection along it. The specific load
        // (Tables 4 and 7, and ISO's light-load factor) is the tangential force at the reference
        // circle per face width.
        let stiffness = t / pair.gear1.base_radius_m / b_mm / mean;
        // ISO defines c_γα as the mean of the mesh stiffness over the cycle: the arithmetic mean of
        // the position-wise secant stiffness, a little above force / mean STE (a harmonic mean).
        let stiffness_mean_of_positions =
            ste.iter().map(|s| t / pair.gear1.base_radius_m / b_mm / s).sum::<f64>() / ste.len() as f64;
        let specific_load = t / pair.gear1.pitch_radius_m / b_mm;
        let iso = iso6336::mesh_stiffness_c_gamma_alpha_at(pair, specific_load);
        println!(
            "{name} T₁ {} N·m (w = {specific_load:.1} N/mm): mean STE {mean:.3} µm, peak-to-peak {:.3} µm; \
             mean mesh stiffness {stiffness:.2} N/(mm·µm), ISO 6336-1 c_γα {iso:.2} (ratio {:.3}); \
             mean of the position-wise stiffness {stiffness_mean_of_positions:.2} (ratio {:.3})",
            sig(t),
            hi - lo,
            stiffness / iso,
            stiffness_mean_of_positions / iso
        );
        if friction > 0.0 {
            let mean_friction_torque = at_t.iter().map(|c| c.friction_torque_nm(pair)).sum::<f64>() / at_t.len() as f64;
            let mean_force = at_t.iter().map(|c| c.mesh_force_n).sum::<f64>() / at_t.len() as f64;
            println!(
                "  tooth friction μ = {}: mean friction torque on gear 1 {mean_friction_torque:.3} N·m against its mesh sense \
                 ({:.3} % of T₁); mean normal force {mean_force:.1} N",
                sig(friction),
                100.0 * mean_friction_torque / t
            );
        }
        // A modified pair's loaded contact ratio: below 1 the reliefs are deeper than the load
        // closes over part of the cycle; say so.
        let place = gearfmu::contact::mesh_kinematics::PairPlacement::new(pair);
        if place.is_modified() {
            let at_t: Vec<(f64, f64)> =
                cases.iter().filter(|c| c.torque_nm == t).map(|c| (c.theta_rad[1], c.ste_m)).collect();
            let deflection = gearfmu::rom::statics::mean_mesh_deflection_m(&place, layers, &at_t);
            let ratio = place.loaded_contact_ratio(deflection);
            println!(
                "  loaded contact ratio {ratio:.3} (ε_α {:.3}; the path where the profile modifications' gap is within the mean mesh deflection, {:.2} µm){}",
                pair.transverse_contact_ratio,
                deflection * 1e6,
                if ratio < 1.0 {
                    " — WARNING: below 1, no tooth pair carries the load within its deflection over part of each mesh cycle"
                } else {
                    ""
                }
            );
            if ratio < 1.0 {
                eprintln!("warning: at {} N·m the loaded contact ratio falls to {ratio:.3} (< 1): the reliefs are deeper than the mesh deflects; `fmu-build build` refuses this pair at such a torque", sig(t));
            }
        }
        // The face load factor, and ISO 6336-1's from the misalignment (f_sh = 0: the FE gears
        // sit on rigid shafts, clamped at their bores; lead crowning halves F_βx, ISO's B₂ = 0.5).
        // ISO's K_Hβ is the face's load distribution: each section's load per face width averaged
        // over the positions of the mesh cycle (a helical pair's contact lines end at different z
        // at each instant, which alone makes one position's factor 1.5 on an aligned pair).
        let (mut mean_load, mut lengths) = (Vec::new(), Vec::new());
        for c in &at_t {
            let (load, l) = c.face_load(layers, penalty);
            if mean_load.is_empty() {
                (mean_load, lengths) = (vec![0.0; load.len()], l);
            }
            for (m, w) in mean_load.iter_mut().zip(&load) {
                *m += w / at_t.len() as f64;
            }
        }
        let face: f64 = lengths.iter().sum();
        let average = mean_load.iter().zip(&lengths).map(|(w, l)| w * l).sum::<f64>() / face;
        let k_mean = mean_load.iter().fold(0.0f64, |m, &w| m.max(w)) / average;
        let k_max = at_t.iter().map(|c| c.face_load_factor(layers, penalty)).fold(0.0f64, f64::max);
        let crowned = pair.gear1.modification.lead_crowning_m > 0.0 || pair.gear2.modification.lead_crowning_m > 0.0;
        let f_beta_y_um = pair.misalignment_m.abs() * 1e6 * if crowned { 0.5 } else { 1.0 };
        println!(
            "  face load factor K_Hβ (largest over mean load per face width, over the mesh cycle): {k_mean:.3} (one position's at most {k_max:.3}); \
             ISO 6336-1 (F_βy = {f_beta_y_um:.1} µm from mounting.misalignment_um{}): {:.3}",
            if crowned { " halved by the lead crowning" } else { "" },
            iso6336::face_load_factor_k_h_beta(pair, f_beta_y_um, specific_load)
        );
        // Zone by zone (spur): the single-zone stiffness and the double/single ratio carry the
        // bodies' torsion, which the bore radii set; the zone contrast does not.
        let positions: Vec<(f64, usize)> =
            cases.iter().filter(|c| c.torque_nm == t).map(|c| (c.ste_m, c.pairs_in_contact)).collect();
        if let Some(z) = iso6336::ZoneComparison::from_sweep(pair, t, &positions) {
            println!(
                "  zones: single contact mean STE {:.3} µm ({} positions), double {:.3} µm ({}); \
                 single-zone stiffness {:.2} N/(mm·µm), ISO c′ {:.2} (ratio {:.3}); \
                 double/single {:.3} (ISO {}); \
                 zone contrast (STE₁ − STE₂)/(F/b) {:.5} mm·µm/N, ISO (1 − 1/1.75)/c′ {:.5} (ratio {:.3}, bore-independent)",
                z.single_ste_m * 1e6,
                z.single_positions,
                z.double_ste_m * 1e6,
                z.double_positions,
                z.single_stiffness,
                z.iso_single_stiffness,
                z.single_stiffness / z.iso_single_stiffness,
                z.double_over_single,
                iso6336::IMPLIED_DOUBLE_OVER_SINGLE,
                z.zone_contrast,
                z.iso_zone_contrast,
                z.zone_contrast / z.iso_zone_contrast
            );
        }
    }
    println!(
        "reduction {offline:.2} s; {} cases in {sweep:.2} s ({:.3} s per case on {} threads)",
        cases.len(),
        sweep / cases.len() as f64 * rayon::current_num_threads() as f64,
        rayon::current_num_threads()
    );
    // One column per axial section (PMOR-Hertz) or node layer (penalty): the load per face width.
    let sections = if penalty { layers.len() } else { layers.len() - 1 };
    let mut table = String::from(
        "method,torque_nm,theta1_rad,theta2_rad,ste_m,mesh_force_n,pairs_in_contact,k_h_beta,friction_torque_nm",
    );
    for s in 0..sections {
        table += &format!(",line_load_{s}_n_per_mm");
    }
    table.push('\n');
    for c in &cases {
        table += &format!(
            "{name},{},{:.12e},{:.12e},{:.9e},{:.6e},{},{:.6},{:.6e}",
            c.torque_nm,
            c.theta_rad[0],
            c.theta_rad[1],
            c.ste_m,
            c.mesh_force_n,
            c.pairs_in_contact,
            c.face_load_factor(layers, penalty),
            c.friction_torque_nm(pair)
        );
        for w in c.face_load(layers, penalty).0 {
            table += &format!(",{:.6e}", w * 1e-3);
        }
        table.push('\n');
    }
    if let Some(path) = &out.csv {
        std::fs::write(path, &table).with_context(|| format!("cannot write {}", path.display()))?;
    }
    if let Some(png) = &out.png {
        let csv = match &out.csv {
            Some(path) => path.clone(),
            None => {
                let path = png.with_extension("csv");
                std::fs::write(&path, &table).with_context(|| format!("cannot write {}", path.display()))?;
                path
            }
        };
        let friction_label =
            if friction > 0.0 { format!(", tooth friction μ = {}", sig(friction)) } else { String::new() };
        plot_ste(&csv, png, &format!("{}: static transmission error, {name}{friction_label}", pair.name))?;
    }
    Ok(())
}

/// `ste`'s options as given, before the spec's defaults fill the gaps.
pub(crate) struct SteOptions {
    pub(crate) torque_nm: Option<Vec<f64>>,
    pub(crate) angles: usize,
    pub(crate) pitches: f64,
    pub(crate) method: StaticMethod,
    pub(crate) depth_mm: Option<f64>,
    pub(crate) p_en: f64,
    pub(crate) eq20: bool,
    pub(crate) friction: f64,
}

/// `ste` with the spec's defaults: its operating torque, and a contact depth of half its module.
pub(crate) fn ste_with_defaults(spec: &Path, o: SteOptions, resolution: Resolution, out: StePlots) -> Result<()> {
    let (pair, mesh_spec) = pair_and_mesh_or(spec, resolution, Some(MeshSpec::dynamic_default()), o.depth_mm)?;
    let torque_nm = o.torque_nm.unwrap_or_else(|| vec![pair.operating_torque_nm]);
    let depth_m = contact_depth_or_default(&pair, o.depth_mm);
    let method = match o.method {
        StaticMethod::PmorHertz => Method::PmorHertz {
            depth_m,
            p_en: o.p_en,
            law: if o.eq20 { ApproachLaw::PaperEq20 } else { ApproachLaw::Weber },
        },
        StaticMethod::Penalty => Method::Penalty { factor: gearfmu::rom::statics::DEFAULT_PENALTY_FACTOR },
    };
    let sweep = SweepOptions { angles: o.angles, pitches: o.pitches, friction: o.friction };
    ste_command(&pair, &mesh_spec, &torque_nm, sweep, method, out)
}

/// Where `ste` writes its table and its plot.
pub(crate) struct StePlots {
    pub(crate) csv: Option<PathBuf>,
    pub(crate) png: Option<PathBuf>,
}

/// The plotting script, carried in the binary so that `fmu-build ste --png` works from any folder.
pub(crate) const PLOT_STE_PY: &str = include_str!("../../scripts/plot_ste.py");

/// Runs scripts/plot_ste.py (fed on stdin) on a CSV of `ste`.
pub(crate) fn plot_ste(csv: &Path, png: &Path, title: &str) -> Result<()> {
    let python = std::env::var_os("GEARFMU_PYTHON").map(PathBuf::from).unwrap_or_else(|| {
        let venv = PathBuf::from(".venv/bin/python");
        if venv.exists() {
            venv
        } else {
            PathBuf::from("python3")
        }
    });
    let mut child = std::process::Command::new(&python)
        .arg("-")
        .arg(csv)
        .arg("--png")
        .arg(png)
        .arg("--title")
        .arg(title)
        .stdin(std::process::Stdio::piped())
        .spawn()
        .with_context(|| format!("--png needs Python with matplotlib; cannot run {}", python.display()))?;
    child.stdin.take().context("python's stdin")?.write_all(PLOT_STE_PY.as_bytes())?;
    let status = child.wait()?;
    if !status.success() {
        anyhow::bail!(
            "{} could not draw {} ({status}); --png needs matplotlib (scripts/setup.sh makes .venv, or set GEARFMU_PYTHON)",
            python.display(),
            png.display()
        );
    }
    Ok(())
}
