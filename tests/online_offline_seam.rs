//! The seam of design §2: the FMU's instantiate/step path (the FMI layer, the FMU glue, the
//! run-time models and the model file) never reaches into the offline FE code, and never builds a
//! mesh law (that is fmu-build's job). A dependency check over the online modules' sources.

const ONLINE: [&str; 18] = [
    "src/fmi2/mod.rs",
    "src/fmi2/instance.rs",
    "src/fmi2/exports.rs",
    "src/fmi2/resource_uri.rs",
    "src/dynamics/fmu.rs",
    "src/dynamics/mesh_law.rs",
    "src/model_file.rs",
    "src/dynamics/pmor/mod.rs",
    "src/dynamics/pmor/model.rs",
    "src/dynamics/pmor/equations.rs",
    "src/dynamics/pmor/contact.rs",
    "src/dynamics/pmor/interpolation.rs",
    "src/dynamics/pmor/linear.rs",
    "src/dynamics/pmor/condensation.rs",
    "src/dynamics/pmor/contact_law.rs",
    "src/dynamics/element_parameters.rs",
    "src/dynamics/any_model.rs",
    "src/dynamics/elements.rs",
];

/// The source without comment lines (comments may name the offline code they refer to).
fn code_only(source: &str) -> String {
    source.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n")
}

#[test]
fn the_online_path_uses_no_offline_code() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for file in ONLINE {
        let text = code_only(&std::fs::read_to_string(root.join(file)).unwrap());
        for forbidden in [
            "crate::fe",
            "fe::",
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
    for file in &ONLINE[..4] {
        let text = code_only(&std::fs::read_to_string(root.join(file)).unwrap()).to_lowercase();
        for word in ["gear", "tooth", "mesh_"] {
            assert!(!text.contains(word), "{file} mentions {word}: the FMI layer must stay generic");
        }
    }
}
