//! What one PMOR-Hertz doStep costs at operating speed, and what of it is the integration
//! (issue 39), measured in release mode:
//!
//!     cargo bench --bench step_path [-- FMU ... [--torque-nm=T] [--inertia-factor=F] [--friction=μ]]
//!
//! (default: out/KurokawaSpur.fmu out/SmallHelical.fmu). The case is issue 38's brake case: both
//! gears start at synchronous speed, gear 1 carries T₁ (`--torque-nm`, else the pair's operating
//! torque: 250 N·m on the Kurokawa spur pair, 201.7 on the small helical), gear 2 a viscous
//! brake fed back from ω₂ after each communication step; 20 ms. It runs two ways in lockstep:
//!
//! - **through the FMI C entry points** (`fmi2SetReal` of the torques, `fmi2DoStep`, `fmi2GetReal`
//!   of ω₂, as a master calls them; only `fmi2DoStep` is timed), the FMU's own step path;
//! - **the integration alone**: `PmorDynamics::advance_knowing` on one dynamics object kept
//!   across the calls, the same inputs, the stored energy handed on as the FMU hands it: the
//!   baseline. It also counts the quasi-static solves (one per right-hand side of the condensed
//!   pair) and the contact evaluations.
//!
//! Five runs per case. Reported: the medians over all their doSteps of µs per doStep and per
//! advance, the median of the paired differences (the per-doStep overhead: what a doStep costs
//! beyond its integration), internal steps, solves and evaluations per doStep, µs per solve and
//! per evaluation (the advance's time over its counts), and the real-time factor. The case at
//! 0.5 kHz and 20 µs is one internal step per doStep on the Kurokawa spur pair: the overhead
//! asked to stay under 10 µs is read there. Each FMU must have been built (`./scripts/demo.sh`
//! builds the spur one; the helical one: `./target/release/fmu-build build
//! examples/small_helical.toml -o out/SmallHelical.fmu`).
use fmi_sys::fmi2::*;
use gearfmu::dynamics::mesh_friction::SlidingFriction;
use gearfmu::dynamics::pmor::PmorDynamics;
use gearfmu::fmi2::exports::*;
use gearfmu::interface::value_reference;
use gearfmu::model_file::{ModelFile, ModelKind, FILE_NAME};
use std::ffi::CString;
use std::path::{Path, PathBuf};
use std::time::Instant;

const END_S: f64 = 0.02;
/// Lockstep runs of each case; the medians over all their doSteps are reported.
const ROUNDS: usize = 5;
const CASES: [(f64, f64); 4] = [(500.0, 2e-5), (1500.0, 2e-5), (1500.0, 1e-4), (3000.0, 2e-5)];

fn median(mut samples: Vec<f64>) -> f64 {
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

/// One FMU's resources unpacked to a folder of its own, with its model file read.
struct Unpacked {
    dir: PathBuf,
    file: ModelFile,
}

fn unpack(fmu: &Path) -> Result<Unpacked, String> {
    let mut archive = zip::ZipArchive::new(std::fs::File::open(fmu).map_err(|e| format!("{}: {e}", fmu.display()))?)
        .map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(
        &mut archive.by_name(&format!("resources/{FILE_NAME}")).map_err(|e| e.to_string())?,
        &mut bytes,
    )
    .map_err(|e| e.to_string())?;
    let stem = fmu.file_stem().and_then(|s| s.to_str()).unwrap_or("fmu");
    let dir = std::env::temp_dir().join(format!("gearfmu-step-path-{}", std::process::id())).join(stem);
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    std::fs::write(dir.join(FILE_NAME), &bytes).map_err(|e| e.to_string())?;
    Ok(Unpacked { dir, file: ModelFile::from_bytes(&bytes)? })
}

/// The brake case's speeds (rad/s) and brake coefficient (N·m·s/rad) at a mesh frequency.
fn brake_case(pair: &Pair, mesh_hz: f64) -> ([f64; 2], f64) {
    let omega_2 = 2.0 * std::f64::consts::PI * mesh_hz / pair.teeth[1];
    ([omega_2 * pair.teeth[1] / pair.teeth[0], omega_2], pair.torque_1_nm * pair.teeth[1] / (pair.teeth[0] * omega_2))
}

/// What the case needs of the pair: the teeth and T₁ (N·m).
struct Pair {
    teeth: [f64; 2],
    torque_1_nm: f64,
}

/// The per-communication-step record of one lockstep run.
struct Run {
    /// µs of each fmi2DoStep, and of the `advance` beside it.
    through_the_api: Vec<f64>,
    integration_alone: Vec<f64>,
    /// Per doStep: internal steps, quasi-static solves, contact evaluations (of the `advance`).
    steps: f64,
    solves: f64,
    evaluations: f64,
}

/// The brake case run both ways in lockstep: at each communication step one fmi2DoStep through
/// the C entry points, then one `advance` of the dynamics kept beside it, each fed back from its
/// own ω₂. Timed one right after the other, the pair shares the machine's state (clock,
/// caches, a neighbour's load): their difference is the doStep's own cost. Each gear's
/// `inertia_i` is `inertia_factor` times its FE value (1: the FMU's default; 2: a gear on a
/// shaft, the real-time table's "×2"). With `friction` > 0 both carry tooth friction of that
/// coefficient, the dynamics with the regularization the FMU set (its `friction_regularization`).
fn lockstep(
    u: &Unpacked,
    pair: &Pair,
    mesh_hz: f64,
    h: f64,
    inertia_factor: f64,
    friction: f64,
) -> Result<Run, String> {
    let ModelKind::PmorHertz(model) = &u.file.model else { return Err("not a PMOR-Hertz FMU".into()) };
    let (omega, brake) = brake_case(pair, mesh_hz);
    // The integration alone: one dynamics object for the whole run, as the FMU's defaults make it.
    let place = gearfmu::contact::mesh_kinematics::PairPlacement::new(&model.pair);
    let damping = model.damping(model.modal_damping_ratio, model.shape_damping_ratio);
    let fe_inertia = [model.gears[0].polar_inertia_kgm2, model.gears[1].polar_inertia_kgm2];
    let inertia = fe_inertia.map(|j| inertia_factor * j);
    let added = [inertia[0] - fe_inertia[0], inertia[1] - fe_inertia[1]];
    let mut dynamics = PmorDynamics::new(model, &place, damping, added);
    dynamics.mesh_damping_n_s_per_m = model.mesh_damper_n_s_per_m(model.pair.mesh_damping_ratio, inertia);
    let mut s = dynamics.start_state([0.0; 2], omega, [pair.torque_1_nm, -brake * omega[1]])?;
    let counts = |d: &PmorDynamics| d.condensed().map_or((0, 0), |q| q.counts.get());
    // The FMU, in process.
    let name = CString::new("step-path").unwrap();
    let guid = CString::new(u.file.guid.clone()).unwrap();
    let uri = CString::new(format!("file://{}", u.dir.display())).unwrap();
    let callbacks = fmi2CallbackFunctions {
        logger: Some(fmi_sys::fmi2::logger::callback_logger_handler),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::null_mut(),
    };
    let c = unsafe {
        fmi2Instantiate(name.as_ptr(), fmi2Type_fmi2CoSimulation, guid.as_ptr(), uri.as_ptr(), &callbacks, 0, 0)
    };
    if c.is_null() {
        return Err("fmi2Instantiate failed".into());
    }
    let vr = |n: &str| value_reference(n).unwrap();
    let ok = |status: fmi2Status, what: &str| {
        if status == fmi2Status_fmi2OK {
            Ok(())
        } else {
            Err(format!("{what} returned {status}"))
        }
    };
    let result = (|| {
        ok(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), "fmi2SetupExperiment")?;
        ok(fmi2EnterInitializationMode(c), "fmi2EnterInitializationMode")?;
        let start = [
            vr("w_1_start"),
            vr("w_2_start"),
            vr("tau_1"),
            vr("tau_2"),
            vr("inertia_1"),
            vr("inertia_2"),
            vr("friction_coefficient"),
        ];
        let values = [omega[0], omega[1], pair.torque_1_nm, -brake * omega[1], inertia[0], inertia[1], friction];
        ok(fmi2SetReal(c, start.as_ptr(), start.len(), values.as_ptr()), "fmi2SetReal")?;
        ok(fmi2ExitInitializationMode(c), "fmi2ExitInitializationMode")?;
        if friction > 0.0 {
            let mut regularization = 0.0;
            ok(fmi2GetReal(c, &vr("friction_regularization"), 1, &mut regularization), "fmi2GetReal")?;
            dynamics.friction = Some(SlidingFriction { coefficient: friction, regularization_m_per_s: regularization });
            s = dynamics.start_state([0.0; 2], omega, [pair.torque_1_nm, -brake * omega[1]])?;
        }
        let (inputs, w2_ref) = ([vr("tau_1"), vr("tau_2")], vr("w_2"));
        let n = (END_S / h).round() as usize;
        let mut run = Run {
            through_the_api: Vec::with_capacity(n),
            integration_alone: Vec::with_capacity(n),
            steps: 0.0,
            solves: 0.0,
            evaluations: 0.0,
        };
        let before = counts(&dynamics);
        let mut w2 = omega[1];
        // As the FMU does, the settling to new torques books against the stored energy the last
        // call returned instead of evaluating the state again.
        let mut stored_j = None;
        for k in 0..n {
            let torques = [pair.torque_1_nm, -brake * w2];
            ok(fmi2SetReal(c, inputs.as_ptr(), 2, torques.as_ptr()), "fmi2SetReal")?;
            let tick = Instant::now();
            let status = fmi2DoStep(c, k as f64 * h, h, 1);
            run.through_the_api.push(tick.elapsed().as_secs_f64() * 1e6);
            ok(status, "fmi2DoStep")?;
            ok(fmi2GetReal(c, &w2_ref, 1, &mut w2), "fmi2GetReal")?;

            let own_w2 = dynamics.port(1, &s)?.1;
            run.steps += (h / dynamics.angular_step_bound_s(&s).min(model.max_step_s) - 1e-9).ceil();
            let tick = Instant::now();
            let end =
                dynamics.advance_knowing(&mut s, [pair.torque_1_nm, -brake * own_w2], h, model.max_step_s, stored_j)?;
            run.integration_alone.push(tick.elapsed().as_secs_f64() * 1e6);
            stored_j = end.map(|o| o.elastic_j + o.contact_j);
        }
        let after = counts(&dynamics);
        run.steps /= n as f64;
        run.solves = (after.1 - before.1) as f64 / n as f64;
        run.evaluations = (after.0 - before.0) as f64 / n as f64;
        Ok(run)
    })();
    fmi2FreeInstance(c);
    result
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut fmus: Vec<PathBuf> = args.iter().filter(|a| a.ends_with(".fmu")).map(PathBuf::from).collect();
    let torque_nm: Option<f64> =
        args.iter().find_map(|a| a.strip_prefix("--torque-nm=")).map(|t| t.parse().expect("--torque-nm=T: T₁ in N·m"));
    let inertia_factor: f64 = args
        .iter()
        .find_map(|a| a.strip_prefix("--inertia-factor="))
        .map_or(1.0, |t| t.parse().expect("--inertia-factor=F: inertia_i over the FE value"));
    let friction: f64 = args
        .iter()
        .find_map(|a| a.strip_prefix("--friction="))
        .map_or(0.0, |t| t.parse().expect("--friction=μ: the tooth friction coefficient"));
    if fmus.is_empty() {
        fmus = vec![root.join("out/KurokawaSpur.fmu"), root.join("out/SmallHelical.fmu")];
    }
    println!("T₁: {}", torque_nm.map_or("each pair's operating torque".to_string(), |t| format!("{t} N·m")));
    println!("inertia_i: {inertia_factor} × the FE value; tooth friction μ = {friction}");
    println!(
        "| FMU | mesh frequency | coupling | µs per doStep (C API) | µs per advance | overhead µs | internal steps | solves | evaluations | µs per solve | µs per evaluation | real-time factor (C API) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for fmu in &fmus {
        let u = match unpack(fmu) {
            Ok(u) => u,
            Err(e) => {
                println!("| {} | skipped: {e} |", fmu.display());
                continue;
            }
        };
        let ModelKind::PmorHertz(model) = &u.file.model else {
            println!("| {} | skipped: not a PMOR-Hertz FMU |", fmu.display());
            continue;
        };
        let pair = Pair {
            teeth: [model.pair.gear1.teeth as f64, model.pair.gear2.teeth as f64],
            torque_1_nm: torque_nm.unwrap_or(model.pair.operating_torque_nm),
        };
        let name = fmu.file_stem().and_then(|s| s.to_str()).unwrap_or("?");
        for (mesh_hz, h) in CASES {
            let row = (0..ROUNDS)
                .map(|_| lockstep(&u, &pair, mesh_hz, h, inertia_factor, friction))
                .collect::<Result<Vec<Run>, String>>();
            let row = row.map(|runs| {
                let all = |f: fn(&Run) -> &Vec<f64>| median(runs.iter().flat_map(|r| f(r).iter().copied()).collect());
                let differences = median(
                    runs.iter()
                        .flat_map(|r| r.through_the_api.iter().zip(&r.integration_alone).map(|(a, b)| a - b))
                        .collect(),
                );
                let last = &runs[runs.len() - 1];
                (
                    all(|r| &r.through_the_api),
                    all(|r| &r.integration_alone),
                    differences,
                    last.steps,
                    last.solves,
                    last.evaluations,
                )
            });
            match row {
                Ok((api, alone, overhead, substeps, solves, evaluations)) => println!(
                    "| {name} | {:.1} kHz | {:.0} µs | {api:.0} | {alone:.0} | {overhead:.1} | {substeps:.2} | {solves:.2} | {evaluations:.2} | {:.1} | {:.1} | {:.1} × |",
                    mesh_hz / 1e3,
                    h * 1e6,
                    alone / solves,
                    alone / evaluations,
                    api / (h * 1e6),
                ),
                Err(e) => println!("| {name} | {:.1} kHz | {:.0} µs | failed: {e} |", mesh_hz / 1e3, h * 1e6),
            }
        }
    }
    let _ = std::fs::remove_dir_all(std::env::temp_dir().join(format!("gearfmu-step-path-{}", std::process::id())));
}
