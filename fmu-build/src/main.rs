//! fmu-build: turns a gear-pair spec into an FMI 2.0 Co-Simulation FMU, and inspects models.
//!
//! `fmu-build build examples/kurokawa_spur.toml -o KurokawaSpur.fmu [--model lumped]`
//! `fmu-build inspect examples/kurokawa_spur.toml [--json mesh.json]`
//! `fmu-build mesh examples/kurokawa_spur.toml [--vtk out/spur] [--png out/spur] [--across N --profile N --rim N --slices N]`
//! `fmu-build modes examples/kurokawa_spur.toml -n 10 [--vtk out/spur]`
//! `fmu-build tooth-stiffness examples/kurokawa_spur.toml [--across N --profile N --rim N --slices N]`
//! `fmu-build element shaft -o Shaft.fmu --stiffness-nm-per-rad 2e4` (inertia, shaft, motor, load)
//! `fmu-build ssp --gear-fmu KurokawaSpur.fmu -o drivetrain.ssp` (motor → shaft → gear pair → shaft → load)

mod drivetrain;
mod model_description;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use gearfmu::contact::hertz::ApproachLaw;
use gearfmu::dynamics::iso6336;
use gearfmu::dynamics::lumped::{mesh_damping_coefficient, mesh_natural_frequency_hz, LumpedMesh, LumpedParameters};
use gearfmu::dynamics::pmor::model::FlankContact;
use gearfmu::fe::clamped_gear::ClampedGear;
use gearfmu::fe::gear_mesh::{mesh_gear, GearMesh, MeshSpec, ProfileGrading};
use gearfmu::fe::hex8::Formulation;
use gearfmu::fe::{eigen, vtk};
use gearfmu::gear::{sig, GearPair, PairSpec};
use gearfmu::interface;
use gearfmu::model_file::{ModelFile, ModelKind};
use gearfmu::rom::sweep::{Method, ReducedPair};
use indicatif::ProgressBar;
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(name = "fmu-build", version, about = "Gear-pair spec → FMI 2.0 Co-Simulation FMU")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
enum ModelChoice {
    /// The FE-based reduced pair (PMOR-Hertz): eigenmodes + global contact shapes per gear in
    /// floating frames, Hertz contact between the deformed flanks.
    PmorHertz,
    /// Rigid gears on a tabulated mesh law (the FE statics' by default, see --mesh-law), backlash
    /// (fast; the reference level).
    Lumped,
    /// The paper's standard PMOR, the reference PMOR-Hertz is compared with (not for use): the
    /// same floating-frame model with contact shapes from the standard CMS statics and
    /// node-to-surface penalty contact (100 × ISO c_γα per node share, the statics' baseline),
    /// RK4, every coordinate dynamic. Drive flanks only.
    PmorPenalty,
}

/// Where the lumped model's mesh law comes from.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum MeshLawChoice {
    /// The loaded transmission error of the PMOR-Hertz FE statics (what `ste` computes, on the
    /// same mesh), tabulated over roll position × mesh force: the FE-grade fast level.
    Fe,
    /// Potential-energy teeth and Weber's contact on the geometry alone: the no-FE estimate
    /// (seconds to build, no mesh; its single-contact stiffness is 15–21 % softer than ISO c′).
    Analytic,
}

/// Options of the PMOR-Hertz build (`fmu-build build --model pmor-hertz`). The defaults that depend
/// on the pair (ROM torque, depth) follow from the spec: see `build_rom`.
#[derive(clap::Args, Clone)]
struct RomOptions {
    /// Fixed-bore eigenmodes per gear n_k (raised to the end of a cluster of the cyclic spectrum).
    #[arg(long, default_value_t = 20, value_parser = count::<1, 200>)]
    modes: usize,
    /// Angular samples of the global contact shapes per mesh cycle n_θ.
    #[arg(long, default_value_t = 20, value_parser = count::<4, 400>)]
    angles: usize,
    /// Torque levels on gear 1 of the static analyses (N·m), comma-separated: n_t shapes per
    /// sample. Default: the spec's operating torque (`[operating] torque_nm`, else the pair's
    /// rated torque). PMOR-Hertz's global shapes are nearly proportional to the load, and levels
    /// whose shapes coincide are refused (a singular mass matrix).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, value_parser = positive_number)]
    rom_torques_nm: Option<Vec<f64>>,
    /// Load-sharing shapes per sample and flank beside the static ones (`rom::sharing`): they
    /// let the pairs in mesh share a dynamic load differently from the static split.
    #[arg(long, default_value_t = 1, value_parser = count::<0, 8>)]
    sharing_shapes: usize,
    /// Depth h (mm) of the partial models and of the Hertz approach. Default: half the normal
    /// module (`rom::reductor::contact_depth_m`; 3 mm on the Kurokawa pairs).
    #[arg(long, allow_negative_numbers = true, value_parser = positive_number)]
    depth_mm: Option<f64>,
    /// Share of the deformation energy the SVD of the attachment modes keeps, in (0, 1] (default:
    /// chosen by measured accuracy, `rom::svd::DEFAULT_P_EN`, 0.999999).
    #[arg(long, allow_negative_numbers = true, value_parser = energy_share)]
    p_en: Option<f64>,
    /// Interpolation of the shapes in the gear angle.
    #[arg(long, value_enum, default_value = "catmull-rom")]
    interpolation: InterpolationChoice,
    /// The FMU's time integrator (its default max_step is 0.6 of this one's stability limit;
    /// the discrete gradient, unconditionally stable, takes velocity Verlet's). Default:
    /// discrete-gradient, verlet with `--dynamics full`.
    #[arg(long, value_enum)]
    integrator: Option<IntegratorChoice>,
    /// Which coordinates carry inertia: the contact shapes and the hub direction quasi-static
    /// (the default: the step set by the body modes and the mesh, velocity Verlet's 20 µs instead
    /// of 1.7 µs on the Kurokawa spur pair, example 3's DTE within 0.2 %: docs/explanation/method.md
    /// §10a), or all of them (the paper's model, a reference; its step is bounded by the shapes
    /// against the contact, ≈ 100 kHz). Default: quasi-static.
    #[arg(long, value_enum)]
    dynamics: Option<DynamicsChoice>,
    /// The memory the build may take (GB). The build estimates its peak once the gears are
    /// meshed, before the FE stage: above this it builds the gears one after the other, and
    /// refuses, with the figure, what will not fit that way either. Default: the machine's
    /// available memory (`MemAvailable`).
    #[arg(long, allow_negative_numbers = true, value_parser = positive_number)]
    memory_limit_gb: Option<f64>,
}

/// A count in [LO, HI] (a value outside is refused with the range, before any work).
fn count<const LO: usize, const HI: usize>(text: &str) -> Result<usize, String> {
    let n: usize = text.trim().parse().map_err(|_| format!("`{text}` is not a whole number"))?;
    if (LO..=HI).contains(&n) {
        Ok(n)
    } else {
        Err(format!("must be in {LO}..={HI}, got {n}"))
    }
}

/// A number, or the message clap prints for a value that is none.
fn number(text: &str) -> Result<f64, String> {
    text.trim().parse().map_err(|_| format!("`{text}` is not a number"))
}

/// A positive, finite number (a torque, a length, a time).
fn positive_number(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a positive finite number, got {}", gearfmu::gear::sig(v)))
    }
}

/// A share of energy in (0, 1].
fn energy_share(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if v > 0.0 && v <= 1.0 {
        Ok(v)
    } else {
        Err(format!("must be in (0, 1] (a share of the deformation energy), got {}", gearfmu::gear::sig(v)))
    }
}

/// A damping ratio in [0, 1).
fn damping_ratio(text: &str) -> Result<f64, String> {
    let v = number(text)?;
    if (0.0..1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("must be in [0, 1) (a fraction of critical damping), got {}", gearfmu::gear::sig(v)))
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum IntegratorChoice {
    /// Velocity Verlet: one right-hand side per step, second order, stable to ωh = 2.
    Verlet,
    /// The paper's classical Runge–Kutta: four right-hand sides per step, fourth order, stable
    /// to ωh = 2√2.
    Rk4,
    /// Energy-conserving discrete gradient (Gonzalez) on the trapezoid: implicit, two to three
    /// quasi-static solves per step, unconditionally stable; the quasi-static dynamics only.
    DiscreteGradient,
}

#[derive(Clone, Copy, ValueEnum)]
enum DynamicsChoice {
    /// The contact shapes and the hub direction quasi-static (`quasi_static`).
    QuasiStatic,
    /// Every reduced coordinate with its inertia.
    Full,
}

#[derive(Clone, Copy, ValueEnum)]
enum InterpolationChoice {
    /// C¹ cubic (Catmull–Rom) over the periodic samples.
    CatmullRom,
    /// The paper's linear interpolation (C⁰).
    Linear,
}

#[derive(Subcommand)]
enum Command {
    /// Build the .fmu for a pair spec. The PMOR-Hertz model takes the spec's [mesh] section or,
    /// where it has none, 10 elements across the tooth, along the profile and in the rim (the
    /// DTE within 2 % of a 12/24/12 mesh; the coarse 4/8/4 is 10 % off); --across etc. override.
    Build {
        spec: PathBuf,
        #[arg(short, long)]
        output: PathBuf,
        #[arg(long, value_enum, default_value = "pmor-hertz")]
        model: ModelChoice,
        /// The lumped model's mesh law (with --model lumped; default fe).
        #[arg(long, value_enum)]
        mesh_law: Option<MeshLawChoice>,
        /// With --model pmor-hertz: also write the lumped FMU of the same pair here, its mesh law
        /// from this build's own FE statics (no second reduction).
        #[arg(long)]
        lumped_fmu: Option<PathBuf>,
        /// The FMU binary (cdylib); default: libgearfmu.so next to this executable.
        #[arg(long)]
        library: Option<PathBuf>,
        #[command(flatten)]
        rom: RomOptions,
        #[command(flatten)]
        resolution: Resolution,
    },
    /// Print the pair's kinematics and mesh figures; optionally dump the lumped mesh as JSON.
    Inspect {
        spec: PathBuf,
        #[arg(long)]
        json: Option<PathBuf>,
        /// The lumped mesh law to print and dump (as `build --model lumped --mesh-law`).
        #[arg(long, value_enum, default_value = "fe")]
        mesh_law: MeshLawChoice,
        #[command(flatten)]
        resolution: Resolution,
    },
    /// Mesh both gears: nodes, elements and DOFs per gear; optionally a VTK file per gear.
    Mesh {
        spec: PathBuf,
        #[command(flatten)]
        resolution: Resolution,
        /// Writes <stem>_gear1.vtu and <stem>_gear2.vtu.
        #[arg(long)]
        vtk: Option<PathBuf>,
        /// Writes <stem>_gear1.png and <stem>_gear2.png: the transverse section, mesh over profile.
        #[arg(long)]
        png: Option<PathBuf>,
    },
    /// Single-tooth compliance at the pitch point by FE (bore clamped, line load on one flank),
    /// against the potential-energy method and ISO 6336-1.
    ToothStiffness {
        spec: PathBuf,
        #[command(flatten)]
        resolution: Resolution,
    },
    /// Lowest natural frequencies (Hz) of each gear with the bore clamped.
    Modes {
        spec: PathBuf,
        #[arg(short = 'n', long, default_value_t = 10, value_parser = count::<1, 500>)]
        count: usize,
        #[command(flatten)]
        resolution: Resolution,
        /// Writes <stem>_gear1.vtu and <stem>_gear2.vtu with the mode shapes.
        #[arg(long)]
        vtk: Option<PathBuf>,
        /// Solve the whole gear (its Cholesky factor and block Lanczos) instead of by harmonics
        /// (one sector per nodal diameter, what the build uses): the independent reference.
        #[arg(long)]
        whole_gear: bool,
    },
    /// A PMOR-Hertz .fmu's reduced pair linearized about its static equilibrium under T₁, at mesh
    /// positions over a pitch: its lowest modes (natural frequency, damping ratio). What a
    /// speed sweep's resonances are read against.
    Linearize {
        fmu: PathBuf,
        /// Torque on gear 1 (N·m). Default: the operating torque the FMU was built for.
        #[arg(long, allow_negative_numbers = true, value_parser = positive_number)]
        torque_nm: Option<f64>,
        /// The instance's mesh_damping_ratio (the mesh damper along the line of action); default:
        /// the FMU's start value (the spec's mounting.mesh_damping_ratio).
        #[arg(long, allow_negative_numbers = true, value_parser = damping_ratio)]
        mesh_damping_ratio: Option<f64>,
        /// Mesh positions over one pitch of gear 2.
        #[arg(long, default_value_t = 4, value_parser = count::<1, 1000>)]
        positions: usize,
        /// Modes printed per position.
        #[arg(short = 'n', long, default_value_t = 4, value_parser = count::<0, 1000>)]
        count: usize,
    },
    /// A drivetrain element as an FMU (same FMI layer and binary as the gear pair): a rigid
    /// inertia, a torsional shaft, a motor (torque ramp, optionally times a speed–torque curve)
    /// or a load (inertia, viscous, quadratic and constant torques). MSL Rotational signs.
    Element {
        #[arg(value_enum)]
        kind: drivetrain::ElementKind,
        #[arg(short, long)]
        output: PathBuf,
        /// The modelName (default: the kind).
        #[arg(long)]
        name: Option<String>,
        #[command(flatten)]
        options: drivetrain::ElementOptions,
        /// The FMU binary (cdylib); default: libgearfmu.so next to this executable.
        #[arg(long)]
        library: Option<PathBuf>,
    },
    /// The demo drivetrain as an SSP 1.0 archive: motor → shaft_1 → the gear FMU → shaft_2 →
    /// load, its element FMUs built here, every parameter set inline; for libcosim
    /// (CosimExecution.from_ssp_file), fmpy (fmpy.ssp) or any SSP master.
    Ssp {
        /// The gear-pair FMU to put in the middle.
        #[arg(long)]
        gear_fmu: PathBuf,
        #[arg(short, long)]
        output: PathBuf,
        #[command(flatten)]
        options: drivetrain::DrivetrainOptions,
        #[arg(long)]
        library: Option<PathBuf>,
    },
    /// Static transmission error: gear 2 held at N angles over P pitches, torque T₁ on gear 1.
    Ste {
        spec: PathBuf,
        /// Torques on gear 1 (N·m), comma-separated. Default: the spec's operating torque.
        #[arg(long, value_delimiter = ',', allow_negative_numbers = true, value_parser = positive_number)]
        torque_nm: Option<Vec<f64>>,
        /// Positions of gear 2 over the pitches.
        #[arg(long, default_value_t = 41, value_parser = count::<1, 100000>)]
        angles: usize,
        /// Pitches of gear 2 the positions span.
        #[arg(long, default_value_t = 1.0, allow_negative_numbers = true, value_parser = positive_number)]
        pitches: f64,
        #[arg(long, value_enum, default_value = "pmor-hertz")]
        method: StaticMethod,
        /// PMOR-Hertz: depth h (mm) of the partial model and of the Hertz approach (default: half
        /// the normal module).
        #[arg(long, allow_negative_numbers = true, value_parser = positive_number)]
        depth_mm: Option<f64>,
        /// PMOR-Hertz: share of the deformation energy the SVD keeps, in (0, 1] (Algorithm 1;
        /// default: chosen by measured accuracy, `rom::svd::DEFAULT_P_EN`, not the paper's 0.99).
        #[arg(long, default_value_t = gearfmu::rom::svd::DEFAULT_P_EN, allow_negative_numbers = true, value_parser = energy_share)]
        p_en: f64,
        /// PMOR-Hertz: the paper's Eq. 20 (made consistent) instead of Weber's approach.
        #[arg(long)]
        eq20: bool,
        #[command(flatten)]
        resolution: Resolution,
        /// One row per case: method,torque_nm,theta1_rad,theta2_rad,ste_m,mesh_force_n,pairs_in_contact,
        /// k_h_beta, then the load per face width of each axial section (line_load_<s>_n_per_mm)
        #[arg(long)]
        csv: Option<PathBuf>,
        /// STE (µm) against θ₂, one curve per torque, contact zones marked. Drawn by
        /// scripts/plot_ste.py with matplotlib: the Python of $GEARFMU_PYTHON, else .venv/bin/python
        /// (scripts/setup.sh makes it), else python3.
        #[arg(long)]
        png: Option<PathBuf>,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum StaticMethod {
    /// Global attachment modes + SVD, Hertz contact per axial section.
    PmorHertz,
    /// The standard PMOR baseline: CMS attachment modes, node-to-surface penalty.
    Penalty,
}

/// Overrides of the spec's [mesh] section.
#[derive(clap::Args, Clone, Copy)]
struct Resolution {
    /// Elements across the tooth (the spec's mesh.elements_across_tooth).
    #[arg(long, value_parser = count::<1, 64>)]
    across: Option<usize>,
    /// Elements along the profile (mesh.elements_along_profile).
    #[arg(long, value_parser = count::<1, 64>)]
    profile: Option<usize>,
    /// Elements through the rim (mesh.elements_in_rim).
    #[arg(long, value_parser = count::<1, 64>)]
    rim: Option<usize>,
    /// Axial slices over the face width (mesh.axial_slices).
    #[arg(long, value_parser = count::<1, 64>)]
    slices: Option<usize>,
    /// Spacing of the rows along the profile (the spec's mesh.profile_grading).
    #[arg(long, value_enum)]
    profile_grading: Option<Grading>,
}

#[derive(Clone, Copy, ValueEnum)]
enum Grading {
    /// sin²: fine at root and tip, coarsest at mid-flank (the default).
    RootAndTip,
    /// Even rows: what the penalty baseline's node-to-surface contact needs.
    Uniform,
}

/// Reduces the pair, runs the sweep (progress on stderr), prints a summary per torque and writes
/// the CSV.
fn ste_command(
    pair: &GearPair,
    mesh_spec: &MeshSpec,
    torques: &[f64],
    angles: usize,
    pitches: f64,
    method: Method,
    out: StePlots,
) -> Result<()> {
    let started = std::time::Instant::now();
    let bar = spinner("reducing both gears".into());
    let reduced = ReducedPair::build(pair, mesh_spec, method, |gear, done| {
        bar.set_message(format!("gear {}: {done} partial models", gear + 1))
    })
    .map_err(anyhow::Error::msg)?;
    let offline = started.elapsed().as_secs_f64();
    if let Some(reports) = &reduced.compression {
        for (i, r) in reports.iter().enumerate() {
            println!("gear {}: {} loadable nodes → n_sv {} (retained {:.4})", i + 1, r.n_c, r.n_sv, r.retained);
        }
    }
    bar.set_message(format!("{} static cases", angles * torques.len()));
    let sweep_start = std::time::Instant::now();
    let cases: Vec<_> =
        reduced.sweep(torques, angles, pitches).into_iter().collect::<Result<_, _>>().map_err(anyhow::Error::msg)?;
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
        let at_t: Vec<_> = cases.iter().filter(|c| c.torque_nm == t).collect();
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
    let mut table = String::from("method,torque_nm,theta1_rad,theta2_rad,ste_m,mesh_force_n,pairs_in_contact,k_h_beta");
    for s in 0..sections {
        table += &format!(",line_load_{s}_n_per_mm");
    }
    table.push('\n');
    for c in &cases {
        table += &format!(
            "{name},{},{:.12e},{:.12e},{:.9e},{:.6e},{},{:.6}",
            c.torque_nm,
            c.theta_rad[0],
            c.theta_rad[1],
            c.ste_m,
            c.mesh_force_n,
            c.pairs_in_contact,
            c.face_load_factor(layers, penalty)
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
        plot_ste(&csv, png, &format!("{}: static transmission error, {name}", pair.name))?;
    }
    Ok(())
}

/// `ste`'s options as given, before the spec's defaults fill the gaps.
struct SteOptions {
    torque_nm: Option<Vec<f64>>,
    angles: usize,
    pitches: f64,
    method: StaticMethod,
    depth_mm: Option<f64>,
    p_en: f64,
    eq20: bool,
}

/// `ste` with the spec's defaults: its operating torque, and a contact depth of half its module.
fn ste_with_defaults(spec: &Path, o: SteOptions, resolution: Resolution, out: StePlots) -> Result<()> {
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
    ste_command(&pair, &mesh_spec, &torque_nm, o.angles, o.pitches, method, out)
}

/// Where `ste` writes its table and its plot.
struct StePlots {
    csv: Option<PathBuf>,
    png: Option<PathBuf>,
}

/// The plotting script, carried in the binary so that `fmu-build ste --png` works from any folder.
const PLOT_STE_PY: &str = include_str!("../../scripts/plot_ste.py");

/// Runs scripts/plot_ste.py (fed on stdin) on a CSV of `ste`.
fn plot_ste(csv: &Path, png: &Path, title: &str) -> Result<()> {
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

/// `Err` unless the folder a file is to be written in exists: a typo in `-o` must not make
/// folders anywhere (and is caught before a minute of offline work, not after).
fn check_output_folder(file: &Path) -> Result<()> {
    match file.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) if !dir.is_dir() => {
            anyhow::bail!("the folder {} of {} does not exist: create it first", dir.display(), file.display())
        }
        _ => Ok(()),
    }
}

fn default_library() -> Result<PathBuf> {
    let exe = std::env::current_exe()?;
    let dir = exe.parent().context("executable has no folder")?;
    Ok(dir.join("libgearfmu.so"))
}

/// The FMU binary's bytes: `library`, else libgearfmu.so next to this executable.
fn library_bytes(library: Option<PathBuf>) -> Result<Vec<u8>> {
    let library = match library {
        Some(l) => l,
        None => default_library()?,
    };
    std::fs::read(&library).with_context(|| {
        format!("cannot read the FMU binary {} (build it: cargo build --release -p gearfmu)", library.display())
    })
}

fn build(
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

/// Packs one model into an .fmu: modelDescription.xml, the binary, the model file.
fn write_fmu(output: &Path, pair: &GearPair, kind: ModelKind, so: &[u8]) -> Result<()> {
    let pair = pair.clone();
    let guid = ModelFile::compute_guid(interface::VARIABLES_TOML, &pair.name, &kind);
    let (starts, description) = match &kind {
        ModelKind::Lumped(mesh) => (
            [
                ("inertia_1", mesh.inertia_1_kgm2),
                ("inertia_2", mesh.inertia_2_kgm2),
                ("mesh_damping_ratio", mesh.mesh_damping_ratio),
                ("max_step", gearfmu::dynamics::fmu::LUMPED_DEFAULT_MAX_STEP_S),
            ],
            format!(
                "Gear pair {} (z {}/{}), lumped model: rigid gears, {}, backlash",
                pair.name,
                pair.gear1.teeth,
                pair.gear2.teeth,
                match mesh.law_source {
                    gearfmu::dynamics::lumped::MeshLawSource::Analytic => "potential-energy mesh stiffness (analytic)",
                    gearfmu::dynamics::lumped::MeshLawSource::FeStatics =>
                        "mesh law from the PMOR-Hertz FE statics (loaded transmission error over roll and load)",
                }
            ),
        ),
        ModelKind::Element(_) => anyhow::bail!("a drivetrain element is written by `fmu-build element`"),
        ModelKind::PmorHertz(m) => (
            [
                ("inertia_1", m.gears[0].polar_inertia_kgm2),
                ("inertia_2", m.gears[1].polar_inertia_kgm2),
                ("mesh_damping_ratio", m.pair.mesh_damping_ratio),
                ("max_step", m.max_step_s),
            ],
            format!(
                "Gear pair {} (z {}/{}), {}: FE gears reduced to {} + {} coordinates (eigenmodes and global contact shapes in floating frames), {}",
                pair.name,
                pair.gear1.teeth,
                pair.gear2.teeth,
                match m.info.contact {
                    FlankContact::Hertz => "PMOR-Hertz model",
                    FlankContact::Penalty { .. } => "standard PMOR reference model",
                },
                m.gears[0].elastic_size() + 1,
                m.gears[1].elastic_size() + 1,
                match m.info.contact {
                    FlankContact::Hertz => "Hertz contact".to_string(),
                    FlankContact::Penalty { factor } =>
                        format!("node-to-surface penalty contact ({} × ISO 6336-1 c_γα per node), drive flanks only", sig(factor)),
                }
            ),
        ),
    };
    let xml = model_description::write(
        interface::variables(),
        &model_description::ModelFacts {
            model_name: &pair.name,
            guid: &guid,
            description: &description,
            model_starts: &starts,
            operating_point_nm: Some((pair.operating_torque_nm, gearfmu::gear::rating::yield_torque_nm(&pair))),
            default_step_s: 1e-5,
        },
    )
    .map_err(anyhow::Error::msg)?;
    let file = ModelFile { guid: guid.clone(), pair_name: pair.name.clone(), model: kind };
    write_fmu_archive(output, &xml, &file, so)?;
    println!("wrote {} (GUID {guid})", output.display());
    Ok(())
}

/// Writes the .fmu archive (`fmu_archive`).
fn write_fmu_archive(output: &Path, xml: &str, file: &ModelFile, so: &[u8]) -> Result<()> {
    let bytes = fmu_archive(xml, file, so)?;
    std::fs::write(output, bytes).with_context(|| format!("cannot create {}", output.display()))
}

/// The .fmu archive's bytes: modelDescription.xml, the binary and the model file.
fn fmu_archive(xml: &str, file: &ModelFile, so: &[u8]) -> Result<Vec<u8>> {
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    zip.start_file("modelDescription.xml", options)?;
    zip.write_all(xml.as_bytes())?;
    zip.start_file(format!("binaries/linux64/{}.so", model_description::MODEL_IDENTIFIER), options)?;
    zip.write_all(so)?;
    zip.start_file(format!("resources/{}", gearfmu::model_file::FILE_NAME), options)?;
    zip.write_all(&file.to_bytes())?;
    Ok(zip.finish()?.into_inner())
}

/// The contact depth h (m): `--depth-mm` where given, else the pair's default (half the module).
fn contact_depth_or_default(pair: &GearPair, depth_mm: Option<f64>) -> f64 {
    depth_mm.map_or_else(|| gearfmu::rom::reductor::contact_depth_m(pair), |d| d * 1e-3)
}

/// The lumped model's mesh: from the FE statics (the reduction `ste` makes, then a table of
/// static cases over roll × force; progress and cost reported) or from the geometry alone.
fn lumped_mesh(pair: &GearPair, mesh: &MeshSpec, law: MeshLawChoice, depth_mm: Option<f64>) -> Result<LumpedMesh> {
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
fn check_loaded_contact_ratio(pair: &GearPair, deflection_m: f64, torque_nm: f64) -> Result<()> {
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
fn lumped_from_table(pair: &GearPair, table: gearfmu::rom::static_mesh_law::StaticMeshLaw) -> LumpedMesh {
    if let Some(why) = &table.capped {
        println!("note: {why}; beyond it the law continues with its last slope");
    }
    LumpedMesh::from_drive_law(pair, gearfmu::dynamics::lumped::MeshLawSource::FeStatics, table.law, table.pairs)
}

/// The offline PMOR-Hertz build: FE models, eigenmodes, static contact shapes, invariants.
fn build_rom(
    pair: &GearPair,
    mesh: &MeshSpec,
    rom: &RomOptions,
    lumped_mesh_law: bool,
    contact: FlankContact,
) -> Result<(gearfmu::dynamics::pmor::model::PmorModel, Option<LumpedMesh>)> {
    use gearfmu::dynamics::pmor::integrator::Integrator;
    use gearfmu::dynamics::pmor::model::Interpolation;
    use gearfmu::dynamics::pmor::quasi_static::Condensation;
    use gearfmu::rom::dynamic_reductor::{build_dynamic_model, DynamicBuildOptions};
    let rom_torques_nm = rom.rom_torques_nm.clone().unwrap_or_else(|| vec![pair.operating_torque_nm]);
    let yield_torque = gearfmu::gear::rating::yield_torque_nm(pair);
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
        sig(gearfmu::dynamics::pmor::linear::step_load_ceiling_of(pair, &rom_torques_nm))
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
    let (model, report) = build_dynamic_model(pair, mesh, &options, |m| {
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

fn inspect(spec: &Path, json: Option<PathBuf>, law: MeshLawChoice, resolution: Resolution) -> Result<()> {
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
        sig(gearfmu::gear::rating::rated_torque_nm(&pair)),
        sig(gearfmu::gear::rating::yield_torque_nm(&pair))
    );
    println!("  ISO 6336-1 c_γα·b {iso_total:.4e} N/m");
    // The geometry is printed; the mesh law takes its FE statics now (with `--mesh-law fe`).
    let mesh = lumped_mesh(&pair, &mesh_spec, law, None)?;
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

/// The pair and its mesh resolution (the spec's [mesh], overridden from the command line).
/// Every command meshes a spec the way the FMU's build does (`MeshSpec::dynamic_default` for the
/// keys the spec's `[mesh]` leaves out): the STE `ste` prints is the one the FMU carries, and a
/// small pair's contact depth reaches past its flank elements on that mesh where the coarse
/// 4/8/4 (the library's test default) leaves it short.
fn pair_and_mesh(spec_path: &Path, r: Resolution) -> Result<(GearPair, MeshSpec)> {
    pair_and_mesh_or(spec_path, r, Some(MeshSpec::dynamic_default()), None)
}

/// The pair and its mesh: the keys the spec's `[mesh]` section sets, `fallback`'s values for the
/// keys it does not set (the spec's defaults without a fallback), then the command line's
/// overrides. Where neither the
/// spec nor the command line sets the axial slices, a helical pair gets as many as its contact
/// depth h (`depth_mm`, default half the module) needs (`fe::gear_mesh::axial_slices_for`).
fn pair_and_mesh_or(
    spec_path: &Path,
    r: Resolution,
    fallback: Option<MeshSpec>,
    depth_mm: Option<f64>,
) -> Result<(GearPair, MeshSpec)> {
    let mut spec = PairSpec::load(spec_path)?;
    let text = std::fs::read_to_string(spec_path)?;
    let table: toml::Table = toml::from_str(&text).context("the spec is not a TOML table")?;
    let spec_mesh = table.get("mesh").and_then(|m| m.as_table());
    if let Some(fallback) = fallback {
        // Key by key: the spec's [mesh] keys over the fallback's (a [mesh] that sets only
        // axial_slices keeps the fallback's 10/10/10), read back through the spec's own type.
        let mut merged = toml::Table::try_from(fallback).context("the fallback mesh as TOML")?;
        merged.extend(spec_mesh.cloned().unwrap_or_default());
        spec.mesh = merged.try_into().context("the spec's [mesh] section")?;
    }
    let slices_set = r.slices.is_some() || spec_mesh.is_some_and(|m| m.contains_key("axial_slices"));
    let m = &mut spec.mesh;
    m.elements_across_tooth = r.across.unwrap_or(m.elements_across_tooth);
    m.elements_along_profile = r.profile.unwrap_or(m.elements_along_profile);
    m.elements_in_rim = r.rim.unwrap_or(m.elements_in_rim);
    m.axial_slices = r.slices.unwrap_or(m.axial_slices);
    if let Some(g) = r.profile_grading {
        m.profile_grading = match g {
            Grading::RootAndTip => ProfileGrading::RootAndTip,
            Grading::Uniform => ProfileGrading::Uniform,
        };
    }
    let pair = GearPair::from_spec(&spec)?;
    let mut mesh = spec.mesh;
    if !slices_set {
        let depth_m = contact_depth_or_default(&pair, depth_mm);
        mesh.axial_slices = mesh.axial_slices.max(gearfmu::fe::gear_mesh::axial_slices_for(&pair, depth_m));
    }
    Ok((pair, mesh))
}

/// Progress of a long command: an indicatif spinner on a terminal; off a terminal (a log file,
/// CI) plain lines on stderr, at most one a second, so a long build is never silent.
struct Progress {
    bar: ProgressBar,
    plain: bool,
    started: std::time::Instant,
    last_line: std::sync::Mutex<Option<std::time::Instant>>,
}

impl Progress {
    fn set_message(&self, message: impl Into<String>) {
        let message = message.into();
        if self.plain {
            let mut last = self.last_line.lock().unwrap_or_else(|p| p.into_inner());
            if last.is_none_or(|at| at.elapsed().as_secs_f64() >= 1.0) {
                eprintln!("[{:6.1} s] {message}", self.started.elapsed().as_secs_f64());
                *last = Some(std::time::Instant::now());
            }
        }
        self.bar.set_message(message);
    }

    /// A stage of the work: off a terminal always printed (stages are few; `set_message`'s
    /// chatty updates are thinned to one a second).
    fn stage(&self, message: String) {
        if self.plain {
            *self.last_line.lock().unwrap_or_else(|p| p.into_inner()) = None;
        }
        self.set_message(message);
    }

    fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }
}

fn spinner(message: String) -> Progress {
    let bar = ProgressBar::new_spinner();
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    let progress = Progress {
        bar,
        plain: !std::io::IsTerminal::is_terminal(&std::io::stderr()),
        started: std::time::Instant::now(),
        last_line: Default::default(),
    };
    progress.set_message(message);
    progress
}

fn output_path(stem: &Path, gear: usize, extension: &str) -> PathBuf {
    let name = format!("{}_gear{gear}.{extension}", stem.file_stem().and_then(|s| s.to_str()).unwrap_or("gear"));
    stem.with_file_name(name)
}

fn node_sets(gm: &GearMesh) -> Vec<(&'static str, Vec<i32>)> {
    let n = gm.mesh.nodes.len();
    let mut bore = vec![0; n];
    for &b in &gm.bore_nodes {
        bore[b] = 1;
    }
    let (mut side, mut tooth) = (vec![0; n], vec![-1; n]);
    for f in &gm.flank_nodes {
        side[f.node] = f.side as i32;
        tooth[f.node] = f.tooth as i32;
    }
    vec![("bore", bore), ("flank_side", side), ("flank_tooth", tooth)]
}

fn mesh_command(spec: &Path, resolution: Resolution, vtk: Option<PathBuf>, png: Option<PathBuf>) -> Result<()> {
    let (pair, mesh_spec) = pair_and_mesh(spec, resolution)?;
    for (i, gear) in [&pair.gear1, &pair.gear2].into_iter().enumerate() {
        let bar = spinner(format!("meshing gear {}", i + 1));
        let gm = mesh_gear(&pair, gear, &mesh_spec);
        bar.finish_and_clear();
        let free = 3 * (gm.mesh.nodes.len() - gm.bore_nodes.len());
        println!(
            "gear {} (z = {}): {} nodes, {} elements, {} DOFs ({} free with the bore clamped), {} flank nodes",
            i + 1,
            gear.teeth,
            gm.mesh.nodes.len(),
            gm.mesh.elements.len(),
            gm.mesh.dofs(),
            free,
            gm.flank_nodes.len()
        );
        if let Some(stem) = &vtk {
            let path = output_path(stem, i + 1, "vtu");
            vtk::write_vtu(&path, &gm.mesh, &node_sets(&gm), &[])?;
            println!("  wrote {}", path.display());
        }
        if let Some(stem) = &png {
            let path = output_path(stem, i + 1, "png");
            gearfmu::fe::profile_png::write_profile_png(&path, &pair, gear, &gm).map_err(anyhow::Error::msg)?;
            println!("  wrote {}", path.display());
        }
    }
    Ok(())
}

fn linearize_command(
    fmu: &Path,
    torque_nm: Option<f64>,
    mesh_damping_ratio: Option<f64>,
    positions: usize,
    count: usize,
) -> Result<()> {
    use gearfmu::dynamics::pmor::linear;
    let file = std::fs::File::open(fmu).with_context(|| format!("cannot open {}", fmu.display()))?;
    let mut archive = zip::ZipArchive::new(file).with_context(|| format!("{} is not an FMU (zip)", fmu.display()))?;
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(
        &mut archive.by_name("resources/model.bin").context("the FMU has no resources/model.bin")?,
        &mut bytes,
    )?;
    let ModelKind::PmorHertz(model) = ModelFile::from_bytes(&bytes).map_err(anyhow::Error::msg)?.model else {
        anyhow::bail!(
            "{} carries the lumped model: its linearized mesh frequency is sqrt(k (r_b1²/J1 + r_b2²/J2))/2π with k its mesh_stiffness output (`inspect`)",
            fmu.display()
        );
    };
    // The instance's dynamics, as the FMU builds it (mesh damper included).
    let file =
        ModelFile { guid: String::new(), pair_name: model.pair.name.clone(), model: ModelKind::PmorHertz(model) };
    let fmu_model = gearfmu::dynamics::fmu::GearPairFmu::from_model_file(file).map_err(anyhow::Error::msg)?;
    let gearfmu::dynamics::fmu::Physics::PmorHertz { model, place } = &fmu_model.physics else { unreachable!() };
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

fn modes_command(
    spec: &Path,
    count: usize,
    resolution: Resolution,
    vtk: Option<PathBuf>,
    whole_gear: bool,
) -> Result<()> {
    use gearfmu::fe::cyclic_symmetry::CyclicGear;
    let (pair, mesh_spec) = pair_and_mesh(spec, resolution)?;
    for (i, gear) in [&pair.gear1, &pair.gear2].into_iter().enumerate() {
        let bar = spinner(format!("gear {}: meshing and assembling", i + 1));
        let model = ClampedGear::new(&pair, gear, &mesh_spec, Formulation::IncompatibleModes);
        let (gm, dofs, k, m) = (&model.mesh, &model.dofs, &model.stiffness, model.mass());
        let cyclic = if whole_gear { None } else { CyclicGear::new(&model).map_err(anyhow::Error::msg)? };
        let (modes, solver) = match cyclic {
            Some(cyclic) => {
                bar.set_message(format!("gear {}: {} harmonics ({} DOFs)", i + 1, cyclic.harmonics(), dofs.n_free));
                let (harmonics, edge, sector) = (cyclic.harmonics(), cyclic.edge_dofs(), cyclic.sector_dofs());
                let factored = cyclic.factorize().map_err(anyhow::Error::msg)?;
                let modes = factored.lowest_modes(k, &m, count, 1e-10, 300).map_err(anyhow::Error::msg)?;
                (modes, format!("by {harmonics} harmonics, sectors of {sector} DOFs with edges of {edge}"))
            }
            None => {
                bar.set_message(format!("gear {}: block Lanczos ({} DOFs)", i + 1, dofs.n_free));
                let chol = model.factorize().map_err(anyhow::Error::msg)?;
                let modes = eigen::lowest_modes_factored(k, &m, &chol, count, 1e-10, 300, |it, converged| {
                    bar.set_message(format!("gear {}: block Lanczos step {it}, {converged}/{count} converged", i + 1))
                })
                .map_err(anyhow::Error::msg)?;
                (
                    modes,
                    format!("whole gear, {:.1} M non-zeros in K's Cholesky factor", chol.factor_nnz() as f64 * 1e-6),
                )
            }
        };
        bar.finish_and_clear();
        println!(
            "gear {} (z = {}, {} DOFs, {solver}): {} block steps; Sturm count below the shift {} = Ritz values below it {}{}",
            i + 1,
            gear.teeth,
            dofs.n_free,
            modes.iterations,
            modes.sturm_count,
            modes.ritz_values_below_shift,
            if modes.sturm_count == modes.ritz_values_below_shift {
                " (no mode missed)"
            } else {
                " — A MODE WAS MISSED"
            }
        );
        for (j, (f, r)) in modes.frequencies_hz().iter().zip(&modes.residuals).enumerate() {
            println!("  mode {:>3}: {:>14.4} Hz   residual {:.1e}", j + 1, f, r);
        }
        if let Some(stem) = &vtk {
            let shapes: Vec<Vec<f64>> = (0..count)
                .map(|c| dofs.expand(&(0..dofs.n_free).map(|r| modes.vectors[(r, c)]).collect::<Vec<_>>()))
                .collect();
            let names: Vec<String> = (0..count).map(|c| format!("mode_{}", c + 1)).collect();
            let fields: Vec<vtk::NodeField> =
                shapes.iter().zip(&names).map(|(v, n)| vtk::NodeField { name: n, components: 3, values: v }).collect();
            let path = output_path(stem, i + 1, "vtu");
            vtk::write_vtu(&path, &gm.mesh, &node_sets(gm), &fields)?;
            println!("  wrote {}", path.display());
        }
    }
    Ok(())
}

fn tooth_stiffness_command(spec: &Path, resolution: Resolution) -> Result<()> {
    let (pair, mesh_spec) = pair_and_mesh(spec, resolution)?;
    let mut pair_compliance = 0.0;
    for (i, gear) in [&pair.gear1, &pair.gear2].into_iter().enumerate() {
        let bar = spinner(format!("gear {}: mesh, assembly, Cholesky", i + 1));
        let fe = gearfmu::fe::tooth_stiffness::single_tooth_compliance(
            &pair,
            gear,
            &mesh_spec,
            Formulation::IncompatibleModes,
        )
        .map_err(anyhow::Error::msg)?;
        bar.finish_and_clear();
        let pem = gearfmu::dynamics::mesh_stiffness::tooth_compliance_per_width(
            gear,
            &pair,
            gear.pitch_radius_m,
            pair.youngs_modulus_pa,
            pair.poisson_ratio,
        );
        println!(
            "gear {} (z = {}, {} DOF): FE {:.5} mm·µm/N, potential energy {:.5} mm·µm/N (FE/PEM {:.3})",
            i + 1,
            gear.teeth,
            fe.dofs,
            fe.compliance_per_width * 1e9,
            pem * 1e9,
            fe.compliance_per_width / pem
        );
        pair_compliance += fe.compliance_per_width * 1e9;
    }
    let c = 1.0 / pair_compliance;
    // The q′ series is for steel (E_st = 206 GPa): compare at the pair's own modulus.
    let c_th = iso6336::theoretical_single_stiffness(&pair) * iso6336::material_factor(&pair);
    println!(
        "pair: FE {c:.2} N/(mm·µm); ISO 6336-1 c′_th·E/E_st {c_th:.2} (FE/ISO {:.3}), c′ = c′_th·C_M·C_B·E/E_st {:.2} (FE/ISO {:.3})",
        c / c_th,
        iso6336::single_stiffness(&pair),
        c / iso6336::single_stiffness(&pair)
    );
    Ok(())
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Build { spec, output, model, mesh_law, lumped_fmu, library, rom, resolution } => {
            build(&spec, &output, model, mesh_law, lumped_fmu.as_deref(), library, &rom, resolution)
        }
        Command::Inspect { spec, json, mesh_law, resolution } => inspect(&spec, json, mesh_law, resolution),
        Command::Mesh { spec, resolution, vtk, png } => mesh_command(&spec, resolution, vtk, png),
        Command::ToothStiffness { spec, resolution } => tooth_stiffness_command(&spec, resolution),
        Command::Modes { spec, count, resolution, vtk, whole_gear } => {
            modes_command(&spec, count, resolution, vtk, whole_gear)
        }
        Command::Linearize { fmu, torque_nm, mesh_damping_ratio, positions, count } => {
            linearize_command(&fmu, torque_nm, mesh_damping_ratio, positions, count)
        }
        Command::Element { kind, output, name, options, library } => (|| {
            check_output_folder(&output)?;
            let element = options.element(kind)?;
            let name = name.unwrap_or_else(|| element.kind().to_string());
            let bytes = drivetrain::element_fmu(&name, element, &library_bytes(library)?)?;
            std::fs::write(&output, bytes).with_context(|| format!("cannot create {}", output.display()))?;
            println!("wrote {}", output.display());
            Ok(())
        })(),
        Command::Ssp { gear_fmu, output, options, library } => (|| {
            check_output_folder(&output)?;
            drivetrain::write_ssp(&output, &gear_fmu, &options, &library_bytes(library)?)
        })(),
        Command::Ste { spec, torque_nm, angles, pitches, method, depth_mm, p_en, eq20, resolution, csv, png } => {
            let options = SteOptions { torque_nm, angles, pitches, method, depth_mm, p_en, eq20 };
            ste_with_defaults(&spec, options, resolution, StePlots { csv, png })
        }
    };
    if let Err(e) = result {
        eprintln!("fmu-build: error: {e:#}");
        std::process::exit(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// The reference documents every command: each subcommand of the CLI (from clap's own
    /// description of it, not a list kept by hand) has its section in docs/reference/cli.md, and
    /// each of its long options appears there.
    #[test]
    fn every_command_and_option_is_in_the_cli_reference() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/reference/cli.md");
        let reference = std::fs::read_to_string(&path).unwrap();
        let mut missing = Vec::new();
        for command in Cli::command().get_subcommands() {
            let name = command.get_name();
            if !reference.contains(&format!("## `fmu-build {name}")) {
                missing.push(format!("command {name}"));
            }
            for arg in command.get_arguments() {
                if let Some(long) = arg.get_long() {
                    if long != "help" && !reference.contains(&format!("--{long}")) {
                        missing.push(format!("{name} --{long}"));
                    }
                }
            }
        }
        assert!(missing.is_empty(), "not in docs/reference/cli.md: {missing:?}");
    }
}
