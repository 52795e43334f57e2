//! Contact mechanics: the analytic Hertz line contact, the mesh kinematics (where the teeth of a
//! placed pair touch), and the loadable flank's grid the contact loads are shared over.

pub mod flank_grid;
pub mod hertz;
pub mod mesh_kinematics;
