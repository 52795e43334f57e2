//! Memory is a limit of the offline build (issue 40): the build estimates its peak once the gears
//! are meshed and their factors analysed, runs the gears one after the other where side by side
//! would not fit, and refuses — naming the figure and the option — what fits neither way. The
//! evidence here is the build's own determinism: the schedule must not change the reduced pair.
//! (The estimate against the measured peak of the four examples is in BENCHMARKS §14.)

#[allow(dead_code)]
mod common;

use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::rom::build_memory::Schedule;
use gearfmu::rom::dynamic_reductor::{build_dynamic_model, DynamicBuildOptions};

#[test]
fn a_build_that_does_not_fit_runs_the_gears_one_after_the_other_or_is_refused_with_the_figure() {
    let pair = common::kurokawa_spur();
    let mesh = MeshSpec::default();
    let small = DynamicBuildOptions { modes: 6, angles: 8, ..Default::default() };
    let unlimited = DynamicBuildOptions { memory_limit_bytes: Some(f64::INFINITY), ..small.clone() };
    let (side_by_side, report) = build_dynamic_model(&pair, &mesh, &unlimited, |_| {}).unwrap();
    assert_eq!(report.schedule, Schedule::SideBySide);
    let (one, side) = (report.memory.peak(Schedule::OneAfterTheOther), report.memory.peak(Schedule::SideBySide));
    println!("estimated peak: {:.3} GB side by side, {:.3} GB one after the other", side / 1e9, one / 1e9);
    assert!(one < side, "one gear at a time needs less");

    // Between the two: one after the other, and the same reduced pair, bit for bit.
    let between = DynamicBuildOptions { memory_limit_bytes: Some(0.5 * (one + side)), ..small.clone() };
    let (sequential, report) = build_dynamic_model(&pair, &mesh, &between, |_| {}).unwrap();
    assert_eq!(report.schedule, Schedule::OneAfterTheOther);
    assert!(sequential == side_by_side, "the schedule changed the reduced pair");

    // Below both: refused before the FE stage, with the estimate and the way out.
    let stages = std::sync::Mutex::new(Vec::new());
    let tight = DynamicBuildOptions { memory_limit_bytes: Some(0.9 * one), ..small };
    let refusal = build_dynamic_model(&pair, &mesh, &tight, |m| stages.lock().unwrap().push(m)).unwrap_err();
    println!("{refusal}");
    assert!(refusal.contains(&format!("{:.1} GB", one / 1e9)), "names the estimate: {refusal}");
    assert!(refusal.contains("--memory-limit-gb") && refusal.contains("[mesh]"), "names the options: {refusal}");
    let stages = stages.into_inner().unwrap();
    assert!(
        stages.iter().all(|s| s.ends_with("FE model")),
        "refused before any factorization, eigen or attachment stage: {stages:?}"
    );
}
