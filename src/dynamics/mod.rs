//! Gear-pair dynamics: the fidelity levels (today the lumped model; the FE-based PMOR-Hertz
//! model joins as another `model_file::ModelKind`) and the FMU glue (`fmu`) that drives them.

pub mod fmu;
pub mod iso6336;
pub mod lumped;
pub mod mesh_law;
pub mod mesh_stiffness;
pub mod pmor;
