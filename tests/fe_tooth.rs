//! Single-tooth stiffness by finite elements at the pitch point of the Kurokawa spur pinion and
//! wheel, against two independent references: the potential-energy method's tooth compliance
//! (beam theory + Sainsot's foundation, `dynamics::mesh_stiffness`) and ISO 6336-1's c′_th.

mod common;

use gearfmu::dynamics::iso6336;
use gearfmu::dynamics::mesh_stiffness::tooth_compliance_per_width;
use gearfmu::fe::gear_mesh::{mesh_gear, MeshSpec};
use gearfmu::fe::hex8::Formulation;
use gearfmu::fe::tooth_stiffness::{single_tooth_compliance, tooth_compliance_along_profile};
use gearfmu::gear::GearPair;

/// The Kurokawa spur pair on the medium mesh (4 axial slices).
fn kurokawa_spur_on_a_medium_mesh() -> (GearPair, MeshSpec) {
    (common::kurokawa_spur(), common::medium_mesh(4))
}

#[test]
fn pitch_point_tooth_compliance_agrees_with_the_potential_energy_method() {
    let (p, spec) = kurokawa_spur_on_a_medium_mesh();
    let mut pair_fe = 0.0;
    for gear in [&p.gear1, &p.gear2] {
        let fe = single_tooth_compliance(&p, gear, &spec, Formulation::IncompatibleModes).unwrap();
        let pem = tooth_compliance_per_width(gear, &p, gear.pitch_radius_m, p.youngs_modulus_pa, p.poisson_ratio);
        let ratio = fe.compliance_per_width / pem;
        println!(
            "z = {}: FE {:.5} mm·µm/N ({} DOF), potential energy {:.5} mm·µm/N, FE/PEM {ratio:.3}",
            gear.teeth,
            fe.compliance_per_width * 1e9,
            fe.dofs,
            pem * 1e9
        );
        // Two independent models of the same tooth (3-D elasticity vs beam + foundation fit).
        assert!((0.9..1.1).contains(&ratio), "FE/PEM = {ratio}");
        pair_fe += fe.compliance_per_width;
    }
    let c_fe = 1.0 / (pair_fe * 1e9);
    // The q′ series is for steel (E_st = 206 GPa): compare at the pair's own modulus.
    let c_th = iso6336::theoretical_single_stiffness(&p) * iso6336::material_factor(&p);
    let c_prime = iso6336::single_stiffness(&p);
    println!(
        "pair at the pitch point: FE {c_fe:.2} N/(mm·µm); ISO c′_th·E/E_st {c_th:.2} (ratio {:.3}); ISO c′ = c′_th·C_M·C_B·E/E_st {c_prime:.2} (ratio {:.3})",
        c_fe / c_th,
        c_fe / c_prime
    );
}

/// The tooth softens as the load climbs toward the tip: FE and the potential-energy method
/// (beam + Sainsot foundation, no FE) must agree on how much. The FE compliance under a line load
/// also holds a local, log-singular part that the mesh sets (see the test above); it is nearly the
/// same at every load radius, so the comparison is on the rise over the pitch circle, where
/// bending dominates.
///
/// Combined into tooth pairs that act independently (no contact term, no coupling through the
/// gear body), both models give a double-contact zone 1.74× as stiff as the single-contact zone:
/// ISO 6336-1's c_γα = c′(0.75ε_α + 0.25) implies 1.75. So the variation of tooth stiffness along
/// the path is not where the PMOR-Hertz STE parts from ISO (issue 4); see BENCHMARKS.md.
#[test]
fn tooth_softening_toward_the_tip_agrees_with_the_potential_energy_method() {
    let (p, spec) = kurokawa_spur_on_a_medium_mesh();
    // Active profile of each gear: from its lowest contact radius to its highest.
    let (start, end) = (p.contact_radii(p.path_start_m), p.contact_radii(p.path_end_m));
    let active = [(start.0, end.0), (end.1, start.1)];
    // Per gear: the load radii and the FE and PEM compliances there (mm·µm/N).
    let mut along = Vec::new();
    for (gear, (r_low, r_high)) in [&p.gear1, &p.gear2].into_iter().zip(active) {
        // The meshed flank starts at its first node row at or above the form circle.
        let gm = mesh_gear(&p, gear, &spec);
        let lowest_row = gm
            .flank_nodes
            .iter()
            .map(|f| gm.mesh.nodes[f.node][0].hypot(gm.mesh.nodes[f.node][1]))
            .fold(f64::MAX, f64::min);
        let r_low = r_low.max(lowest_row + 1e-6);
        let mut radii: Vec<f64> = (0..=6).map(|i| r_low + (r_high - r_low) * i as f64 / 6.0).collect();
        radii.push(gear.pitch_radius_m);
        let fe: Vec<f64> = tooth_compliance_along_profile(&p, gear, &spec, Formulation::IncompatibleModes, &radii)
            .unwrap()
            .iter()
            .map(|c| c.compliance_per_width * 1e9)
            .collect();
        let pem: Vec<f64> = radii
            .iter()
            .map(|&r| tooth_compliance_per_width(gear, &p, r, p.youngs_modulus_pa, p.poisson_ratio) * 1e9)
            .collect();
        let (fe_pitch, pem_pitch) = (fe[7], pem[7]);
        for i in 0..7 {
            let (fe_rise, pem_rise) = (fe[i] - fe_pitch, pem[i] - pem_pitch);
            println!(
                "z = {}: r {:.2} mm: FE {:.5}, PEM {:.5} mm·µm/N; rise over the pitch circle FE {fe_rise:+.5}, PEM {pem_rise:+.5}",
                gear.teeth,
                radii[i] * 1e3,
                fe[i],
                pem[i]
            );
            // Where bending dominates (a rise above 0.01 mm·µm/N, the upper half of the active
            // profile), two independent models of the same tooth must agree on it.
            if pem_rise > 0.01 {
                assert!(
                    (fe_rise / pem_rise - 1.0).abs() < 0.2,
                    "z = {}: FE rise {fe_rise} vs PEM {pem_rise}",
                    gear.teeth
                );
            }
        }
        along.push((radii[..7].to_vec(), fe[..7].to_vec(), pem[..7].to_vec()));
    }
    // What it does to the pair: the structural pair stiffness (no contact term) averaged over the
    // double-contact zone (two pairs, at u and u + p_b) against the single-contact zone. ISO's
    // c_γα = c′(0.75ε_α + 0.25) implies 1.75 when c′ is the single-zone stiffness.
    let interpolate = |xs: &[f64], ys: &[f64], x: f64| {
        let k = xs.windows(2).position(|w| x <= w[1]).unwrap_or(xs.len() - 2);
        let t = ((x - xs[k]) / (xs[k + 1] - xs[k])).clamp(0.0, 1.0);
        ys[k] + t * (ys[k + 1] - ys[k])
    };
    let pair_stiffness = |u: f64, which: usize| {
        let (r1, r2) = p.contact_radii(u);
        let (g1, g2) = (&along[0], &along[1]);
        let c1 = interpolate(&g1.0, if which == 0 { &g1.1 } else { &g1.2 }, r1);
        let c2 = interpolate(&g2.0, if which == 0 { &g2.1 } else { &g2.2 }, r2);
        1.0 / (c1 + c2)
    };
    let (a, pb, eps) = (p.path_start_m, p.base_pitch_m, p.transverse_contact_ratio);
    let n = 40;
    let mut ratios = Vec::new();
    for (which, name) in [(0, "FE"), (1, "potential energy")] {
        let double = (0..n)
            .map(|i| a + (eps - 1.0) * pb * (i as f64 + 0.5) / n as f64)
            .map(|u| pair_stiffness(u, which) + pair_stiffness(u + pb, which))
            .sum::<f64>()
            / n as f64;
        let single = (0..n)
            .map(|i| a + (eps - 1.0) * pb + (2.0 - eps) * pb * (i as f64 + 0.5) / n as f64)
            .map(|u| pair_stiffness(u, which))
            .sum::<f64>()
            / n as f64;
        println!(
            "{name}: structural pair stiffness, double-contact zone / single-contact zone = {:.3}",
            double / single
        );
        ratios.push(double / single);
    }
    assert!((ratios[0] / ratios[1] - 1.0).abs() < 0.05, "FE {} vs potential energy {}", ratios[0], ratios[1]);
}
