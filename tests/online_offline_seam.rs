//! The seam of design §2: the FMU's instantiate/step path (the FMI layer, the FMU glue, the
//! run-time models and the model file) never reaches into the offline FE code, and never builds a
//! mesh law (that is fmu-build's job).
//!
//! The online files are derived from the code, not listed by hand: every source file the FMI
//! entry points (`src/fmi2/exports.rs`) reach through the items they name, and the methods their
//! types' own modules give them (`scripts/import_circles.py --reachable-from`, the same reading
//! of the sources as the CI's circle check). An online file that imports `fe::` or `rom::` makes
//! those files online, and the test fails naming them.

use std::path::Path;
use std::process::Command;

/// Files the step path must reach (the derivation is not vacuous): the entry points, both
/// gear-pair models' steps (the PMOR-Hertz integrators are methods in their own files), the
/// penalty reference's contact, the drivetrain elements and the model file.
const ANCHORS: [&str; 9] = [
    "src/fmi2/exports.rs",
    "src/fmu/gear_pair.rs",
    "src/dynamics/lumped.rs",
    "src/dynamics/pmor/integrator.rs",
    "src/dynamics/pmor/quasi_static.rs",
    "src/dynamics/pmor/penalty.rs",
    "src/dynamics/pmor/linear.rs",
    "src/drivetrain/elements.rs",
    "src/model_file.rs",
];

/// Offline code: the FE model and the reductors, and the closed forms that build a mesh law or
/// a stiffness table (the FMU reads tables, it does not make them).
const OFFLINE_FILES: [&str; 4] =
    ["src/fe/", "src/rom/", "src/closed_forms/mesh_stiffness.rs", "src/closed_forms/iso6336.rs"];

fn online_files(root: &Path) -> Vec<String> {
    let out = Command::new("python3")
        .current_dir(root)
        .args(["scripts/import_circles.py", "--reachable-from", "src/fmi2/exports.rs"])
        .output()
        .expect("python3 runs scripts/import_circles.py (the standard library only)");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap().lines().map(str::to_string).collect()
}

/// The source without comment lines (comments may name the offline code they refer to).
fn code_only(source: &str) -> String {
    source.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n")
}

#[test]
fn the_online_path_uses_no_offline_code() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let online = online_files(root);
    println!("{} online files: {}", online.len(), online.join(" "));
    for anchor in ANCHORS {
        assert!(online.iter().any(|f| f == anchor), "{anchor} is on the step path but not derived: {online:?}");
    }
    let leaks: Vec<&String> = online.iter().filter(|f| OFFLINE_FILES.iter().any(|o| f.starts_with(o))).collect();
    assert!(leaks.is_empty(), "the FMU's step path reaches offline code: {leaks:?}");
    for file in &online {
        let text = code_only(&std::fs::read_to_string(root.join(file)).unwrap());
        for forbidden in [
            "crate::fe",
            "fe::",
            "crate::rom",
            "rom::",
            "mesh_stiffness::",
            "static_deflection_table",
            "LumpedMesh::from_pair",
            "gear_mesh",
            "dynamic_reductor",
            "attachment",
            "statics::",
        ] {
            assert!(!text.contains(forbidden), "{file} refers to offline code ({forbidden})");
        }
    }
    // The FMI layer knows nothing about gears.
    for file in online.iter().filter(|f| f.starts_with("src/fmi2/")) {
        let text = code_only(&std::fs::read_to_string(root.join(file)).unwrap()).to_lowercase();
        for word in ["gear", "tooth", "mesh_"] {
            assert!(!text.contains(word), "{file} mentions {word}: the FMI layer must stay generic");
        }
    }
}
