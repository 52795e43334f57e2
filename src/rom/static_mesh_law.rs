//! The lumped model's mesh law from the FE statics: the loaded transmission error of the
//! PMOR-Hertz static analyses, tabulated over roll position × mesh force — the chain the
//! commercial tools use (loaded tooth contact analysis → transmission-error / mesh-stiffness map
//! → system dynamics), here on the same reduction `fmu-build ste` solves.
//!
//! Row i of the table is roll position ξᵢ = i·p_b/N, in the lumped model's coordinate
//! ξ = r_b1·θ₁ + ξ₀ (ξ₀ puts a tooth pair at the pitch point at θ₁ = 0, `LumpedMesh`). A static
//! case holds gear 2 at θ₂ and finds θ₁ with r_b1·θ₁ = r_b2·θ₂ + δ, δ the static transmission
//! error; so the case that belongs to row i at force F_k has r_b2·θ₂ = ξᵢ − ξ₀ − δ_k(ξᵢ). δ is
//! a few tens of µm against a base pitch of about 15 mm: one fixed-point pass from the case at
//! r_b2·θ₂ = ξᵢ − ξ₀ settles it to well below the table's own resolution where the STE is
//! smooth, and only moves the row across a contact change by δ's change there.
//!
//! Row i starts at the no-load transmission error δ₀(ξᵢ) under F₀ = 0: where the rigid flanks
//! first touch (`PairPlacement::modification_opening_m`): zero for unmodified flanks, and the
//! reliefs' and crownings' opening where the flanks are modified (issue 27), so that the lumped
//! model's mesh opens where the statics' contact does.
//!
//! The mesh force F is the lumped model's: along the transverse line of action, with the torque
//! on gear 1 T₁ = r_b1·F. Levels are dense at light load, where Hertz contact is most
//! nonlinear (`mesh_stiffness::force_levels`' spacing), and stop at the yield force
//! (`closed_forms::rating`): the statics refuse a case beyond it, and the law continues past its last
//! level with its last slope, where the FMU already logs the yield warning.
//!
//! Tooth friction's elastic share (`MeshLaw::with_friction_share`). Each case is solved again
//! with friction μ_b = `FRICTION_SHARE_MU` (the statics' tangential loads and friction arms,
//! `rom::statics`), at the same angle and torque. Its normal forces carry less or more than
//! T₁/r_b1 (friction's torque carries the rest), so the row's friction points (F′_k, δ′_k) lie
//! off the levels: δ′ is interpolated back to each F_k, and e_k = (δ′(F_k) − δ_k)/μ_b is the
//! share per unit μ at fixed mesh force, the lumped model's variable (first order in μ; the
//! lumped model's friction torques carry the arms, this table the teeth's bending under friction).

use super::statics::{StaticCase, StaticModel};
use crate::contact::mesh_kinematics::Flank;
use crate::dynamics::mesh_friction::ContactSpread;
use crate::dynamics::mesh_law::MeshLaw;
use crate::gear::GearPair;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Roll positions per base pitch and force levels of the FE-fed law, chosen by measurement
/// (BENCHMARKS §9): against the statics at 200 positions and 22–700 N·m on the Kurokawa spur
/// pair, 128 × 24 leaves the mean within 0.04 %, the peak-to-peak within 0.8 % and the pointwise
/// RMS error at 0.6 % of the peak-to-peak; 12 levels leave the mean 0.6 % off at light load
/// (the Hertz curve between quadratically spaced levels), 256 rows gain nothing at 12 levels.
pub const TABLE_ROWS: usize = 128;
pub const FORCE_LEVELS: usize = 24;

/// The μ at which friction's elastic share is taken: the middle of lubricated gear steel's
/// 0.02–0.1. The share is first order in μ (`friction_statics::friction_changes_the_ste_to_first_order_in_mu`
/// measures how linear).
pub const FRICTION_SHARE_MU: f64 = 0.05;

/// The force levels: F_k = F_top·(k/K)², F_top the smaller of 1500 N/mm of face width (the
/// analytic law's top) and the yield force.
pub fn force_levels(pair: &GearPair, levels: usize) -> Vec<f64> {
    let f_top = (1500.0e3 * pair.face_width_m).min(crate::closed_forms::rating::yield_mesh_force_n(pair));
    (0..=levels).map(|k| f_top * (k as f64 / levels as f64).powi(2)).collect()
}

/// The drive flank's law from the statics of a reduced pair (`ReducedPair::static_model`, or the
/// PMOR-Hertz build's own): N rows × the levels, and the tooth pairs in contact at each (laid
/// out as the law's deflections). `progress(done)` counts rows.
///
/// The statics refuse a case beyond their validity (the Hertz half-width rule, b ≤ h/4; a root
/// past yield): a small pair reaches it below the top level. The table then ends at the highest
/// level every roll position solves, and the law continues past it with its last slope; that
/// level must cover twice the operating torque, else the build is refused with the statics'
/// reason. `StaticMeshLaw::capped` says where and why it ended.
pub fn drive_law_from_statics(
    pair: &GearPair,
    model: &StaticModel,
    levels: &[f64],
    rows: usize,
    progress: impl Fn(usize) + Sync,
) -> Result<StaticMeshLaw, String> {
    // Generic only at the door: the body below is compiled once, here, not again in
    // every crate (each test, fmu-build) that passes a progress closure of its own.
    drive_law_from_statics_dyn(pair, model, levels, rows, &progress)
}

fn drive_law_from_statics_dyn(
    pair: &GearPair,
    model: &StaticModel,
    levels: &[f64],
    rows: usize,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<StaticMeshLaw, String> {
    let (rb1, rb2) = (pair.gear1.base_radius_m, pair.gear2.base_radius_m);
    let pitch2 = 2.0 * std::f64::consts::PI / pair.gear2.teeth as f64;
    let roll_offset = pair.pitch_point_m() - pair.path_start_m;
    let done = std::sync::atomic::AtomicUsize::new(0);
    let layers = &model.gears[0].flank.layer_z_m;
    let z_mid: Vec<f64> = layers.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
    // A model that cannot carry friction (a standard CMS basis without the flank tangents) gives
    // a law without the share, and says why (`StaticMeshLaw::friction_share_missing`).
    let with_friction = model.frictional(FRICTION_SHARE_MU);
    // The case whose bore roll r_b1·θ₁ + ξ₀ is ξ, at torque T₁ (one fixed-point pass), and the
    // gear-2 angle it settled at.
    let case_at = |roll: f64, torque: f64| -> Result<(StaticCase, f64), String> {
        let theta2_of = |delta: f64| ((roll - roll_offset - delta) / rb2).rem_euclid(pitch2);
        let first = model.solve(theta2_of(0.0), torque)?;
        let theta2 = theta2_of(first.ste_m);
        Ok((model.solve(theta2, torque)?, theta2))
    };
    // The same case with friction: its normal forces' share of T₁/r_b1 and its STE, or None
    // where those statics refuse it.
    let friction_at = |theta2: f64, torque: f64| -> Option<(f64, f64)> {
        let case = with_friction.as_ref().ok()?.solve(theta2, torque).ok()?;
        Some((case.transverse_force_n, case.ste_m))
    };
    if levels.len() < 2 {
        return Err("the mesh law needs a force level above zero".into());
    }
    // Per roll position: the STE and the pairs in contact up the levels, until the statics refuse
    // one (then that level and its reason).
    type Row = (Vec<f64>, Vec<u32>, Vec<Vec<(f64, f64)>>, Option<(usize, String)>, Vec<(f64, f64)>);
    let table: Vec<Row> = (0..rows)
        .into_par_iter()
        .map(|i| {
            let roll = pair.base_pitch_m * i as f64 / rows as f64;
            // Under no load: where the rigid flanks first touch, δ₀(ξ) — zero for unmodified
            // flanks, the reliefs' and crownings' opening where they are modified.
            let no_load = || -> Result<f64, String> {
                let at = |delta: f64| {
                    let theta2 = ((roll - roll_offset - delta) / rb2).rem_euclid(pitch2);
                    model.placement.modification_opening_m(Flank::Drive, theta2, &z_mid)
                };
                let first = at(0.0).ok_or("no flank within reach")?;
                at(first).ok_or_else(|| "no flank within reach".to_string())
            };
            let (mut row, mut pairs, mut contacts) = (vec![0.0], vec![0], vec![Vec::new()]);
            match no_load() {
                Ok(delta) => row[0] = delta,
                Err(e) => {
                    let why = format!("roll {roll:.4e} m, no load: {e}");
                    return (row, pairs, contacts, Some((0, why)), Vec::new());
                }
            }
            let mut refused = None;
            // Friction's points (F′, δ′), from no load on, until its statics first refuse a case.
            let mut friction = vec![(0.0, row[0])];
            let mut friction_solves = with_friction.is_ok();
            for (k, &force) in levels.iter().enumerate().skip(1) {
                match case_at(roll, force * rb1) {
                    Ok((case, theta2)) => {
                        row.push(case.ste_m);
                        pairs.push(case.pairs_in_contact as u32);
                        contacts.push(case.elements.iter().map(|e| (e.force_n, contact_point_m(pair, e))).collect());
                        if friction_solves {
                            match friction_at(theta2, force * rb1) {
                                Some(point) => friction.push(point),
                                None => friction_solves = false,
                            }
                        }
                    }
                    Err(e) => {
                        refused = Some((k, format!("roll {roll:.4e} m, force {force:.4e} N: {e}")));
                        break;
                    }
                }
            }
            // Under no load: the pairs the lightest load touches.
            pairs[0] = pairs.get(1).copied().unwrap_or(0);
            progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
            (row, pairs, contacts, refused, friction)
        })
        .collect();
    // The highest level every roll position reached, and the first refusal that set it.
    let top = table.iter().map(|(row, ..)| row.len() - 1).min().unwrap_or(0);
    let capped =
        table.iter().filter_map(|(.., r, _)| r.as_ref()).find(|(k, _)| *k == top + 1).map(|(_, why)| why.clone());
    let operating_force = 2.0 * pair.operating_torque_nm / rb1;
    if levels[top] < operating_force.min(levels[levels.len() - 1]) {
        return Err(format!(
            "mesh law from the statics: they refuse loads from {:.4e} N on, below twice the operating torque ({:.4e} N): {}",
            levels[top + 1],
            operating_force,
            capped.unwrap_or_default()
        ));
    }
    let kept = &levels[..=top];
    let mut deflection = Vec::with_capacity(rows * kept.len());
    let mut pairs = Vec::with_capacity(rows * kept.len());
    let mut contacts = Vec::with_capacity(rows * kept.len());
    let mut friction_share = Vec::with_capacity(rows * kept.len());
    let mut share_missing = with_friction.as_ref().err().cloned();
    for (i, (row, n, c, _, friction)) in table.into_iter().enumerate() {
        if share_missing.is_none() {
            match friction_share_of_row(&row[..kept.len()], kept, &friction) {
                Ok(share) => friction_share.extend(share),
                Err(e) => {
                    share_missing = Some(format!("roll {:.4e} m: {e}", pair.base_pitch_m * i as f64 / rows as f64))
                }
            }
        }
        // F(δ) must be single-valued: the deflection grows with the force.
        if let Some(k) = (1..kept.len()).find(|&k| !(row[k] > row[k - 1])) {
            return Err(format!(
                "mesh law from the statics: at roll {:.4e} m the STE does not grow from {:.4e} N to {:.4e} N ({:.6e} → {:.6e} m)",
                pair.base_pitch_m * i as f64 / rows as f64,
                kept[k - 1],
                kept[k],
                row[k - 1],
                row[k]
            ));
        }
        deflection.extend_from_slice(&row[..kept.len()]);
        pairs.extend_from_slice(&n[..kept.len()]);
        contacts.extend(c.into_iter().take(kept.len()));
    }
    let mut law = MeshLaw::new(pair.base_pitch_m, kept.to_vec(), deflection);
    if share_missing.is_none() {
        match law.clone().with_friction_share(friction_share, crate::gear::MAX_FRICTION_COEFFICIENT) {
            Ok(with_share) => law = with_share,
            Err(e) => share_missing = Some(e),
        }
    }
    Ok(StaticMeshLaw {
        friction_share_missing: share_missing
            .map(|why| format!("the law carries friction's torques only, not the teeth's answer to friction: {why}")),
        law,
        pairs,
        spread: ContactSpread::from_contacts(kept.len(), pair.base_pitch_m, &contacts)?,
        capped: capped.map(|why| format!("the table ends at {:.4e} N, where the statics refuse: {why}", kept[top])),
    })
}

/// The FE-fed law: the drive flank's table, its tooth-pair counts, and where the statics ended it
/// below the planned top level (if they did).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StaticMeshLaw {
    pub law: MeshLaw,
    pub pairs: Vec<u32>,
    /// Where the load is carried along the line of action, per row and level (tooth friction's
    /// contacts, `mesh_friction`).
    pub spread: ContactSpread,
    pub capped: Option<String>,
    /// Why the law has no friction's elastic share (`MeshLaw::with_friction_share`), where it has
    /// none: the statics could not carry friction, or the share failed its checks.
    pub friction_share_missing: Option<String>,
}

/// e_k = (δ′(F_k) − δ_k)/μ_b of one row: δ′ interpolated at F_k between friction's points
/// (F′, δ′), which start at (0, δ₀) and grow with F′. Beyond the last point (the top level, or
/// where the friction statics refused a case) the last segment's slope continues.
fn friction_share_of_row(row: &[f64], levels: &[f64], points: &[(f64, f64)]) -> Result<Vec<f64>, String> {
    if points.len() < 2 {
        return Err("the statics with friction solve no loaded case".into());
    }
    if let Some(w) = points.windows(2).find(|w| !(w[1].0 > w[0].0)) {
        return Err(format!(
            "with friction, the normal forces do not grow with the torque ({:.4e} → {:.4e} N)",
            w[0].0, w[1].0
        ));
    }
    Ok(levels
        .iter()
        .zip(row)
        .map(|(&f, &d)| {
            let m = points.partition_point(|p| p.0 <= f).clamp(1, points.len() - 1) - 1;
            let (a, b) = (points[m], points[m + 1]);
            let at_f = a.1 + (b.1 - a.1) * (f - a.0) / (b.0 - a.0);
            (at_f - d) / FRICTION_SHARE_MU
        })
        .collect())
}

/// Where a static contact element touches, as a point u (m from T₁) of the transverse line of
/// action (`mesh_kinematics::line_of_action_point_m`).
pub fn contact_point_m(pair: &GearPair, e: &super::statics::ElementResult) -> f64 {
    crate::contact::mesh_kinematics::line_of_action_point_m(pair, e.kind, e.radius_m)
}
