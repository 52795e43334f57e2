//! Closed forms and standards, the independent evidence and the analytic fallbacks: ISO 6336-1's
//! mesh stiffness (`iso6336`), the potential-energy mesh stiffness of the analytic lumped law
//! (`mesh_stiffness`), the tooth-root rating (`rating`, `root_stress`: Lewis' nominal stress)
//! that sizes a pair's operating torque and guards its validity, and the sliding kinematics and
//! ISO/TR 14179-2's gear loss factor of mesh friction (`gear_loss`).

pub mod gear_loss;
pub mod iso6336;
pub mod mesh_stiffness;
pub mod rating;
pub mod root_stress;
