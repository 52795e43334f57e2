//! Fuzzing (issue 13, item 3) with proptest: the spec parser, the model-file decoder, the
//! serialized-FMU-state decoder, and random FMI call sequences checked against an independent
//! model of the FMI 2.0 Co-Simulation state machine. Every target asserts "no panic, and a clear
//! Err where the input is bad"; the call sequences also assert every status and phase. The three
//! FMU targets run on the lumped FMU and again on the PMOR-Hertz one (`*_pmor_hertz`).
//!
//! Short run (CI): `cargo test --release --test fuzz` (spec 2000, lumped 500 each, PMOR-Hertz
//! 100–300 cases; about 6 s).
//! Long run: `GEARFMU_FUZZ_SECONDS=600 cargo test --release --test fuzz -- --test-threads=1 --nocapture`
//! repeats batches of `PROPTEST_CASES` (default below) per target, each with a fresh random
//! seed, until the budget is spent, and prints cases and cases per second per target.

use fmi_sys::fmi2::*;
use gearfmu::dynamics::lumped::LumpedMesh;
use gearfmu::dynamics::pmor::PmorState;
use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::fmi2::exports::*;
use gearfmu::fmi2::instance::{deserialize_snapshot, serialize_snapshot, time_tolerance, Instance, Snapshot};
use gearfmu::fmi2::Phase;
use gearfmu::fmu::gear_pair::{GearPairFmu, GearPairState, LUMPED_DEFAULT_MAX_STEP_S};
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::interface::{value_reference, variables};
use gearfmu::model_file::{ModelFile, ModelKind, FILE_NAME};
use gearfmu::rom::dynamic_reductor::{build_dynamic_model, DynamicBuildOptions};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRunner};
use sha2::{Digest, Sha256};
use std::collections::HashMap;
use std::ffi::CString;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

// ---------------------------------------------------------------------------------------------
// Running: a short batch by default, batches until GEARFMU_FUZZ_SECONDS is spent for a long run.

/// Cases per batch: PROPTEST_CASES if set, else `short`.
fn cases(short: u32) -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(short)
}

/// Runs `test` on `strategy`: one batch, or batches until `GEARFMU_FUZZ_SECONDS`; prints the
/// number of cases and the rate; fails with the (shrunk) input on the first failure.
fn fuzz<S: Strategy>(name: &str, short: u32, strategy: S, test: impl Fn(S::Value) -> Result<(), TestCaseError>)
where
    S::Value: std::fmt::Debug,
{
    let budget = std::env::var("GEARFMU_FUZZ_SECONDS").ok().and_then(|s| s.parse::<f64>().ok());
    let per_batch = cases(short);
    let start = Instant::now();
    let mut done = 0u64;
    loop {
        let mut runner = TestRunner::new(Config { cases: per_batch, failure_persistence: None, ..Config::default() });
        if let Err(e) = runner.run(&strategy, &test) {
            panic!("fuzz target {name} failed after {done} cases: {e}");
        }
        done += per_batch as u64;
        match budget {
            Some(seconds) if start.elapsed().as_secs_f64() < seconds => continue,
            _ => break,
        }
    }
    let t = start.elapsed().as_secs_f64();
    eprintln!(
        "fuzz {name}: {done} cases in {t:.1} s = {:.0} cases/s, no finding ({})",
        done as f64 / t,
        stats_of(name)
    );
}

/// Outcome counts per target ("target/outcome" → count), printed after each run so a run shows
/// which paths it reached (accepted and refused inputs, statuses).
static STATS: Mutex<Option<HashMap<String, u64>>> = Mutex::new(None);

fn stat(target: &str, outcome: &str) {
    *STATS.lock().unwrap().get_or_insert_with(HashMap::new).entry(format!("{target}/{outcome}")).or_default() += 1;
}

fn stats_of(target: &str) -> String {
    let stats = STATS.lock().unwrap();
    let mut v: Vec<(String, u64)> = stats
        .iter()
        .flatten()
        .filter_map(|(k, n)| k.strip_prefix(&format!("{target}/")).map(|o| (o.to_string(), *n)))
        .collect();
    v.sort();
    v.iter().map(|(o, n)| format!("{o} {n}")).collect::<Vec<_>>().join(", ")
}

/// Runs `f`, turning a panic into a test failure that prints `input`.
fn no_panic<T>(what: &str, input: &dyn std::fmt::Debug, f: impl FnOnce() -> T) -> Result<T, TestCaseError> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|p| {
        let msg = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        TestCaseError::fail(format!("{what} panicked ({msg}) on input {input:?}"))
    })
}

// ---------------------------------------------------------------------------------------------
// The FMU in-process, as tests/fmi_c_api.rs does it.

/// Error log lines per instance name, captured through the `log` facade fmi-sys's logger uses.
static LINES: Mutex<Option<HashMap<String, Vec<String>>>> = Mutex::new(None);
struct Capture;
impl log::Log for Capture {
    fn enabled(&self, _: &log::Metadata) -> bool {
        true
    }
    fn log(&self, r: &log::Record) {
        let mut lines = LINES.lock().unwrap();
        lines.get_or_insert_with(HashMap::new).entry(r.target().to_string()).or_default().push(r.args().to_string());
    }
    fn flush(&self) {}
}

/// Takes (and forgets) the log lines of an instance.
fn take_logs(instance: &str) -> Vec<String> {
    LINES.lock().unwrap().as_mut().and_then(|m| m.remove(instance)).unwrap_or_default()
}

/// A unique instance name, so concurrent targets never mix their log lines.
fn unique_name(prefix: &str) -> String {
    static N: AtomicU64 = AtomicU64::new(0);
    format!("{prefix}-{}", N.fetch_add(1, Ordering::Relaxed))
}

struct Resources {
    dir: PathBuf,
    guid: String,
    /// The model file's bytes.
    model_bin: Vec<u8>,
    /// The max_step an instance starts with.
    default_max_step_s: f64,
    /// Whether reading mesh_force or mesh_stiffness may be refused: PMOR-Hertz evaluates the
    /// contact for them, and a state outside the Hertz law's range is an error, not a number.
    contact_outputs_can_fail: bool,
    /// An instance held for the whole run, as a master holding one instance while it creates
    /// others: the targets' instances then share its model data (`fmu::shared_model`)
    /// instead of decoding the file each case. The decoder has its own target.
    _anchor: usize,
}

/// A resources folder holding `model` for `pair`, under the process's temporary directory.
fn write_resources(
    folder: &str,
    pair: &GearPair,
    model: ModelKind,
    default_max_step_s: f64,
    contact_outputs_can_fail: bool,
) -> Resources {
    let guid = ModelFile::compute_guid(gearfmu::interface::VARIABLES_TOML, &pair.name, &model);
    let dir = std::env::temp_dir().join(format!("gearfmu-fuzz-{}", std::process::id())).join(folder);
    std::fs::create_dir_all(&dir).unwrap();
    let model_bin = ModelFile { guid: guid.clone(), pair_name: pair.name.clone(), model }.to_bytes();
    std::fs::write(dir.join(FILE_NAME), &model_bin).unwrap();
    let anchor = instantiate_at(&unique_name(&format!("{folder}-anchor")), &dir, &guid);
    assert!(!anchor.is_null(), "the anchor instance of {folder} failed");
    Resources { dir, guid, model_bin, default_max_step_s, contact_outputs_can_fail, _anchor: anchor as usize }
}

fn kurokawa_spur() -> GearPair {
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
    GearPair::from_spec(&PairSpec::load(&spec).unwrap()).unwrap()
}

/// The lumped spur FMU's resources folder (model file written with the crate's own API).
fn resources() -> &'static Resources {
    static R: OnceLock<Resources> = OnceLock::new();
    R.get_or_init(|| {
        log::set_logger(&Capture).ok();
        log::set_max_level(log::LevelFilter::Trace);
        let pair = kurokawa_spur();
        let model = ModelKind::Lumped(LumpedMesh::from_pair(&pair).unwrap());
        write_resources("resources", &pair, model, LUMPED_DEFAULT_MAX_STEP_S, false)
    })
}

/// The PMOR-Hertz spur FMU's resources folder: the default mesh with a small basis (6 modes, 8
/// angular samples), so that a call sequence's steps stay cheap. The FMI layer and the model's
/// checks are the same code as the default build's; only the sizes differ.
fn pmor_resources() -> &'static Resources {
    static R: OnceLock<Resources> = OnceLock::new();
    R.get_or_init(|| {
        resources();
        let pair = kurokawa_spur();
        let options = DynamicBuildOptions { modes: 6, angles: 8, ..Default::default() };
        let (model, _) = build_dynamic_model(&pair, &MeshSpec::default(), &options, |_| {}).unwrap();
        let max_step = model.max_step_s;
        write_resources("resources-pmor", &pair, ModelKind::PmorHertz(Box::new(model)), max_step, true)
    })
}

/// The lumped mesh law's largest tangent stiffness (a scan of its tables, done once).
/// The lumped law's stiffest mesh, frictionless and with friction's share (as the FMU keeps it).
static STIFFEST: OnceLock<[f64; 2]> = OnceLock::new();

/// The lumped mesh inside the resources' model file.
fn lumped_mesh() -> &'static LumpedMesh {
    static M: OnceLock<LumpedMesh> = OnceLock::new();
    M.get_or_init(|| match ModelFile::from_bytes(&resources().model_bin).unwrap().model {
        ModelKind::Lumped(mesh) => mesh,
        ModelKind::PmorHertz(_) | ModelKind::Element(_) => unreachable!("the fuzz FMU is lumped"),
    })
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
    let uri = format!("file://{}", dir.display().to_string().replace(' ', "%20"));
    let (name, guid, uri) = (CString::new(name).unwrap(), CString::new(guid).unwrap(), CString::new(uri).unwrap());
    let cb = callbacks();
    // Logging off: errors and discards are logged anyway, which is what the targets look at.
    unsafe { fmi2Instantiate(name.as_ptr(), fmi2Type_fmi2CoSimulation, guid.as_ptr(), uri.as_ptr(), &cb, 0, 0) }
}

fn instantiate(name: &str) -> fmi2Component {
    instantiate_from(name, resources())
}

fn instantiate_from(name: &str, r: &Resources) -> fmi2Component {
    let c = instantiate_at(name, &r.dir, &r.guid);
    assert!(!c.is_null(), "instantiate failed: {:?}", take_logs(name));
    c
}

/// The instance's phase, read through the component pointer (white-box: the C API has no query).
fn phase_of(c: fmi2Component) -> Phase {
    unsafe { &*(c as *const Instance<gearfmu::FmuModel>) }.phase
}

const OK: fmi2Status = fmi2Status_fmi2OK;
const DISCARD: fmi2Status = fmi2Status_fmi2Discard;
const ERR: fmi2Status = fmi2Status_fmi2Error;

fn vr(name: &str) -> u32 {
    value_reference(name).unwrap()
}

/// An instance of `r` initialized and stepped 20 times under drive and a viscous load, its FMU
/// state serialized: the real bytes the state targets mutate.
fn serialized_state_of(r: &Resources) -> Vec<u8> {
    let name = unique_name("state-source");
    let c = instantiate_from(&name, r);
    assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), OK);
    assert_eq!(fmi2EnterInitializationMode(c), OK);
    assert_eq!(fmi2ExitInitializationMode(c), OK);
    let h = 1e-4;
    for k in 0..20 {
        let mut w2 = 0.0;
        assert_eq!(fmi2GetReal(c, &vr("w_2"), 1, &mut w2), OK);
        assert_eq!(fmi2SetReal(c, [vr("tau_1"), vr("tau_2")].as_ptr(), 2, [185.0, -20.0 * w2].as_ptr()), OK);
        assert_eq!(fmi2DoStep(c, k as f64 * h, h, 1), OK, "{:?}", take_logs(&name));
    }
    let mut s: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(unsafe { fmi2GetFMUstate(c, &mut s) }, OK);
    let mut size = 0;
    assert_eq!(unsafe { fmi2SerializedFMUstateSize(c, s, &mut size) }, OK);
    let mut bytes = vec![0u8; size];
    assert_eq!(fmi2SerializeFMUstate(c, s, bytes.as_mut_ptr() as *mut fmi2Byte, size), OK);
    assert_eq!(unsafe { fmi2FreeFMUstate(c, &mut s) }, OK);
    fmi2FreeInstance(c);
    bytes
}

// ---------------------------------------------------------------------------------------------
// Byte and text mutations.

#[derive(Debug, Clone)]
enum ByteEdit {
    /// XOR the byte at (index mod len) with a non-zero mask.
    Flip(usize, u8),
    /// Set the byte at (index mod len).
    Set(usize, u8),
    /// Delete `n` bytes at (index mod len).
    Delete(usize, usize),
    /// Insert bytes at (index mod (len + 1)).
    Insert(usize, Vec<u8>),
    /// Cut to (index mod (len + 1)) bytes.
    Truncate(usize),
    /// Append bytes.
    Extend(Vec<u8>),
}

fn byte_edit() -> impl Strategy<Value = ByteEdit> {
    prop_oneof![
        4 => (any::<usize>(), 1u8..=255).prop_map(|(i, m)| ByteEdit::Flip(i, m)),
        2 => (any::<usize>(), prop_oneof![Just(0u8), Just(0xff), Just(0x80), Just(0x7f), any::<u8>()])
            .prop_map(|(i, b)| ByteEdit::Set(i, b)),
        1 => (any::<usize>(), 1usize..16).prop_map(|(i, n)| ByteEdit::Delete(i, n)),
        1 => (any::<usize>(), proptest::collection::vec(any::<u8>(), 1..16)).prop_map(|(i, b)| ByteEdit::Insert(i, b)),
        1 => any::<usize>().prop_map(ByteEdit::Truncate),
        1 => proptest::collection::vec(any::<u8>(), 1..64).prop_map(ByteEdit::Extend),
    ]
}

fn apply_bytes(bytes: &mut Vec<u8>, edits: &[ByteEdit]) {
    for e in edits {
        let len = bytes.len();
        match e {
            ByteEdit::Flip(i, m) if len > 0 => bytes[i % len] ^= m,
            ByteEdit::Set(i, b) if len > 0 => bytes[i % len] = *b,
            ByteEdit::Delete(i, n) if len > 0 => {
                let at = i % len;
                bytes.drain(at..(at + n).min(len));
            }
            ByteEdit::Insert(i, b) => {
                let at = i % (len + 1);
                bytes.splice(at..at, b.iter().copied());
            }
            ByteEdit::Truncate(i) => bytes.truncate(i % (len + 1)),
            ByteEdit::Extend(b) => bytes.extend_from_slice(b),
            _ => {}
        }
    }
}

/// Hostile numbers: NaN, ±inf, zero, negative, huge, tiny, subnormal, and ordinary ones.
fn hostile_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(0.0),
        Just(-0.0),
        Just(-1.0),
        Just(1e300),
        Just(-1e300),
        Just(f64::MAX),
        Just(1e-300),
        Just(5e-324),
        any::<f64>(),
        -1e3..1e3f64,
        0.0..100.0f64,
    ]
}

#[derive(Debug, Clone)]
enum TextEdit {
    /// Byte-level edit of the text (then read back as lossy UTF-8).
    Bytes(ByteEdit),
    DeleteLine(usize),
    DuplicateLine(usize),
    /// Replace the (index mod count)-th number (a value after '=') with a float.
    Float(usize, f64),
    /// … with an integer.
    Integer(usize, i64),
    /// Insert a random line.
    InsertLine(usize, String),
    /// Multiply the (index mod count)-th number by a plausible factor (stays near valid specs).
    Scale(usize, f64),
}

fn text_edit() -> impl Strategy<Value = TextEdit> {
    prop_oneof![
        2 => byte_edit().prop_map(TextEdit::Bytes),
        1 => any::<usize>().prop_map(TextEdit::DeleteLine),
        1 => any::<usize>().prop_map(TextEdit::DuplicateLine),
        4 => (any::<usize>(), hostile_f64()).prop_map(|(i, x)| TextEdit::Float(i, x)),
        2 => (any::<usize>(), prop_oneof![any::<i64>(), -5i64..200, Just(i64::MAX), Just(100_000)])
            .prop_map(|(i, n)| TextEdit::Integer(i, n)),
        1 => (any::<usize>(), "[a-z_\\[\\]=\"0-9. -]{0,40}").prop_map(|(i, s)| TextEdit::InsertLine(i, s)),
        4 => (any::<usize>(), prop_oneof![0.2..5.0f64, Just(0.0), Just(-1.0), Just(1e-6), Just(1e6)])
            .prop_map(|(i, k)| TextEdit::Scale(i, k)),
    ]
}

/// A float as TOML writes it (nan, inf, -inf are TOML floats; Rust's "NaN" is not).
fn toml_float(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{x:?}")
    }
}

/// The byte ranges of the values after '=' that look like numbers.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        if let Some(eq) = line.find('=') {
            let value = &line[eq + 1..];
            let lead = value.len() - value.trim_start().len();
            let start = offset + eq + 1 + lead;
            let len = value
                .trim_start()
                .find(|c: char| !(c.is_ascii_alphanumeric() || "+-._".contains(c)))
                .unwrap_or(value.trim_start().len());
            let token = &text[start..start + len];
            if len > 0 && token.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '+') {
                spans.push((start, start + len));
            }
        }
        offset += line.len();
    }
    spans
}

fn apply_text(text: &str, edits: &[TextEdit]) -> String {
    let mut text = text.to_string();
    for e in edits {
        match e {
            TextEdit::Bytes(b) => {
                let mut bytes = text.into_bytes();
                apply_bytes(&mut bytes, std::slice::from_ref(b));
                text = String::from_utf8_lossy(&bytes).into_owned();
            }
            TextEdit::DeleteLine(i) | TextEdit::DuplicateLine(i) | TextEdit::InsertLine(i, _) => {
                let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
                let n = lines.len();
                match e {
                    TextEdit::DeleteLine(_) if n > 0 => {
                        lines.remove(i % n);
                    }
                    TextEdit::DuplicateLine(_) if n > 0 => {
                        let l = lines[i % n].clone();
                        lines.insert(i % n, l);
                    }
                    TextEdit::InsertLine(_, s) => lines.insert(i % (n + 1), s.clone()),
                    _ => {}
                }
                text = lines.join("\n");
            }
            TextEdit::Float(i, _) | TextEdit::Integer(i, _) | TextEdit::Scale(i, _) => {
                let spans = number_spans(&text);
                if spans.is_empty() {
                    continue;
                }
                let (a, b) = spans[i % spans.len()];
                let new = match e {
                    TextEdit::Float(_, x) => toml_float(*x),
                    TextEdit::Integer(_, n) => n.to_string(),
                    TextEdit::Scale(_, k) => match text[a..b].parse::<i64>() {
                        Ok(n) => ((n as f64 * k).round() as i64).to_string(),
                        Err(_) => text[a..b].parse::<f64>().map(|x| toml_float(x * k)).unwrap_or_default(),
                    },
                    _ => unreachable!(),
                };
                text.replace_range(a..b, &new);
            }
        }
    }
    text
}

// ---------------------------------------------------------------------------------------------
// (a) The spec parser.

fn example(name: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(name)).unwrap()
}

/// Parses and builds a pair; Ok must be a usable pair, Err must say something.
fn check_spec(text: &str) -> Result<(), TestCaseError> {
    let result = no_panic("PairSpec::from_toml + GearPair::from_spec", &text, || {
        PairSpec::from_toml(text).and_then(|s| GearPair::from_spec(&s))
    })?;
    stat("spec_parser", if result.is_ok() { "accepted" } else { "refused" });
    match result {
        Ok(pair) => {
            for (what, x) in [
                ("center distance", pair.center_distance_m),
                ("base pitch", pair.base_pitch_m),
                ("face width", pair.face_width_m),
                ("transverse contact ratio", pair.transverse_contact_ratio),
                ("Young's modulus", pair.youngs_modulus_pa),
            ] {
                prop_assert!(x.is_finite() && x > 0.0, "accepted spec gives {what} = {x}: {text:?}");
            }
            prop_assert!(
                pair.backlash_loa_m.is_finite(),
                "accepted spec gives backlash {}: {text:?}",
                pair.backlash_loa_m
            );
        }
        Err(e) => prop_assert!(!e.to_string().trim().is_empty(), "an empty error for {text:?}"),
    }
    Ok(())
}

#[test]
fn fuzz_spec_parser() {
    let spur = example("kurokawa_spur.toml");
    let helical = example("kurokawa_helical.toml");
    // The originals are accepted (the mutations start from good inputs).
    for t in [&spur, &helical] {
        assert!(PairSpec::from_toml(t).and_then(|s| GearPair::from_spec(&s)).is_ok());
    }
    let strategy = prop_oneof![
        8 => (prop_oneof![Just(spur.clone()), Just(helical.clone())], proptest::collection::vec(text_edit(), 1..6))
            .prop_map(|(base, edits)| apply_text(&base, &edits)),
        1 => any::<String>(),
        1 => "[a-z_\\[\\]=\"0-9.\n -]{0,200}",
    ];
    fuzz("spec_parser", 2000, strategy, |text| check_spec(&text));
}

// ---------------------------------------------------------------------------------------------
// (b) The model-file decoder.

/// Recomputes a model file's checksum over its (edited) body, so the edit reaches the decoder.
fn reseal_model_file(mut bytes: Vec<u8>) -> Vec<u8> {
    if bytes.len() >= 44 {
        let digest = Sha256::digest(&bytes[44..]);
        bytes[12..44].copy_from_slice(&digest);
    }
    bytes
}

#[derive(Debug, Clone)]
enum ModelFileCase {
    /// Edited bytes, checksum left as it was.
    Raw(Vec<ByteEdit>),
    /// Edited body (after the 44-byte header), checksum recomputed.
    Resealed(Vec<ByteEdit>),
}

/// The lumped spur model with its mesh-law tables decimated 8× along the roll position (128 rows
/// of 1024): the same structure and code paths for the decoder and the FMU, an eighth of the bytes
/// to checksum and decode per case.
fn small_lumped_model_bin() -> Vec<u8> {
    use gearfmu::dynamics::mesh_law::MeshLaw;
    let mut mesh = lumped_mesh().clone();
    let decimate = |law: &MeshLaw| {
        let k = law.force_levels_n.len();
        let rows: Vec<f64> = law.deflection_m.chunks(k).step_by(8).flatten().copied().collect();
        assert_eq!(rows.len() % k, 0);
        MeshLaw::new(law.base_pitch_m, law.force_levels_n.clone(), rows)
    };
    mesh.drive = decimate(&mesh.drive);
    mesh.coast = decimate(&mesh.coast);
    let k = mesh.drive.force_levels_n.len();
    mesh.drive_pairs = mesh.drive_pairs.chunks(k).step_by(8).flatten().copied().collect();
    mesh.coast_pairs = mesh.coast_pairs.chunks(k).step_by(8).flatten().copied().collect();
    let pair = kurokawa_spur();
    let model = ModelKind::Lumped(mesh);
    let guid = ModelFile::compute_guid(gearfmu::interface::VARIABLES_TOML, &pair.name, &model);
    ModelFile { guid, pair_name: pair.name, model }.to_bytes()
}

#[test]
fn fuzz_model_file_decoder() {
    model_file_decoder("model_file_decoder", small_lumped_model_bin(), 500);
}

/// The PMOR-Hertz model file (the small-basis spur model of `pmor_resources`): its decoder and
/// the model checks at instantiate, initialization and a step.
#[test]
fn fuzz_model_file_decoder_pmor_hertz() {
    model_file_decoder("model_file_decoder_pmor_hertz", pmor_resources().model_bin.clone(), 100);
}

fn model_file_decoder(target: &'static str, original: Vec<u8>, short: u32) {
    assert!(ModelFile::from_bytes(&original).is_ok());
    let edits = || proptest::collection::vec(byte_edit(), 1..8);
    let strategy = prop_oneof![
        1 => edits().prop_map(ModelFileCase::Raw),
        3 => edits().prop_map(ModelFileCase::Resealed),
    ];
    fuzz(target, short, strategy, |case| {
        let bytes = match &case {
            ModelFileCase::Raw(e) => {
                let mut b = original.clone();
                apply_bytes(&mut b, e);
                b
            }
            ModelFileCase::Resealed(e) => {
                let mut body = original[44..].to_vec();
                apply_bytes(&mut body, e);
                reseal_model_file([&original[..44], &body[..]].concat())
            }
        };
        let result = no_panic("ModelFile::from_bytes", &case, || ModelFile::from_bytes(&bytes))?;
        stat(target, if result.is_ok() { "decoded" } else { "refused" });
        match result {
            Err(e) => prop_assert!(!e.trim().is_empty()),
            Ok(file) => {
                // A raw edit that decodes must have left the bytes as they were (SHA-256).
                if let ModelFileCase::Raw(_) = case {
                    prop_assert_eq!(&bytes, &original, "a raw edit passed the checksum");
                }
                // A decoded file must also load into the FMU without panicking, and an FMU
                // instantiated on it must answer initialization, a step and the outputs with
                // valid statuses, without a panic inside (the guard would turn one into an
                // Error, but a panic is still a bug) and in bounded time.
                let guid = file.guid.clone();
                no_panic("GearPairFmu::from_model_file", &case, || GearPairFmu::from_model_file(file).map(|_| ()))?
                    .ok();
                if CString::new(guid.clone()).is_ok() {
                    let dir = resources()
                        .dir
                        .parent()
                        .unwrap()
                        .join(format!("edited-{target}-{:?}", std::thread::current().id()));
                    std::fs::create_dir_all(&dir).unwrap();
                    std::fs::write(dir.join(FILE_NAME), &bytes).unwrap();
                    let name = unique_name("model-file");
                    let t0 = Instant::now();
                    let c = no_panic("fmi2Instantiate", &case, || instantiate_at(&name, &dir, &guid))?;
                    if c.is_null() {
                        stat(target, "instantiate refused");
                    } else {
                        let calls = no_panic("FMI calls on an edited model file", &case, || {
                            let mut statuses = vec![
                                fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0),
                                fmi2EnterInitializationMode(c),
                                fmi2ExitInitializationMode(c),
                            ];
                            statuses.push(fmi2DoStep(c, 0.0, 1e-4, 1));
                            let vrs: Vec<u32> =
                                variables().iter().filter(|v| v.kind == "Real").map(|v| v.value_reference).collect();
                            let mut values = vec![0.0; vrs.len()];
                            statuses.push(fmi2GetReal(c, vrs.as_ptr(), vrs.len(), values.as_mut_ptr()));
                            fmi2FreeInstance(c);
                            statuses
                        })?;
                        prop_assert!(calls.iter().all(|s| status_is_valid(*s)), "statuses {calls:?}");
                        stat(target, if calls[3] == OK { "instance stepped" } else { "instance refused" });
                    }
                    prop_assert!(t0.elapsed() < Duration::from_secs(2), "took {:?}", t0.elapsed());
                    let logs = take_logs(&name);
                    prop_assert!(!logs.iter().any(|l| l.contains("panic")), "a panic inside the FMU: {logs:?}");
                }
            }
        }
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// (c) The serialized-FMU-state decoder.

/// Splits a serialized FMU state into (GUID, payload) if its framing is intact.
fn state_parts(bytes: &[u8]) -> (Vec<u8>, Vec<u8>) {
    let guid_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let guid = bytes[16..16 + guid_len].to_vec();
    let at = 16 + guid_len;
    let payload_len = u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
    (guid, bytes[at + 8..at + 8 + payload_len].to_vec())
}

/// A serialized FMU state with the given GUID and payload, framing and checksum correct.
fn seal_state(guid: &[u8], payload: &[u8]) -> Vec<u8> {
    let mut b = b"GFMUSTAT".to_vec();
    b.extend_from_slice(&2u32.to_le_bytes());
    b.extend_from_slice(&(guid.len() as u32).to_le_bytes());
    b.extend_from_slice(guid);
    b.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    b.extend_from_slice(payload);
    let d = Sha256::digest(&b);
    b.extend_from_slice(&d);
    b
}

fn any_phase() -> impl Strategy<Value = Phase> {
    prop_oneof![
        Just(Phase::Instantiated),
        Just(Phase::InitializationMode),
        Just(Phase::StepComplete),
        Just(Phase::StepFailed),
        Just(Phase::Terminated),
        Just(Phase::Error),
        Just(Phase::Fatal),
    ]
}

/// A value that is mostly plausible and sometimes hostile.
fn field_f64(plausible: f64) -> impl Strategy<Value = f64> {
    prop_oneof![3 => Just(plausible), 1 => (0.5..2.0f64).prop_map(move |k| k * plausible), 2 => hostile_f64()]
}

#[derive(Debug, Clone)]
enum StateCase {
    /// Edited bytes, framing and checksum left as they were.
    Raw(Vec<ByteEdit>),
    /// Edited postcard payload, framing and checksum recomputed.
    Resealed(Vec<ByteEdit>),
    /// A state of the right type with hostile field values, properly serialized.
    Forged(Box<Snapshot<GearPairState>>),
}

fn forged_state(real: Snapshot<GearPairState>) -> impl Strategy<Value = StateCase> {
    let s = real.state.clone();
    let lumped = move |m: gearfmu::dynamics::lumped::LumpedState| {
        (
            field_f64(m.theta_1),
            field_f64(m.omega_1),
            field_f64(m.theta_2),
            field_f64(m.omega_2),
            field_f64(m.input_work_j),
            field_f64(m.dissipated_j),
            field_f64(m.friction_dissipated_j),
            field_f64(m.friction_elastic_work_j),
        )
            .prop_map(
                |(
                    theta_1,
                    omega_1,
                    theta_2,
                    omega_2,
                    input_work_j,
                    dissipated_j,
                    friction_dissipated_j,
                    friction_elastic_work_j,
                )| {
                    gearfmu::dynamics::lumped::LumpedState {
                        theta_1,
                        omega_1,
                        theta_2,
                        omega_2,
                        input_work_j,
                        dissipated_j,
                        friction_dissipated_j,
                        friction_elastic_work_j,
                    }
                },
            )
    };
    (
        (field_f64(s.torques_nm[0]), field_f64(s.torques_nm[1])),
        lumped(s.start),
        lumped(s.mech),
        prop_oneof![2 => Just(s.max_step_s), 1 => hostile_f64(), 1 => 1e-12..1e-2f64],
        (
            field_f64(s.params.inertia_1_kgm2),
            field_f64(s.params.inertia_2_kgm2),
            field_f64(s.params.mesh_damping_ratio),
            field_f64(s.params.friction_coefficient),
            field_f64(s.params.sliding_regularization_m_per_s),
        ),
        // ISO/TR 14179-2's law: its inputs and the μ it applied.
        (
            prop_oneof![Just(0.0), Just(30.0), hostile_f64()],
            prop_oneof![Just(0.5), hostile_f64()],
            field_f64(s.params.lubrication.lubricant_factor),
            field_f64(s.friction_coefficient_applied),
        ),
        (field_f64(real.time), prop_oneof![Just(None), hostile_f64().prop_map(Some)], any_phase()),
    )
        .prop_map(move |(tau, start, mech, max_step_s, (i1, i2, z, mu, eps), law, (time, stop_time, phase))| {
            let mut state = s.clone();
            state.torques_nm = [tau.0, tau.1];
            state.start = start;
            state.mech = mech;
            state.max_step_s = max_step_s;
            state.params.inertia_1_kgm2 = i1;
            state.params.inertia_2_kgm2 = i2;
            state.params.mesh_damping_ratio = z;
            state.params.friction_coefficient = mu;
            state.params.sliding_regularization_m_per_s = eps;
            (
                state.params.lubrication.oil_viscosity_mpa_s,
                state.params.lubrication.roughness_ra_um,
                state.params.lubrication.lubricant_factor,
                state.friction_coefficient_applied,
            ) = law;
            StateCase::Forged(Box::new(Snapshot { state, time, stop_time, phase }))
        })
}

fn status_is_valid(s: fmi2Status) -> bool {
    (fmi2Status_fmi2OK..=fmi2Status_fmi2Pending).contains(&s)
}

#[test]
fn fuzz_state_decoder() {
    let r = resources();
    let original = serialized_state_of(r);
    let real = gear_snapshot(deserialize_snapshot(&original, &r.guid).unwrap()).unwrap();
    let forged = forged_state(real);
    state_decoder("state_decoder", r, original, forged, 500, |st, initialized| {
        prop_assert!(st.pmor.is_none());
        if initialized {
            let limit = gearfmu::dynamics::lumped::rk4_stability_limit_s(
                lumped_mesh(),
                &st.params,
                STIFFEST.get_or_init(|| {
                    [0.0, gearfmu::gear::MAX_FRICTION_COEFFICIENT]
                        .map(|max| gearfmu::dynamics::lumped::stiffest_tangent_stiffness(lumped_mesh(), max))
                })[usize::from(st.params.friction_coefficient > 0.0 || st.params.lubricated_flanks().is_some())],
            );
            prop_assert!(st.max_step_s <= limit, "an initialized state with max_step {} > {limit}", st.max_step_s);
        }
        Ok(())
    });
}

/// The PMOR-Hertz state: the reduced pair's own fields forged too (angles, elastic coordinates of
/// the wrong length or hostile value, the anchored pitch as any integer).
#[test]
fn fuzz_state_decoder_pmor_hertz() {
    let r = pmor_resources();
    let original = serialized_state_of(r);
    let real = gear_snapshot(deserialize_snapshot(&original, &r.guid).unwrap()).unwrap();
    let pmor = real.state.pmor.clone().expect("an initialized PMOR-Hertz state");
    let sizes = [pmor.eta[0].len(), pmor.eta[1].len()];
    // Either the FMI-level fields forged (the reduced pair's state as it was) or the reduced
    // pair's own (the rest as it was): both at once would almost never be accepted.
    let outer = forged_state(real.clone());
    let inner = forged_pmor_state(pmor).prop_map(move |p| {
        let mut snap = real.clone();
        snap.state.pmor = p;
        StateCase::Forged(Box::new(snap))
    });
    let forged = prop_oneof![outer, inner];
    state_decoder("state_decoder_pmor_hertz", r, original, forged, 100, move |st, _| {
        if let Some(p) = &st.pmor {
            let all = [&p.theta[..], &p.omega[..], &p.eta[0], &p.eta[1], &p.eta_dot[0], &p.eta_dot[1]].concat();
            prop_assert!(all.iter().all(|x| x.is_finite()), "a non-finite PMOR-Hertz state was accepted");
            for i in 0..2 {
                prop_assert!(p.eta[i].len() == sizes[i] && p.eta_dot[i].len() == sizes[i]);
            }
        }
        Ok(())
    });
}

/// A PMOR-Hertz state with hostile fields: each field mostly as it was, sometimes hostile; the
/// elastic coordinates sometimes one entry hostile or one too many or too few; sometimes none.
fn forged_pmor_state(real: PmorState) -> impl Strategy<Value = Option<PmorState>> {
    let coords = |v: Vec<f64>| {
        let n = v.len();
        prop_oneof![
            4 => Just(v.clone()),
            2 => (0..n.max(1), hostile_f64()).prop_map({
                let v = v.clone();
                move |(i, x)| {
                    let mut v = v.clone();
                    if let Some(e) = v.get_mut(i) {
                        *e = x;
                    }
                    v
                }
            }),
            1 => Just(v[..n.saturating_sub(1)].to_vec()),
            1 => Just([&v[..], &[0.0]].concat()),
        ]
    };
    let p = real.clone();
    (
        [field_f64(p.theta[0]), field_f64(p.theta[1]), field_f64(p.omega[0]), field_f64(p.omega[1])],
        [
            coords(p.eta[0].clone()),
            coords(p.eta[1].clone()),
            coords(p.eta_dot[0].clone()),
            coords(p.eta_dot[1].clone()),
        ],
        [
            prop_oneof![3 => Just(p.anchor[0]), 1 => any::<i64>(), 1 => -3i64..3],
            prop_oneof![3 => Just(p.anchor[1]), 1 => any::<i64>(), 1 => -3i64..3],
        ],
        (
            field_f64(p.input_work_j),
            field_f64(p.dissipated_j),
            field_f64(p.torques_nm[0]),
            field_f64(p.friction_dissipated_j),
        ),
        0..8u8,
    )
        .prop_map(
            move |(
                [t1, t2, w1, w2],
                [e1, e2, d1, d2],
                anchor,
                (input_work_j, dissipated_j, tau_1, friction_dissipated_j),
                none,
            )| {
                (none != 0).then(|| PmorState {
                    theta: [t1, t2],
                    omega: [w1, w2],
                    eta: [e1, e2],
                    eta_dot: [d1, d2],
                    anchor,
                    torques_nm: [tau_1, 0.0],
                    input_work_j,
                    dissipated_j,
                    friction_dissipated_j,
                })
            },
        )
}

/// The state decoder against the instances of `r`: raw and resealed byte edits of `original`, and
/// `forged` states; `model_checks` holds an accepted state to the model kind's own contract
/// (`initialized`: a phase after fmi2ExitInitializationMode).
fn state_decoder(
    target: &'static str,
    r: &'static Resources,
    original: Vec<u8>,
    forged: impl Strategy<Value = StateCase>,
    short: u32,
    model_checks: impl Fn(&GearPairState, bool) -> Result<(), TestCaseError>,
) {
    let guid = r.guid.clone();
    let (state_guid, payload) = state_parts(&original);
    assert_eq!(state_guid, guid.as_bytes());
    let edits = || proptest::collection::vec(byte_edit(), 1..6);
    let strategy = prop_oneof![
        1 => edits().prop_map(StateCase::Raw),
        3 => edits().prop_map(StateCase::Resealed),
        3 => forged,
    ];
    fuzz(target, short, strategy, |case| {
        let bytes = match &case {
            StateCase::Raw(e) => {
                let mut b = original.clone();
                apply_bytes(&mut b, e);
                b
            }
            StateCase::Resealed(e) => {
                let mut p = payload.clone();
                apply_bytes(&mut p, e);
                seal_state(&state_guid, &p)
            }
            StateCase::Forged(snapshot) => serialize_snapshot(&any_snapshot((**snapshot).clone()), &guid).unwrap(),
        };
        let decoded = no_panic("deserialize_snapshot", &case, || {
            deserialize_snapshot(&bytes, &guid)
                .and_then(|s| gear_snapshot(s).ok_or_else(|| "an element's state, not a gear pair's".to_string()))
        })?;
        if let (StateCase::Raw(_), Ok(_)) = (&case, &decoded) {
            prop_assert_eq!(&bytes, &original, "a raw edit passed the checksum");
        }
        if let Err(e) = &decoded {
            prop_assert!(!e.trim().is_empty());
        }
        // Through the C API: DeSerialize, and if accepted SetFMUstate and one DoStep.
        let name = unique_name("state");
        let c = instantiate_from(&name, r);
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        let status = no_panic("fmi2DeSerializeFMUstate", &case, || unsafe {
            fmi2DeSerializeFMUstate(c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut s)
        })?;
        prop_assert!(status == OK || status == ERR, "DeSerialize returned {status}");
        let kind = match &case {
            StateCase::Raw(_) => "raw",
            StateCase::Resealed(_) => "resealed",
            StateCase::Forged(_) => "forged",
        };
        let decoded_ok = if decoded.is_ok() { "decoded" } else { "undecodable" };
        stat(target, &format!("{kind} {decoded_ok} {}", if status == OK { "accepted" } else { "refused" }));
        if status == ERR {
            prop_assert!(s.is_null());
            let logs = take_logs(&name);
            prop_assert!(
                logs.iter().any(|l| l.contains("fmi2DeSerializeFMUstate:")),
                "no log line for a refused state: {logs:?}"
            );
        } else {
            prop_assert!(decoded.is_ok(), "the C API accepted what deserialize_snapshot refuses");
            let snap = decoded.unwrap();
            // What the FMU accepts must be a state it can be in (the check_state contract).
            let st = &snap.state;
            prop_assert!(snap.phase != Phase::Fatal && snap.time.is_finite());
            prop_assert!(st.max_step_s.is_normal() && st.max_step_s > 0.0);
            prop_assert!(st.params.inertia_1_kgm2 > 0.0 && st.params.inertia_2_kgm2 > 0.0);
            prop_assert!((0.0..1.0).contains(&st.params.mesh_damping_ratio));
            model_checks(st, matches!(snap.phase, Phase::StepComplete | Phase::StepFailed | Phase::Terminated))?;
            let status = no_panic("fmi2SetFMUstate", &case, || fmi2SetFMUstate(c, s))?;
            prop_assert_eq!(status, OK, "a decoded state was refused by SetFMUstate: {:?}", take_logs(&name));
            prop_assert_eq!(phase_of(c), snap.phase);
            // One step from the restored time, bounded work: h = 100 max_step at most.
            let h = (100.0 * st.max_step_s).min(1e-3);
            let t0 = Instant::now();
            let status = no_panic("fmi2DoStep", &case, || fmi2DoStep(c, snap.time, h, 1))?;
            prop_assert!(status_is_valid(status));
            prop_assert!(t0.elapsed() < Duration::from_secs(2), "DoStep took {:?}", t0.elapsed());
            stat(target, if status == OK { "step OK" } else { "step refused" });
            let logs = take_logs(&name);
            prop_assert!(!logs.iter().any(|l| l.contains("panic")), "a panic inside the FMU: {logs:?}");
            if snap.phase != Phase::StepComplete {
                prop_assert_eq!(status, ERR, "DoStep accepted in phase {:?}", snap.phase);
            }
            prop_assert_eq!(unsafe { fmi2FreeFMUstate(c, &mut s) }, OK);
        }
        fmi2FreeInstance(c);
        take_logs(&name);
        Ok(())
    });
}

// ---------------------------------------------------------------------------------------------
// (d) Random FMI call sequences against a model of the FMI 2.0 CS state machine.

#[derive(Debug, Clone)]
enum Call {
    SetupExperiment {
        start: f64,
        stop: Option<f64>,
    },
    EnterInit,
    ExitInit,
    /// `at_time`: currentCommunicationPoint is the FMU's time; otherwise time + `off`.
    DoStep {
        h: f64,
        at_time: bool,
        off: f64,
    },
    SetReal(Vec<(u32, f64)>),
    GetReal(Vec<u32>),
    /// Overwrite pool state (index) if Some, else a new one.
    GetFMUstate(Option<usize>),
    SetFMUstate(usize),
    FreeFMUstate(usize),
    /// Serialize pool state (index), DeSerialize it (optionally with one byte flipped).
    SerializeRoundTrip {
        index: usize,
        corrupt: Option<(usize, u8)>,
        wrong_size: bool,
    },
    Terminate,
    Reset,
    /// 0: GetStatus, 1: Real, 2: Integer, 3: Boolean, 4: String; kind 0..=4 (4 is no kind).
    Status {
        which: u8,
        kind: u32,
    },
    /// The call a well-behaved master would make next in the model's phase (keeps sequences
    /// out of the Error phase long enough to reach deep states); `h` for a DoStep.
    Next(f64),
}

/// What [`Call::Next`] is in a phase.
fn next_call(p: Phase, h: f64) -> Call {
    match p {
        Phase::Instantiated => Call::EnterInit,
        Phase::InitializationMode => Call::ExitInit,
        Phase::StepComplete => Call::DoStep { h, at_time: true, off: 0.0 },
        _ => Call::Reset,
    }
}

fn any_vr() -> impl Strategy<Value = u32> {
    let valid: Vec<u32> = variables().iter().map(|v| v.value_reference).collect();
    prop_oneof![6 => proptest::sample::select(valid), 1 => 0u32..60, 1 => any::<u32>()]
}

fn call() -> impl Strategy<Value = Call> {
    let step = prop_oneof![
        6 => 1e-6..1e-3f64,
        1 => Just(0.0),
        1 => Just(-1e-4),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(1e9),
        1 => Just(1e300),
        1 => Just(5e-324),
        1 => hostile_f64(),
    ];
    let value = prop_oneof![4 => hostile_f64(), 2 => 1e-9..1e-4f64, 2 => 0.0..1.0f64, 1 => 1e-4..1.0f64];
    prop_oneof![
        2 => (prop_oneof![3 => Just(0.0), 1 => hostile_f64()], prop_oneof![Just(None), (0.0..1.0f64).prop_map(Some), hostile_f64().prop_map(Some)])
            .prop_map(|(start, stop)| Call::SetupExperiment { start, stop }),
        3 => Just(Call::EnterInit),
        3 => Just(Call::ExitInit),
        8 => (step, prop::bool::weighted(0.85), prop_oneof![Just(f64::NAN), Just(1.0), Just(-1.0), Just(1e-3)])
            .prop_map(|(h, at_time, off)| Call::DoStep { h, at_time, off }),
        5 => proptest::collection::vec((any_vr(), value), 1..4).prop_map(Call::SetReal),
        3 => proptest::collection::vec(any_vr(), 0..4).prop_map(Call::GetReal),
        2 => prop_oneof![Just(None), (0usize..4).prop_map(Some)].prop_map(Call::GetFMUstate),
        2 => (0usize..4).prop_map(Call::SetFMUstate),
        1 => (0usize..4).prop_map(Call::FreeFMUstate),
        2 => (0usize..4, prop_oneof![3 => Just(None), 1 => (any::<usize>(), 1u8..=255).prop_map(Some)], prop::bool::weighted(0.1))
            .prop_map(|(index, corrupt, wrong_size)| Call::SerializeRoundTrip { index, corrupt, wrong_size }),
        2 => Just(Call::Terminate),
        2 => Just(Call::Reset),
        3 => (0u8..5, 0u32..5).prop_map(|(which, kind)| Call::Status { which, kind }),
        16 => (1e-6..1e-3f64).prop_map(Call::Next),
    ]
}

/// Which phases each call is allowed in: FMI 2.0.4 §4.2.4 (CS state machine), written out here
/// independently of `allowed` in src/fmi2/instance.rs.
fn allowed_in(call: &Call, p: Phase) -> bool {
    use Phase::*;
    match call {
        Call::SetupExperiment { .. } | Call::EnterInit => p == Instantiated,
        Call::ExitInit => p == InitializationMode,
        Call::DoStep { .. } => p == StepComplete,
        Call::SetReal(_) => matches!(p, Instantiated | InitializationMode | StepComplete),
        Call::GetReal(_) => matches!(p, InitializationMode | StepComplete | StepFailed | Terminated | Error),
        Call::GetFMUstate(_)
        | Call::SetFMUstate(_)
        | Call::FreeFMUstate(_)
        | Call::SerializeRoundTrip { .. }
        | Call::Reset => p != Fatal,
        Call::Terminate => matches!(p, StepComplete | StepFailed),
        Call::Status { .. } => matches!(p, StepComplete | StepFailed | Terminated),
        Call::Next(h) => allowed_in(&next_call(p, *h), p),
    }
}

/// What the model knows of an FMU state it holds.
#[derive(Debug, Clone, Copy)]
struct Record {
    phase: Phase,
    time: f64,
    stop: Option<f64>,
    max_step: f64,
}

/// The model: the phase, time, stop time and max_step the FMU should have.
struct Machine {
    rec: Record,
    pool: Vec<(fmi2FMUstate, Record)>,
    /// The max_step an instance starts with (and returns to at Reset).
    default_max_step_s: f64,
    /// `Resources::contact_outputs_can_fail`.
    contact_outputs_can_fail: bool,
}

fn fresh(max_step: f64) -> Record {
    Record { phase: Phase::Instantiated, time: 0.0, stop: None, max_step }
}

/// Runs one call; returns (status, the statuses the model allows, the phases it allows after).
fn run_call(
    c: fmi2Component,
    m: &mut Machine,
    call: &Call,
) -> Result<(fmi2Status, Vec<fmi2Status>, Vec<Phase>), TestCaseError> {
    let before = m.rec;
    let allowed = allowed_in(call, before.phase);
    let error_phase = if before.phase == Phase::Fatal { Phase::Fatal } else { Phase::Error };
    // Outcome sets for an allowed call whose argument checks may refuse it.
    let ok_or_error = |ok_phase: Phase| (vec![OK, ERR], vec![ok_phase, error_phase]);
    let pool_index = |m: &Machine, i: usize| if m.pool.is_empty() { None } else { Some(i % m.pool.len()) };
    let (status, expect, phases): (fmi2Status, Vec<fmi2Status>, Vec<Phase>) = match call {
        Call::SetupExperiment { start, stop } => {
            let s = fmi2SetupExperiment(c, 0, 0.0, *start, stop.is_some() as i32, stop.unwrap_or(0.0));
            let good = start.is_finite() && stop.is_none_or(|t| t.is_finite() && t >= *start);
            if allowed && s == OK {
                m.rec.time = *start;
                m.rec.stop = *stop;
            }
            (s, vec![if good { OK } else { ERR }], vec![if good { before.phase } else { error_phase }])
        }
        Call::EnterInit => (fmi2EnterInitializationMode(c), vec![OK], vec![Phase::InitializationMode]),
        Call::ExitInit => {
            let s = fmi2ExitInitializationMode(c);
            if allowed && s == OK {
                // Where the master left max_step alone, the PMOR-Hertz FMU lowers its default to
                // its share of the stability limit with the instance's own parameters (a set
                // inertia or mesh damping ratio), if that is shorter: never raised, never zero.
                let mut read = f64::NAN;
                let status = fmi2GetReal(c, [vr("max_step")].as_ptr(), 1, &mut read);
                prop_assert_eq!(status, OK);
                prop_assert!(
                    read > 0.0 && read <= before.max_step,
                    "max_step after initialization {read:e}, before {:e}",
                    before.max_step
                );
                m.rec.max_step = read;
            }
            let (e, p) = ok_or_error(Phase::StepComplete);
            (s, e, p)
        }
        Call::DoStep { h, at_time, off } => {
            // Keep one call's work small: h/max_step between 1e4 and 1e8 sub-steps would be
            // legal but slow, so such an h is cut to 1e3 sub-steps (above 1e8 it is refused
            // before any work, which is what is tested).
            let mut h = *h;
            let n = h / before.max_step;
            if n > 1e4 && n < 1e8 {
                h = 1e3 * before.max_step;
            }
            let current = if *at_time { before.time } else { before.time + off };
            let t0 = Instant::now();
            let s = fmi2DoStep(c, current, h, 1);
            prop_assert!(t0.elapsed() < Duration::from_secs(2), "DoStep(h = {h}) took {:?}", t0.elapsed());
            let bad_args = !(h.is_finite() && h > 0.0)
                || !current.is_finite()
                || (current - before.time).abs() > time_tolerance(before.time, h);
            if allowed && s == OK {
                m.rec.time = current + h;
            }
            if bad_args {
                (s, vec![ERR], vec![error_phase])
            } else {
                // Refused (Error) or failed in the model (StepFailed).
                (s, vec![OK, ERR], vec![Phase::StepComplete, Phase::StepFailed, error_phase])
            }
        }
        Call::SetReal(pairs) => {
            let (vrs, values): (Vec<u32>, Vec<f64>) = pairs.iter().copied().unzip();
            let s = fmi2SetReal(c, vrs.as_ptr(), vrs.len(), values.as_ptr());
            let valid: Vec<u32> = variables().iter().filter(|v| v.kind == "Real").map(|v| v.value_reference).collect();
            let surely_bad = pairs.iter().any(|(r, x)| !x.is_finite() || !valid.contains(r));
            if allowed && s == OK {
                if let Some((_, x)) = pairs.iter().rev().find(|(r, _)| *r == vr("max_step")) {
                    m.rec.max_step = *x;
                }
            }
            if surely_bad {
                (s, vec![ERR], vec![error_phase])
            } else {
                let (e, p) = ok_or_error(before.phase);
                (s, e, p)
            }
        }
        Call::GetReal(vrs) => {
            let mut values = vec![f64::NAN; vrs.len()];
            let s = fmi2GetReal(c, vrs.as_ptr(), vrs.len(), values.as_mut_ptr());
            let reals: Vec<u32> = variables().iter().filter(|v| v.kind == "Real").map(|v| v.value_reference).collect();
            if vrs.iter().all(|r| reals.contains(r)) {
                if allowed && s == OK {
                    let ms = vrs.iter().position(|r| *r == vr("max_step"));
                    if let Some(i) = ms {
                        prop_assert_eq!(values[i], before.max_step, "max_step read back");
                    }
                }
                // Every output the contact makes (its force and stiffness, the shaft force and the
                // friction losses) evaluates it, which a start beyond Hertz's range refuses.
                let contact = [
                    "mesh_force",
                    "mesh_stiffness",
                    "force_tangential",
                    "force_radial",
                    "force_axial",
                    "mesh_power_loss",
                    "mesh_efficiency",
                ]
                .map(vr);
                if m.contact_outputs_can_fail && vrs.iter().any(|r| contact.contains(r)) {
                    (s, vec![OK, ERR], vec![before.phase, error_phase])
                } else {
                    (s, vec![OK], vec![before.phase])
                }
            } else {
                (s, vec![ERR], vec![error_phase])
            }
        }
        Call::GetFMUstate(index) => {
            let target = index.and_then(|i| pool_index(m, i));
            let s = match target {
                Some(i) => unsafe { fmi2GetFMUstate(c, &mut m.pool[i].0) },
                None => {
                    let mut st: fmi2FMUstate = std::ptr::null_mut();
                    let s = unsafe { fmi2GetFMUstate(c, &mut st) };
                    if !st.is_null() {
                        m.pool.push((st, before));
                    }
                    s
                }
            };
            if allowed && s == OK {
                if let Some(i) = target {
                    m.pool[i].1 = before;
                }
            }
            (s, vec![OK], vec![before.phase])
        }
        Call::SetFMUstate(i) => match pool_index(m, *i) {
            None => {
                let s = fmi2SetFMUstate(c, std::ptr::null_mut());
                (s, vec![ERR], vec![error_phase])
            }
            Some(i) => {
                let (st, rec) = m.pool[i];
                let s = fmi2SetFMUstate(c, st);
                if allowed && s == OK {
                    m.rec = rec;
                }
                (s, vec![OK], vec![rec.phase])
            }
        },
        Call::FreeFMUstate(i) => {
            let s = match pool_index(m, *i) {
                None => unsafe { fmi2FreeFMUstate(c, std::ptr::null_mut()) },
                Some(i) => {
                    let s = unsafe { fmi2FreeFMUstate(c, &mut m.pool[i].0) };
                    if allowed && s == OK {
                        prop_assert!(m.pool[i].0.is_null(), "FreeFMUstate left the pointer set");
                        m.pool.remove(i);
                    }
                    s
                }
            };
            (s, vec![OK], vec![before.phase])
        }
        Call::SerializeRoundTrip { index, corrupt, wrong_size } => match pool_index(m, *index) {
            None => {
                let mut size = 0;
                let s = unsafe { fmi2SerializedFMUstateSize(c, std::ptr::null_mut(), &mut size) };
                (s, vec![ERR], vec![error_phase])
            }
            Some(i) => {
                let (st, rec) = m.pool[i];
                let mut size = 0;
                let s = unsafe { fmi2SerializedFMUstateSize(c, st, &mut size) };
                if !(allowed && s == OK) {
                    (s, vec![OK], vec![before.phase])
                } else {
                    prop_assert!(size > 0);
                    let mut bytes = vec![0u8; size];
                    let n = if *wrong_size { size - 1 } else { size };
                    let s = fmi2SerializeFMUstate(c, st, bytes.as_mut_ptr() as *mut fmi2Byte, n);
                    if *wrong_size {
                        (s, vec![ERR], vec![Phase::Error])
                    } else if s != OK {
                        (s, vec![OK], vec![before.phase])
                    } else {
                        if let Some((at, mask)) = corrupt {
                            bytes[at % size] ^= mask;
                        }
                        let mut out: fmi2FMUstate = std::ptr::null_mut();
                        let s =
                            unsafe { fmi2DeSerializeFMUstate(c, bytes.as_ptr() as *const fmi2Byte, size, &mut out) };
                        if s == OK {
                            m.pool.push((out, rec));
                        }
                        if corrupt.is_some() {
                            (s, vec![ERR], vec![Phase::Error])
                        } else {
                            (s, vec![OK], vec![before.phase])
                        }
                    }
                }
            }
        },
        Call::Terminate => (fmi2Terminate(c), vec![OK], vec![Phase::Terminated]),
        Call::Reset => {
            let s = fmi2Reset(c);
            if allowed && s == OK {
                m.rec = fresh(m.default_max_step_s);
            }
            (s, vec![OK], vec![Phase::Instantiated])
        }
        Call::Status { which, kind } => {
            let (s, answered) = match which {
                0 => {
                    let mut v = 0;
                    (fmi2GetStatus(c, *kind as fmi2StatusKind, &mut v), false)
                }
                1 => {
                    let mut v = f64::NAN;
                    let s = fmi2GetRealStatus(c, *kind as fmi2StatusKind, &mut v);
                    if allowed && s == OK {
                        prop_assert_eq!(v, before.time, "fmi2LastSuccessfulTime");
                    }
                    (s, *kind == fmi2StatusKind_fmi2LastSuccessfulTime as u32)
                }
                2 => {
                    let mut v = 0;
                    (fmi2GetIntegerStatus(c, *kind as fmi2StatusKind, &mut v), false)
                }
                3 => {
                    let mut v = -1;
                    let s = fmi2GetBooleanStatus(c, *kind as fmi2StatusKind, &mut v);
                    if allowed && s == OK {
                        prop_assert_eq!(v, 0, "fmi2Terminated");
                    }
                    (s, *kind == fmi2StatusKind_fmi2Terminated as u32)
                }
                _ => {
                    let mut v: fmi2String = std::ptr::null();
                    (fmi2GetStringStatus(c, *kind as fmi2StatusKind, &mut v), false)
                }
            };
            (s, vec![if answered { OK } else { DISCARD }], vec![before.phase])
        }
        Call::Next(_) => unreachable!("resolved by the caller"),
    };
    if allowed {
        Ok((status, expect, phases))
    } else {
        Ok((status, vec![ERR], vec![error_phase]))
    }
}

#[test]
fn fuzz_call_sequences() {
    call_sequences("call_sequences", resources(), 500);
}

/// The same target against the PMOR-Hertz FMU: its own model checks (inertias that may only
/// grow, the stability check linearized again for a new damping ratio, the contact's validity
/// errors) behind the same state machine.
#[test]
fn fuzz_call_sequences_pmor_hertz() {
    call_sequences("call_sequences_pmor_hertz", pmor_resources(), 300);
}

fn call_sequences(target: &'static str, r: &'static Resources, short: u32) {
    let strategy = proptest::collection::vec(call(), 1..=40);
    fuzz(target, short, strategy, |calls| {
        let name = unique_name("seq");
        let c = instantiate_from(&name, r);
        let mut m = Machine {
            rec: fresh(r.default_max_step_s),
            pool: Vec::new(),
            default_max_step_s: r.default_max_step_s,
            contact_outputs_can_fail: r.contact_outputs_can_fail,
        };
        let result = no_panic("an FMI call sequence", &calls, || -> Result<(), TestCaseError> {
            for (k, call) in calls.iter().enumerate() {
                let call = &match call {
                    Call::Next(h) => next_call(m.rec.phase, *h),
                    other => other.clone(),
                };
                let (status, expect, phases) = run_call(c, &mut m, call)?;
                let actual = phase_of(c);
                let verdict = match (allowed_in(call, m.rec.phase), status) {
                    (false, _) => "not allowed",
                    (true, OK) => "OK",
                    (true, DISCARD) => "Discard",
                    (true, _) => "Error",
                };
                let call_name = format!("{call:?}");
                let call_name = call_name.split(|c: char| !c.is_alphanumeric()).next().unwrap_or_default();
                stat(target, &format!("{call_name} {verdict}"));
                prop_assert!(status_is_valid(status), "call {k} {call:?} returned status {status}");
                prop_assert!(
                    expect.contains(&status),
                    "call {k} {call:?} in phase {:?} returned {status}, the model expects one of {expect:?}; log: {:?}",
                    m.rec.phase,
                    take_logs(&name)
                );
                prop_assert!(
                    phases.contains(&actual),
                    "after call {k} {call:?} (status {status}) the FMU is in phase {actual:?}, the model expects one of {phases:?}"
                );
                if status == ERR || status == DISCARD {
                    let logs = take_logs(&name);
                    prop_assert!(!logs.is_empty(), "call {k} {call:?} returned {status} without a log line");
                    prop_assert!(!logs.iter().any(|l| l.contains("panic")), "a panic inside the FMU: {logs:?}");
                }
                m.rec.phase = actual;
            }
            for (mut st, _) in std::mem::take(&mut m.pool) {
                prop_assert_eq!(unsafe { fmi2FreeFMUstate(c, &mut st) }, OK);
                prop_assert!(st.is_null());
            }
            Ok(())
        })?;
        fmi2FreeInstance(c);
        take_logs(&name);
        result
    });
}

// ---------------------------------------------------------------------------------------------
// Regressions: what the targets found, pinned.

/// The spur example with one `key = value` line replaced.
fn spur_with(key: &str, value: &str) -> String {
    let text = example("kurokawa_spur.toml");
    let line = text.lines().find(|l| l.starts_with(&format!("{key} ="))).unwrap().to_string();
    text.replace(&line, &format!("{key} = {value}"))
}

/// Found by `fuzz_spec_parser`: a value that passes "positive and finite" in the spec's units
/// but is zero or infinite in SI (face width 5e-324 mm → 0 m, E = 1e300 GPa → inf Pa) was
/// accepted, as was a subnormal one; each is now refused naming the field.
#[test]
fn regression_spec_values_out_of_range_in_si_are_refused() {
    for (key, value) in [
        ("face_width_mm", "5e-324"),
        ("module_mm", "1e-310"),
        ("youngs_modulus_gpa", "1e300"),
        ("bore_radius_mm", "5e-324"),
        ("density_kg_m3", "5e-324"),
        ("module_mm", "3.3337608712355604e240"),
    ] {
        let text = spur_with(key, value);
        let err = PairSpec::from_toml(&text).and_then(|s| GearPair::from_spec(&s)).map(|_| ()).unwrap_err();
        assert!(err.to_string().contains(key), "{key} = {value}: {err}");
        assert!(!err.to_string().contains("NaN") || err.to_string().contains("out of floating-point range"));
    }
}

/// Found by the long run of the spec target (1.25·10⁶ cases): teeth a micrometre high left the
/// fillet table one point long and its lookup panicked. Refused now, naming the field.
#[test]
fn regression_teeth_too_low_for_the_cutter_round_are_refused() {
    let text = example("kurokawa_helical.toml")
        .replace("addendum_coefficient = 1.0", "addendum_coefficient = 1e-6")
        .replace("dedendum_coefficient = 1.25", "dedendum_coefficient = 1.2499999999999999e-6");
    assert!(
        text.contains("addendum_coefficient = 1e-6") && text.contains("dedendum_coefficient = 1.2499999999999999e-6")
    );
    let err = PairSpec::from_toml(&text).and_then(|s| GearPair::from_spec(&s)).map(|_| ()).unwrap_err();
    assert!(err.to_string().contains("rack.dedendum_coefficient"), "{err}");
}

/// Found by the PMOR-Hertz call-sequence target: with a start angle that presses the flanks
/// beyond the Hertz law's range, a GetReal of tau_1 failed, because every output of an
/// uninitialized PMOR-Hertz instance evaluated the contact. Angles, speeds and inputs need no
/// contact; the contact outputs at such a state are an error with a log line, not a number.
#[test]
fn regression_pmor_outputs_without_contact_do_not_evaluate_it() {
    let name = unique_name("pmor-start");
    let c = instantiate_from(&name, pmor_resources());
    let (start, tau, force) = (vr("phi_1_start"), vr("tau_1"), vr("mesh_force"));
    assert_eq!(fmi2SetReal(c, &start, 1, &0.392), OK);
    assert_eq!(fmi2EnterInitializationMode(c), OK);
    let mut value = f64::NAN;
    assert_eq!(fmi2GetReal(c, &tau, 1, &mut value), OK, "{:?}", take_logs(&name));
    assert_eq!(value, 0.0);
    assert_eq!(fmi2GetReal(c, &start, 1, &mut value), OK);
    assert_eq!(value, 0.392);
    assert_eq!(fmi2GetReal(c, &force, 1, &mut value), ERR);
    let logs = take_logs(&name);
    assert!(logs.iter().any(|l| l.contains("Hertz")), "{logs:?}");
    fmi2FreeInstance(c);
}

/// Found by `fuzz_call_sequences_pmor_hertz` in CI (its call-sequence model expected the
/// build's max_step after initialization): with a set inertia_1 (939.78 kg·m² at the bore) and
/// max_step left alone, fmi2ExitInitializationMode lowers the PMOR-Hertz FMU's default max_step
/// to its share of that instance's stability limit (documented in `exit_initialization`). The
/// step read back is positive and not above the build's, and doSteps complete.
#[test]
fn regression_pmor_max_step_follows_the_instance_parameters_at_initialization() {
    let r = pmor_resources();
    let name = unique_name("pmor-inertia");
    let c = instantiate_from(&name, r);
    let (inertia, step) = (vr("inertia_1"), vr("max_step"));
    assert_eq!(fmi2EnterInitializationMode(c), OK);
    assert_eq!(fmi2SetReal(c, &inertia, 1, &939.7813441446419), OK, "{:?}", take_logs(&name));
    assert_eq!(fmi2ExitInitializationMode(c), OK, "{:?}", take_logs(&name));
    let mut value = f64::NAN;
    assert_eq!(fmi2GetReal(c, &step, 1, &mut value), OK);
    eprintln!("max_step after initialization {value:e} s (the build's {:e} s)", r.default_max_step_s);
    assert!(value > 0.0 && value <= r.default_max_step_s, "max_step {value:e}, build's {:e}", r.default_max_step_s);
    for k in 0..3 {
        assert_eq!(fmi2DoStep(c, k as f64 * 1e-6, 1e-6, 1), OK, "{:?}", take_logs(&name));
    }
    fmi2FreeInstance(c);
}

/// A state taken after initialization carries the stability contract of
/// fmi2ExitInitializationMode (max_step within RK4's limit on the stiffest mesh mode); a forged
/// one that breaks it (max_step 1e-3 s, or inertias so small the default max_step is unstable)
/// must be refused when restored, as ExitInitializationMode would refuse it, while the same
/// settings in a state taken before initialization stay restorable.
#[test]
fn regression_restored_state_is_held_to_the_stability_contract() {
    let guid = resources().guid.clone();
    let real = gear_snapshot(deserialize_snapshot(&serialized_state_of(resources()), &guid).unwrap()).unwrap();
    let mut big_step = real.clone();
    big_step.state.max_step_s = 1e-3;
    let mut light = real.clone();
    light.state.params.inertia_1_kgm2 = 1e-9;
    light.state.params.inertia_2_kgm2 = 1e-9;
    for (what, forged) in [("max_step 1e-3", big_step), ("inertias 1e-9", light)] {
        for phase in [Phase::StepComplete, Phase::StepFailed, Phase::Terminated, Phase::Instantiated] {
            let mut forged = forged.clone();
            forged.phase = phase;
            let bytes = serialize_snapshot(&any_snapshot(forged.clone()), &guid).unwrap();
            let name = unique_name("stability");
            let c = instantiate(&name);
            let mut s: fmi2FMUstate = std::ptr::null_mut();
            let status = unsafe { fmi2DeSerializeFMUstate(c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut s) };
            if phase == Phase::Instantiated {
                assert_eq!(status, OK, "{what} before initialization: {:?}", take_logs(&name));
                assert_eq!(fmi2SetFMUstate(c, s), OK);
                // ExitInitializationMode refuses it, as it refuses the same settings from SetReal.
                assert_eq!(fmi2EnterInitializationMode(c), OK);
                assert_eq!(fmi2ExitInitializationMode(c), ERR);
                assert!(take_logs(&name).iter().any(|l| l.contains("stability limit")));
                assert_eq!(unsafe { fmi2FreeFMUstate(c, &mut s) }, OK);
            } else {
                assert_eq!(status, ERR, "{what} in phase {phase:?} was accepted");
                let logs = take_logs(&name);
                assert!(logs.iter().any(|l| l.contains("stability limit")), "{what}: {logs:?}");
                // The instance stays usable: Reset, initialize, step.
                assert_eq!(fmi2Reset(c), OK);
                assert_eq!(fmi2EnterInitializationMode(c), OK);
                assert_eq!(fmi2ExitInitializationMode(c), OK);
                assert_eq!(fmi2DoStep(c, 0.0, 1e-4, 1), OK);
            }
            fmi2FreeInstance(c);
        }
    }
}

/// Found by CI's run of `fuzz_call_sequences`: a start angle of 1e300 rad is finite, but the lumped
/// mesh's energy at it is not (NaN). fmi2ExitInitializationMode stored it as the energy reference,
/// and the state taken afterwards was then refused by fmi2SetFMUstate. Such start values are now
/// refused at fmi2ExitInitializationMode, with a log line, and the instance stays usable.
///
/// Found again by `fuzz_call_sequences_pmor_hertz` (w_1_start = 1e300 rad/s): the refusal came
/// after the infinite energy was written into the state, so the state fmi2GetFMUstate took in the
/// Error phase could not be restored. A refused ExitInitializationMode now leaves the state as it
/// was (the generic layer keeps the model's work only on success): the state taken after the
/// refusal restores, in both FMUs.
#[test]
fn regression_start_values_beyond_the_energys_range_are_refused_at_initialization() {
    for (what, r, start) in [("lumped", resources(), "phi_1_start"), ("PMOR-Hertz", pmor_resources(), "w_1_start")] {
        let name = unique_name("huge-start");
        let c = instantiate_from(&name, r);
        let start = vr(start);
        assert_eq!(fmi2SetReal(c, &start, 1, &1e300), OK);
        assert_eq!(fmi2EnterInitializationMode(c), OK);
        assert_eq!(fmi2ExitInitializationMode(c), ERR, "{what}");
        let logs = take_logs(&name);
        assert!(logs.iter().any(|l| l.contains("start energy")), "{what}: {logs:?}");
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!(unsafe { fmi2GetFMUstate(c, &mut s) }, OK, "{what}");
        assert_eq!(fmi2SetFMUstate(c, s), OK, "{what}: {:?}", take_logs(&name));
        assert_eq!(unsafe { fmi2FreeFMUstate(c, &mut s) }, OK, "{what}");
        assert_eq!(fmi2Reset(c), OK);
        assert_eq!(fmi2EnterInitializationMode(c), OK);
        assert_eq!(fmi2ExitInitializationMode(c), OK);
        assert_eq!(fmi2DoStep(c, 0.0, 1e-6, 1), OK, "{what}: {:?}", take_logs(&name));
        fmi2FreeInstance(c);
    }
}

/// Found by `fuzz_model_file_decoder`: a model file with a valid checksum but an empty force
/// table instantiated, and fmi2ExitInitializationMode panicked (divide by zero, turned into an
/// Error by the guard). Such data is now refused at fmi2Instantiate with a log line.
#[test]
fn regression_malformed_lumped_model_data_is_refused_at_instantiate() {
    let mut file = ModelFile::from_bytes(&resources().model_bin).unwrap();
    let ModelKind::Lumped(mesh) = &mut file.model else { unreachable!() };
    mesh.drive.force_levels_n.clear();
    let dir = resources().dir.parent().unwrap().join("malformed");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(FILE_NAME), file.to_bytes()).unwrap();
    let name = unique_name("malformed");
    let c = instantiate_at(&name, &dir, &file.guid);
    assert!(c.is_null());
    let logs = take_logs(&name);
    assert!(logs.iter().any(|l| l.contains("fmi2Instantiate: the drive mesh law is malformed")), "{logs:?}");
}

/// A gear pair FMU's snapshot as its own state, and back (the binary's FMU state holds
/// `AnyState`, the state of whichever model the FMU carries).
fn gear_snapshot(
    s: gearfmu::fmi2::instance::Snapshot<gearfmu::fmu::any_model::AnyState>,
) -> Option<gearfmu::fmi2::instance::Snapshot<gearfmu::fmu::gear_pair::GearPairState>> {
    let gearfmu::fmi2::instance::Snapshot { state, time, stop_time, phase } = s;
    Some(gearfmu::fmi2::instance::Snapshot { state: state.into_gear_pair()?, time, stop_time, phase })
}

fn any_snapshot(
    s: gearfmu::fmi2::instance::Snapshot<gearfmu::fmu::gear_pair::GearPairState>,
) -> gearfmu::fmi2::instance::Snapshot<gearfmu::fmu::any_model::AnyState> {
    let gearfmu::fmi2::instance::Snapshot { state, time, stop_time, phase } = s;
    gearfmu::fmi2::instance::Snapshot { state: state.into(), time, stop_time, phase }
}
