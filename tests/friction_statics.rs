//! Tooth friction in the statics (issue 42): experiment.

use gearfmu::contact::hertz::ApproachLaw;
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::rom::sweep::{Method, ReducedPair};

fn pair(file: &str) -> (GearPair, PairSpec) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(file);
    let spec = PairSpec::load(&path).unwrap();
    (GearPair::from_spec(&spec).unwrap(), spec)
}

#[test]
fn experiment() {
    let (p, spec) = pair("kurokawa_spur.toml");
    let hertz = Method::PmorHertz { depth_m: 3e-3, p_en: gearfmu::rom::svd::DEFAULT_P_EN, law: ApproachLaw::Weber };
    let t0 = std::time::Instant::now();
    let a = ReducedPair::build_for_friction(&p, &spec.mesh, hertz, |_, _| {}).unwrap();
    eprintln!("pmor build {:.1} s", t0.elapsed().as_secs_f64());
    let t0 = std::time::Instant::now();
    let b = ReducedPair::build_for_friction(&p, &spec.mesh, Method::Penalty { factor: 100.0 }, |_, _| {}).unwrap();
    eprintln!("penalty build {:.1} s", t0.elapsed().as_secs_f64());
    let angles = 24;
    for torque in [185.0, 370.251] {
        for (name, r) in [("pmor", &a), ("penalty", &b)] {
            let s0 = r.sweep_with_friction(&[torque], angles, 1.0, 0.0);
            let s1 = r.sweep_with_friction(&[torque], angles, 1.0, 0.05);
            let mut m = [0.0; 2];
            for k in 0..angles {
                let (c0, c1) = (s0[k].as_ref().unwrap(), s1[k].as_ref().unwrap());
                m[0] += c0.ste_m / angles as f64;
                m[1] += c1.ste_m / angles as f64;
                let fr: f64 = c1.elements.iter().map(|e| e.friction_force_n).sum();
                eprintln!(
                    "{name} T {torque} k {k:2}: pairs {} STE0 {:.4} STEμ {:.4} µm Δ {:+.3} %  F0 {:.1} Fμ {:.1} friction {:.1}",
                    c1.pairs_in_contact,
                    c0.ste_m * 1e6,
                    c1.ste_m * 1e6,
                    (c1.ste_m / c0.ste_m - 1.0) * 100.0,
                    c0.mesh_force_n,
                    c1.mesh_force_n,
                    fr
                );
            }
            eprintln!("{name} T {torque}: mean STE0 {:.4} STEμ {:.4} Δ {:+.3} %", m[0] * 1e6, m[1] * 1e6, (m[1] / m[0] - 1.0) * 100.0);
        }
    }
}

#[test]
fn cross_compliance() {
    for file in ["kurokawa_spur.toml", "kurokawa_helical.toml"] {
        let (p, spec) = pair(file);
        let hertz = Method::PmorHertz { depth_m: 3e-3, p_en: gearfmu::rom::svd::DEFAULT_P_EN, law: ApproachLaw::Weber };
        let a = ReducedPair::build_for_friction(&p, &spec.mesh, hertz, |_, _| {}).unwrap();
        let b = ReducedPair::build_for_friction(&p, &spec.mesh, Method::Penalty { factor: 100.0 }, |_, _| {}).unwrap();
        for i in 0..2 {
            let g = &a.gears[i];
            let rows = &g.flank.row_radius_m;
            let sections = g.flank.layer_z_m.len() - 1;
            let tooth = g.flank.teeth[0];
            for s in [0, sections / 2] {
                for k in 0..2 * rows.len() - 1 {
                    let r = if k % 2 == 0 { rows[k / 2] } else { 0.5 * (rows[k / 2] + rows[k / 2 + 1]) };
                    let mut out = Vec::new();
                    for red in [&a.gears[i], &b.gears[i]] {
                        let sh = red.flank.point_shares(tooth, r, s).unwrap();
                        let gap = red.projected_row(&sh, red.flank.normal(&sh));
                        let nt = red.tangential_load_response(&sh).unwrap().dot(&gap);
                        let nn = red.load_response(&sh).dot(&gap);
                        // reciprocity: tangential displacement from normal load
                        let trow = {
                            let mut row = vec![0.0; red.size()];
                            for &(kk, w) in &sh {
                                let t = red.flank.transverse_tangent(kk);
                                let pr = red.projected_row(&vec![(kk, w)], t);
                                row.iter_mut().zip(&pr).for_each(|(x, y)| *x += y);
                            }
                            row
                        };
                        let tn = red.load_response(&sh).dot(&trow);
                        let tt = red.tangential_load_response(&sh).unwrap().dot(&trow);
                        out.push((nt, nn, tn, tt));
                    }
                    eprintln!(
                        "{file} gear {} s {s} r {:.2} mm: c_nt pmor {:.3e} fe {:.3e} ({:+.1} %); c_nn {:.3e} / {:.3e}; c_tn {:.3e}/{:.3e}; c_tt {:.3e}/{:.3e}",
                        i + 1,
                        r * 1e3,
                        out[0].0,
                        out[1].0,
                        (out[0].0 / out[1].0 - 1.0) * 100.0,
                        out[0].1,
                        out[1].1,
                        out[0].2,
                        out[1].2,
                        out[0].3,
                        out[1].3,
                    );
                }
            }
        }
    }
}
