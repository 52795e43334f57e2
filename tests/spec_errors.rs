//! A malformed pair spec is refused with a message that names the field and the rule.

use gearfmu::gear::{GearPair, PairSpec};

const SPUR: &str = include_str!("../examples/kurokawa_spur.toml");

fn refused(toml: &str) -> String {
    match PairSpec::from_toml(toml).and_then(|s| GearPair::from_spec(&s)) {
        Ok(_) => panic!("spec accepted:\n{toml}"),
        Err(e) => e.to_string(),
    }
}

fn edit(from: &str, to: &str) -> String {
    assert!(SPUR.contains(from), "{from} not in the example");
    SPUR.replacen(from, to, 1)
}

#[test]
fn the_examples_are_accepted() {
    for text in [SPUR, include_str!("../examples/kurokawa_helical.toml")] {
        GearPair::from_spec(&PairSpec::from_toml(text).unwrap()).unwrap();
    }
}

#[test]
fn unknown_key_is_named() {
    let e = refused(&edit("module_mm = 6.0", "module_mm = 6.0\nmodul_mm = 6.0"));
    assert!(e.contains("unknown field `modul_mm`"), "{e}");
}

#[test]
fn zero_or_negative_teeth() {
    let e = refused(&edit("teeth = 21", "teeth = 0"));
    assert!(e.contains("gear1.teeth") && e.contains("positive integer"), "{e}");
    let e = refused(&edit("teeth = 31", "teeth = -31"));
    assert!(e.contains("gear2.teeth") && e.contains("positive integer"), "{e}");
}

#[test]
fn undercut_is_refused() {
    // z = 12 at 20° without profile shift: the rack cuts below the interference point.
    let e = refused(&edit("teeth = 21", "teeth = 12"));
    assert!(e.contains("gear1.teeth") && e.contains("undercuts"), "{e}");
    // …unless the spec says it is wanted: 14/14 teeth are undercut at 20° (z < 2/sin²α ≈ 17.1)
    // but mesh without tip interference (√(r_a² − r_b²) = 27.3 mm < a·sin α = 28.7 mm).
    let both_14 = edit("teeth = 21", "teeth = 14").replacen("teeth = 31", "teeth = 14", 1);
    let e = refused(&both_14);
    assert!(e.contains("undercuts"), "{e}");
    let allowed = both_14.replace("teeth = 14", "teeth = 14\nallow_undercut = true");
    let accepted = PairSpec::from_toml(&allowed).and_then(|s| GearPair::from_spec(&s));
    assert!(accepted.is_ok(), "{:?}", accepted.err());
}

#[test]
fn contact_ratio_below_one_is_refused() {
    // Pulling the gears 5 mm apart shortens the path of contact below one base pitch.
    let e = refused(&edit("face_width_mm = 15.0", "face_width_mm = 15.0\ncenter_distance_mm = 161.0"));
    assert!(e.contains("mounting.center_distance_mm") && e.contains("contact ratio"), "{e}");
}

#[test]
fn tip_interference_is_refused() {
    // A long-addendum rack on a 21-tooth pinion meshing a 150-tooth wheel: the wheel's tip reaches
    // below the pinion's form circle.
    let text =
        edit("addendum_coefficient = 1.0", "addendum_coefficient = 1.2").replacen("teeth = 31", "teeth = 150", 1);
    let e = refused(&text);
    assert!(e.contains("gear2.teeth") && e.contains("tip interference"), "{e}");
}

#[test]
fn center_distance_that_cannot_mesh() {
    let e = refused(&edit("face_width_mm = 15.0", "face_width_mm = 15.0\ncenter_distance_mm = 155.0"));
    assert!(e.contains("mounting.center_distance_mm") && e.contains("cannot mesh"), "{e}");
    let e = refused(&edit("face_width_mm = 15.0", "face_width_mm = 15.0\ncenter_distance_mm = 140.0"));
    assert!(e.contains("mounting.center_distance_mm"), "{e}");
}

#[test]
fn non_physical_material_and_sizes() {
    assert!(refused(&edit("poisson_ratio = 0.3", "poisson_ratio = 0.5")).contains("material.poisson_ratio"));
    assert!(refused(&edit("face_width_mm = 15.0", "face_width_mm = -15.0")).contains("mounting.face_width_mm"));
    assert!(refused(&edit("bore_radius_mm = 20.0", "bore_radius_mm = 60.0")).contains("gear1.bore_radius_mm"));
}

#[test]
fn tip_edge_radius_must_fit_on_the_tip_land() {
    let spec = |v: &str| edit("bore_radius_mm = 25.0", &format!("bore_radius_mm = 25.0\ntip_edge_radius_mm = {v}"));
    let message = refused(&spec("2.5"));
    assert!(message.contains("gear2.tip_edge_radius_mm") && message.contains("half the tip land"), "{message}");
    assert!(refused(&spec("0.0")).contains("gear2.tip_edge_radius_mm"));
    let pair = GearPair::from_spec(&PairSpec::from_toml(&spec("0.3")).unwrap()).unwrap();
    assert_eq!(pair.gear2.tip_edge_radius_m, 0.3e-3);
    // The default: 0.1 × m_n.
    assert!(
        (GearPair::from_spec(&PairSpec::from_toml(SPUR).unwrap()).unwrap().gear1.tip_edge_radius_m - 0.6e-3).abs()
            < 1e-15
    );
}

#[test]
fn yield_strength_must_be_positive() {
    let spec = edit("density_kg_m3 = 7700.0", "density_kg_m3 = 7700.0\nyield_strength_mpa = -5.0");
    assert!(refused(&spec).contains("material.yield_strength_mpa"));
}

/// `[friction]`: a constant μ, or ISO/TR 14179-2's law with its inputs (X_L defaulting to mineral
/// oil's 1.0); the two laws' fields are not mixed, and each rule names its field.
#[test]
fn friction_law_fields() {
    let with = |section: &str| format!("{SPUR}\n[friction]\n{section}\n");
    let law = "law = \"iso-tr-14179-2\"\noil_viscosity_mpa_s = 30.0\nroughness_ra_um = 0.5";
    let pair = GearPair::from_spec(&PairSpec::from_toml(&with(law)).unwrap()).unwrap();
    let flanks = pair.lubricated_flanks.expect("the law");
    assert_eq!((flanks.oil_viscosity_mpa_s, flanks.roughness_ra_um, flanks.lubricant_factor), (30.0, 0.5, 1.0));
    assert_eq!(pair.friction_coefficient, 0.0);
    let e = refused(&with(&format!("{law}\ncoefficient = 0.05")));
    assert!(e.contains("friction.coefficient") && e.contains("left out"), "{e}");
    let e = refused(&with("law = \"iso-tr-14179-2\"\noil_viscosity_mpa_s = 30.0"));
    assert!(e.contains("friction.roughness_ra_um") && e.contains("required"), "{e}");
    let e = refused(&with(&format!("{law}\nlubricant_factor = 5.0")));
    assert!(e.contains("friction.lubricant_factor") && e.contains("[0.1, 2]"), "{e}");
    let e = refused(&with("coefficient = 0.05\nroughness_ra_um = 0.5"));
    assert!(e.contains("friction.roughness_ra_um") && e.contains("law"), "{e}");
    let e = refused(&with("law = \"iso\""));
    assert!(e.contains("law"), "{e}");
}
