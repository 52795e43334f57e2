//! The command line: every command and option (clap's derive), the value parsers' rules, and
//! how a command's mesh resolution and contact depth default (`pair_and_mesh`).

use anyhow::{Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use gearfmu::fe::gear_mesh::{MeshSpec, ProfileGrading};
use gearfmu::gear::{GearPair, PairSpec};
use std::path::{Path, PathBuf};

use crate::cli_values::{count, damping_ratio, energy_share, friction_coefficient, positive_number};
use crate::drivetrain;

#[derive(Parser)]
#[command(name = "fmu-build", version, about = "Gear-pair spec → FMI 2.0 Co-Simulation FMU")]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum ModelChoice {
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
pub(crate) enum MeshLawChoice {
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
pub(crate) struct RomOptions {
    /// Fixed-bore eigenmodes per gear n_k (raised to the end of a cluster of the cyclic spectrum).
    #[arg(long, default_value_t = 20, value_parser = count::<1, 200>)]
    pub(crate) modes: usize,
    /// Angular samples of the global contact shapes per mesh cycle n_θ.
    #[arg(long, default_value_t = 20, value_parser = count::<4, 400>)]
    pub(crate) angles: usize,
    /// Torque levels on gear 1 of the static analyses (N·m), comma-separated: n_t shapes per
    /// sample. Default: the spec's operating torque (`[operating] torque_nm`, else the pair's
    /// rated torque). PMOR-Hertz's global shapes are nearly proportional to the load, and levels
    /// whose shapes coincide are refused (a singular mass matrix).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, value_parser = positive_number)]
    pub(crate) rom_torques_nm: Option<Vec<f64>>,
    /// Load-sharing shapes per sample and flank beside the static ones (`rom::sharing`): they
    /// let the pairs in mesh share a dynamic load differently from the static split.
    #[arg(long, default_value_t = 1, value_parser = count::<0, 8>)]
    pub(crate) sharing_shapes: usize,
    /// Depth h (mm) of the partial models and of the Hertz approach. Default: half the normal
    /// module (`rom::reductor::contact_depth_m`; 3 mm on the Kurokawa pairs).
    #[arg(long, allow_negative_numbers = true, value_parser = positive_number)]
    pub(crate) depth_mm: Option<f64>,
    /// Share of the deformation energy the SVD of the attachment modes keeps, in (0, 1] (default:
    /// chosen by measured accuracy, `rom::svd::DEFAULT_P_EN`, 0.999999).
    #[arg(long, allow_negative_numbers = true, value_parser = energy_share)]
    pub(crate) p_en: Option<f64>,
    /// Interpolation of the shapes in the gear angle.
    #[arg(long, value_enum, default_value = "catmull-rom")]
    pub(crate) interpolation: InterpolationChoice,
    /// The FMU's time integrator (its default max_step is 0.6 of this one's stability limit;
    /// the discrete gradient, unconditionally stable, takes velocity Verlet's). Default:
    /// discrete-gradient, verlet with `--dynamics full`.
    #[arg(long, value_enum)]
    pub(crate) integrator: Option<IntegratorChoice>,
    /// Which coordinates carry inertia: the contact shapes and the hub direction quasi-static
    /// (the default: the step set by the body modes and the mesh, velocity Verlet's 20 µs instead
    /// of 1.7 µs on the Kurokawa spur pair, example 3's DTE within 0.2 %: docs/explanation/method.md
    /// §10a), or all of them (the paper's model, a reference; its step is bounded by the shapes
    /// against the contact, ≈ 100 kHz). Default: quasi-static.
    #[arg(long, value_enum)]
    pub(crate) dynamics: Option<DynamicsChoice>,
    /// The memory the build may take (GB). The build estimates its peak once the gears are
    /// meshed, before the FE stage: above this it builds the gears one after the other, and
    /// refuses, with the figure, what will not fit that way either. Default: the machine's
    /// available memory (`MemAvailable`).
    #[arg(long, allow_negative_numbers = true, value_parser = positive_number)]
    pub(crate) memory_limit_gb: Option<f64>,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum IntegratorChoice {
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
pub(crate) enum DynamicsChoice {
    /// The contact shapes and the hub direction quasi-static (`quasi_static`).
    QuasiStatic,
    /// Every reduced coordinate with its inertia.
    Full,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum InterpolationChoice {
    /// C¹ cubic (Catmull–Rom) over the periodic samples.
    CatmullRom,
    /// The paper's linear interpolation (C⁰).
    Linear,
}

#[derive(Subcommand)]
pub(crate) enum Command {
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
        /// Takes the law a built lumped FMU carries instead of making it (no FE work): what that
        /// FMU runs. Built from SPEC, it says so, else refused.
        #[arg(long, conflicts_with = "mesh_law")]
        from_fmu: Option<PathBuf>,
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
        /// Tooth friction: Coulomb's μ at every contact, against the sliding of the pair turning
        /// in its mesh sense (the friction arms in the torque balance, the tangential loads on the
        /// teeth). Default 0: the STE as ISO and the literature define it, whatever the spec's
        /// friction. The penalty baseline then reduces with a second attachment mode per node,
        /// along the flank tangent.
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = friction_coefficient)]
        friction: f64,
        #[command(flatten)]
        resolution: Resolution,
        /// One row per case: method,torque_nm,theta1_rad,theta2_rad,ste_m,mesh_force_n,pairs_in_contact,
        /// k_h_beta, friction_torque_nm (friction's torque on gear 1, against its mesh sense), then
        /// the load per face width of each axial section (line_load_<s>_n_per_mm)
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
pub(crate) enum StaticMethod {
    /// Global attachment modes + SVD, Hertz contact per axial section.
    PmorHertz,
    /// The standard PMOR baseline: CMS attachment modes, node-to-surface penalty.
    Penalty,
}

/// Overrides of the spec's [mesh] section.
#[derive(clap::Args, Clone, Copy)]
pub(crate) struct Resolution {
    /// Elements across the tooth (the spec's mesh.elements_across_tooth).
    #[arg(long, value_parser = count::<1, 64>)]
    pub(crate) across: Option<usize>,
    /// Elements along the profile (mesh.elements_along_profile).
    #[arg(long, value_parser = count::<1, 64>)]
    pub(crate) profile: Option<usize>,
    /// Elements through the rim (mesh.elements_in_rim).
    #[arg(long, value_parser = count::<1, 64>)]
    pub(crate) rim: Option<usize>,
    /// Axial slices over the face width (mesh.axial_slices).
    #[arg(long, value_parser = count::<1, 64>)]
    pub(crate) slices: Option<usize>,
    /// Spacing of the rows along the profile (the spec's mesh.profile_grading).
    #[arg(long, value_enum)]
    pub(crate) profile_grading: Option<Grading>,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum Grading {
    /// sin²: fine at root and tip, coarsest at mid-flank (the default).
    RootAndTip,
    /// Even rows: what the penalty baseline's node-to-surface contact needs.
    Uniform,
}

/// The pair and its mesh resolution (the spec's [mesh], overridden from the command line).
/// Every command meshes a spec the way the FMU's build does (`MeshSpec::dynamic_default` for the
/// keys the spec's `[mesh]` leaves out): the STE `ste` prints is the one the FMU carries, and a
/// small pair's contact depth reaches past its flank elements on that mesh where the coarse
/// 4/8/4 (the library's test default) leaves it short.
pub(crate) fn pair_and_mesh(spec_path: &Path, r: Resolution) -> Result<(GearPair, MeshSpec)> {
    pair_and_mesh_or(spec_path, r, Some(MeshSpec::dynamic_default()), None)
}

/// The pair and its mesh: the keys the spec's `[mesh]` section sets, `fallback`'s values for the
/// keys it does not set (the spec's defaults without a fallback), then the command line's
/// overrides. Where neither the
/// spec nor the command line sets the axial slices, a helical pair gets as many as its contact
/// depth h (`depth_mm`, default half the module) needs (`fe::gear_mesh::axial_slices_for`).
pub(crate) fn pair_and_mesh_or(
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

/// The contact depth h (m): `--depth-mm` where given, else the pair's default (half the module).
pub(crate) fn contact_depth_or_default(pair: &GearPair, depth_mm: Option<f64>) -> f64 {
    depth_mm.map_or_else(|| gearfmu::rom::reductor::contact_depth_m(pair), |d| d * 1e-3)
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
