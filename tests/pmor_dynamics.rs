//! The PMOR-Hertz dynamic model (design §4.5) against independent references: the FE model it
//! was reduced from (eigenfrequencies, inertia), the statics it must reproduce in the slow limit,
//! and conservation of energy.

mod common;

use gearfmu::contact::mesh_kinematics::PairPlacement;
use gearfmu::dynamics::pmor::model::PmorModel;
use gearfmu::dynamics::pmor::PmorDynamics;
use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::rom::dynamic_reductor::{build_dynamic_model, DynamicBuildOptions, DynamicBuildReport};
use std::sync::OnceLock;

fn spur_model() -> &'static (PmorModel, DynamicBuildReport) {
    static MODEL: OnceLock<(PmorModel, DynamicBuildReport)> = OnceLock::new();
    MODEL.get_or_init(|| {
        let pair = common::kurokawa_spur();
        let t = std::time::Instant::now();
        let out = build_dynamic_model(&pair, &MeshSpec::default(), &DynamicBuildOptions::default(), |m| eprintln!("{m}"))
            .unwrap();
        eprintln!("offline build {:.1} s", t.elapsed().as_secs_f64());
        out
    })
}

#[test]
fn explore() {
    let (model, report) = spur_model();
    eprintln!("modes Hz {:?}", report.modes_hz);
    eprintln!("invariance {:?} closure {:?} resid {:?} inertia {:?} n_sv {:?}", report.invariance_residual, report.closure_residual, report.residualization, report.polar_inertia_kgm2, report.n_sv);
    for g in &model.gears {
        let k = &g.pair_invariants(10, 10).k_ss;
        let m = &g.pair_invariants(10, 10).s_s;
        eprintln!("shape k {:?} m {:?} -> f {:?}", k, m, (0..g.shapes).map(|t| (k[(t,t)]/m[(t,t)]).sqrt()/6.283).collect::<Vec<_>>());
    }
    for g in &model.gears {
        use gearfmu::dynamics::pmor::equations::{gear_terms, Damping};
        let st = g.stencil(model.interpolation, 0.3 * g.pitch_rad()).unwrap();
        let n = g.elastic_size();
        let t = gear_terms(g, &st, &vec![0.0; n], 0.0, &vec![0.0; n], Damping { modes_ratio: 0.0, shapes_ratio: 0.0 });
        let mut k = nalgebra::DMatrix::<f64>::zeros(n + 1, n + 1);
        for j in 0..g.modes() { k[(1 + j, 1 + j)] = g.eigenvalues[j]; }
        for a in 0..g.shapes { for b in 0..g.shapes {
            let mut v = 0.0; for (x, wa) in st.weights.w.iter().enumerate() { for (y, wb) in st.weights.w.iter().enumerate() {
                let (lo, hi) = if x <= y { (x, y) } else { (y, x) };
                let kk = &g.pair_invariants(st.a0 + lo, st.a0 + hi).k_ss; v += wa * wb * if x <= y { kk[(a, b)] } else { kk[(b, a)] }; } }
            k[(1 + g.modes() + a, 1 + g.modes() + b)] = v; } }
        let l = t.mass.clone().cholesky().unwrap().l();
        let li = l.try_inverse().unwrap();
        let a = &li * &k * li.transpose();
        let mut ev: Vec<f64> = nalgebra::SymmetricEigen::new(a).eigenvalues.iter().map(|x| x.max(0.0).sqrt() / 6.2832).collect();
        ev.sort_by(f64::total_cmp);
        eprintln!("coupled freqs Hz {:?}", ev);
        eprintln!("M theta row {:?}", t.mass.row(0));
    }
    let place = PairPlacement::new(&model.pair);
    let dynamics = PmorDynamics { model, place: &place, damping: model.damping(0.0, 0.0), added_inertia_kgm2: [0.0; 2] };
    let rb = [model.pair.gear1.base_radius_m, model.pair.gear2.base_radius_m];
    let w2: f64 = std::env::var("W2").map(|v| v.parse().unwrap()).unwrap_or(20.0);
    let h: f64 = std::env::var("H").map(|v| v.parse().unwrap()).unwrap_or(1e-6);
    let steps: usize = std::env::var("STEPS").map(|v| v.parse().unwrap()).unwrap_or(2000);
    let w1 = w2 * rb[1] / rb[0];
    let t1: f64 = std::env::var("T1").map(|v| v.parse().unwrap()).unwrap_or(200.0);
    let torques = [t1, -t1 * rb[1] / rb[0]];
    let te0: f64 = std::env::var("TE0").map(|v| v.parse().unwrap()).unwrap_or(5e-6);
    let mut s = model.initial_state([te0 / rb[0], 0.0], [w1, w2]);
    if let Ok(v) = std::env::var("FREE") {
        let v: f64 = v.parse().unwrap();
        for i in 0..2 {
            let n = s.eta_dot[i].len();
            for k in 0..n { s.eta_dot[i][k] = v * ((k * 7 + i * 3) % 5) as f64 / 5.0; }
            s.eta_dot[i][n - 1] = v; s.eta_dot[i][n - 2] = -v;
        }
    }
    let e0 = dynamics.outputs(&s).unwrap();
    let pot = |s: &gearfmu::dynamics::pmor::PmorState| -(torques[0] * s.theta[0] + torques[1] * s.theta[1]);
    let base = e0.total_energy_j() + pot(&s);
    eprintln!("E0 kin {} el {} contact {} F {}", e0.kinetic_j, e0.elastic_j, e0.contact_j, e0.contact.normal_force_n);
    let t0 = std::time::Instant::now();
    for k in 0..steps {
        dynamics.step(&mut s, torques, h).unwrap();
        if k % (steps / 20) == 0 || k == steps - 1 {
            let o = dynamics.outputs(&s).unwrap();
            let e = o.total_energy_j() + pot(&s);
            eprintln!("t {:.4e} dE {:.3e} kin {:.6e} el {:.3e} c {:.3e} F {:.1} te {:.3e} anchors {:?}", (k+1) as f64 * h, e - base, o.kinetic_j, o.elastic_j, o.contact_j, o.contact.normal_force_n, rb[0]*s.theta[0]-rb[1]*s.theta[1], s.anchor);
        }
    }
    eprintln!("{:.1} us per step", t0.elapsed().as_secs_f64() / steps as f64 * 1e6);
}

#[test]
fn explore_start() {
    let (model, _) = spur_model();
    let place = PairPlacement::new(&model.pair);
    let dynamics = PmorDynamics { model, place: &place, damping: model.damping(0.01, 0.05), added_inertia_kgm2: [0.0; 2] };
    let rb = [model.pair.gear1.base_radius_m, model.pair.gear2.base_radius_m];
    let mut s = model.initial_state([0.0, 0.0], [0.0, 0.0]);
    for k in 0..100 {
        if k == 1 {
            let y = dynamics.pack(&s);
            let f0 = dynamics.rhs(&y, s.anchor, [120.0, -150.0]).unwrap().0;
            let n = y.len();
            let mut jac = nalgebra::DMatrix::<f64>::zeros(n, n);
            for c in 0..n {
                let mut yp = y.clone();
                let dh = 1e-9 * y[c].abs().max(1e-9);
                yp[c] += dh;
                let fp = dynamics.rhs(&yp, s.anchor, [120.0, -150.0]).unwrap().0;
                for r in 0..n { jac[(r, c)] = (fp[r] - f0[r]) / dh; }
            }
            let ev = jac.complex_eigenvalues();
            let mut mags: Vec<(f64, usize)> = ev.iter().enumerate().map(|(i, z)| (z.norm(), i)).collect();
            mags.sort_by(|a, b| b.0.total_cmp(&a.0));
            eprintln!("largest |lambda| {:?}", &mags[..6].iter().map(|(m, i)| (m / 6.2832, ev[*i])).collect::<Vec<_>>());
        }
        if let Err(e) = dynamics.step(&mut s, [120.0, -150.0], std::env::var("H").map(|v| v.parse().unwrap()).unwrap_or(1e-6)) { eprintln!("fail {k}: {e}"); break; }
        let o = match dynamics.outputs(&s) { Ok(o) => o, Err(e) => {
            eprintln!("outputs fail {e}");
            for j in gearfmu::dynamics::pmor::contact::candidate_pairs(model, s.theta[1]) { for sec in 0..4 {
                let c = place.section_contact(s.theta, j, sec, 0.0);
                eprintln!("j {j} sec {sec} {:?}", c.map(|c| (c.kind, c.rigid_penetration_m, c.radius_m, c.teeth)));
            }}
            eprintln!("eta {:?}", s.eta);
            break; } };
        eprintln!("{k} te {:.3e} F {:.1} th {:?} om {:?} eta1 {:.3e} {:.3e}", rb[0]*s.theta[0]-rb[1]*s.theta[1], o.contact.normal_force_n, s.theta, s.omega, s.eta[0].iter().map(|x| x.abs()).fold(0.0, f64::max), s.eta[1].iter().map(|x| x.abs()).fold(0.0, f64::max));
    }
}
