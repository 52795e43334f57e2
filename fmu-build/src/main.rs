//! fmu-build: turns a gear-pair spec into an FMI 2.0 Co-Simulation FMU, and inspects models.
//!
//! `fmu-build build examples/kurokawa_spur.toml -o KurokawaSpur.fmu [--model lumped]`
//! `fmu-build inspect examples/kurokawa_spur.toml [--json mesh.json]`

mod model_description;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use gearfmu::dynamics::iso6336;
use gearfmu::dynamics::lumped::{mesh_damping_coefficient, mesh_natural_frequency_hz, LumpedMesh, LumpedParameters};
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::interface;
use gearfmu::model_file::{ModelFile, ModelKind};
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
    /// Rigid gears, potential-energy mesh stiffness, backlash (fast; the reference level).
    Lumped,
}

#[derive(Subcommand)]
enum Command {
    /// Build the .fmu for a pair spec.
    Build {
        spec: PathBuf,
        #[arg(short, long)]
        output: PathBuf,
        #[arg(long, value_enum, default_value = "lumped")]
        model: ModelChoice,
        /// The FMU binary (cdylib); default: libgearfmu.so next to this executable.
        #[arg(long)]
        library: Option<PathBuf>,
    },
    /// Print the pair's kinematics and mesh figures; optionally dump the lumped mesh as JSON.
    Inspect {
        spec: PathBuf,
        #[arg(long)]
        json: Option<PathBuf>,
    },
}

fn load_pair(spec: &Path) -> Result<GearPair> {
    let spec = PairSpec::load(spec)?;
    Ok(GearPair::from_spec(&spec)?)
}

fn default_library() -> Result<PathBuf> {
    let exe = std::env::current_exe()?;
    let dir = exe.parent().context("executable has no folder")?;
    Ok(dir.join("libgearfmu.so"))
}

fn build(spec: &Path, output: &Path, model: ModelChoice, library: Option<PathBuf>) -> Result<()> {
    let pair = load_pair(spec)?;
    let library = match library {
        Some(l) => l,
        None => default_library()?,
    };
    let so = std::fs::read(&library).with_context(|| {
        format!("cannot read the FMU binary {} (build it: cargo build --release -p gearfmu)", library.display())
    })?;
    let kind = match model {
        ModelChoice::Lumped => ModelKind::Lumped(LumpedMesh::from_pair(&pair).map_err(anyhow::Error::msg)?),
    };
    let guid = ModelFile::compute_guid(interface::VARIABLES_TOML, &pair.name, &kind);
    let ModelKind::Lumped(mesh) = &kind;
    let starts = [
        ("inertia_1", mesh.inertia_1_kgm2),
        ("inertia_2", mesh.inertia_2_kgm2),
        ("mesh_damping_ratio", mesh.mesh_damping_ratio),
    ];
    let description = format!(
        "Gear pair {} (z {}/{}), lumped model: rigid gears, potential-energy mesh stiffness, backlash",
        pair.name, pair.gear1.teeth, pair.gear2.teeth
    );
    let xml = model_description::write(
        &interface::variables(),
        &model_description::ModelFacts {
            model_name: &pair.name,
            guid: &guid,
            description: &description,
            model_starts: &starts,
        },
    )
    .map_err(anyhow::Error::msg)?;
    let file = ModelFile { guid: guid.clone(), pair_name: pair.name.clone(), model: kind };

    if let Some(dir) = output.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let out = std::fs::File::create(output).with_context(|| format!("cannot create {}", output.display()))?;
    let mut zip = zip::ZipWriter::new(out);
    let options = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    zip.start_file("modelDescription.xml", options)?;
    zip.write_all(xml.as_bytes())?;
    zip.start_file(format!("binaries/linux64/{}.so", model_description::MODEL_IDENTIFIER), options)?;
    zip.write_all(&so)?;
    zip.start_file(format!("resources/{}", gearfmu::model_file::FILE_NAME), options)?;
    zip.write_all(&file.to_bytes())?;
    zip.finish()?;
    println!("wrote {} (GUID {guid})", output.display());
    Ok(())
}

fn inspect(spec: &Path, json: Option<PathBuf>) -> Result<()> {
    let pair = load_pair(spec)?;
    let mesh = LumpedMesh::from_pair(&pair).map_err(anyhow::Error::msg)?;
    let params = LumpedParameters::defaults(&mesh);
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
    println!("  inertias          {:.5} / {:.5} kg·m²", params.inertia_1_kgm2, params.inertia_2_kgm2);
    println!("  ISO 6336-1 c_γα·b {iso_total:.4e} N/m");
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
        });
        std::fs::write(&path, serde_json::to_string_pretty(&value)?)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Build { spec, output, model, library } => build(&spec, &output, model, library),
        Command::Inspect { spec, json } => inspect(&spec, json),
    };
    if let Err(e) = result {
        eprintln!("fmu-build: error: {e:#}");
        std::process::exit(1);
    }
}
