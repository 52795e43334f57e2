//! The drivetrain elements shipped as FMUs of their own beside the gear pair (inertia, shaft,
//! motor, load; `fmu-build element` and `ssp`): their parameters and their physics.

pub mod element_parameters;
pub mod elements;
