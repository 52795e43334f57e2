//! Gear-pair dynamics: the fidelity levels (the lumped model, and the FE-based PMOR-Hertz reduced
//! pair in `pmor`), each a `model_file::ModelKind`, and the FMU glue (`fmu`) that drives them.

pub mod fmu;
pub mod iso6336;
pub mod lumped;
pub mod mesh_law;
pub mod mesh_stiffness;
pub mod pmor;
pub mod rk4_stability;
pub mod shared_model;
