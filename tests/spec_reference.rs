//! The spec reference (docs/reference/spec.md) documents every field a spec can hold (issue 25):
//! a spec with every optional field set is serialized, and each of its keys, written
//! `section.key` as the reference writes it, must appear there in backticks. A field added to
//! the spec types without a line in the reference fails here; so does a field renamed in one
//! place only. The struct literals below list every field, so a new field is also a compile
//! error until it is added here (and therefore checked).

use gearfmu::fe::gear_mesh::{MeshSpec, ProfileGrading};
use gearfmu::gear::modification::{ModificationSpec, ReliefShape};
use gearfmu::gear::spec::{
    FrictionLawSpec, FrictionSpec, GearSpec, HelixHand, LumpedSpec, MaterialSpec, MountingSpec, OperatingSpec, RackSpec,
};
use gearfmu::gear::{HertzContact, PairSpec};

fn gear(teeth: i64) -> GearSpec {
    GearSpec {
        teeth,
        profile_shift: 0.1,
        bore_radius_mm: 20.0,
        inertia_kgm2: Some(0.01),
        allow_undercut: true,
        tip_edge_radius_mm: Some(0.5),
        modification: Some(ModificationSpec {
            tip_relief_um: 10.0,
            tip_relief_length_mm: 5.0,
            tip_relief_shape: ReliefShape::Parabolic,
            root_relief_um: 5.0,
            root_relief_length_mm: 3.0,
            root_relief_shape: ReliefShape::Parabolic,
            profile_crowning_um: 2.0,
            lead_crowning_um: 8.0,
            helix_slope_um: 3.0,
            end_relief_um: 10.0,
            end_relief_length_mm: 2.0,
        }),
    }
}

/// Every field set, none left to its serde default (None would not be serialized).
fn full_spec() -> PairSpec {
    PairSpec {
        name: "Full".into(),
        rack: RackSpec {
            module_mm: 6.0,
            pressure_angle_deg: 20.0,
            helix_angle_deg: 10.0,
            helix_hand: HelixHand::Left,
            addendum_coefficient: 1.0,
            dedendum_coefficient: 1.25,
            cutter_tip_radius_coefficient: 0.38,
        },
        material: MaterialSpec {
            youngs_modulus_gpa: 200.0,
            poisson_ratio: 0.3,
            density_kg_m3: 7700.0,
            yield_strength_mpa: 1000.0,
        },
        mounting: MountingSpec {
            face_width_mm: 15.0,
            center_distance_mm: Some(156.0),
            backlash_mm: 0.1,
            mesh_damping_ratio: 0.05,
            misalignment_um: 12.0,
        },
        gear1: gear(21),
        gear2: gear(31),
        lumped: LumpedSpec { hertz_contact: HertzContact::Weber },
        operating: OperatingSpec { torque_nm: Some(250.0) },
        // Both laws' fields, though a valid spec sets one law's (the walk needs every key).
        friction: FrictionSpec {
            coefficient: 0.05,
            law: FrictionLawSpec::IsoTr14179_2,
            oil_viscosity_mpa_s: Some(30.0),
            roughness_ra_um: Some(0.5),
            lubricant_factor: Some(1.0),
        },
        mesh: MeshSpec {
            elements_across_tooth: 4,
            elements_along_profile: 8,
            elements_in_rim: 4,
            axial_slices: 4,
            profile_grading: ProfileGrading::Uniform,
        },
    }
}

#[test]
fn every_spec_field_is_in_the_spec_reference() {
    let reference_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/reference/spec.md");
    let reference = std::fs::read_to_string(&reference_path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", reference_path.display()));
    let value = toml::Value::try_from(full_spec()).unwrap();
    let mut keys = Vec::new();
    for (section, entry) in value.as_table().unwrap() {
        match entry.as_table() {
            Some(fields) => {
                for (k, v) in fields {
                    match v.as_table() {
                        // A sub-table (`[gearN.modification]`): its keys, one level down.
                        Some(sub) => keys.extend(sub.keys().map(|s| format!("{section}.{k}.{s}"))),
                        None => keys.push(format!("{section}.{k}")),
                    }
                }
            }
            None => keys.push(section.clone()),
        }
    }
    assert!(keys.len() > 30, "only {} keys: the walk is broken", keys.len());
    let missing: Vec<&String> = keys.iter().filter(|k| !reference.contains(&format!("`{k}`"))).collect();
    assert!(missing.is_empty(), "fields missing from docs/reference/spec.md (as `section.key`): {missing:?}");
}

/// The full spec parses back (the reference's keys are the parser's keys, not a translation).
#[test]
fn the_full_spec_round_trips_through_toml() {
    let text = toml::to_string(&full_spec()).unwrap();
    assert_eq!(PairSpec::from_toml(&text).unwrap(), full_spec());
}
