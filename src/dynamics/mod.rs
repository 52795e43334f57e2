//! Gear-pair dynamics. Each fidelity level is a model behind [`GearPairModel`]; the FMU glue
//! (`dynamics::fmu`) drives whichever the FMU's resources name.

pub mod iso6336;
pub mod lumped;
pub mod mesh_stiffness;
