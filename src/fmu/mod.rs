//! The models the exported FMI functions drive (`crate::fmi2` knows none of them): the gear-pair
//! FMU (`gear_pair`: variables, parameters, validity, the step over a `dynamics` model), the
//! drivetrain element FMUs' dispatch (`any_model`), and one model file shared by the instances
//! that load it (`shared_model`).

pub mod any_model;
pub mod gear_pair;
pub mod shared_model;
