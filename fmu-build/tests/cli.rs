//! Every value the command line or a spec can carry is range-checked before any work, and the
//! message names the field (or option) the user set and the rule it broke (issue 25, item 4).
//! Each test runs the real binary on a value a user once got past it.

use std::path::PathBuf;
use std::process::Command;

const SPUR: &str = include_str!("../../examples/kurokawa_spur.toml");

/// A unique scratch folder for one test, removed when the test ends.
struct Scratch(PathBuf);

impl Scratch {
    fn join(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn scratch(name: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("gearfmu-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    Scratch(dir)
}

/// Runs fmu-build; returns (success, stdout + stderr).
fn fmu_build(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_fmu-build")).args(args).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.success(), text)
}

/// The spur example with one edit, written to a scratch file (removed with the guard).
fn spec_with(name: &str, from: &str, to: &str) -> (Scratch, PathBuf) {
    assert!(SPUR.contains(from), "{from} not in the example");
    let dir = scratch(name);
    let path = dir.join("spec.toml");
    std::fs::write(&path, SPUR.replacen(from, to, 1)).unwrap();
    (dir, path)
}

fn refused(args: &[&str], needles: &[&str]) -> String {
    let (ok, text) = fmu_build(args);
    assert!(!ok, "accepted: fmu-build {}\n{text}", args.join(" "));
    for n in needles {
        assert!(text.contains(n), "`{n}` missing from the message of fmu-build {}:\n{text}", args.join(" "));
    }
    text
}

fn spec_refused(name: &str, from: &str, to: &str, needles: &[&str]) -> String {
    let (_dir, spec) = spec_with(name, from, to);
    refused(&["inspect", spec.to_str().unwrap()], needles)
}

const EXAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/kurokawa_spur.toml");

#[test]
fn p_en_above_one_is_refused_naming_the_option_and_its_range() {
    refused(&["build", EXAMPLE, "-o", "x.fmu", "--p-en", "1.5"], &["--p-en", "(0, 1]", "1.5"]);
    refused(&["ste", EXAMPLE, "--p-en", "0"], &["--p-en", "(0, 1]"]);
    refused(&["ste", EXAMPLE, "--friction", "1.5"], &["--friction", "[0, 1)", "1.5"]);
    refused(&["ste", EXAMPLE, "--friction", "-0.1"], &["--friction", "[0, 1)"]);
}

/// The standard PMOR reference is the paper's model (standard CMS gears, RK4 on every
/// coordinate): an option it would ignore is refused, naming it, before any work.
#[test]
fn options_the_reference_model_would_ignore_are_refused_naming_them() {
    let dir = scratch("penalty-options");
    let out = dir.join("reference.fmu");
    let out = out.to_str().unwrap();
    let text = refused(
        &["build", EXAMPLE, "-o", out, "--model", "pmor-penalty", "--integrator", "verlet", "--depth-mm", "2"],
        &["--integrator", "--depth-mm", "do not apply to --model pmor-penalty"],
    );
    assert!(!text.contains("--dynamics") && !text.contains("--p-en,"), "{text}");
    refused(&["build", EXAMPLE, "-o", out, "--model", "pmor-penalty", "--dynamics", "full"], &["--dynamics"]);
    refused(&["build", EXAMPLE, "-o", out, "--model", "pmor-penalty", "--p-en", "0.99"], &["--p-en"]);
    assert!(!std::path::Path::new(out).exists(), "nothing is written");
}

#[test]
fn zero_modes_are_refused_naming_the_option_and_its_range() {
    refused(&["build", EXAMPLE, "-o", "x.fmu", "--modes", "0"], &["--modes", "1..=200"]);
}

#[test]
fn a_negative_rom_torque_is_refused_as_a_value_not_an_unknown_flag() {
    let text =
        refused(&["build", EXAMPLE, "-o", "x.fmu", "--rom-torques-nm", "-100"], &["--rom-torques-nm", "positive"]);
    assert!(!text.contains("unexpected argument"), "{text}");
}

#[test]
fn a_rom_torque_past_the_yield_torque_is_refused_before_the_build() {
    let dir = scratch("rom-yield");
    let out = dir.join("x.fmu");
    // The Kurokawa spur pair yields at 1956 N·m (closed_forms::rating).
    refused(
        &["build", EXAMPLE, "-o", out.to_str().unwrap(), "--rom-torques-nm", "5000"],
        &["--rom-torques-nm", "yield torque"],
    );
}

#[test]
fn an_output_into_a_missing_folder_is_refused_and_no_folder_is_made() {
    let scratch = scratch("missing-folder");
    let dir = scratch.join("not-there");
    let out = dir.join("x.fmu");
    refused(&["build", EXAMPLE, "-o", out.to_str().unwrap(), "--model", "lumped"], &["does not exist"]);
    assert!(!dir.exists(), "fmu-build made {}", dir.display());
}

#[test]
fn a_missing_spec_file_prints_the_os_error_once() {
    let text = refused(&["inspect", "/nonexistent/spec.toml"], &["cannot read spec file /nonexistent/spec.toml"]);
    assert_eq!(text.matches("No such file").count(), 1, "{text}");
}

#[test]
fn a_hundred_thousand_teeth_are_refused_naming_the_field() {
    spec_refused("teeth", "teeth = 31", "teeth = 100000", &["gear2.teeth", "at most 500", "100000"]);
}

#[test]
fn a_yield_strength_of_one_megapascal_is_refused_naming_the_field() {
    spec_refused(
        "yield",
        "density_kg_m3 = 7700.0",
        "density_kg_m3 = 7700.0\nyield_strength_mpa = 1.0",
        &["material.yield_strength_mpa", "[20, 5000] MPa"],
    );
}

#[test]
fn a_module_of_1e200_is_refused_with_a_short_number() {
    let text = spec_refused(
        "module",
        "module_mm = 6.0",
        "module_mm = 1e200",
        &["rack.module_mm", "[0.1, 100] mm", "1.00000e200"],
    );
    assert!(!text.contains("0000000000"), "a 200-digit number in the message:\n{text}");
}

#[test]
fn a_short_addendum_is_reported_against_the_addendum_not_an_unset_center_distance() {
    let text = spec_refused(
        "addendum",
        "addendum_coefficient = 1.0",
        "addendum_coefficient = 0.55",
        &["rack.addendum_coefficient", "contact ratio"],
    );
    assert!(!text.contains("center_distance_mm`"), "{text}");
}

#[test]
fn a_large_profile_shift_is_reported_against_the_profile_shift() {
    let text =
        spec_refused("shift", "teeth = 21", "teeth = 21\nprofile_shift = 1.2", &["gear1.profile_shift", "x₁ = 1.2"]);
    assert!(!text.contains("gear2.teeth"), "{text}");
}

#[test]
fn an_operating_torque_past_the_yield_torque_is_refused_naming_the_field() {
    spec_refused("operating", "torque_nm = 250.0", "torque_nm = 3000.0", &["operating.torque_nm", "yield"]);
}

#[test]
fn linearize_refuses_a_damping_ratio_of_one() {
    refused(&["linearize", "x.fmu", "--mesh-damping-ratio", "1.0"], &["--mesh-damping-ratio", "[0, 1)"]);
}

#[test]
fn mesh_counts_are_range_checked() {
    refused(&["mesh", EXAMPLE, "--across", "0"], &["--across", "1..=64"]);
    refused(&["mesh", EXAMPLE, "--slices", "1000"], &["--slices", "1..=64"]);
}

/// The spec's defaults reach what the user runs: `inspect` prints the operating, rated and yield
/// torques (the example sets 250 N·m; a third of the yield torque is the rating), and the gear
/// loss factor of the library's closed form (`closed_forms::gear_loss`) with its efficiency.
#[test]
fn inspect_prints_the_operating_point() {
    let (ok, text) = fmu_build(&["inspect", EXAMPLE]);
    assert!(ok, "{text}");
    let line = text.lines().find(|l| l.contains("torque on gear 1")).expect("a torque line");
    assert!(line.contains("operating 250 N·m"), "{line}");
    let spec = gearfmu::gear::PairSpec::load(std::path::Path::new(EXAMPLE)).unwrap();
    let h_v = gearfmu::closed_forms::gear_loss::gear_loss_factor(&gearfmu::gear::GearPair::from_spec(&spec).unwrap())
        .unwrap();
    let line = text.lines().find(|l| l.contains("gear loss factor")).expect("a gear loss line");
    assert!(line.contains(&format!("H_V {h_v:.4}")), "{line}");
    assert!(line.contains(&format!("{:.2} % at μ = 0.05", 100.0 * (1.0 - 0.05 * h_v))), "{line}");
}

/// `inspect --from-fmu` reads back the law a lumped FMU carries (evidence: the law `inspect`
/// makes itself from the same spec, the same JSON to the byte; `--mesh-law analytic` both ways,
/// so no FE work); an FMU of another pair is refused, naming the file.
#[test]
fn inspect_from_a_lumped_fmu_dumps_the_law_it_carries_and_refuses_another_pairs() {
    let dir = scratch("from-fmu");
    let spur = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/kurokawa_spur.toml");
    let helical = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/kurokawa_helical.toml");
    let (fmu, made, carried) = (dir.join("lumped.fmu"), dir.join("made.json"), dir.join("carried.json"));
    let fmu = fmu.to_str().unwrap();
    let (ok, text) = fmu_build(&["build", spur, "-o", fmu, "--model", "lumped", "--mesh-law", "analytic"]);
    assert!(ok, "{text}");
    let (ok, text) = fmu_build(&["inspect", spur, "--mesh-law", "analytic", "--json", made.to_str().unwrap()]);
    assert!(ok, "{text}");
    let (ok, text) = fmu_build(&["inspect", spur, "--from-fmu", fmu, "--json", carried.to_str().unwrap()]);
    assert!(ok, "{text}");
    let read = |p: &PathBuf| std::fs::read_to_string(p).unwrap();
    assert_eq!(read(&made), read(&carried), "the FMU's law differs from the one inspect makes");
    refused(&["inspect", helical, "--from-fmu", fmu], &["was not built from this spec"]);
}
