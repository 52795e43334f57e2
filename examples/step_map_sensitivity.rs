//! Study (issue 38): why two masters that feed the discrete-gradient FMU the same inputs, one
//! with h = 1e-4 s and one with h one ulp longer (libcosim forms h as a difference of
//! nanosecond times), drew apart on example 3 when the body modes up to 6 × the mesh mode are
//! dynamic. Runs example 3 in process (185 N·m after a 5 ms haversine ramp, a viscous load of
//! 20 N·m·s/rad on gear 2 fed back from ω₂ at each step's start, from rest) twice with the
//! given body cut-off, and prints, per communication step, the two runs' difference in ω₂ and
//! in each block of the state (θ, ω, the slow body coordinates η_Φ, the shapes η_Ψ), with the
//! body mode that carries most of it.
//!
//!     cargo run --release --example step_map_sensitivity -- out/KurokawaSpur.fmu 6 [t_end_ms]
#[path = "common/fmu_model.rs"]
mod fmu_model;
use gearfmu::dynamics::pmor::{quasi_static, PmorDynamics, PmorState};

const COMM_STEP_S: f64 = 1e-4;
const TORQUE_NM: f64 = 185.0;
const RAMP_S: f64 = 5e-3;
const LOAD_N_M_S: f64 = 20.0;

fn run(d: &PmorDynamics, h: f64, steps: usize, max_step: f64) -> Result<Vec<PmorState>, String> {
    let mut s = d.start_state([0.0; 2], [0.0; 2], [0.0; 2])?;
    let mut states = vec![s.clone()];
    for k in 0..steps {
        let t = k as f64 * COMM_STEP_S;
        let tau_1 =
            if t < RAMP_S { TORQUE_NM * 0.5 * (1.0 - (std::f64::consts::PI * t / RAMP_S).cos()) } else { TORQUE_NM };
        let (_, w_2) = d.port(1, &s)?;
        d.advance(&mut s, [tau_1, -LOAD_N_M_S * w_2], h, max_step)?;
        states.push(s.clone());
    }
    Ok(states)
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or("usage: step_map_sensitivity FMU [cutoff factor] [t_end_ms]")?;
    let factor: f64 = args.get(2).map_or(Ok(6.0), |t| t.parse()).map_err(|_| "cutoff factor")?;
    let t_end_ms: f64 = args.get(3).map_or(Ok(16.0), |t| t.parse()).map_err(|_| "t_end_ms")?;
    let max_step_arg: Option<f64> = args.get(4).map(|t| t.parse()).transpose().map_err(|_| "max_step")?;
    let model = fmu_model::pmor_model(path)?;
    let place = gearfmu::contact::mesh_kinematics::PairPlacement::new(&model.pair);
    let damping = model.damping(model.modal_damping_ratio, model.shape_damping_ratio);
    let mut d = PmorDynamics::new(&model, &place, damping, [0.0; 2]);
    let inertia = [model.gears[0].polar_inertia_kgm2, model.gears[1].polar_inertia_kgm2];
    d.mesh_damping_n_s_per_m = model.mesh_damper_n_s_per_m(model.pair.mesh_damping_ratio, inertia);
    let mesh_mode_hz = quasi_static::mesh_mode_estimate_hz(&model);
    d.set_quasi_static_cutoff(factor * mesh_mode_hz);
    let steps = (t_end_ms * 1e-3 / COMM_STEP_S).round() as usize;
    let h_next = f64::from_bits(COMM_STEP_S.to_bits() + 1);
    let max_step = max_step_arg.unwrap_or(model.max_step_s);
    let wall = std::time::Instant::now();
    let a = run(&d, COMM_STEP_S, steps, max_step)?;
    let wall_s = wall.elapsed().as_secs_f64();
    let (evaluations, solves) = d.condensed().map_or((0, 0), |q| q.counts.get());
    let b = run(&d, h_next, steps, max_step)?;
    let g = &model.gears;
    let hz = |lambda: f64| lambda.max(0.0).sqrt() / (2.0 * std::f64::consts::PI);
    println!(
        "cut-off {factor} × {mesh_mode_hz:.0} Hz; max_step {:e} s; modes {} / {}, shapes {} / {}",
        max_step,
        g[0].modes(),
        g[1].modes(),
        g[0].shapes,
        g[1].shapes
    );
    for (i, gear) in g.iter().enumerate() {
        let list: Vec<String> = gear.eigenvalues.iter().map(|&l| format!("{:.0}", hz(l))).collect();
        println!("gear {} body modes (Hz): {}", i + 1, list.join(" "));
    }
    println!(
        "one run: {wall_s:.3} s, {evaluations} contact evaluations, {solves} quasi-static solves ({:.1} / {:.1} per communication step)",
        evaluations as f64 / steps as f64,
        solves as f64 / steps as f64
    );
    println!(
        "step  t_ms   dω₂          dθ₂          |dη_Φ| g1/g2          |dη_Ψ| g1/g2          top mode (gear, j, Hz, dη̇)"
    );
    for k in 0..=steps {
        let (sa, sb) = (&a[k], &b[k]);
        let mut top = (0, 0, 0.0_f64);
        let mut norms = [[0.0_f64; 2]; 2];
        for i in 0..2 {
            let n_k = g[i].modes();
            for j in 0..sa.eta[i].len() {
                let de = sb.eta[i][j] - sa.eta[i][j];
                norms[usize::from(j >= n_k)][i] += de * de;
                if j < n_k && (sb.eta_dot[i][j] - sa.eta_dot[i][j]).abs() > top.2.abs() {
                    top = (i, j, sb.eta_dot[i][j] - sa.eta_dot[i][j]);
                }
            }
        }
        if k % 5 == 0 || k + 1 >= steps {
            println!(
                "{k:4} {:6.2} {:+.3e} {:+.3e} {:.2e}/{:.2e} {:.2e}/{:.2e} ({}, {}, {:.0}, {:+.2e}; itself {:+.2e})",
                k as f64 * COMM_STEP_S * 1e3,
                sb.omega[1] - sa.omega[1],
                sb.theta[1] - sa.theta[1],
                norms[0][0].sqrt(),
                norms[0][1].sqrt(),
                norms[1][0].sqrt(),
                norms[1][1].sqrt(),
                top.0 + 1,
                top.1,
                hz(g[top.0].eigenvalues[top.1]),
                top.2,
                sa.eta_dot[top.0][top.1]
            );
        }
    }
    Ok(())
}
