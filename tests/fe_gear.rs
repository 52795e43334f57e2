//! The gear mesh against independent references: exact section area (mass), tooth periodicity,
//! rigid-body modes of the unclamped gear, and the involute's normals.

use gearfmu::fe::assembly::{self, DofMap, Material};
use gearfmu::fe::gear_mesh::{mesh_gear, section_area, GearMesh, MeshSpec, ProfileGrading};
use gearfmu::fe::hex8::Formulation;
use gearfmu::gear::{GearPair, PairSpec};
use std::path::Path;

fn pair(name: &str) -> GearPair {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(name);
    GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap()
}

fn material(p: &GearPair) -> Material {
    Material { youngs_modulus_pa: p.youngs_modulus_pa, poisson_ratio: p.poisson_ratio, density_kg_m3: p.density_kg_m3 }
}

/// Mass of the meshed gear = ρ·(profile area × face width − bore), the area by quadrature of the
/// exact profile (fillet + involute), within 0.5 %, for both spacings of the profile rows.
#[test]
fn meshed_mass_equals_density_times_exact_volume() {
    let uniform = MeshSpec { profile_grading: ProfileGrading::Uniform, ..Default::default() };
    for (name, spec) in [
        ("kurokawa_spur.toml", MeshSpec::default()),
        ("kurokawa_helical.toml", MeshSpec::default()),
        ("kurokawa_spur.toml", uniform),
    ] {
        let p = pair(name);
        for gear in [&p.gear1, &p.gear2] {
            let gm = mesh_gear(&p, gear, &spec);
            let meshed = gm.mesh.volume() * p.density_kg_m3;
            let exact = section_area(&p, gear) * p.face_width_m * p.density_kg_m3;
            let error = (meshed - exact) / exact;
            println!(
                "{name} {:?} z = {}: meshed mass {meshed:.5} kg, exact {exact:.5} kg, error {:+.3} %",
                spec.profile_grading,
                gear.teeth,
                100.0 * error
            );
            assert!(error.abs() < 5e-3);
        }
    }
}

/// The lumped model's inertia (quadrature of the profile) against the meshed gear's rotational
/// inertia r_zᵀ M r_z from the consistent mass matrix (two independent integrations).
#[test]
fn gear_inertia_matches_the_meshed_rotational_inertia() {
    for name in ["kurokawa_spur.toml", "kurokawa_helical.toml"] {
        let p = pair(name);
        for gear in [&p.gear1, &p.gear2] {
            let gm = mesh_gear(&p, gear, &MeshSpec::default());
            let dofs = DofMap::unclamped(gm.mesh.nodes.len());
            let m = assembly::mass(&gm.mesh, &material(&p), &dofs);
            let rz = gearfmu::fe::mesh::rigid_body_mode(&gm.mesh.nodes, 5);
            let meshed: f64 = assembly::mul(&m, &rz).iter().zip(&rz).map(|(a, b)| a * b).sum();
            let error = (gear.inertia_kgm2 - meshed) / meshed;
            println!(
                "{name} z = {}: inertia {:.6} kg·m², meshed {meshed:.6} kg·m², {:+.3} %",
                gear.teeth,
                gear.inertia_kgm2,
                100.0 * error
            );
            assert!(error.abs() < 5e-3);
        }
    }
}

/// Every tooth meshed alike: rotating sector k's nodes by one pitch gives sector k+1's.
#[test]
fn rotation_by_one_pitch_maps_nodes_onto_nodes() {
    let p = pair("kurokawa_helical.toml");
    let gm = mesh_gear(&p, &p.gear1, &MeshSpec::default());
    let (z, per) = (gm.teeth, gm.nodes_per_sector);
    let a = 2.0 * std::f64::consts::PI / z as f64;
    let layer = z * per;
    let mut worst: f64 = 0.0;
    for n in 0..gm.mesh.nodes.len() {
        let (l, rest) = (n / layer, n % layer);
        let (k, i) = (rest / per, rest % per);
        let image = l * layer + ((k + 1) % z) * per + i;
        let [x, y, zc] = gm.mesh.nodes[n];
        let rotated = [x * a.cos() - y * a.sin(), x * a.sin() + y * a.cos(), zc];
        let target = gm.mesh.nodes[image];
        worst = worst.max((0..3).map(|c| (rotated[c] - target[c]).abs()).fold(0.0, f64::max));
    }
    assert!(worst < 1e-12, "largest mismatch {worst} m");
}

/// The half turn about the x axis maps the mesh onto itself (what the coast flanks of the
/// PMOR-Hertz model rest on): an involution of the nodes, flank nodes of tooth k, side s, slice l
/// onto tooth −k, side −s, slice n − l with the normal turned likewise, and the unclamped mass
/// and stiffness invariant under it (Kᵀ·(Hf) = H(K f) for a test field) — for a helical gear,
/// where a mirror would swap the hand of helix.
#[test]
fn half_turn_about_x_maps_the_mesh_onto_itself() {
    let p = pair("kurokawa_helical.toml");
    let gm = mesh_gear(&p, &p.gear1, &MeshSpec::default());
    let map = gm.half_turn_about_x().unwrap();
    for (n, &m) in map.iter().enumerate() {
        assert_eq!(map[m], n, "not an involution at node {n}");
    }
    let (z, slices) = (gm.teeth, MeshSpec::default().axial_slices);
    let mut flank_checked = 0;
    for f in &gm.flank_nodes {
        let image =
            gm.flank_nodes.iter().find(|g| g.node == map[f.node]).expect("a flank node's image is a flank node");
        assert_eq!(image.tooth, (z - f.tooth) % z);
        assert_eq!(image.side, -f.side);
        assert_eq!(image.slice, slices - f.slice);
        let turned = [f.normal[0], -f.normal[1], -f.normal[2]];
        assert!((0..3).all(|c| (turned[c] - image.normal[c]).abs() < 1e-9), "normal of node {}", f.node);
        flank_checked += 1;
    }
    assert!(flank_checked > 100);
    let dofs = DofMap::unclamped(gm.mesh.nodes.len());
    let k = assembly::stiffness(&gm.mesh, &material(&p), Formulation::IncompatibleModes, &dofs);
    let turn = |f: &[f64]| GearMesh::half_turn_field(&map, f);
    let field: Vec<f64> = (0..3 * map.len()).map(|d| ((d * 7919) % 1000) as f64 * 1e-3 - 0.5).collect();
    let (k_turned, turned_k) = (assembly::mul(&k, &turn(&field)), turn(&assembly::mul(&k, &field)));
    let scale = turned_k.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let worst = k_turned.iter().zip(&turned_k).fold(0.0_f64, |a, (x, y)| a.max((x - y).abs()));
    assert!(worst < 1e-9 * scale, "K is not invariant under the half turn: {worst:e} of {scale:e}");
}

/// The unclamped gear's K has the six rigid-body motions in its null space (K·r = 0).
#[test]
fn unclamped_gear_has_six_rigid_body_modes() {
    let p = pair("kurokawa_spur.toml");
    let gm = mesh_gear(&p, &p.gear1, &MeshSpec::default());
    let dofs = DofMap::unclamped(gm.mesh.nodes.len());
    let k = assembly::stiffness(&gm.mesh, &material(&p), Formulation::IncompatibleModes, &dofs);
    let k_max = k.as_ref().val().iter().map(|v| v.abs()).fold(0.0, f64::max);
    for mode in 0..6 {
        let r = gearfmu::fe::mesh::rigid_body_mode(&gm.mesh.nodes, mode);
        let kr = assembly::mul(&k, &r);
        let norm_kr = kr.iter().map(|v| v * v).sum::<f64>().sqrt();
        let norm_r = r.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(norm_kr < 1e-9 * k_max * norm_r, "mode {mode}: ‖Kr‖ = {norm_kr:e}");
    }
}

/// The transverse normal of an involute is tangent to the base circle: the line through a flank
/// point along its normal passes at distance r_b from the axis (closed form of the involute).
#[test]
fn flank_normals_are_tangent_to_the_base_circle() {
    let p = pair("kurokawa_spur.toml");
    for gear in [&p.gear1, &p.gear2] {
        let gm = mesh_gear(&p, gear, &MeshSpec::default());
        assert!(!gm.flank_nodes.is_empty());
        for f in &gm.flank_nodes {
            let [x, y, _] = gm.mesh.nodes[f.node];
            let n = f.normal;
            let distance = (x * n[1] - y * n[0]).abs() / n[0].hypot(n[1]);
            assert!(
                (distance - gear.base_radius_m).abs() < 1e-7 * gear.base_radius_m,
                "{distance} vs {}",
                gear.base_radius_m
            );
            assert!(n[2].abs() < 1e-9, "spur flank normals have no axial part");
        }
    }
}

/// The hand of helix and the helicoid, measured on the generated nodes against textbook helical
/// gear geometry (not the mesher's twist formula):
/// - the lead: a node's twist per unit face width, measured from its polar angle in the first
///   and in every other slice, times the node's radius r, is the local helix angle,
///   tan β_r = 2πr/p_z with the textbook lead p_z = π m_n z / sin β (so tan β_r = tan β·r/r_p at
///   any radius); its sign is the hand (+ right, − left), gear 2 opposite to the spec's gear 1;
/// - the involute helicoid: every flank normal makes the base helix angle with the transverse
///   plane, |n_z| = sin β_b with sin β_b = sin β·cos α_n (ISO 21771), and is perpendicular to the
///   measured helix through its node.
#[test]
fn helical_mesh_lead_and_normals_match_textbook_helicoid_geometry() {
    use gearfmu::gear::spec::HelixHand;
    use std::f64::consts::PI;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join("kurokawa_helical.toml");
    for hand in [HelixHand::Right, HelixHand::Left] {
        let mut spec = PairSpec::load(&path).unwrap();
        spec.rack.helix_hand = hand;
        let (m_n, alpha_n, beta) = (
            spec.rack.module_mm * 1e-3,
            spec.rack.pressure_angle_deg.to_radians(),
            spec.rack.helix_angle_deg.to_radians(),
        );
        assert!(beta > 0.0);
        let sin_beta_b = beta.sin() * alpha_n.cos();
        let p = GearPair::from_spec(&spec).unwrap();
        for (gear, sign) in [(&p.gear1, hand.sign()), (&p.gear2, -hand.sign())] {
            let lead = PI * m_n * gear.teeth as f64 / beta.sin();
            let gm = mesh_gear(&p, gear, &MeshSpec::default());
            let at = |n: usize| gm.mesh.nodes[n];
            let flank: Vec<_> = gm.flank_nodes.iter().filter(|f| f.tooth == 0 && f.side == 1).collect();
            let (mut checked, mut worst_lead, mut worst_normal): (usize, f64, f64) = (0, 0.0, 0.0);
            for f in &flank {
                let x = at(f.node);
                // The same profile row in the first slice: same radius, lowest z.
                let r = x[0].hypot(x[1]);
                let base = flank
                    .iter()
                    .map(|g| at(g.node))
                    .filter(|y| (y[0].hypot(y[1]) - r).abs() < 1e-12)
                    .min_by(|a, b| a[2].total_cmp(&b[2]))
                    .unwrap();
                let n = f.normal;
                worst_normal = worst_normal.max((n[2].abs() - sin_beta_b).abs());
                assert!(
                    (n[2].abs() - sin_beta_b).abs() < 1e-6,
                    "{hand:?} z {}: |n_z| {} vs sin β_b {sin_beta_b}",
                    gear.teeth,
                    n[2]
                );
                let dz = x[2] - base[2];
                if dz < 1e-6 {
                    continue;
                }
                let turned = x[1].atan2(x[0]) - base[1].atan2(base[0]);
                let measured = r * turned / dz; // tan β_r, signed by the hand
                let expected = sign * 2.0 * PI * r / lead;
                worst_lead = worst_lead.max((measured - expected).abs() / expected.abs());
                assert!(
                    (measured / expected - 1.0).abs() < 1e-9,
                    "{hand:?} z {}: tan β_r measured {measured}, lead gives {expected}",
                    gear.teeth
                );
                // The measured helix's tangent through the node: d/dz of (r cos φ, r sin φ, z).
                let rate = turned / dz;
                let t = [-x[1] * rate, x[0] * rate, 1.0];
                assert!((n[0] * t[0] + n[1] * t[1] + n[2] * t[2]).abs() < 1e-6, "normal not on the flank");
                checked += 1;
            }
            println!(
                "{hand:?} z {}: {checked} nodes, lead p_z = π m_n z / sin β = {:.2} mm; largest relative error of \
                 tan β_r {worst_lead:.1e}, of |n_z| − sin β_b {worst_normal:.1e}",
                gear.teeth,
                lead * 1e3
            );
            assert!(checked > 20);
        }
    }
}
