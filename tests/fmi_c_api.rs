//! The FMI 2.0 C interface, called in-process exactly as a master calls it: the state machine,
//! argument checks with their status and log line, FMU state get/set/serialize, and isolation
//! of instances. Log lines reach a real variadic logger (fmi-sys's C handler formats "%s").

use fmi_sys::fmi2::*;
use gearfmu::dynamics::lumped::LumpedMesh;
use gearfmu::fmi2::exports::*;
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::interface::value_reference;
use gearfmu::model_file::{ModelFile, ModelKind, FILE_NAME};
use std::ffi::{CStr, CString};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

/// Log lines per instance name, captured through the `log` facade that fmi-sys's logger uses.
static LINES: Mutex<Vec<(String, String)>> = Mutex::new(Vec::new());
struct Capture;
impl log::Log for Capture {
    fn enabled(&self, _: &log::Metadata) -> bool {
        true
    }
    fn log(&self, r: &log::Record) {
        LINES.lock().unwrap().push((r.target().to_string(), r.args().to_string()));
    }
    fn flush(&self) {}
}

fn logs(instance: &str) -> Vec<String> {
    LINES.lock().unwrap().iter().filter(|(n, _)| n == instance).map(|(_, m)| m.clone()).collect()
}

fn assert_logged(instance: &str, needle: &str) {
    let lines = logs(instance);
    assert!(lines.iter().any(|l| l.contains(needle)), "no log line with {needle:?} for {instance}: {lines:?}");
}

/// A resources folder with the spur pair's model data; returns (folder, GUID).
fn resources() -> &'static (PathBuf, String) {
    static R: OnceLock<(PathBuf, String)> = OnceLock::new();
    R.get_or_init(|| {
        log::set_logger(&Capture).ok();
        log::set_max_level(log::LevelFilter::Trace);
        let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
        let pair = GearPair::from_spec(&PairSpec::load(&spec).unwrap()).unwrap();
        let model = ModelKind::Lumped(LumpedMesh::from_pair(&pair).unwrap());
        let guid = ModelFile::compute_guid(gearfmu::interface::VARIABLES_TOML, &pair.name, &model);
        let dir = std::env::temp_dir().join(format!("gearfmu-c-api-{}", std::process::id())).join("res ources");
        std::fs::create_dir_all(&dir).unwrap();
        let file = ModelFile { guid: guid.clone(), pair_name: pair.name, model };
        std::fs::write(dir.join(FILE_NAME), file.to_bytes()).unwrap();
        (dir, guid)
    })
}

fn uri(dir: &Path) -> String {
    format!("file://{}", dir.display().to_string().replace(' ', "%20"))
}

fn callbacks() -> fmi2CallbackFunctions {
    fmi2CallbackFunctions {
        logger: Some(fmi_sys::fmi2::logger::callback_logger_handler),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::null_mut(),
    }
}

fn instantiate_at(name: &str, dir: &Path, guid: &str) -> fmi2Component {
    let (name, guid, uri) = (CString::new(name).unwrap(), CString::new(guid).unwrap(), CString::new(uri(dir)).unwrap());
    let cb = callbacks();
    fmi2Instantiate(name.as_ptr(), fmi2Type_fmi2CoSimulation, guid.as_ptr(), uri.as_ptr(), &cb, 0, 1)
}

fn instantiate(name: &str) -> fmi2Component {
    let (dir, guid) = resources();
    let c = instantiate_at(name, dir, guid);
    assert!(!c.is_null(), "instantiate failed: {:?}", logs(name));
    c
}

fn vr(name: &str) -> u32 {
    value_reference(name).unwrap()
}

const OK: fmi2Status = fmi2Status_fmi2OK;
const ERR: fmi2Status = fmi2Status_fmi2Error;

fn initialized(name: &str, stop_time: Option<f64>) -> fmi2Component {
    let c = instantiate(name);
    assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, stop_time.is_some() as i32, stop_time.unwrap_or(0.0)), OK);
    assert_eq!(fmi2EnterInitializationMode(c), OK);
    assert_eq!(fmi2ExitInitializationMode(c), OK);
    c
}

fn set(c: fmi2Component, name: &str, value: f64) -> fmi2Status {
    fmi2SetReal(c, &vr(name), 1, &value)
}

fn get(c: fmi2Component, name: &str) -> f64 {
    let mut v = f64::NAN;
    assert_eq!(fmi2GetReal(c, &vr(name), 1, &mut v), OK);
    v
}

const OUTPUTS: [&str; 8] = ["phi_1", "phi_2", "w_1", "w_2", "dte", "dte_angle", "mesh_force", "mesh_stiffness"];

/// Steps n times with 185 N·m on gear 1 and a viscous load on gear 2; returns the outputs.
fn run(c: fmi2Component, t0: f64, n: usize, h: f64) -> Vec<[f64; 8]> {
    let mut out = Vec::new();
    for k in 0..n {
        assert_eq!(set(c, "tau_1", 185.0), OK);
        assert_eq!(set(c, "tau_2", -20.0 * get(c, "w_2")), OK);
        assert_eq!(fmi2DoStep(c, t0 + k as f64 * h, h, 1), OK);
        out.push(OUTPUTS.map(|o| get(c, o)));
    }
    out
}

#[test]
fn version_and_types_platform() {
    assert_eq!(unsafe { CStr::from_ptr(fmi2GetVersion()) }.to_str().unwrap(), "2.0");
    assert_eq!(unsafe { CStr::from_ptr(fmi2GetTypesPlatform()) }.to_str().unwrap(), "default");
}

#[test]
fn calls_in_the_wrong_phase_are_refused_and_logged() {
    let c = instantiate("wrong-phase");
    assert_eq!(fmi2DoStep(c, 0.0, 1e-4, 1), ERR);
    assert_logged("wrong-phase", "fmi2DoStep: not allowed in phase Instantiated");
    // After an error only Reset, SetFMUstate, Get* and FreeInstance are allowed.
    assert_eq!(fmi2EnterInitializationMode(c), ERR);
    assert_logged("wrong-phase", "fmi2EnterInitializationMode: not allowed in phase Error");
    assert_eq!(fmi2Reset(c), OK);
    assert_eq!(fmi2EnterInitializationMode(c), OK);
    assert_eq!(fmi2ExitInitializationMode(c), OK);
    assert_eq!(fmi2DoStep(c, 0.0, 1e-4, 1), OK);
    assert_eq!(fmi2Terminate(c), OK);
    assert_eq!(fmi2DoStep(c, 1e-4, 1e-4, 1), ERR);
    assert_logged("wrong-phase", "not allowed in phase Terminated");
    fmi2FreeInstance(c);
}

#[test]
fn bad_arguments_are_refused_with_a_log_line() {
    let c = initialized("bad-args", Some(1e-3));
    let mut v = 0.0;
    assert_eq!(fmi2GetReal(c, &999, 1, &mut v), ERR);
    assert_logged("bad-args", "unknown value reference 999");
    assert_eq!(fmi2Reset(c), OK);
    let c = {
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 1, 1e-3), OK);
        assert_eq!(fmi2EnterInitializationMode(c), OK);
        assert_eq!(fmi2ExitInitializationMode(c), OK);
        c
    };
    // NULL arrays with n > 0; n = 0 is a valid empty call.
    assert_eq!(fmi2GetReal(c, std::ptr::null(), 0, std::ptr::null_mut()), OK);
    assert_eq!(fmi2GetReal(c, &vr("w_1"), 1, std::ptr::null_mut()), ERR);
    assert_logged("bad-args", "fmi2GetReal: vr or value is NULL");
    let fresh = |c| {
        assert_eq!(fmi2Reset(c), OK);
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 1, 1e-3), OK);
        assert_eq!(fmi2EnterInitializationMode(c), OK);
        assert_eq!(fmi2ExitInitializationMode(c), OK);
    };
    fresh(c);
    assert_eq!(fmi2DoStep(c, 0.5, 1e-4, 1), ERR);
    assert_logged("bad-args", "currentCommunicationPoint 0.5 is not the FMU's time 0");
    fresh(c);
    assert_eq!(fmi2DoStep(c, 0.0, 0.0, 1), ERR);
    assert_logged("bad-args", "communicationStepSize must be finite and > 0, got 0");
    fresh(c);
    assert_eq!(fmi2DoStep(c, 0.0, -1e-4, 1), ERR);
    assert_logged("bad-args", "communicationStepSize must be finite and > 0, got -0.0001");
    fresh(c);
    assert_eq!(fmi2DoStep(c, 0.0, 2e-3, 1), ERR);
    assert_logged("bad-args", "goes past stopTime 0.001");
    fresh(c);
    assert_eq!(set(c, "max_step", 1e-6), ERR);
    assert_logged("bad-args", "max_step is a fixed parameter");
    fresh(c);
    assert_eq!(set(c, "w_1", 3.0), ERR);
    assert_logged("bad-args", "w_1 is an output and cannot be set");
    fresh(c);
    let mut b = 0;
    assert_eq!(fmi2GetBoolean(c, &0, 1, &mut b), ERR);
    assert_logged("bad-args", "fmi2GetBoolean: unknown value reference 0");
    fresh(c);
    let category = CString::new("logNoSuchThing").unwrap();
    assert_eq!(fmi2SetDebugLogging(c, 1, 1, &category.as_ptr()), ERR);
    assert_logged("bad-args", "unknown log category \"logNoSuchThing\"");
    fresh(c);
    let mut pairs = -1;
    assert_eq!(fmi2GetInteger(c, &vr("contact_pairs"), 1, &mut pairs), OK);
    assert_eq!(pairs, 0, "no torque yet: the flanks just touch");
    fmi2FreeInstance(c);
    // A NULL component is refused without a crash.
    assert_eq!(fmi2DoStep(std::ptr::null_mut(), 0.0, 1e-4, 1), ERR);
}

#[test]
fn parameters_before_init_are_applied() {
    let c = instantiate("params");
    assert_eq!(set(c, "w_1_start", 20.0), OK);
    assert_eq!(set(c, "w_2_start", 20.0 * 21.0 / 31.0), OK);
    assert_eq!(set(c, "max_step", -1.0), ERR);
    assert_logged("params", "max_step must be > 0, got -1");
    assert_eq!(fmi2Reset(c), OK);
    assert_eq!(set(c, "w_1_start", 20.0), OK);
    assert_eq!(fmi2EnterInitializationMode(c), OK);
    assert_eq!(fmi2ExitInitializationMode(c), OK);
    assert_eq!(get(c, "w_1"), 20.0);
    fmi2FreeInstance(c);
}

/// FMI 2.0 after an error: the master restores a state saved earlier, and the run goes on as if
/// the bad input had never come. Checked bit for bit against an uninterrupted instance.
#[test]
fn nan_input_is_refused_and_the_run_continues_from_a_saved_state() {
    let reference = initialized("nan-reference", None);
    let expected = run(reference, 0.0, 40, 1e-4);
    let c = initialized("nan", None);
    let before = run(c, 0.0, 20, 1e-4);
    assert_eq!(before[..], expected[..20]);
    let mut state: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(fmi2GetFMUstate(c, &mut state), OK);
    assert_eq!(set(c, "tau_1", f64::NAN), ERR);
    assert_logged("nan", "value reference 0: value NaN is not finite; input refused");
    assert_eq!(set(c, "tau_1", f64::INFINITY), ERR);
    assert_eq!(fmi2DoStep(c, 20.0 * 1e-4, 1e-4, 1), ERR, "in the Error phase nothing steps");
    assert_eq!(fmi2SetFMUstate(c, state), OK);
    let after = run(c, 20.0 * 1e-4, 20, 1e-4);
    assert_eq!(after[..], expected[20..], "the run after SetFMUstate must equal the uninterrupted run");
    assert_eq!(fmi2FreeFMUstate(c, &mut state), OK);
    assert!(state.is_null());
    fmi2FreeInstance(c);
    fmi2FreeInstance(reference);
}

/// An infinite input on a healthy instance (not only after a NaN) is refused with its log line and
/// changes nothing: after fmi2Reset the run reproduces an untouched instance bit for bit.
#[test]
fn infinite_input_on_a_healthy_instance_is_refused_and_logged() {
    let reference = initialized("inf-reference", None);
    let expected = run(reference, 0.0, 10, 1e-4);
    for (name, input, value, text) in [
        ("inf-plus", "tau_1", f64::INFINITY, "value inf is not finite; input refused"),
        ("inf-minus", "tau_2", f64::NEG_INFINITY, "value -inf is not finite; input refused"),
    ] {
        let c = initialized(name, None);
        assert_eq!(run(c, 0.0, 5, 1e-4)[..], expected[..5]);
        assert_eq!(set(c, input, value), ERR);
        assert_logged(name, &format!("value reference {}: {text}", vr(input)));
        assert_eq!(fmi2DoStep(c, 5e-4, 1e-4, 1), ERR, "in the Error phase nothing steps");
        assert_eq!(fmi2Reset(c), OK);
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), OK);
        assert_eq!(fmi2EnterInitializationMode(c), OK);
        assert_eq!(fmi2ExitInitializationMode(c), OK);
        assert_eq!(run(c, 0.0, 10, 1e-4)[..], expected[..], "{name}: the run after fmi2Reset");
        fmi2FreeInstance(c);
    }
    fmi2FreeInstance(reference);
}

/// fmi2SetDebugLogging (FMI 2.0 §2.1.5): only the categories switched on reach the logger, and
/// with logging off nothing does — except errors, which are always reported with their reason.
#[test]
fn log_categories_select_what_reaches_the_logger() {
    let events = CString::new("logEvents").unwrap();
    let errors = CString::new("logStatusError").unwrap();
    let initialize = |c| {
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), OK);
        assert_eq!(fmi2EnterInitializationMode(c), OK);
        assert_eq!(fmi2ExitInitializationMode(c), OK);
    };
    let event_logged = |name: &str| logs(name).iter().any(|l| l.contains("initialized at t = 0"));
    // All categories (loggingOn at instantiate): the initialization event arrives.
    let c = instantiate("log-all");
    initialize(c);
    assert!(event_logged("log-all"), "{:?}", logs("log-all"));
    fmi2FreeInstance(c);
    // logEvents alone: still there.
    let c = instantiate("log-events");
    assert_eq!(fmi2SetDebugLogging(c, 1, 1, &events.as_ptr()), OK);
    initialize(c);
    assert!(event_logged("log-events"), "{:?}", logs("log-events"));
    fmi2FreeInstance(c);
    // logStatusError alone: the event is suppressed, an error is not.
    let c = instantiate("log-errors");
    assert_eq!(fmi2SetDebugLogging(c, 1, 1, &errors.as_ptr()), OK);
    initialize(c);
    assert!(!event_logged("log-errors"), "{:?}", logs("log-errors"));
    assert_eq!(set(c, "tau_1", f64::NAN), ERR);
    assert_logged("log-errors", "value NaN is not finite");
    fmi2FreeInstance(c);
    // Logging off for every category: silent, but the error and its reason still arrive.
    let c = instantiate("log-off");
    assert_eq!(fmi2SetDebugLogging(c, 0, 0, std::ptr::null()), OK);
    initialize(c);
    assert!(logs("log-off").is_empty(), "{:?}", logs("log-off"));
    assert_eq!(set(c, "tau_1", f64::NAN), ERR);
    assert_logged("log-off", "value NaN is not finite");
    fmi2FreeInstance(c);
}

#[test]
fn fmu_state_get_set_and_serialize_reproduce_outputs_bit_for_bit() {
    let c = initialized("state", None);
    run(c, 0.0, 30, 1e-4);
    let mut state: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(fmi2GetFMUstate(c, &mut state), OK);
    let first = run(c, 30e-4, 30, 1e-4);
    assert_eq!(fmi2SetFMUstate(c, state), OK);
    let again = run(c, 30e-4, 30, 1e-4);
    assert_eq!(first, again);

    let mut size = 0usize;
    assert_eq!(fmi2SerializedFMUstateSize(c, state, &mut size), OK);
    let mut bytes = vec![0u8; size];
    assert_eq!(fmi2SerializeFMUstate(c, state, bytes.as_mut_ptr() as *mut fmi2Byte, size), OK);
    let other = initialized("state-2", None);
    let mut restored: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(fmi2DeSerializeFMUstate(other, bytes.as_ptr() as *const fmi2Byte, size, &mut restored), OK);
    assert_eq!(fmi2SetFMUstate(other, restored), OK);
    assert_eq!(run(other, 30e-4, 30, 1e-4), first, "a deserialized state in another instance continues identically");

    // A damaged byte stream is refused with a message, never a crash.
    bytes[0] ^= 0xff;
    let mut bad: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(fmi2DeSerializeFMUstate(other, bytes.as_ptr() as *const fmi2Byte, size, &mut bad), ERR);
    assert_logged("state-2", "serialized FMU state has a wrong header");
    for s in [&mut state, &mut restored] {
        assert_eq!(fmi2FreeFMUstate(c, s), OK);
    }
    fmi2FreeInstance(c);
    fmi2FreeInstance(other);
}

#[test]
fn two_instances_share_nothing() {
    let solo = initialized("solo", None);
    let solo_out = run(solo, 0.0, 25, 1e-4);
    let a = initialized("a", None);
    let b = initialized("b", None);
    let mut a_out = Vec::new();
    for k in 0..25 {
        let t = k as f64 * 1e-4;
        assert_eq!(set(b, "tau_1", -50.0), OK);
        assert_eq!(fmi2DoStep(b, t, 1e-4, 1), OK);
        a_out.extend(run(a, t, 1, 1e-4));
    }
    assert_eq!(a_out, solo_out, "instance a is unaffected by instance b");
    assert!(get(b, "w_1") < 0.0 && get(a, "w_1") > 0.0);
    for c in [solo, a, b] {
        fmi2FreeInstance(c);
    }
}

#[test]
fn instantiate_refuses_a_wrong_guid_bad_uri_and_damaged_model_data() {
    let (dir, guid) = resources();
    assert!(instantiate_at("guid", dir, "{00000000-0000-0000-0000-000000000000}").is_null());
    assert_logged("guid", "does not match the FMU's model data");

    let name = CString::new("uri").unwrap();
    let (g, bad_uri) = (CString::new(guid.as_str()).unwrap(), CString::new("http://example.org/resources").unwrap());
    let cb = callbacks();
    assert!(
        fmi2Instantiate(name.as_ptr(), fmi2Type_fmi2CoSimulation, g.as_ptr(), bad_uri.as_ptr(), &cb, 0, 0).is_null()
    );
    assert_logged("uri", "fmuResourceLocation must be a local file URI");
    assert!(
        fmi2Instantiate(name.as_ptr(), fmi2Type_fmi2ModelExchange, g.as_ptr(), bad_uri.as_ptr(), &cb, 0, 0).is_null()
    );
    assert_logged("uri", "supports only fmi2CoSimulation");

    let good = std::fs::read(dir.join(FILE_NAME)).unwrap();
    let damaged_dir = dir.with_file_name("damaged");
    std::fs::create_dir_all(&damaged_dir).unwrap();
    let mut corrupted = good.clone();
    let last = corrupted.len() - 1;
    corrupted[last] ^= 0x55;
    std::fs::write(damaged_dir.join(FILE_NAME), &corrupted).unwrap();
    assert!(instantiate_at("corrupt", &damaged_dir, guid).is_null());
    assert_logged("corrupt", "corrupted (checksum mismatch)");
    let mut wrong_version = good.clone();
    wrong_version[8] = 99;
    std::fs::write(damaged_dir.join(FILE_NAME), &wrong_version).unwrap();
    assert!(instantiate_at("version", &damaged_dir, guid).is_null());
    assert_logged("version", "format version 99");
    std::fs::write(damaged_dir.join(FILE_NAME), b"not a model").unwrap();
    assert!(instantiate_at("magic", &damaged_dir, guid).is_null());
    assert_logged("magic", "bad magic");
    std::fs::remove_file(damaged_dir.join(FILE_NAME)).unwrap();
    assert!(instantiate_at("missing", &damaged_dir, guid).is_null());
    assert_logged("missing", "cannot read");
}
