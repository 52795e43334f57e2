//! Reduction for the PMOR-Hertz method (design §4.4): global attachment modes, and later their
//! SVD compression, the static contact solver and the ROM file.

pub mod attachment;
pub mod build_cache;
pub mod build_memory;
pub mod dynamic_reductor;
pub mod flank;
pub mod reductor;
pub mod sharing;
pub mod static_mesh_law;
pub mod statics;
pub mod svd;
pub mod sweep;
