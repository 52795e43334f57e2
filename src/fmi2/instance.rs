//! One FMU instance: the FMI 2.0 state machine around a [`Model`], with argument checks and
//! logging. Every public method here is one fmi2 function minus the C types; `exports` does the
//! pointer conversions and catches panics.

use super::{Model, Phase};
use fmi_sys::fmi2::*;
use serde::{Deserialize, Serialize};
use std::ffi::{CStr, CString};

/// Allowed phases per function (FMI 2.0.4, Table "state machine of calling sequence", CS).
pub mod allowed {
    use super::Phase::*;
    const fn m(p: super::Phase) -> u32 {
        p as u32
    }
    pub const ANY_BUT_FATAL: u32 =
        m(Instantiated) | m(InitializationMode) | m(StepComplete) | m(StepFailed) | m(Terminated) | m(Error);
    pub const SETUP_EXPERIMENT: u32 = m(Instantiated);
    pub const ENTER_INIT: u32 = m(Instantiated);
    pub const EXIT_INIT: u32 = m(InitializationMode);
    pub const TERMINATE: u32 = m(StepComplete) | m(StepFailed);
    pub const GET: u32 = m(InitializationMode) | m(StepComplete) | m(StepFailed) | m(Terminated) | m(Error);
    pub const SET: u32 = m(Instantiated) | m(InitializationMode) | m(StepComplete);
    pub const DO_STEP: u32 = m(StepComplete);
    pub const GET_STATUS: u32 = m(StepComplete) | m(StepFailed) | m(Terminated);
    pub const SET_INPUT_DERIVATIVES: u32 = m(Instantiated) | m(InitializationMode) | m(StepComplete);
    pub const GET_OUTPUT_DERIVATIVES: u32 = m(StepComplete) | m(StepFailed) | m(Terminated) | m(Error);
}

/// Log categories declared in modelDescription.xml.
pub const LOG_CATEGORIES: [&str; 3] = ["logStatusError", "logStatusWarning", "logEvents"];

/// What an FMU state holds: the model's state, the time and the phase it was taken in.
#[derive(Clone, Serialize, Deserialize)]
pub struct Snapshot<S> {
    pub state: S,
    pub time: f64,
    pub stop_time: Option<f64>,
    pub phase: Phase,
}

pub struct Instance<M: Model> {
    pub name: CString,
    callbacks: fmi2CallbackFunctions,
    logging_on: bool,
    enabled_categories: [bool; LOG_CATEGORIES.len()],
    pub phase: Phase,
    pub time: f64,
    pub stop_time: Option<f64>,
    pub model: M,
    pub state: M::State,
}

pub type Status = fmi2Status;
pub const OK: Status = fmi2Status_fmi2OK;
pub const ERROR: Status = fmi2Status_fmi2Error;

impl<M: Model> Instance<M> {
    pub fn new(name: CString, model: M, callbacks: fmi2CallbackFunctions, logging_on: bool) -> Self {
        let state = model.initial_state();
        Instance {
            name,
            callbacks,
            logging_on,
            enabled_categories: [true; LOG_CATEGORIES.len()],
            phase: Phase::Instantiated,
            time: 0.0,
            stop_time: None,
            model,
            state,
        }
    }

    /// Passes one message to the master's logger, always with "%s" as the format so that a
    /// message containing '%' is never interpreted. Errors are logged even with logging off.
    pub fn log(&self, status: Status, category: usize, message: &str) {
        let wanted = status == ERROR || (self.logging_on && self.enabled_categories[category]);
        if let (true, Some(logger)) = (wanted, self.callbacks.logger) {
            let text = CString::new(message.replace('\0', " ")).unwrap_or_default();
            let category = CString::new(LOG_CATEGORIES[category]).unwrap_or_default();
            unsafe {
                logger(
                    self.callbacks.componentEnvironment,
                    self.name.as_ptr(),
                    status,
                    category.as_ptr(),
                    c"%s".as_ptr(),
                    text.as_ptr(),
                )
            };
        }
    }

    /// An error: logged, and the instance enters the Error phase (FMI 2.0: only Get*, Reset,
    /// SetFMUstate and FreeInstance may follow).
    pub fn fail(&mut self, function: &str, message: &str) -> Status {
        self.log(ERROR, 0, &format!("{function}: {message}"));
        if self.phase != Phase::Fatal {
            self.phase = Phase::Error;
        }
        ERROR
    }

    /// The one guard: is `function` allowed in the current phase?
    pub fn check_phase(&mut self, function: &str, mask: u32) -> Result<(), Status> {
        if self.phase as u32 & mask != 0 {
            Ok(())
        } else {
            let phase = self.phase;
            Err(self.fail(function, &format!("not allowed in phase {phase:?}")))
        }
    }

    pub fn set_debug_logging(&mut self, on: bool, categories: &[&CStr]) -> Status {
        let mut enabled = [categories.is_empty(); LOG_CATEGORIES.len()];
        for c in categories {
            let name = c.to_string_lossy();
            match LOG_CATEGORIES.iter().position(|k| *k == name) {
                Some(i) => enabled[i] = true,
                None => return self.fail("fmi2SetDebugLogging", &format!("unknown log category \"{name}\"")),
            }
        }
        self.logging_on = on;
        self.enabled_categories = enabled;
        OK
    }

    pub fn setup_experiment(&mut self, start_time: f64, stop_time: Option<f64>) -> Status {
        if !start_time.is_finite() {
            return self.fail("fmi2SetupExperiment", &format!("startTime must be finite, got {start_time}"));
        }
        if let Some(stop) = stop_time {
            if !(stop.is_finite() && stop >= start_time) {
                return self.fail(
                    "fmi2SetupExperiment",
                    &format!("stopTime {stop} must be finite and ≥ startTime {start_time}"),
                );
            }
        }
        self.time = start_time;
        self.stop_time = stop_time;
        OK
    }

    pub fn exit_initialization(&mut self) -> Status {
        match self.model.exit_initialization(&mut self.state) {
            Ok(()) => {
                self.phase = Phase::StepComplete;
                self.log(OK, 2, &format!("initialized at t = {}", self.time));
                OK
            }
            Err(e) => self.fail("fmi2ExitInitializationMode", &e),
        }
    }

    pub fn do_step(&mut self, current: f64, h: f64) -> Status {
        const F: &str = "fmi2DoStep";
        let tolerance = 1e-9 * self.time.abs().max(1.0);
        if !current.is_finite() || (current - self.time).abs() > tolerance {
            return self.fail(F, &format!("currentCommunicationPoint {current} is not the FMU's time {}", self.time));
        }
        if !(h.is_finite() && h > 0.0) {
            return self.fail(F, &format!("communicationStepSize must be finite and > 0, got {h}"));
        }
        if let Some(stop) = self.stop_time {
            if current + h > stop + 1e-9 * stop.abs().max(1.0) {
                return self.fail(F, &format!("step to {} goes past stopTime {stop}", current + h));
            }
        }
        match self.model.do_step(&mut self.state, h) {
            Ok(()) => {
                // Take the master's time grid, so that t never drifts from its sum.
                self.time = current + h;
                OK
            }
            Err(e) => {
                self.phase = Phase::StepFailed;
                self.log(ERROR, 0, &format!("{F}: {e}"));
                ERROR
            }
        }
    }

    pub fn set_reals(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        for (&vr, &value) in vrs.iter().zip(values) {
            if !value.is_finite() {
                return self
                    .fail("fmi2SetReal", &format!("value reference {vr}: value {value} is not finite; input refused"));
            }
        }
        // Check everything before changing anything: a refused call changes nothing.
        let mut trial = self.state.clone();
        for (&vr, &value) in vrs.iter().zip(values) {
            if let Err(e) = self.model.set_real(&mut trial, vr, value, self.phase) {
                return self.fail("fmi2SetReal", &e);
            }
        }
        self.state = trial;
        OK
    }

    pub fn get_reals(&mut self, vrs: &[u32], values: &mut [f64]) -> Status {
        for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
            match self.model.get_real(&self.state, vr) {
                Ok(v) => *value = v,
                Err(e) => return self.fail("fmi2GetReal", &e),
            }
        }
        OK
    }

    pub fn get_integers(&mut self, vrs: &[u32], values: &mut [i32]) -> Status {
        for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
            match self.model.get_integer(&self.state, vr) {
                Ok(v) => *value = v,
                Err(e) => return self.fail("fmi2GetInteger", &e),
            }
        }
        OK
    }

    pub fn snapshot(&self) -> Snapshot<M::State> {
        Snapshot { state: self.state.clone(), time: self.time, stop_time: self.stop_time, phase: self.phase }
    }

    pub fn restore(&mut self, snapshot: &Snapshot<M::State>) {
        self.state = snapshot.state.clone();
        self.time = snapshot.time;
        self.stop_time = snapshot.stop_time;
        self.phase = snapshot.phase;
    }

    pub fn reset(&mut self) {
        self.state = self.model.initial_state();
        self.time = 0.0;
        self.stop_time = None;
        self.phase = Phase::Instantiated;
    }
}

/// The serialized FMU state: a version tag, then the snapshot in postcard.
const STATE_FORMAT: &[u8; 8] = b"GFMUST01";

pub fn serialize_snapshot<S: Serialize>(snapshot: &Snapshot<S>) -> Result<Vec<u8>, String> {
    let mut bytes = STATE_FORMAT.to_vec();
    bytes.extend(postcard::to_allocvec(snapshot).map_err(|e| format!("cannot serialize FMU state: {e}"))?);
    Ok(bytes)
}

pub fn deserialize_snapshot<S: for<'de> Deserialize<'de>>(bytes: &[u8]) -> Result<Snapshot<S>, String> {
    let body = bytes
        .strip_prefix(STATE_FORMAT.as_slice())
        .ok_or("serialized FMU state has a wrong header (not from this FMU version)")?;
    postcard::from_bytes(body).map_err(|e| format!("serialized FMU state is corrupted: {e}"))
}
