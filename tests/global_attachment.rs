//! Global attachment responses (total − partial model at depth h) against two independent
//! expectations:
//! 1. Mesh convergence: under a line load the total FE response is log-singular (it grows without
//!    bound as the mesh refines); removing the partial model's response must leave a global part
//!    that converges.
//! 2. Consistency with the Hertz contact referred to the same depth (design §4.3): when h grows,
//!    the global part must lose exactly what Weber's approach gains for one body,
//!    Δδ/(P/l) = 2(1−ν²)/(πE)·ln(h₂/h₁) — the closed form, independent of the FE.

use gearfmu::fe::assembly::Cholesky;
use gearfmu::fe::clamped_gear::ClampedGear;
use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::fe::hex8::Formulation;
use gearfmu::fe::tooth_stiffness::pitch_line_load;
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::rom::attachment::total_and_global_response;

/// (total, global at each h) compliance per width (mm·µm/N) at the pitch point of the spur pinion.
fn compliances(across: usize, profile: usize, rim: usize, depths: &[f64]) -> (f64, Vec<f64>) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
    let p = GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap();
    let spec = MeshSpec {
        elements_across_tooth: across,
        elements_along_profile: profile,
        elements_in_rim: rim,
        axial_slices: 4,
        ..Default::default()
    };
    let model = ClampedGear::new(&p, &p.gear1, &spec, Formulation::IncompatibleModes);
    let (gm, dofs, material) = (&model.mesh, &model.dofs, &model.material);
    let chol = Cholesky::new(&model.stiffness).unwrap();
    let force = 1000.0;
    let load = pitch_line_load(gm, &p.gear1, spec.axial_slices, force).unwrap();
    let work = |u: &[f64]| load.iter().map(|&(n, f)| (0..3).map(|c| f[c] * u[3 * n + c]).sum::<f64>()).sum::<f64>();
    let per_width = |u: &[f64]| work(u) / (force * force) * p.face_width_m * 1e9;
    let mut total = 0.0;
    let mut global = Vec::new();
    for &h in depths {
        let (t, g) =
            total_and_global_response(&gm.mesh, material, Formulation::IncompatibleModes, dofs, &chol, &load, h)
                .unwrap();
        total = per_width(&t);
        global.push(per_width(&g));
    }
    (total, global)
}

#[test]
fn global_response_converges_where_the_total_does_not_and_matches_weber_depth_dependence() {
    let depths = [3e-3, 4e-3];
    let (total_a, global_a) = compliances(8, 16, 8, &depths);
    let (total_b, global_b) = compliances(10, 20, 10, &depths);
    let (d_total, d_global) = ((total_b - total_a) / total_a, (global_b[0] - global_a[0]) / global_a[0]);
    println!(
        "8/16/8:   total {total_a:.5}, global(h=3 mm) {:.5}, global(h=4 mm) {:.5} mm·µm/N",
        global_a[0], global_a[1]
    );
    println!(
        "10/20/10: total {total_b:.5}, global(h=3 mm) {:.5}, global(h=4 mm) {:.5} mm·µm/N",
        global_b[0], global_b[1]
    );
    println!(
        "refinement changes the total by {:+.2} %, the global part by {:+.2} %",
        100.0 * d_total,
        100.0 * d_global
    );
    // 1. The total grows with refinement (log-singular); the global part moves far less.
    assert!(d_total > 0.02, "the total should still grow under refinement: {d_total}");
    assert!(d_global.abs() < 0.25 * d_total, "global {d_global} vs total {d_total}");
    // 2. What the global part loses from h = 3 to 4 mm, Weber's approach for one body gains.
    let (e, nu) = (2e11, 0.3);
    let weber_gain = 2.0 * (1.0 - nu * nu) / (std::f64::consts::PI * e) * (4.0f64 / 3.0).ln() * 1e9;
    for (name, g) in [("8/16/8", &global_a), ("10/20/10", &global_b)] {
        let loss = g[0] - g[1];
        println!(
            "{name}: global loss {loss:.5} vs Weber gain {weber_gain:.5} mm·µm/N (ratio {:.2})",
            loss / weber_gain
        );
        assert!((loss / weber_gain - 1.0).abs() < 0.2, "{name}: {loss} vs {weber_gain}");
    }
}

/// The partial model is local (Saint-Venant): cutting it at `LATERAL_REACH`·h from the load, instead
/// of keeping the whole half-space within depth h (the reference, other teeth included), leaves the
/// global compliance at the load unchanged to well under the 3 % mesh-independence band of the
/// statics, while the partial model shrinks to a small fraction of the gear.
#[test]
fn partial_model_cut_at_the_lateral_reach_keeps_the_global_compliance() {
    use gearfmu::rom::attachment::{PartialResponse, LATERAL_REACH};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
    let p = GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap();
    let spec = MeshSpec::default();
    let model = ClampedGear::new(&p, &p.gear1, &spec, Formulation::IncompatibleModes);
    let (gm, dofs, material) = (&model.mesh, &model.dofs, &model.material);
    let force = 1000.0;
    let load = pitch_line_load(gm, &p.gear1, spec.axial_slices, force).unwrap();
    let total = dofs.expand(&Cholesky::new(&model.stiffness).unwrap().solve(&dofs.load_vector(&load)));
    let h = 3e-3;
    let work_on_load = |nodes: &[usize], u: &[f64]| {
        let mut work = 0.0;
        for &(n, f) in &load {
            if let Some(k) = nodes.iter().position(|&m| m == n) {
                work += (0..3).map(|c| f[c] * u[3 * k + c]).sum::<f64>();
            }
        }
        work
    };
    let all: Vec<usize> = (0..gm.mesh.nodes.len()).collect();
    let total_work = work_on_load(&all, &total);
    let global_compliance = |reach_m: f64| {
        let partial =
            PartialResponse::solve_with_reach(&gm.mesh, material, Formulation::IncompatibleModes, &load, h, reach_m)
                .unwrap();
        let global = total_work - work_on_load(&partial.nodes, &partial.displacement);
        (global / (force * force) * p.face_width_m * 1e9, partial.nodes.len())
    };
    let (cut, cut_nodes) = global_compliance(LATERAL_REACH * h);
    let (reference, reference_nodes) = global_compliance(f64::INFINITY);
    let change = (cut - reference) / reference;
    println!(
        "global compliance at the pitch point: reach {LATERAL_REACH}·h {cut:.5} ({cut_nodes} nodes), \
         half-space {reference:.5} mm·µm/N ({reference_nodes} nodes of {}): {:+.3} %",
        gm.mesh.nodes.len(),
        100.0 * change
    );
    assert!(change.abs() < 0.01, "the cut partial model changes the global compliance by {change}");
    assert!(cut_nodes * 3 < reference_nodes, "{cut_nodes} vs {reference_nodes}: the cut should be much smaller");
}

/// The tooth periodicity of the FE gear (a conservation-free, solver-independent identity): the
/// attachment modes of a flank grid on several teeth, solved for the first tooth and turned onto
/// the others (`global_attachment_modes_of_teeth`), equal the modes solved node by node on every
/// tooth, on both gears of a spur and of a helical pair, drive and coast flanks. Their reduced
/// stiffness from the partial models' section reactions equals the projection with K.
#[test]
fn attachment_modes_turned_from_one_tooth_equal_the_modes_solved_on_every_tooth_and_carry_their_cuts_reactions() {
    use gearfmu::contact::mesh_kinematics::{Flank, PairPlacement};
    use gearfmu::rom::attachment::{global_attachment_modes, global_attachment_modes_of_teeth};
    use gearfmu::rom::flank::FlankGrid;
    for example in ["kurokawa_spur", "kurokawa_helical"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("examples/{example}.toml"));
        let p = GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap();
        let place = PairPlacement::new(&p);
        let depth = gearfmu::rom::reductor::contact_depth_m(&p);
        let spec =
            MeshSpec { axial_slices: gearfmu::fe::gear_mesh::axial_slices_for(&p, depth).max(2), ..Default::default() };
        for (i, gear) in [&p.gear1, &p.gear2].into_iter().enumerate() {
            let model = ClampedGear::new(&p, gear, &spec, Formulation::IncompatibleModes);
            let chol = model.factorize().unwrap();
            for flank in [Flank::Drive, Flank::Coast] {
                let grid = FlankGrid::contact_flank_in_reach(&model.mesh, i, flank, &place, 1).unwrap();
                assert!(grid.teeth.len() >= 3, "{example} gear {}: a grid on several teeth", i + 1);
                assert!(
                    gearfmu::rom::attachment::teeth_from_the_first(&model.mesh, &grid).is_some(),
                    "{example} gear {} {flank:?}: every tooth of the grid is the first one turned (else nothing is turned)",
                    i + 1
                );
                let (mesh, material, dofs) = (&model.mesh.mesh, &model.material, &model.dofs);
                let direct =
                    global_attachment_modes(mesh, material, model.formulation, dofs, &chol, &grid.nodes, depth, |_| {})
                        .unwrap();
                let turned_modes = global_attachment_modes_of_teeth(
                    &model.mesh,
                    material,
                    model.formulation,
                    dofs,
                    &chol,
                    &grid,
                    depth,
                    |_| {},
                )
                .unwrap();
                let (direct_modes, direct, turned) = (&direct, &direct.psi, &turned_modes.psi);
                let scale = (0..direct.ncols())
                    .flat_map(|j| (0..direct.nrows()).map(move |r| (r, j)))
                    .map(|(r, j)| direct[(r, j)].abs())
                    .fold(0.0, f64::max);
                let worst = (0..direct.ncols())
                    .flat_map(|j| (0..direct.nrows()).map(move |r| (r, j)))
                    .map(|(r, j)| (direct[(r, j)] - turned[(r, j)]).abs())
                    .fold(0.0, f64::max);
                println!(
                    "{example} gear {} {flank:?}: {} teeth × {} nodes, max |ψ_turned − ψ_direct| = {:.2e} of max |ψ| {scale:.2e}",
                    i + 1,
                    grid.teeth.len(),
                    grid.len() / grid.teeth.len(),
                    worst
                );
                assert!(worst <= 1e-9 * scale, "{example} gear {} {flank:?}: turned modes differ by {worst:e}", i + 1);
                // K·ψ_j = −r_j, the reaction of the cut (`GlobalAttachmentModes`): the reduced
                // stiffness from the section reactions equals the Galerkin projection ψᵀKψ with the
                // gear's stiffness, for the modes solved on every tooth and for the turned ones.
                for (name, modes) in [("solved on every tooth", direct_modes), ("turned", &turned_modes)] {
                    let galerkin = gearfmu::rom::svd::projected_stiffness(&model.stiffness, &modes.psi);
                    let k_scale = (0..galerkin.ncols()).map(|j| galerkin[(j, j)]).fold(0.0, f64::max);
                    let from_reactions = modes.reduced_stiffness(dofs);
                    let worst = (0..galerkin.ncols())
                        .flat_map(|j| (0..galerkin.nrows()).map(move |r| (r, j)))
                        .map(|(r, j)| (from_reactions[(r, j)] - galerkin[(r, j)]).abs())
                        .fold(0.0, f64::max);
                    println!("  {name}: max |−ψᵀR − ψᵀKψ| = {worst:.2e} of max diag {k_scale:.2e}");
                    assert!(
                        worst <= 1e-10 * k_scale,
                        "{example} gear {} {flank:?} {name}: the reactions' K_r differs from ψᵀKψ by {worst:e}",
                        i + 1
                    );
                }
            }
        }
    }
}
