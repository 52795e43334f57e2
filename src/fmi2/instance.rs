//! One FMU instance: the FMI 2.0 state machine around a [`Model`], with argument checks and
//! logging. Every public method here is one fmi2 function minus the C types; `exports` does the
//! pointer conversions and catches panics.

use super::{Model, Phase};
use fmi_sys::fmi2::*;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
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
pub const LOG_CATEGORIES: [&str; 4] = ["logStatusError", "logStatusWarning", "logEvents", "logStatusDiscard"];
/// Index of "logStatusDiscard" in [`LOG_CATEGORIES`].
const LOG_DISCARD: usize = 3;

/// What an FMU state holds: the model's state, the time and the phase it was taken in.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Snapshot<S> {
    pub state: S,
    pub time: f64,
    pub stop_time: Option<f64>,
    pub phase: Phase,
}

pub struct Instance<M: Model> {
    pub name: CString,
    /// The GUID the instance was created with; every serialized FMU state carries it.
    pub guid: String,
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
pub const WARNING: Status = fmi2Status_fmi2Warning;
pub const DISCARD: Status = fmi2Status_fmi2Discard;

impl<M: Model> Instance<M> {
    pub fn new(name: CString, guid: String, model: M, callbacks: fmi2CallbackFunctions, logging_on: bool) -> Self {
        let state = model.initial_state();
        Instance {
            name,
            guid,
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
    /// message containing '%' is never interpreted. Errors, discards and warnings (a refusal, or a
    /// result outside the model's validity: what the master must be able to explain) are logged
    /// even with logging off.
    pub fn log(&self, status: Status, category: usize, message: &str) {
        let wanted = status == ERROR
            || status == DISCARD
            || status == WARNING
            || (self.logging_on && self.enabled_categories[category]);
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

    /// A request the instance cannot honour but that leaves it intact (fmi2Discard): logged, the
    /// phase unchanged.
    pub fn discard(&self, function: &str, message: &str) -> Status {
        self.log(DISCARD, LOG_DISCARD, &format!("{function}: {message}"));
        DISCARD
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
        // The model works on a copy, kept only on success: a refusal (a start energy beyond f64)
        // must not leave half-set values in the state an fmi2GetFMUstate would then capture.
        let mut next = self.state.clone();
        match self.model.exit_initialization(&mut next) {
            Ok(()) => {
                self.state = next;
                self.phase = Phase::StepComplete;
                self.log(OK, 2, &format!("initialized at t = {}", self.time));
                OK
            }
            Err(e) => self.fail("fmi2ExitInitializationMode", &e),
        }
    }

    pub fn do_step(&mut self, current: f64, h: f64) -> Status {
        const F: &str = "fmi2DoStep";
        if !(h.is_finite() && h > 0.0) {
            return self.fail(F, &format!("communicationStepSize must be finite and > 0, got {h}"));
        }
        // The master's time may differ from ours by rounding only: a billionth of the step plus
        // a few ulps of t (never a fraction of |t|, which at t = 1e9 s would be a whole second).
        let tolerance = time_tolerance(self.time, h);
        if !current.is_finite() || (current - self.time).abs() > tolerance {
            return self.fail(
                F,
                &format!(
                    "currentCommunicationPoint {current} is not the FMU's time {} (differs by {:e} s, tolerance {tolerance:e} s)",
                    self.time,
                    current - self.time
                ),
            );
        }
        if let Some(stop) = self.stop_time {
            if current + h > stop + time_tolerance(stop, h) {
                return self.fail(F, &format!("step to {} goes past stopTime {stop}", current + h));
            }
        }
        // Refuse, before any work, a step the model cannot finish in bounded time.
        if let Err(e) = self.model.check_step(&self.state, h) {
            return self.fail(F, &e);
        }
        match self.model.do_step(&mut self.state, h) {
            Ok(()) => {
                // Take the master's time grid, so that t never drifts from its sum.
                self.time = current + h;
                // A result outside the model's validity is never a silent number: logged whatever
                // the debug-logging setting, once per rule, and the step stands.
                for warning in self.model.take_warnings(&mut self.state) {
                    self.log(WARNING, 1, &format!("{F} at t = {}: {warning}", self.time));
                }
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

    pub fn get_booleans(&mut self, vrs: &[u32], values: &mut [i32]) -> Status {
        for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
            match self.model.get_boolean(&self.state, vr) {
                Ok(v) => *value = v as i32,
                Err(e) => return self.fail("fmi2GetBoolean", &e),
            }
        }
        OK
    }

    pub fn set_booleans(&mut self, vrs: &[u32], values: &[i32]) -> Status {
        // Check everything before changing anything: a refused call changes nothing.
        let mut trial = self.state.clone();
        for (&vr, &value) in vrs.iter().zip(values) {
            if let Err(e) = self.model.set_boolean(&mut trial, vr, value != 0, self.phase) {
                return self.fail("fmi2SetBoolean", &e);
            }
        }
        self.state = trial;
        OK
    }

    pub fn snapshot(&self) -> Snapshot<M::State> {
        Snapshot { state: self.state.clone(), time: self.time, stop_time: self.stop_time, phase: self.phase }
    }

    /// Checks a snapshot before it may replace the instance's state: the time and phase must be
    /// ones this FMU can be in, and the model's parameters pass the rules fmi2SetReal applies.
    pub fn check_snapshot(&self, snapshot: &Snapshot<M::State>) -> Result<(), String> {
        if !snapshot.time.is_finite() {
            return Err(format!("the FMU state's time {} is not finite", snapshot.time));
        }
        if let Some(stop) = snapshot.stop_time {
            if !(stop.is_finite() && stop >= snapshot.time - time_tolerance(stop, 0.0)) {
                return Err(format!("the FMU state's stopTime {stop} is not finite and ≥ its time {}", snapshot.time));
            }
        }
        if snapshot.phase == Phase::Fatal {
            return Err("the FMU state was taken in phase Fatal, which no FMU state can be".into());
        }
        // A state taken after initialization must also pass what fmi2ExitInitializationMode
        // checks (found while fuzzing the state decoder: a forged StepComplete state with
        // max_step above the stability limit was restored and stepped).
        let initialized = matches!(snapshot.phase, Phase::StepComplete | Phase::StepFailed | Phase::Terminated);
        self.model.check_state(&snapshot.state, initialized)
    }

    /// Restores a snapshot after [`Self::check_snapshot`]; a refused one changes nothing.
    pub fn restore(&mut self, snapshot: &Snapshot<M::State>) -> Result<(), String> {
        self.check_snapshot(snapshot).map_err(|e| format!("the FMU state is refused: {e}"))?;
        self.state = snapshot.state.clone();
        self.time = snapshot.time;
        self.stop_time = snapshot.stop_time;
        self.phase = snapshot.phase;
        Ok(())
    }

    /// The serialized form of an FMU state of this instance (see [`STATE_MAGIC`]).
    pub fn serialize(&self, snapshot: &Snapshot<M::State>) -> Result<Vec<u8>, String> {
        serialize_snapshot(snapshot, &self.guid)
    }

    /// Decodes a serialized FMU state and checks it as [`Self::restore`] would.
    pub fn deserialize(&self, bytes: &[u8]) -> Result<Snapshot<M::State>, String> {
        let snapshot = deserialize_snapshot(bytes, &self.guid)?;
        self.check_snapshot(&snapshot).map_err(|e| format!("the FMU state is refused: {e}"))?;
        Ok(snapshot)
    }

    pub fn reset(&mut self) {
        self.state = self.model.initial_state();
        self.time = 0.0;
        self.stop_time = None;
        self.phase = Phase::Instantiated;
    }
}

/// How far the master's time may be from the instance's: a billionth of the step h plus four
/// machine epsilons of |t| (2 to 4 ulps of t): the rounding of a sum of steps, never a fraction
/// of t itself.
pub fn time_tolerance(t: f64, h: f64) -> f64 {
    1e-9 * h + 4.0 * f64::EPSILON * t.abs()
}

/// The serialized FMU state:
///
/// | bytes | content |
/// |---|---|
/// | 8 | magic `GFMUSTAT` |
/// | 4 | format version, u32 little-endian ([`STATE_VERSION`]) |
/// | 4 + n | length of the GUID (u32 LE), then the GUID of the FMU that took the state (UTF-8) |
/// | 8 + m | length of the payload (u64 LE), then the snapshot in postcard |
/// | 32 | SHA-256 over all the bytes before it |
///
/// Nothing may follow the checksum. A state decodes only in an FMU with the same GUID (the same
/// interface, model data and model kind).
pub const STATE_MAGIC: &[u8; 8] = b"GFMUSTAT";
pub const STATE_VERSION: u32 = 2;
const DIGEST_LEN: usize = 32;

pub fn serialize_snapshot<S: Serialize>(snapshot: &Snapshot<S>, guid: &str) -> Result<Vec<u8>, String> {
    let payload = postcard::to_allocvec(snapshot).map_err(|e| format!("cannot serialize FMU state: {e}"))?;
    let guid_len = u32::try_from(guid.len()).map_err(|_| "the GUID is too long to serialize".to_string())?;
    let mut bytes = STATE_MAGIC.to_vec();
    bytes.extend_from_slice(&STATE_VERSION.to_le_bytes());
    bytes.extend_from_slice(&guid_len.to_le_bytes());
    bytes.extend_from_slice(guid.as_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&payload);
    let digest = Sha256::digest(&bytes);
    bytes.extend_from_slice(&digest);
    Ok(bytes)
}

/// Reads `n` bytes at `*at`, or says what is missing.
fn take<'a>(bytes: &'a [u8], at: &mut usize, n: usize, what: &str) -> Result<&'a [u8], String> {
    let end = at.checked_add(n).filter(|&e| e <= bytes.len()).ok_or_else(|| {
        format!("serialized FMU state is truncated: {} bytes, the {what} needs {n} more at byte {}", bytes.len(), at)
    })?;
    let slice = &bytes[*at..end];
    *at = end;
    Ok(slice)
}

pub fn deserialize_snapshot<S: for<'de> Deserialize<'de>>(bytes: &[u8], guid: &str) -> Result<Snapshot<S>, String> {
    let mut at = 0;
    if take(bytes, &mut at, STATE_MAGIC.len(), "magic")? != STATE_MAGIC.as_slice() {
        return Err("serialized FMU state has a wrong magic (not a state of this FMU kind)".into());
    }
    let version = u32::from_le_bytes(take(bytes, &mut at, 4, "format version")?.try_into().unwrap_or_default());
    if version != STATE_VERSION {
        return Err(format!(
            "serialized FMU state has format version {version}; this FMU reads version {STATE_VERSION}"
        ));
    }
    let guid_len = u32::from_le_bytes(take(bytes, &mut at, 4, "GUID length")?.try_into().unwrap_or_default());
    let state_guid = take(bytes, &mut at, guid_len as usize, "GUID")?;
    let payload_len = u64::from_le_bytes(take(bytes, &mut at, 8, "payload length")?.try_into().unwrap_or_default());
    let payload_len = usize::try_from(payload_len).map_err(|_| format!("payload length {payload_len} is too large"))?;
    let payload = take(bytes, &mut at, payload_len, "payload")?;
    let body_len = at;
    let digest = take(bytes, &mut at, DIGEST_LEN, "SHA-256 checksum")?;
    if at != bytes.len() {
        return Err(format!(
            "serialized FMU state has {} trailing bytes after its checksum (expected {at} bytes, got {})",
            bytes.len() - at,
            bytes.len()
        ));
    }
    if Sha256::digest(&bytes[..body_len]).as_slice() != digest {
        return Err("serialized FMU state is corrupted: its SHA-256 checksum does not match".into());
    }
    if state_guid != guid.as_bytes() {
        return Err(format!(
            "serialized FMU state is from another FMU: GUID {} (this FMU's is {guid})",
            String::from_utf8_lossy(state_guid)
        ));
    }
    let (snapshot, rest) =
        postcard::take_from_bytes(payload).map_err(|e| format!("serialized FMU state is corrupted: {e}"))?;
    if !rest.is_empty() {
        return Err(format!("serialized FMU state's payload has {} trailing bytes", rest.len()));
    }
    Ok(snapshot)
}
