//! The PMOR-Hertz model a built gearfmu FMU carries (`resources/model.bin`), for the studies in
//! `examples/` that run its dynamics in process.
use gearfmu::dynamics::pmor::model::PmorModel;
use gearfmu::model_file::{ModelFile, ModelKind};

pub fn pmor_model(fmu: &str) -> Result<PmorModel, String> {
    let file = std::fs::File::open(fmu).map_err(|e| format!("{fmu}: {e}"))?;
    let mut archive = zip::ZipArchive::new(file).map_err(|e| format!("{fmu} is not an FMU: {e}"))?;
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(&mut archive.by_name("resources/model.bin").map_err(|e| e.to_string())?, &mut bytes)
        .map_err(|e| e.to_string())?;
    match ModelFile::from_bytes(&bytes)?.model {
        ModelKind::PmorHertz(model) => Ok(*model),
        _ => Err(format!("{fmu} does not carry a PMOR-Hertz model")),
    }
}
