//! Single-tooth stiffness by finite elements at the pitch point of the Kurokawa spur pinion and
//! wheel, against two independent references: the potential-energy method's tooth compliance
//! (beam theory + Sainsot's foundation, `dynamics::mesh_stiffness`) and ISO 6336-1's c′_th.

use gearfmu::dynamics::iso6336;
use gearfmu::dynamics::mesh_stiffness::tooth_compliance_per_width;
use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::fe::hex8::Formulation;
use gearfmu::fe::tooth_stiffness::single_tooth_compliance;
use gearfmu::gear::{GearPair, PairSpec};

#[test]
fn pitch_point_tooth_compliance_agrees_with_the_potential_energy_method() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
    let p = GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap();
    let spec = MeshSpec {
        elements_across_tooth: 6,
        elements_along_profile: 12,
        elements_in_rim: 6,
        axial_slices: 4,
        ..Default::default()
    };
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
