//! gearfmu: FE-grade gear-pair dynamics as an FMI 2.0 Co-Simulation FMU.
//!
//! Offline (fmu-build): `gear` (spec, geometry) → `fe` (FE model per gear) → `rom` (reduction,
//! statics, the dynamic reductor) or `dynamics` (lumped mesh stiffness) → `model_file` (the only
//! thing that crosses). Online (the FMU): `fmi2`, the generic FMI layer,
//! drives `dynamics::fmu` through the model file. The method and the code map: `docs/explanation/method.md`.

pub mod contact;
pub mod dynamics;
pub mod fe;
pub mod fmi2;
pub mod gear;
pub mod interface;
pub mod model_file;
pub mod rom;

/// The model the exported fmi2 functions drive.
pub type FmuModel = dynamics::any_model::AnyModel;
