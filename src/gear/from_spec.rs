//! A [`PairSpec`] read into a [`GearPair`]: every rule a spec must meet, each refusal naming the
//! field and the rule (`SpecError`), then the geometry and the operating torque (the pair's
//! rating where the spec gives none).

use super::involute::{inv, inv_inverse};
use super::lubrication::LubricatedFlanks;
use super::spec::PairSpec;
use super::spec_error::{invalid, SpecError};
use super::{fillet, modification, sig, spec, Gear, GearPair};
use super::{
    DEFAULT_TIP_EDGE_RADIUS_OVER_MODULE, MAX_FRICTION_COEFFICIENT, MAX_TEETH, MODULE_RANGE_MM, YIELD_RANGE_MPA,
};
use crate::closed_forms::rating;
use std::f64::consts::PI;

impl GearPair {
    pub fn from_spec(spec: &PairSpec) -> Result<GearPair, SpecError> {
        build_pair(spec)
    }
}

/// A positive, finite and normal number (a subnormal one is no physical value: it underflows to
/// zero in the first product).
fn positive(field: &str, value: f64) -> Result<f64, SpecError> {
    if value.is_normal() && value > 0.0 {
        Ok(value)
    } else {
        Err(invalid(field, format!("must be a positive finite number, got {}", sig(value))))
    }
}

/// [`positive`], converted to SI by `scale`; the SI value must be positive, finite and normal
/// too (found by fuzzing: `face_width_mm = 5e-324` became 0 m and `youngs_modulus_gpa = 1e300`
/// became inf Pa, and both specs were accepted).
fn positive_si(field: &str, value: f64, scale: f64) -> Result<f64, SpecError> {
    let si = positive(field, value)? * scale;
    if si.is_normal() {
        Ok(si)
    } else {
        Err(invalid(field, format!("{} is out of range: it is {} in SI units", sig(value), sig(si))))
    }
}

/// `Err` naming the field and the closed range [lo, hi] (`unit_and_why` follows the bounds).
fn within(field: &str, value: f64, (lo, hi): (f64, f64), unit_and_why: &str) -> Result<(), SpecError> {
    if (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(invalid(field, format!("must be in [{lo}, {hi}] {unit_and_why}, got {}", sig(value))))
    }
}

/// ISO/TR 14179-2's law, where `[friction] law` chooses it: its inputs are then required (X_L
/// defaults to mineral oil's 1.0) and `coefficient` must be left out; under the constant law
/// they must be left out.
fn lubricated_flanks(f: &spec::FrictionSpec) -> Result<Option<LubricatedFlanks>, SpecError> {
    let inputs = [
        ("friction.oil_viscosity_mpa_s", f.oil_viscosity_mpa_s),
        ("friction.roughness_ra_um", f.roughness_ra_um),
        ("friction.lubricant_factor", f.lubricant_factor),
    ];
    match f.law {
        spec::FrictionLawSpec::Constant => match inputs.iter().find(|(_, v)| v.is_some()) {
            Some((field, _)) => Err(invalid(
                field,
                "is an input of ISO/TR 14179-2's law: set `law = \"iso-tr-14179-2\"` too, or leave it out",
            )),
            None => Ok(None),
        },
        spec::FrictionLawSpec::IsoTr14179_2 => {
            if f.coefficient != 0.0 {
                return Err(invalid(
                    "friction.coefficient",
                    "must be left out under `law = \"iso-tr-14179-2\"`: the law gives μ from the load and the speed",
                ));
            }
            let required = |(field, value): (&str, Option<f64>)| {
                value.ok_or_else(|| invalid(field, "is required by `law = \"iso-tr-14179-2\"`"))
            };
            let flanks = LubricatedFlanks {
                oil_viscosity_mpa_s: required(inputs[0])?,
                roughness_ra_um: required(inputs[1])?,
                lubricant_factor: f.lubricant_factor.unwrap_or(1.0),
            };
            flanks.check().map_err(|(field, rule)| invalid(&format!("friction.{field}"), rule))?;
            Ok(Some(flanks))
        }
    }
}

fn build_pair(spec: &PairSpec) -> Result<GearPair, SpecError> {
    let m = &spec.mesh;
    for (field, value) in [
        ("mesh.elements_across_tooth", m.elements_across_tooth),
        ("mesh.elements_along_profile", m.elements_along_profile),
        ("mesh.elements_in_rim", m.elements_in_rim),
        ("mesh.axial_slices", m.axial_slices),
    ] {
        if value == 0 {
            return Err(invalid(field, "must be at least 1"));
        }
    }
    let rack = &spec.rack;
    let mn = positive_si("rack.module_mm", rack.module_mm, 1e-3)?;
    within(
        "rack.module_mm",
        rack.module_mm,
        MODULE_RANGE_MM,
        "mm (the range of gear modules the FE mesh and the Hertz law are sized for)",
    )?;
    let alpha_n_deg = positive("rack.pressure_angle_deg", rack.pressure_angle_deg)?;
    if alpha_n_deg >= 45.0 {
        return Err(invalid("rack.pressure_angle_deg", "must be below 45°"));
    }
    if !(0.0..45.0).contains(&rack.helix_angle_deg) {
        return Err(invalid("rack.helix_angle_deg", "must be in [0°, 45°)"));
    }
    let ha = positive("rack.addendum_coefficient", rack.addendum_coefficient)?;
    let hf = positive("rack.dedendum_coefficient", rack.dedendum_coefficient)?;
    let rho_f = rack.cutter_tip_radius_coefficient;
    if !(0.0..=0.6).contains(&rho_f) || hf <= ha {
        return Err(invalid(
            "rack.cutter_tip_radius_coefficient",
            "must be in [0, 0.6] with dedendum_coefficient > addendum_coefficient (tip clearance)",
        ));
    }
    // The cutter's tip round rises ρ_f·(1 − sin α_n) above its tip line; it must fit within the
    // cutter's addendum, the gear's dedendum, or the cutter has no straight flank to generate
    // an involute (found by fuzzing: addendum 1e-6, dedendum 1.25e-6 panicked in the fillet).
    if rho_f * (1.0 - rack.pressure_angle_deg.to_radians().sin()) >= hf {
        return Err(invalid(
            "rack.dedendum_coefficient",
            "must exceed the height of the cutter's tip round, cutter_tip_radius_coefficient·(1 − sin α_n)",
        ));
    }
    let mat = &spec.material;
    let e = positive_si("material.youngs_modulus_gpa", mat.youngs_modulus_gpa, 1e9)?;
    let nu = mat.poisson_ratio;
    if !(0.0..0.5).contains(&nu) {
        return Err(invalid("material.poisson_ratio", "must be in [0, 0.5)"));
    }
    let rho = positive("material.density_kg_m3", mat.density_kg_m3)?;
    let b = positive_si("mounting.face_width_mm", spec.mounting.face_width_mm, 1e-3)?;
    if !(spec.mounting.backlash_mm.is_finite() && spec.mounting.backlash_mm >= 0.0) {
        return Err(invalid("mounting.backlash_mm", "must be a finite number ≥ 0"));
    }
    let zeta = spec.mounting.mesh_damping_ratio;
    if !(zeta.is_finite() && (0.0..1.0).contains(&zeta)) {
        return Err(invalid("mounting.mesh_damping_ratio", "must be in [0, 1)"));
    }
    let mu = spec.friction.coefficient;
    if !(mu.is_finite() && (0.0..=MAX_FRICTION_COEFFICIENT).contains(&mu)) {
        return Err(invalid(
            "friction.coefficient",
            format!(
                "must be in [0, {MAX_FRICTION_COEFFICIENT}] (lubricated gear steel runs at 0.02–0.1, dry steel up to 0.3), got {}",
                sig(mu)
            ),
        ));
    }
    let lubricated_flanks = lubricated_flanks(&spec.friction)?;

    let alpha_n = alpha_n_deg.to_radians();
    let beta = rack.helix_angle_deg.to_radians();
    let alpha_t = (alpha_n.tan() / beta.cos()).atan();
    let mt = mn / beta.cos();
    let beta_b = (beta.tan() * alpha_t.cos()).atan();

    let gear = |which: &str, g: &spec::GearSpec, helix_hand: spec::HelixHand| -> Result<Gear, SpecError> {
        if g.teeth <= 0 {
            return Err(invalid(&format!("{which}.teeth"), "must be a positive integer"));
        }
        if g.teeth > MAX_TEETH {
            return Err(invalid(
                &format!("{which}.teeth"),
                format!(
                    "must be at most {MAX_TEETH}, got {} (every tooth is meshed: the FE model grows with z)",
                    g.teeth
                ),
            ));
        }
        let z = g.teeth as f64;
        let x = g.profile_shift;
        if !x.is_finite() || x.abs() > 1.5 {
            return Err(invalid(&format!("{which}.profile_shift"), "must be in [-1.5, 1.5]"));
        }
        let r = z * mt / 2.0;
        let rb = r * alpha_t.cos();
        let ra = r + mn * (ha + x);
        let rf = r - mn * (hf - x);
        // Undercut: the end of the rack's straight flank (height h_lim below the datum line,
        // measured along the normal to the pitch line) must not pass below the interference
        // point, which lies r·sin²α_t below the pitch line.
        let h_lim = mn * (hf - rho_f * (1.0 - alpha_n.sin()) - x);
        if h_lim > r * alpha_t.sin().powi(2) + 1e-12 && !g.allow_undercut {
            return Err(invalid(
                &format!("{which}.teeth"),
                format!(
                    "the rack cutter undercuts this gear (z = {}, x = {x}): need \
                     (h_fP − ρ_fP(1−sin α_n) − x)·m_n ≤ r·sin²α_t; raise the teeth or the profile shift, \
                     or set allow_undercut = true",
                    g.teeth
                ),
            ));
        }
        // The generated involute starts where the rack's straight flank ends.
        let u_form = r * alpha_t.sin() - h_lim / alpha_t.sin();
        let form_radius = rb.hypot(u_form.max(0.0));
        let bore = positive_si(&format!("{which}.bore_radius_mm"), g.bore_radius_mm, 1e-3)?;
        if bore >= rf - mn {
            return Err(invalid(
                &format!("{which}.bore_radius_mm"),
                format!("must leave a rim of at least one module below the root circle ({:.2} mm)", rf * 1e3),
            ));
        }
        let psi_p = (PI / 2.0 + 2.0 * x * alpha_n.tan()) / z;
        let half_tip = psi_p + inv(alpha_t) - inv((rb / ra).acos());
        if half_tip <= 0.0 {
            return Err(invalid(&format!("{which}.profile_shift"), "the tooth comes to a point below the tip circle"));
        }
        let tip_land = 2.0 * ra * half_tip;
        let tip_edge_radius = match g.tip_edge_radius_mm {
            None => DEFAULT_TIP_EDGE_RADIUS_OVER_MODULE * mn,
            Some(v) => {
                let field = format!("{which}.tip_edge_radius_mm");
                let v = positive_si(&field, v, 1e-3)?;
                if v > 0.5 * tip_land {
                    return Err(invalid(
                        &field,
                        format!(
                            "must not exceed half the tip land ({:.3} mm), got {:.3} mm",
                            0.5e3 * tip_land,
                            v * 1e3
                        ),
                    ));
                }
                v
            }
        };
        let inertia_override = match g.inertia_kgm2 {
            Some(j) => Some(positive(&format!("{which}.inertia_kgm2"), j)?),
            None => None,
        };
        let mut gear = Gear {
            teeth: g.teeth as u32,
            profile_shift: x,
            pitch_radius_m: r,
            base_radius_m: rb,
            tip_radius_m: ra,
            root_radius_m: rf,
            bore_radius_m: bore,
            form_radius_m: form_radius,
            half_thickness_angle_pitch_rad: psi_p,
            fillet: fillet::fillet_profile(
                &fillet::RackCutter {
                    pitch_m: PI * mt,
                    pressure_angle_rad: alpha_t,
                    dedendum_m: hf * mn,
                    tip_radius_m: rho_f * mn * (1.0 - alpha_n.sin()) / (1.0 - alpha_t.sin()),
                    profile_shift_m: x * mn,
                },
                r,
                g.teeth as u32,
            ),
            inertia_kgm2: 0.0,
            inertia_overridden: inertia_override.is_some(),
            tip_edge_radius_m: tip_edge_radius,
            helix_hand,
            modification: Default::default(),
        };
        // Polar moment of inertia of the real section (fillet + involute), unless overridden.
        gear.inertia_kgm2 = inertia_override.unwrap_or(rho * b * gear.section_moments(alpha_t).1);
        Ok(gear)
    };
    let g1 = gear("gear1", &spec.gear1, rack.helix_hand)?;
    let g2 = gear("gear2", &spec.gear2, rack.helix_hand.opposite())?;

    // Operating center distance and pressure angle.
    let (z1, z2) = (g1.teeth as f64, g2.teeth as f64);
    let inv_w0 = inv(alpha_t) + 2.0 * alpha_n.tan() * (g1.profile_shift + g2.profile_shift) / (z1 + z2);
    let alpha_w0 = inv_inverse(inv_w0);
    let a0 = (g1.base_radius_m + g2.base_radius_m) / alpha_w0.cos();
    let a = match spec.mounting.center_distance_mm {
        None => a0,
        Some(a_mm) => positive_si("mounting.center_distance_mm", a_mm, 1e-3)?,
    };
    let cos_w = (g1.base_radius_m + g2.base_radius_m) / a;
    if cos_w >= 1.0 {
        return Err(invalid("mounting.center_distance_mm", "is not larger than the sum of the base radii"));
    }
    let alpha_w = cos_w.acos();
    // Backlash the center distance makes: operating circular pitch minus both tooth thicknesses
    // at the operating pitch circles, then measured along the LOA.
    let rw1 = g1.base_radius_m / cos_w;
    let rw2 = g2.base_radius_m / cos_w;
    let s_w1 = 2.0 * rw1 * g1.half_thickness_angle(rw1, alpha_t);
    let s_w2 = 2.0 * rw2 * g2.half_thickness_angle(rw2, alpha_t);
    let backlash_geom_loa = (2.0 * PI * rw1 / z1 - s_w1 - s_w2) * cos_w;
    if backlash_geom_loa < -1e-9 {
        return Err(invalid(
            "mounting.center_distance_mm",
            format!(
                "the gears cannot mesh at {:.4} mm: below the zero-backlash distance {:.4} mm the teeth interfere",
                a * 1e3,
                a0 * 1e3
            ),
        ));
    }
    let backlash_loa = backlash_geom_loa.max(0.0) + spec.mounting.backlash_mm * 1e-3 / beta_b.cos();

    let loa = a * alpha_w.sin();
    let path_start = loa - (g2.tip_radius_m.powi(2) - g2.base_radius_m.powi(2)).sqrt();
    let path_end = (g1.tip_radius_m.powi(2) - g1.base_radius_m.powi(2)).sqrt();
    // Tip interference: each tip must meet the mate's involute, not its fillet or the region
    // inside its base circle.
    let u_form1 = (g1.form_radius_m.powi(2) - g1.base_radius_m.powi(2)).max(0.0).sqrt();
    let u_form2 = (g2.form_radius_m.powi(2) - g2.base_radius_m.powi(2)).max(0.0).sqrt();
    // The field named is one the user set: a profile shift where one is given (it moves both the
    // tip and the form circle), else the teeth of the gear whose tip interferes.
    let culprit = |tip_gear: &str, other: &str| -> String {
        let shift = |which: &str| if which == "gear1" { spec.gear1.profile_shift } else { spec.gear2.profile_shift };
        if shift(other) != 0.0 {
            format!("{other}.profile_shift")
        } else if shift(tip_gear) != 0.0 {
            format!("{tip_gear}.profile_shift")
        } else {
            format!("{tip_gear}.teeth")
        }
    };
    let shifts = format!("x₁ = {}, x₂ = {}", sig(g1.profile_shift), sig(g2.profile_shift));
    if path_start < u_form1 - 1e-12 {
        return Err(invalid(
            &culprit("gear2", "gear1"),
            format!(
                "tip interference: gear 2's tip reaches below gear 1's form circle (into the fillet) \
                 at z {}/{}, {shifts}",
                g1.teeth, g2.teeth
            ),
        ));
    }
    if loa - path_end < u_form2 - 1e-12 {
        return Err(invalid(
            &culprit("gear1", "gear2"),
            format!(
                "tip interference: gear 1's tip reaches below gear 2's form circle (into the fillet) \
                 at z {}/{}, {shifts}",
                g1.teeth, g2.teeth
            ),
        ));
    }
    let pbt = PI * mt * alpha_t.cos();
    let eps_alpha = (path_end - path_start) / pbt;
    // Every check above is a comparison that NaN passes: sizes so large that squares overflow
    // (found by fuzzing: module_mm = 3e240 gave ε_α = NaN and was accepted) are refused here.
    let derived = [
        ("center distance", a),
        ("line of action", loa),
        ("path of contact start", path_start),
        ("path of contact end", path_end),
        ("base pitch", pbt),
        ("transverse contact ratio", eps_alpha),
        ("backlash", backlash_loa),
        ("gear 1 tip radius", g1.tip_radius_m),
        ("gear 2 tip radius", g2.tip_radius_m),
        ("gear 1 form radius", g1.form_radius_m),
        ("gear 2 form radius", g2.form_radius_m),
    ];
    if let Some((what, x)) = derived.iter().find(|(_, x)| !x.is_finite()) {
        return Err(invalid(
            "rack.module_mm",
            format!("the pair's {what} is {x}: the sizes of this spec are out of floating-point range"),
        ));
    }
    if eps_alpha < 1.0 {
        // Named against what the user set: the center distance if given, else the teeth's height.
        let field = if spec.mounting.center_distance_mm.is_some() {
            "mounting.center_distance_mm"
        } else {
            "rack.addendum_coefficient"
        };
        return Err(invalid(
            field,
            format!(
                "transverse contact ratio ε_α = {eps_alpha:.3} < 1: the mesh is not continuous \
                 (addendum coefficient {}, center distance {:.3} mm)",
                sig(ha),
                a * 1e3
            ),
        ));
    }
    let mut pair = GearPair {
        name: spec.name.clone(),
        gear1: g1,
        gear2: g2,
        normal_module_m: mn,
        normal_pressure_angle_rad: alpha_n,
        helix_angle_rad: beta,
        base_helix_angle_rad: beta_b,
        transverse_pressure_angle_rad: alpha_t,
        face_width_m: b,
        center_distance_m: a,
        operating_pressure_angle_rad: alpha_w,
        base_pitch_m: pbt,
        path_start_m: path_start,
        path_end_m: path_end,
        transverse_contact_ratio: eps_alpha,
        overlap_ratio: b * beta.sin() / (PI * mn),
        backlash_loa_m: backlash_loa,
        youngs_modulus_pa: e,
        poisson_ratio: nu,
        density_kg_m3: rho,
        yield_strength_pa: {
            let field = "material.yield_strength_mpa";
            let y = positive_si(field, mat.yield_strength_mpa, 1e6)?;
            within(field, mat.yield_strength_mpa, YIELD_RANGE_MPA, "MPa (gear materials, plastics to hardened steel)")?;
            y
        },
        mesh_damping_ratio: zeta,
        friction_coefficient: mu,
        lubricated_flanks,
        operating_torque_nm: 0.0,
        rack_dedendum_coefficient: hf,
        hertz_contact: spec.lumped.hertz_contact,
        misalignment_m: 0.0,
    };
    // Flank modifications, checked against each gear's active profile (roll lengths: gear 1
    // from T₁, gear 2 from T₂ along the line of action).
    let loa_m = pair.loa_length_m();
    let active = [[path_start, path_end], [loa_m - path_end, loa_m - path_start]];
    for (which, g, active) in [("gear1", &spec.gear1, active[0]), ("gear2", &spec.gear2, active[1])] {
        if let Some(m) = &g.modification {
            let built = modification::build(which, m, active, b, mn)?;
            if which == "gear1" {
                pair.gear1.modification = built;
            } else {
                pair.gear2.modification = built;
            }
        }
    }
    let f_ma = spec.mounting.misalignment_um;
    if !f_ma.is_finite() || f_ma.abs() > modification::MAX_AMOUNT_OVER_MODULE * mn * 1e6 {
        return Err(invalid(
            "mounting.misalignment_um",
            format!("must be finite and within ±{:.0} µm, got {f_ma}", modification::MAX_AMOUNT_OVER_MODULE * mn * 1e6),
        ));
    }
    pair.misalignment_m = f_ma * 1e-6;
    let yield_torque = rating::yield_torque_nm(&pair);
    pair.operating_torque_nm = match spec.operating.torque_nm {
        None => rating::rated_torque_nm(&pair),
        Some(t) => {
            let t = positive("operating.torque_nm", t)?;
            if t > yield_torque {
                return Err(invalid(
                    "operating.torque_nm",
                    format!(
                        "{} N·m bends a tooth root past material.yield_strength_mpa: one pair carrying it at the tip \
                         yields at {} N·m (nominal root stress, Lewis); the linear-elastic model does not hold there",
                        sig(t),
                        sig(yield_torque)
                    ),
                ));
            }
            t
        }
    };
    Ok(pair)
}
