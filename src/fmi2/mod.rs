//! The FMI 2.0 Co-Simulation layer. It knows nothing about gears: it holds the FMI state
//! machine, checks every argument, logs through the master's callback and handles FMU states,
//! and talks to a model only through [`Model`]. Modelled on modelica/Reference-FMUs: one generic
//! set of entry points (`exports`), one guard with a table of allowed states (`instance`), and a
//! small per-model implementation elsewhere (`crate::fmu::gear_pair`).

pub mod exports;
pub mod instance;
pub mod resource_uri;

use serde::{de::DeserializeOwned, Serialize};
use std::path::Path;

/// The phases of an FMI 2.0 Co-Simulation slave (FMI 2.0.4, Fig. 7), one bit each so that the
/// table of allowed phases per function is a set of masks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[repr(u32)]
pub enum Phase {
    Instantiated = 1 << 0,
    InitializationMode = 1 << 1,
    StepComplete = 1 << 2,
    StepFailed = 1 << 3,
    Terminated = 1 << 4,
    Error = 1 << 5,
    Fatal = 1 << 6,
}

/// A model behind the FMI layer. The model itself is immutable data loaded once (e.g. the ROM);
/// everything that changes lives in `State`, a plain struct, so an FMU state is a copy of it.
pub trait Model: Sized + Send + 'static {
    type State: Clone + Serialize + DeserializeOwned + Send + 'static;

    /// Loads the model from the FMU's resources folder; `guid` is the one the master passed.
    fn load(resources: &Path, guid: &str) -> Result<Self, String>;
    /// State right after instantiation (start values of parameters and inputs).
    fn initial_state(&self) -> Self::State;
    /// Sets a real variable; `phase` decides what may be set (parameters only before init).
    fn set_real(&self, state: &mut Self::State, vr: u32, value: f64, phase: Phase) -> Result<(), String>;
    fn get_real(&self, state: &Self::State, vr: u32) -> Result<f64, String>;
    fn get_integer(&self, state: &Self::State, vr: u32) -> Result<i32, String>;
    fn get_boolean(&self, state: &Self::State, vr: u32) -> Result<bool, String>;
    fn set_boolean(&self, state: &mut Self::State, vr: u32, value: bool, phase: Phase) -> Result<(), String>;
    /// Applies the start values and computes initial outputs (fmi2ExitInitializationMode).
    fn exit_initialization(&self, state: &mut Self::State) -> Result<(), String>;
    /// Refuses, before any work, a step of size h (finite, > 0) that cannot be done in bounded
    /// time with this state's settings (e.g. too many sub-steps); the message says why.
    fn check_step(&self, state: &Self::State, h: f64) -> Result<(), String>;
    /// Checks a state restored from an FMU state (possibly deserialized from outside) with the
    /// rules `set_real` applies to each parameter, and that it fits this model; `initialized`
    /// (a state taken after fmi2ExitInitializationMode) adds the checks that call makes.
    fn check_state(&self, state: &Self::State, initialized: bool) -> Result<(), String>;
    /// Advances from the current time by h (> 0) with the inputs held.
    fn do_step(&self, state: &mut Self::State, h: f64) -> Result<(), String>;
    /// Warnings the last step raised (a result outside the model's validity), each to be logged
    /// once as fmi2Warning; taken, so the state no longer holds them.
    fn take_warnings(&self, _state: &mut Self::State) -> Vec<String> {
        Vec::new()
    }
}
