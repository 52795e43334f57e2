//! gearfmu: FE-grade gear-pair dynamics as an FMI 2.0 Co-Simulation FMU.
//!
//! Offline (fmu-build) → the model file → online (the FMU's binary):
//!
//! - `gear`: the spec read into a pair's geometry (involutes, fillets, flank modifications).
//! - `fe`: each gear's FE model (mesh, hex8 elements, assembly, cyclic symmetry, eigenmodes).
//! - `contact`: the Hertz line contact and the mesh kinematics (where teeth touch).
//! - `rom`: the reductors (PMOR-Hertz, standard PMOR) and the statics; their output is data.
//! - `closed_forms`: ISO 6336-1 stiffness, the potential-energy mesh law, tooth-root rating.
//! - `model_file`: the one thing that crosses from offline to online; `interface`: the FMU variables.
//! - `dynamics`: the gear-pair models the FMU runs (lumped, PMOR-Hertz, the penalty reference).
//! - `drivetrain`: the element FMUs (inertia, shaft, motor, load).
//! - `fmu`: what the exported functions drive (the gear-pair FMU, the elements' dispatch).
//! - `fmi2`: the generic FMI 2.0 layer (states, guards, the C entry points); knows no gear.
//!
//! The method and the code map: `docs/explanation/method.md`.

pub mod closed_forms;
pub mod contact;
pub mod drivetrain;
pub mod dynamics;
pub mod fe;
pub mod fmi2;
pub mod fmu;
pub mod gear;
pub mod interface;
pub mod model_file;
pub mod rom;

/// The model the exported fmi2 functions drive.
pub type FmuModel = fmu::any_model::AnyModel;

/// The allocator of the FMU's binary and of every gearfmu tool (issue 39): mimalloc. A doStep
/// makes a few dozen small vectors per contact evaluation, and glibc's malloc and free took
/// 14 % of a spur pair's doStep samples; with mimalloc the doStep is about a fifth shorter
/// (BENCHMARKS §13). Only Rust's own allocations go through it: the FMU hands no memory to the
/// master to free, and takes none from it (`canNotUseMemoryManagementFunctions`). Its
/// local-dynamic TLS model (Cargo.toml) lets a process load many FMU binaries: with the default
/// initial-exec model the loader runs out of static TLS after a few dozen.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;
