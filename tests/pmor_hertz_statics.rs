//! PMOR-Hertz static contact analyses of the Kurokawa spur pair on the coarse default mesh,
//! against independent references:
//! - ISO 6336-1's single stiffness c′ in the single-contact zone (392 N/mm, within 6 %);
//! - the lumped model (potential-energy teeth on the analytic profile + the same Weber contact,
//!   no FE), compared zone by zone: the mean STE over the single-contact positions and over the
//!   double-contact positions separately (a mean over the whole pitch hides differences of
//!   opposite sign in the two zones); a regression guard on measured figures, see below;
//! - ISO 6336-1: the mean mesh stiffness against c_γα (with ISO's (w/100)^0.25 below 100 N/mm).
//!   It is met at 22 N/mm (within 20 %). At 392 N/mm both this model and the lumped one come out
//!   ≈ 0.8 × c_γα: ISO's c_γα = c′(0.75ε_α + 0.25) implies a double-contact zone 1.75× as stiff
//!   as c′, while the FE pair stiffness (this model and the penalty baseline alike) falls toward
//!   the ends of the path. That ratio is reported here, not asserted; see BENCHMARKS.md;
//! - the kinematics of the involute pair: at light load the single-contact share of a pitch is
//!   2 − ε_α, with ε_α from the textbook formula written out here (tip radii, base radii, centre
//!   distance), not from the path ends the code uses; under load it shrinks (deflection brings
//!   the next pair in early).
//!
//! Not asserted, because it would be no evidence: the torque balance Σ P·arm = T₁. The Newton
//! solver stops on exactly that residual (FORCE_TOLERANCE in rom::statics), so checking it only
//! re-reads the stopping rule. The penalty baseline ("standard PMOR") on this coarse flank is no
//! reference either (its node-to-surface error makes its STE 1.7× PMOR-Hertz's here); it is
//! compared at the paper's flank resolution in BENCHMARKS.md ("Both methods at the paper's flank
//! resolution").

mod common;

use gearfmu::closed_forms::iso6336;
use gearfmu::contact::hertz::ApproachLaw;
use gearfmu::dynamics::lumped::LumpedMesh;
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::rom::reductor::ReducedGear;
use gearfmu::rom::statics::{ContactModel, StaticModel};
use std::f64::consts::PI;

fn spur() -> GearPair {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
    GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap()
}

/// ε_α of the spur pair from the textbook formula, written out from the spec's numbers
/// (examples/kurokawa_spur.toml: m 6 mm, α 20°, z 21/31, addendum 1·m, no profile shift, standard
/// centre distance): (√(r_a1² − r_b1²) + √(r_a2² − r_b2²) − a·sin α) / (π m cos α).
fn textbook_spur_contact_ratio(p: &GearPair) -> f64 {
    assert_eq!((p.gear1.teeth, p.gear2.teeth), (21, 31), "the spec changed: update the numbers here");
    let (m, alpha, z1, z2) = (6e-3, 20f64.to_radians(), 21.0, 31.0);
    let (ra1, ra2) = (m * (z1 / 2.0 + 1.0), m * (z2 / 2.0 + 1.0));
    let (rb1, rb2) = (m * z1 / 2.0 * alpha.cos(), m * z2 / 2.0 * alpha.cos());
    let a = m * (z1 + z2) / 2.0;
    ((ra1 * ra1 - rb1 * rb1).sqrt() + (ra2 * ra2 - rb2 * rb2).sqrt() - a * alpha.sin()) / (PI * m * alpha.cos())
}

fn reduce(p: &GearPair) -> [ReducedGear; 2] {
    common::reduce_pmor_hertz(p)
}

/// Per angle of the sweep: (STE, pairs in contact) of PMOR-Hertz and of the lumped law.
struct Sample {
    ste: f64,
    pairs: usize,
    lumped_ste: f64,
    lumped_pairs: u32,
}

#[test]
fn spur_static_transmission_error_zone_by_zone_against_the_lumped_model_iso_and_kinematics() {
    let p = spur();
    let hertz = reduce(&p);
    let model = StaticModel::new(&p, [&hertz[0], &hertz[1]], ContactModel::Hertz { law: ApproachLaw::Weber }).unwrap();
    let lumped = LumpedMesh::from_pair(&p).unwrap();
    let eps_alpha = textbook_spur_contact_ratio(&p);
    let pitch = 2.0 * PI / p.gear2.teeth as f64;
    let angles = 24;
    let b_mm = p.face_width_m * 1e3;
    let mut single_share = Vec::new();
    // Measured on this mesh (p_en 99.9 %, n_sv 28 / 24), PMOR-Hertz mean STE / lumped mean STE:
    //   22 N/mm:  single-contact zone 0.872 (2.092 vs 2.400 µm), double-contact zone 1.137;
    //   392 N/mm: single-contact zone 0.860 (33.93 vs 39.44 µm), double-contact zone 1.146.
    // The mean over the pitch (the old check, within 10 %) is 1.005 and 1.025: it hid a lumped
    // law 14 % softer than PMOR-Hertz in single contact and 13 % stiffer in double contact. These
    // differences are between two models, so the bands below are the measured figures ± 3 %, a
    // regression guard on them, not agreement: PMOR-Hertz's mean STE moves by +1.9 % from 8 to 24
    // flank rows (BENCHMARKS.md, "Penalty baseline under flank refinement") and by < 0.5 % with
    // p_en; the lumped table interpolates to 0.5 %. Which model is right in single contact is
    // settled by ISO c′ below (PMOR-Hertz 0.961 × c′; the lumped law is 17 % soft,
    // lumped_physics::weber_law_single_contact_stiffness_against_iso_6336_c_prime).
    let expected = [(22.0, 0.872, 1.137), (392.0, 0.860, 1.146)];
    for (specific_load, single_expected, double_expected) in expected {
        let c_gamma = iso6336::mesh_stiffness_c_gamma_alpha_at(&p, specific_load);
        // Table 4's specific load is per face width at the operating pitch point.
        let force = specific_load * b_mm;
        let torque = force * p.gear1.base_radius_m;
        let curve: Vec<Sample> = (0..angles)
            .map(|k| {
                let theta2 = pitch * (k as f64 + 0.5) / angles as f64;
                let case = model.solve(theta2, torque).unwrap();
                // The lumped law's roll at the same kinematic position: ξ = r_b2·θ₂ + (u_C − u_A).
                let roll = p.gear2.base_radius_m * theta2 + lumped.roll_offset_m;
                let n = lumped.drive.rows();
                let row = ((roll / p.base_pitch_m).rem_euclid(1.0) * n as f64).round() as usize % n;
                Sample {
                    ste: case.ste_m,
                    pairs: case.pairs_in_contact,
                    lumped_ste: lumped.drive.static_deflection(force, roll),
                    lumped_pairs: lumped.drive_pairs_under(0)[row],
                }
            })
            .collect();
        let mean = curve.iter().map(|c| c.ste).sum::<f64>() / angles as f64;
        let stiffness = force / (mean * 1e6) / b_mm; // N/(mm·µm)
        let single = curve.iter().filter(|c| c.pairs == 1).count() as f64 / angles as f64;
        let (min, max) = curve.iter().fold((f64::MAX, f64::MIN), |(a, b), c| (a.min(c.ste), b.max(c.ste)));
        println!(
            "{specific_load} N/mm: mean STE {:.3} µm, peak-to-peak {:.3} µm, stiffness {stiffness:.2} N/(mm·µm) \
             (ISO c_γα {c_gamma:.2}), single-contact share {single:.3} (2 − ε_α = {:.3}, textbook ε_α)",
            mean * 1e6,
            (max - min) * 1e6,
            2.0 - eps_alpha
        );
        // Zone by zone: positions where both models have the same number of pairs in contact.
        let zone = |pairs: usize| {
            let in_zone: Vec<&Sample> =
                curve.iter().filter(|c| c.pairs == pairs && c.lumped_pairs as usize == pairs).collect();
            let n = in_zone.len() as f64;
            let (a, b) = in_zone.iter().fold((0.0, 0.0), |(a, b), c| (a + c.ste, b + c.lumped_ste));
            (a / n, b / n, in_zone.len())
        };
        let disagree = curve.iter().filter(|c| c.pairs != c.lumped_pairs as usize).count();
        let ((s_fe, s_lu, s_n), (d_fe, d_lu, d_n)) = (zone(1), zone(2));
        println!(
            "    single-contact zone ({s_n} positions): PMOR-Hertz {:.3} µm, lumped {:.3} µm, ratio {:.3}; \
             double-contact zone ({d_n}): {:.3} vs {:.3} µm, ratio {:.3}; {disagree} positions where the pair \
             counts differ (zone ends) left out",
            s_fe * 1e6,
            s_lu * 1e6,
            s_fe / s_lu,
            d_fe * 1e6,
            d_lu * 1e6,
            d_fe / d_lu
        );
        assert!(s_n >= 4 && d_n >= 4, "too few positions in a zone: {s_n} single, {d_n} double");
        assert!((s_fe / s_lu / single_expected - 1.0).abs() < 0.03, "single zone ratio {}", s_fe / s_lu);
        assert!((d_fe / d_lu / double_expected - 1.0).abs() < 0.03, "double zone ratio {}", d_fe / d_lu);
        if specific_load >= 100.0 {
            // ISO 6336-1's single stiffness c′ (method B, C_M, C_B, E/E_st; ISO's loads ≥ 100 N/mm)
            // is the reference for the single-contact zone. Measured at 392 N/mm: 0.961. Within
            // 6 %: the default mesh (4/8/4) is about 5 % stiffer than the medium one (BENCHMARKS.md,
            // "Single-tooth compliance at the pitch point"), truncation at p_en 99.9 % < 0.5 %.
            let single_stiffness = force / (s_fe * 1e6) / b_mm;
            let c_prime = iso6336::single_stiffness(&p);
            println!(
                "    single-contact zone stiffness {single_stiffness:.2} N/(mm·µm), ISO c′ {c_prime:.2}, ratio {:.3}",
                single_stiffness / c_prime
            );
            assert!(
                (single_stiffness / c_prime - 1.0).abs() < 0.06,
                "single zone / ISO c′ = {}",
                single_stiffness / c_prime
            );
        }
        if specific_load < 100.0 {
            assert!(
                (stiffness / c_gamma - 1.0).abs() < 0.2,
                "mean mesh stiffness / ISO c_γα = {}",
                stiffness / c_gamma
            );
        }
        single_share.push(single);
    }
    // At light load the single-contact share of a pitch is the kinematic 2 − ε_α (to the angular
    // resolution of the sweep); under load it shrinks.
    assert!((single_share[0] - (2.0 - eps_alpha)).abs() <= 1.5 / angles as f64);
    assert!(single_share[1] < single_share[0], "tip contact under load must shorten single contact");
}
