//! Contact mechanics: the analytic Hertz line contact (used by the lumped mesh now and by the
//! PMOR-Hertz statics later).

pub mod hertz;
pub mod mesh_kinematics;
