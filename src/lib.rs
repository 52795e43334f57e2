//! gearfmu: FE-grade gear-pair dynamics as an FMI 2.0 Co-Simulation FMU.
//!
//! Offline (fmu-build): `gear` → stiffness/ROM → `model_data` file. Online (the FMU): `fmi2`
//! (generic FMI layer) drives `dynamics` through the model data. See `../shared/design.md`.

pub mod dynamics;
pub mod gear;
