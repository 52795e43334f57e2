//! The 34 exported fmi2 functions (common + Co-Simulation). Each is a few lines: convert the C
//! arguments, run the body inside [`guard`] (NULL check, allowed-phase check, panic catch), and
//! hand over to [`Instance`]. The model type is chosen once, at the crate root (`crate::FmuModel`).

use super::instance::{allowed, Instance, Snapshot, ERROR, OK};
use super::{resource_uri::resource_path, Model};
use fmi_sys::fmi2::*;
use std::ffi::{CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

type M = crate::FmuModel;
type Inst = Instance<M>;
type FmuState = Snapshot<<M as Model>::State>;

static TYPES_PLATFORM: &CStr = c"default";
static VERSION: &CStr = c"2.0";

/// NULL check, phase check and panic catch around the body of one fmi2 function.
fn guard(c: fmi2Component, function: &str, mask: u32, body: impl FnOnce(&mut Inst) -> fmi2Status) -> fmi2Status {
    if c.is_null() {
        return ERROR;
    }
    let instance = unsafe { &mut *(c as *mut Inst) };
    if let Err(status) = instance.check_phase(function, mask) {
        return status;
    }
    match catch_unwind(AssertUnwindSafe(|| body(&mut *instance))) {
        Ok(status) => status,
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            instance.fail(function, &format!("internal error (panic): {what}"))
        }
    }
}

/// Borrows `n` elements behind a C array; n = 0 with a NULL pointer is an empty slice.
fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    match (p.is_null(), n) {
        (_, 0) => Some(&[]),
        (true, _) => None,
        (false, n) => Some(unsafe { std::slice::from_raw_parts(p, n) }),
    }
}

fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    match (p.is_null(), n) {
        (_, 0) => Some(&mut []),
        (true, _) => None,
        (false, n) => Some(unsafe { std::slice::from_raw_parts_mut(p, n) }),
    }
}

#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> fmi2String {
    TYPES_PLATFORM.as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> fmi2String {
    VERSION.as_ptr()
}

/// # Safety
/// FMI 2.0's contract: `functions` points to the master's callback table and every string is
/// NULL or NUL-terminated (NULLs are refused). Unsafe in Rust because it reads through them.
#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: fmi2String,
    fmu_type: fmi2Type,
    fmu_guid: fmi2String,
    resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    let result = catch_unwind(|| {
        if functions.is_null() || instance_name.is_null() {
            return std::ptr::null_mut();
        }
        let callbacks = unsafe { *functions };
        let name = unsafe { CStr::from_ptr(instance_name) }.to_owned();
        // Report an instantiation failure through the master's logger (no instance exists yet).
        let refuse = |message: String| {
            if let Some(logger) = callbacks.logger {
                let text = CString::new(message).unwrap_or_default();
                unsafe {
                    logger(
                        callbacks.componentEnvironment,
                        name.as_ptr(),
                        fmi2Status_fmi2Error,
                        c"logStatusError".as_ptr(),
                        c"%s".as_ptr(),
                        text.as_ptr(),
                    )
                };
            }
            std::ptr::null_mut()
        };
        if name.to_bytes().is_empty() {
            return refuse("fmi2Instantiate: instanceName must not be empty".into());
        }
        if fmu_type != fmi2Type_fmi2CoSimulation {
            return refuse("fmi2Instantiate: this FMU supports only fmi2CoSimulation".into());
        }
        if fmu_guid.is_null() || resource_location.is_null() {
            return refuse("fmi2Instantiate: fmuGUID and fmuResourceLocation must not be NULL".into());
        }
        let guid = unsafe { CStr::from_ptr(fmu_guid) }.to_string_lossy().into_owned();
        let uri = unsafe { CStr::from_ptr(resource_location) }.to_string_lossy().into_owned();
        let loaded = resource_path(&uri).and_then(|dir| M::load(&dir, &guid));
        match loaded {
            Ok(model) => {
                Box::into_raw(Box::new(Inst::new(name.clone(), guid.clone(), model, callbacks, logging_on != 0)))
                    as fmi2Component
            }
            Err(e) => refuse(format!("fmi2Instantiate: {e}")),
        }
    });
    result.unwrap_or(std::ptr::null_mut())
}

#[no_mangle]
pub extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if !c.is_null() {
        let _ = catch_unwind(|| drop(unsafe { Box::from_raw(c as *mut Inst) }));
    }
}

#[no_mangle]
pub extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    on: fmi2Boolean,
    n: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    guard(c, "fmi2SetDebugLogging", allowed::ANY_BUT_FATAL, |i| {
        let Some(raw) = slice(categories, n) else { return i.fail("fmi2SetDebugLogging", "categories is NULL") };
        if raw.iter().any(|p| p.is_null()) {
            return i.fail("fmi2SetDebugLogging", "a category name is NULL");
        }
        let names: Vec<&CStr> = raw.iter().map(|&p| unsafe { CStr::from_ptr(p) }).collect();
        i.set_debug_logging(on != 0, &names)
    })
}

#[no_mangle]
pub extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    _tolerance_defined: fmi2Boolean,
    _tolerance: fmi2Real,
    start_time: fmi2Real,
    stop_time_defined: fmi2Boolean,
    stop_time: fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2SetupExperiment", allowed::SETUP_EXPERIMENT, |i| {
        i.setup_experiment(start_time, (stop_time_defined != 0).then_some(stop_time))
    })
}

#[no_mangle]
pub extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2EnterInitializationMode", allowed::ENTER_INIT, |i| {
        i.phase = super::Phase::InitializationMode;
        OK
    })
}

#[no_mangle]
pub extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2ExitInitializationMode", allowed::EXIT_INIT, |i| i.exit_initialization())
}

#[no_mangle]
pub extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2Terminate", allowed::TERMINATE, |i| {
        i.phase = super::Phase::Terminated;
        OK
    })
}

#[no_mangle]
pub extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    guard(c, "fmi2Reset", allowed::ANY_BUT_FATAL, |i| {
        i.reset();
        OK
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2GetReal", allowed::GET, |i| match (slice(vr, n), slice_mut(value, n)) {
        (Some(vr), Some(value)) => i.get_reals(vr, value),
        _ => i.fail("fmi2GetReal", "vr or value is NULL"),
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    guard(c, "fmi2GetInteger", allowed::GET, |i| match (slice(vr, n), slice_mut(value, n)) {
        (Some(vr), Some(value)) => i.get_integers(vr, value),
        _ => i.fail("fmi2GetInteger", "vr or value is NULL"),
    })
}

/// Strings: this interface has none, so any value reference is unknown.
fn no_such_variables(i: &mut Inst, function: &str, vr: *const fmi2ValueReference, n: usize) -> fmi2Status {
    match slice(vr, n) {
        None => i.fail(function, "vr is NULL"),
        Some([]) => OK,
        Some(vrs) => {
            i.fail(function, &format!("unknown value reference {} (this FMU has no variables of that type)", vrs[0]))
        }
    }
}

#[no_mangle]
pub extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    guard(c, "fmi2GetBoolean", allowed::GET, |i| match (slice(vr, n), slice_mut(value, n)) {
        (Some(vr), Some(value)) => i.get_booleans(vr, value),
        _ => i.fail("fmi2GetBoolean", "vr or value is NULL"),
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    _v: *mut fmi2String,
) -> fmi2Status {
    guard(c, "fmi2GetString", allowed::GET, |i| no_such_variables(i, "fmi2GetString", vr, n))
}

#[no_mangle]
pub extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2SetReal", allowed::SET, |i| match (slice(vr, n), slice(value, n)) {
        (Some(vr), Some(value)) => i.set_reals(vr, value),
        _ => i.fail("fmi2SetReal", "vr or value is NULL"),
    })
}

#[no_mangle]
pub extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    _v: *const fmi2Integer,
) -> fmi2Status {
    // The only Integer variable (contact_pairs) is an output: nothing can be set.
    guard(c, "fmi2SetInteger", allowed::SET, |i| match slice(vr, n) {
        None => i.fail("fmi2SetInteger", "vr is NULL"),
        Some([]) => OK,
        Some(vrs) => i.fail("fmi2SetInteger", &format!("value reference {} is not a settable Integer", vrs[0])),
    })
}

#[no_mangle]
pub extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    guard(c, "fmi2SetBoolean", allowed::SET, |i| match (slice(vr, n), slice(value, n)) {
        (Some(vr), Some(value)) => i.set_booleans(vr, value),
        _ => i.fail("fmi2SetBoolean", "vr or value is NULL"),
    })
}

#[no_mangle]
pub extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    _v: *const fmi2String,
) -> fmi2Status {
    guard(c, "fmi2SetString", allowed::SET, |i| no_such_variables(i, "fmi2SetString", vr, n))
}

/// # Safety
/// `state` is NULL (refused) or points to writable storage for one `fmi2FMUstate`, which holds
/// NULL or a state this FMU made.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    guard(c, "fmi2GetFMUstate", allowed::ANY_BUT_FATAL, |i| {
        if state.is_null() {
            return i.fail("fmi2GetFMUstate", "FMUstate pointer is NULL");
        }
        unsafe {
            // A non-NULL *state is a state of ours to overwrite (FMI 2.0 §2.1.8).
            if (*state).is_null() {
                *state = Box::into_raw(Box::new(i.snapshot())) as fmi2FMUstate;
            } else {
                *((*state) as *mut FmuState) = i.snapshot();
            }
        }
        OK
    })
}

#[no_mangle]
pub extern "C" fn fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    guard(c, "fmi2SetFMUstate", allowed::ANY_BUT_FATAL, |i| {
        if state.is_null() {
            return i.fail("fmi2SetFMUstate", "FMUstate is NULL");
        }
        let snapshot = unsafe { &*(state as *const FmuState) };
        // A refused state changes nothing but the phase (Error, from which SetFMUstate with a
        // good state or Reset recovers).
        match i.restore(snapshot) {
            Ok(()) => OK,
            Err(e) => i.fail("fmi2SetFMUstate", &e),
        }
    })
}

/// # Safety
/// `state` is NULL (refused) or points to an `fmi2FMUstate` that holds NULL or a state this FMU
/// made and has not freed.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    guard(c, "fmi2FreeFMUstate", allowed::ANY_BUT_FATAL, |_| {
        if !state.is_null() && unsafe { !(*state).is_null() } {
            unsafe {
                drop(Box::from_raw(*state as *mut FmuState));
                *state = std::ptr::null_mut();
            }
        }
        OK
    })
}

fn serialized(i: &mut Inst, function: &str, state: fmi2FMUstate) -> Result<Vec<u8>, fmi2Status> {
    if state.is_null() {
        return Err(i.fail(function, "FMUstate is NULL"));
    }
    let bytes = i.serialize(unsafe { &*(state as *const FmuState) });
    bytes.map_err(|e| i.fail(function, &e))
}

/// # Safety
/// `state` is a state this FMU made (NULL is refused); `size` is NULL (refused) or writable.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    guard(c, "fmi2SerializedFMUstateSize", allowed::ANY_BUT_FATAL, |i| {
        if size.is_null() {
            return i.fail("fmi2SerializedFMUstateSize", "size is NULL");
        }
        match serialized(i, "fmi2SerializedFMUstateSize", state) {
            Ok(bytes) => {
                unsafe { *size = bytes.len() };
                OK
            }
            Err(status) => status,
        }
    })
}

#[no_mangle]
pub extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    state: fmi2FMUstate,
    out: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    guard(c, "fmi2SerializeFMUstate", allowed::ANY_BUT_FATAL, |i| {
        let bytes = match serialized(i, "fmi2SerializeFMUstate", state) {
            Ok(bytes) => bytes,
            Err(status) => return status,
        };
        if bytes.len() != size {
            return i.fail("fmi2SerializeFMUstate", &format!("size {size} is not the serialized size {}", bytes.len()));
        }
        match slice_mut(out as *mut u8, size) {
            Some(dst) => {
                dst.copy_from_slice(&bytes);
                OK
            }
            None => i.fail("fmi2SerializeFMUstate", "serializedState is NULL"),
        }
    })
}

/// # Safety
/// `bytes` holds `size` readable bytes (NULL with 0 is empty); `state` is NULL (refused) or
/// points to writable storage for one `fmi2FMUstate`.
#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    bytes: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    guard(c, "fmi2DeSerializeFMUstate", allowed::ANY_BUT_FATAL, |i| {
        let (Some(bytes), false) = (slice(bytes as *const u8, size), state.is_null()) else {
            return i.fail("fmi2DeSerializeFMUstate", "serializedState or FMUstate is NULL");
        };
        match i.deserialize(bytes) {
            Ok(snapshot) => {
                unsafe {
                    if !(*state).is_null() {
                        drop(Box::from_raw(*state as *mut FmuState));
                    }
                    *state = Box::into_raw(Box::new(snapshot)) as fmi2FMUstate;
                }
                OK
            }
            Err(e) => i.fail("fmi2DeSerializeFMUstate", &e),
        }
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _unknown: *const fmi2ValueReference,
    _nu: usize,
    _known: *const fmi2ValueReference,
    _nk: usize,
    _dv_known: *const fmi2Real,
    _dv_unknown: *mut fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2GetDirectionalDerivative", allowed::ANY_BUT_FATAL, |i| {
        i.fail("fmi2GetDirectionalDerivative", "not supported (providesDirectionalDerivative=false)")
    })
}

#[no_mangle]
pub extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _n: usize,
    _order: *const fmi2Integer,
    _value: *const fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2SetRealInputDerivatives", allowed::SET_INPUT_DERIVATIVES, |i| {
        i.fail("fmi2SetRealInputDerivatives", "not supported (canInterpolateInputs=false)")
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _n: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    guard(c, "fmi2GetRealOutputDerivatives", allowed::GET_OUTPUT_DERIVATIVES, |i| {
        i.fail("fmi2GetRealOutputDerivatives", "not supported (maxOutputDerivativeOrder=0)")
    })
}

#[no_mangle]
pub extern "C" fn fmi2DoStep(
    c: fmi2Component,
    current: fmi2Real,
    h: fmi2Real,
    _no_set_prior: fmi2Boolean,
) -> fmi2Status {
    guard(c, "fmi2DoStep", allowed::DO_STEP, |i| i.do_step(current, h))
}

#[no_mangle]
pub extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    // Steps are synchronous: there is never a step in progress to cancel.
    guard(c, "fmi2CancelStep", 0, |_| ERROR)
}

// The status kinds, under names that may appear in patterns.
const DO_STEP_STATUS: fmi2StatusKind = fmi2StatusKind_fmi2DoStepStatus;
const PENDING_STATUS: fmi2StatusKind = fmi2StatusKind_fmi2PendingStatus;
const LAST_SUCCESSFUL_TIME: fmi2StatusKind = fmi2StatusKind_fmi2LastSuccessfulTime;
const TERMINATED: fmi2StatusKind = fmi2StatusKind_fmi2Terminated;

/// The name of a status kind, for log lines.
fn kind_name(kind: fmi2StatusKind) -> String {
    match kind {
        DO_STEP_STATUS => "fmi2DoStepStatus".into(),
        PENDING_STATUS => "fmi2PendingStatus".into(),
        LAST_SUCCESSFUL_TIME => "fmi2LastSuccessfulTime".into(),
        TERMINATED => "fmi2Terminated".into(),
        other => format!("status kind {other} (not an fmi2StatusKind)"),
    }
}

/// The status queries (FMI 2.0.4 §4.2.3). Steps here are synchronous: fmi2DoStep never returns
/// fmi2Pending, so fmi2DoStepStatus and fmi2PendingStatus have no answer; the answerable ones
/// are fmi2LastSuccessfulTime (Real) and fmi2Terminated (Boolean). A kind without an answer
/// for the queried type is fmi2Discard with a log line, and the instance stays as it was.
fn status_query<T>(
    c: fmi2Component,
    function: &str,
    kind: fmi2StatusKind,
    value: *mut T,
    answer: impl FnOnce(&Inst, fmi2StatusKind) -> Result<T, String>,
) -> fmi2Status {
    guard(c, function, allowed::GET_STATUS, |i| {
        if value.is_null() {
            return i.fail(function, "value is NULL");
        }
        match answer(i, kind) {
            Ok(v) => {
                unsafe { *value = v };
                OK
            }
            Err(why) => i.discard(function, &format!("{} cannot be given: {why}", kind_name(kind))),
        }
    })
}

const SYNCHRONOUS: &str = "steps are synchronous (fmi2DoStep never returns fmi2Pending)";

fn wrong_type(kind: fmi2StatusKind, type_name: &str) -> String {
    match kind {
        DO_STEP_STATUS | PENDING_STATUS => SYNCHRONOUS.into(),
        LAST_SUCCESSFUL_TIME => "it is a Real status (fmi2GetRealStatus)".into(),
        TERMINATED => "it is a Boolean status (fmi2GetBooleanStatus)".into(),
        _ => format!("unknown kind for the {type_name} status"),
    }
}

#[no_mangle]
pub extern "C" fn fmi2GetStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Status) -> fmi2Status {
    status_query(c, "fmi2GetStatus", kind, value, |_, kind| Err(wrong_type(kind, "fmi2Status")))
}

#[no_mangle]
pub extern "C" fn fmi2GetRealStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Real) -> fmi2Status {
    status_query(c, "fmi2GetRealStatus", kind, value, |i, kind| match kind {
        // The end of the last completed communication step: the instance's time.
        LAST_SUCCESSFUL_TIME => Ok(i.time),
        _ => Err(wrong_type(kind, "Real")),
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetIntegerStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Integer) -> fmi2Status {
    // FMI 2.0 defines no Integer status.
    status_query(c, "fmi2GetIntegerStatus", kind, value, |_, kind| Err(wrong_type(kind, "Integer")))
}

#[no_mangle]
pub extern "C" fn fmi2GetBooleanStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Boolean) -> fmi2Status {
    status_query(c, "fmi2GetBooleanStatus", kind, value, |_, kind| match kind {
        // "fmi2True if the slave wants to terminate the simulation": this one never asks to; it
        // refuses a step with fmi2Error, never with fmi2Discard.
        TERMINATED => Ok(fmi2False as fmi2Boolean),
        _ => Err(wrong_type(kind, "Boolean")),
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetStringStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2String) -> fmi2Status {
    status_query(c, "fmi2GetStringStatus", kind, value, |_, kind| Err(wrong_type(kind, "String")))
}
