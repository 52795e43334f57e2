//! The FMU archive: modelDescription.xml, the model file and the FMU binary zipped, and the model
//! file read back from a built FMU; where the binary comes from (`--library`, else beside
//! fmu-build); the output folder checked first.

use anyhow::{Context, Result};
use gearfmu::dynamics::pmor::model::FlankContact;
use gearfmu::gear::{sig, GearPair};
use gearfmu::interface;
use gearfmu::model_file::{ModelFile, ModelKind};
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::model_description;

/// `Err` unless the folder a file is to be written in exists: a typo in `-o` must not make
/// folders anywhere (and is caught before a minute of offline work, not after).
pub(crate) fn check_output_folder(file: &Path) -> Result<()> {
    match file.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) if !dir.is_dir() => {
            anyhow::bail!("the folder {} of {} does not exist: create it first", dir.display(), file.display())
        }
        _ => Ok(()),
    }
}

pub(crate) fn default_library() -> Result<PathBuf> {
    let exe = std::env::current_exe()?;
    let dir = exe.parent().context("executable has no folder")?;
    Ok(dir.join("libgearfmu.so"))
}

/// The FMU binary's bytes: `library`, else libgearfmu.so next to this executable.
pub(crate) fn library_bytes(library: Option<PathBuf>) -> Result<Vec<u8>> {
    let library = match library {
        Some(l) => l,
        None => default_library()?,
    };
    std::fs::read(&library).with_context(|| {
        format!("cannot read the FMU binary {} (build it: cargo build --release -p gearfmu)", library.display())
    })
}

/// Packs one model into an .fmu: modelDescription.xml, the binary, the model file.
pub(crate) fn write_fmu(output: &Path, pair: &GearPair, kind: ModelKind, so: &[u8]) -> Result<()> {
    let pair = pair.clone();
    let guid = ModelFile::compute_guid(interface::VARIABLES_TOML, &pair.name, &kind);
    // ISO/TR 14179-2's inputs: the spec's, or the law unset.
    let lubrication = pair.lubricated_flanks.unwrap_or_default();
    let (starts, description) = match &kind {
        ModelKind::Lumped(mesh) => (
            [
                ("inertia_1", mesh.inertia_1_kgm2),
                ("inertia_2", mesh.inertia_2_kgm2),
                ("mesh_damping_ratio", mesh.mesh_damping_ratio),
                ("max_step", gearfmu::fmu::gear_pair::LUMPED_DEFAULT_MAX_STEP_S),
                ("friction_coefficient", mesh.friction_coefficient),
                ("oil_viscosity", lubrication.oil_viscosity_mpa_s),
                ("flank_roughness_ra", lubrication.roughness_ra_um),
                ("lubricant_factor", lubrication.lubricant_factor),
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
                ("friction_coefficient", m.pair.friction_coefficient),
                ("oil_viscosity", lubrication.oil_viscosity_mpa_s),
                ("flank_roughness_ra", lubrication.roughness_ra_um),
                ("lubricant_factor", lubrication.lubricant_factor),
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
            operating_point_nm: Some((pair.operating_torque_nm, gearfmu::closed_forms::rating::yield_torque_nm(&pair))),
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
pub(crate) fn write_fmu_archive(output: &Path, xml: &str, file: &ModelFile, so: &[u8]) -> Result<()> {
    let bytes = fmu_archive(xml, file, so)?;
    std::fs::write(output, bytes).with_context(|| format!("cannot create {}", output.display()))
}

/// The .fmu archive's bytes: modelDescription.xml, the binary and the model file.
pub(crate) fn fmu_archive(xml: &str, file: &ModelFile, so: &[u8]) -> Result<Vec<u8>> {
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

/// The model file a built gearfmu FMU carries (`resources/model.bin`), read back: what
/// `linearize` and `inspect --from-fmu` work on.
pub(crate) fn read_model_file(fmu: &Path) -> Result<ModelFile> {
    use std::io::Read;
    let file = std::fs::File::open(fmu).with_context(|| format!("cannot open {}", fmu.display()))?;
    let mut archive =
        zip::ZipArchive::new(file).with_context(|| format!("{} is not an FMU (a zip archive)", fmu.display()))?;
    let name = format!("resources/{}", gearfmu::model_file::FILE_NAME);
    let mut bytes = Vec::new();
    archive
        .by_name(&name)
        .with_context(|| format!("{} has no {name}: not a gearfmu FMU", fmu.display()))?
        .read_to_end(&mut bytes)?;
    ModelFile::from_bytes(&bytes).map_err(anyhow::Error::msg)
}
