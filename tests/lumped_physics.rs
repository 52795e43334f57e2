//! The lumped model against independent references: a power balance (steady speed), ISO 6336-1
//! mesh stiffness, the mesh natural frequency √(k̄/m_e), conservation of energy, and the
//! kinematics of backlash (contact loss, back-flank contact).

use gearfmu::contact::hertz::{ApproachLaw, Body, LineContact};
use gearfmu::dynamics::iso6336;
use gearfmu::dynamics::lumped::{mesh_natural_frequency_hz, LumpedMesh, LumpedModel, LumpedParameters, LumpedState};
use gearfmu::dynamics::mesh_stiffness::structural_compliance_per_width;
use gearfmu::gear::{GearPair, HertzContact, PairSpec};
use rustfft::{num_complex::Complex, FftPlanner};
use std::path::Path;

const PAIRS: [&str; 2] = ["kurokawa_spur.toml", "kurokawa_helical.toml"];

fn pair(name: &str) -> GearPair {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(name);
    GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap()
}

fn pair_with(name: &str, contact: HertzContact) -> GearPair {
    GearPair { hertz_contact: contact, ..pair(name) }
}

fn lumped(p: &GearPair) -> LumpedMesh {
    LumpedMesh::from_pair(p).unwrap()
}

/// The paper's Example 3 drive: 185 N·m with a haversine ramp over 5 ms.
fn seed_torque(t: f64) -> f64 {
    185.0 * if t < 5e-3 { 0.5 * (1.0 - (std::f64::consts::PI * t / 5e-3).cos()) } else { 1.0 }
}

/// Runs the seed example (gear 2 loaded by a viscous torque −c·ω₂, held over each 1 µs step)
/// and returns ω₂ averaged over the last `average_over` seconds.
fn run_seed(model: &LumpedModel, t_end: f64, load_c: f64, average_over: f64) -> f64 {
    let h = 1e-6;
    let mut s = LumpedState::default();
    let steps = (t_end / h).round() as usize;
    let averaged = (average_over / h).round() as usize;
    let mut sum = 0.0;
    for k in 0..steps {
        let t = k as f64 * h;
        let torques = [seed_torque(t + 0.5 * h), -load_c * s.omega_2];
        s = model.rk4_step(&s, torques, h);
        if k >= steps - averaged {
            sum += s.omega_2;
        }
    }
    sum / averaged as f64
}

/// Power balance: at steady state T₁ω₁ = c·ω₂² and ω₁ = ω₂·z₂/z₁, so ω₂ = T₁z₂/(z₁c).
#[test]
fn seed_example_reaches_the_power_balance_speed() {
    for name in PAIRS {
        let p = pair(name);
        let mesh = lumped(&p);
        let model = LumpedModel::with_defaults(&mesh);
        let load_c = 20.0;
        let expected = 185.0 * p.gear2.teeth as f64 / (p.gear1.teeth as f64 * load_c);
        // Each tooth-pair change rings the mesh (≈3 kHz), so ω₂ is averaged over two whole mesh
        // periods, 2·2π/(z₂ω₂), after 60 ms (> 15 time constants J_eq/c of both pairs).
        let mesh_period = 2.0 * std::f64::consts::PI / (p.gear2.teeth as f64 * expected);
        let omega_2 = run_seed(&model, 0.060, load_c, 2.0 * mesh_period);
        let error = (omega_2 - expected).abs() / expected;
        println!(
            "{name}: mean ω₂ = {omega_2:.4} rad/s, power balance {expected:.4} rad/s, error {:.3} %",
            100.0 * error
        );
        assert!(error < 0.005, "{name}: ω₂ {omega_2} vs {expected}");
    }
}

/// ISO 6336-1 method B: c_γα = c′(0.75ε_α + 0.25) with c′ from the q′ series, C_M 0.8, C_B,
/// against the mean secant stiffness at 200 N/mm (ISO's range is ≥ 100 N/mm). Asserted for the
/// potential-energy teeth with Yang & Lin's linearized contact; the load-dependent Weber contact
/// (the default) is printed beside it: it is softer, see the closing note of issue 2.
#[test]
fn linearized_contact_mesh_stiffness_within_20_percent_of_iso_6336() {
    for name in PAIRS {
        let p = pair(name);
        let iso = iso6336::to_newton_per_metre(iso6336::mesh_stiffness_c_gamma_alpha(&p), p.face_width_m);
        let force = 200.0e3 * p.face_width_m;
        let linear = lumped(&pair_with(name, HertzContact::Linearized)).drive.mean_secant_stiffness(force) / iso;
        let weber = lumped(&pair_with(name, HertzContact::Weber)).drive.mean_secant_stiffness(force) / iso;
        println!("{name}: ISO c_γα·b = {iso:.4e} N/m; mean secant stiffness at 200 N/mm: linearized contact {linear:.3} × ISO, Weber contact {weber:.3} × ISO");
        assert!((0.8..=1.2).contains(&linear), "{name}: ratio {linear}");
    }
}

/// Where a single tooth pair carries the whole load (spur, single-contact zone), the mesh law must
/// be the closed form δ(F) = F·c_teeth/b + δ_Hertz(F): the teeth in series with Weber's line
/// contact. And the stiffness is load-dependent: the secant stiffness grows with load.
#[test]
fn weber_mesh_law_matches_the_single_pair_closed_form_and_stiffens_with_load() {
    let p = pair_with("kurokawa_spur.toml", HertzContact::Weber);
    let mesh = lumped(&p);
    let n = mesh.drive.rows();
    let i = (0..n).find(|&i| mesh.drive_pairs[i] == 1 && mesh.drive_pairs[(i + 8) % n] == 1).unwrap() + 4;
    let roll = p.base_pitch_m * i as f64 / n as f64;
    // The one pair touching at this roll: u = u_A + ξ + j·p_b inside the path.
    let u = (-2..=2)
        .map(|j| p.path_start_m + roll + j as f64 * p.base_pitch_m)
        .find(|u| (p.path_start_m..=p.path_end_m).contains(u))
        .unwrap();
    let (r1, r2) = p.contact_radii(u);
    let (rho1, rho2) = p.radii_of_curvature(u);
    let alpha_t = p.transverse_pressure_angle_rad;
    let depth = |g: &gearfmu::gear::Gear, r: f64| r * g.profile_half_thickness_angle(r, alpha_t).sin();
    let body = |rho, h| Body {
        youngs_modulus_pa: p.youngs_modulus_pa,
        poisson_ratio: p.poisson_ratio,
        radius_of_curvature_m: rho,
        reference_depth_m: h,
    };
    let contact = LineContact {
        length_m: p.face_width_m,
        bodies: [body(rho1, depth(&p.gear1, r1)), body(rho2, depth(&p.gear2, r2))],
        law: ApproachLaw::Weber,
    };
    let teeth = structural_compliance_per_width(&p, u) / p.face_width_m;
    let mut previous_secant = 0.0;
    for specific_load in [25.0, 100.0, 400.0, 1000.0] {
        let force = specific_load * 1e3 * p.face_width_m;
        let closed_form = force * teeth + contact.hertz_approach(force);
        let law = mesh.drive.static_deflection(force, roll);
        let error = (law - closed_form).abs() / closed_form;
        // The law interpolates linearly between force levels (dense where the contact is most
        // nonlinear); 0.5 % bounds that interpolation.
        println!(
            "{specific_load} N/mm: δ law {:.4} µm, closed form {:.4} µm, error {:.3} %",
            law * 1e6,
            closed_form * 1e6,
            100.0 * error
        );
        assert!(error < 5e-3, "{specific_load} N/mm: {law} vs {closed_form}");
        let secant = mesh.drive.mean_secant_stiffness(force);
        assert!(secant > previous_secant, "secant stiffness must grow with load");
        previous_secant = secant;
    }
}

/// FFT peak (Hz) of a signal sampled at h, searched within ±50 % of `near`.
fn spectral_peak(signal: &[f64], h: f64, near: f64) -> f64 {
    let n = signal.len();
    let mean = signal.iter().sum::<f64>() / n as f64;
    let mut buf: Vec<Complex<f64>> = signal.iter().map(|x| Complex::new(x - mean, 0.0)).collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buf);
    let df = 1.0 / (n as f64 * h);
    let (lo, hi) = ((0.5 * near / df) as usize, (1.5 * near / df) as usize);
    (lo..hi).max_by(|&a, &b| buf[a].norm().total_cmp(&buf[b].norm())).unwrap() as f64 * df
}

/// Response of undamped gears, preloaded by a balanced torque T₀ and started at the static
/// deflection, to a balanced step ΔT: the TE difference between the runs with and without the
/// step. While contact holds, a step small against the preload sees the mesh linearized about
/// the preload (tangent stiffness), so the difference is the step response alone, free of the
/// parametric excitation both runs share.
fn step_response(mesh: &LumpedMesh, theta_1: f64, omega_1: f64, samples: usize, h: f64) -> Vec<f64> {
    let params = LumpedParameters { mesh_damping_ratio: 0.0, ..LumpedParameters::defaults(mesh) };
    let model = LumpedModel::new(mesh, params);
    let ratio = mesh.base_radius_2_m / mesh.base_radius_1_m;
    let (preload, step) = (300.0, 20.0);
    let roll = mesh.base_radius_1_m * theta_1 + mesh.roll_offset_m;
    let static_te = mesh.drive.static_deflection(preload / mesh.base_radius_1_m, roll);
    let start = LumpedState {
        theta_1,
        theta_2: (mesh.base_radius_1_m * theta_1 - static_te) / mesh.base_radius_2_m,
        omega_1,
        omega_2: omega_1 / ratio,
        ..Default::default()
    };
    let (mut with_step, mut without) = (start, start);
    let mut te = Vec::with_capacity(samples);
    for _ in 0..samples {
        with_step = model.rk4_step(&with_step, [preload + step, -(preload + step) * ratio], h);
        without = model.rk4_step(&without, [preload, -preload * ratio], h);
        let (a, b) = (model.mesh_state(&with_step), model.mesh_state(&without));
        assert!(a.force_n > 0.0 && b.force_n > 0.0, "contact lost: the linear superposition would not hold");
        te.push(a.transmission_error_m - b.transmission_error_m);
    }
    te
}

/// Closed form f = √(k/m_e)/2π with 1/m_e = r_b1²/J₁ + r_b2²/J₂ and k the tangent stiffness at
/// the preload (the mesh is load-dependent). Helical pair (stiffness varies ±10 %): rolling at
/// ω₁ = 80 rad/s, against the mean tangent stiffness. Spur pair (square-wave stiffness): at rest,
/// in single and in double contact, against the local tangent stiffness.
#[test]
fn torque_step_rings_at_the_mesh_natural_frequency() {
    let h = 2e-6;
    let helical = lumped(&pair("kurokawa_helical.toml"));
    let params = LumpedParameters::defaults(&helical);
    let mid_load = 310.0 / helical.base_radius_1_m; // preload 300 N·m + half the 20 N·m step
    let predicted = mesh_natural_frequency_hz(&helical, &params, mid_load);
    let measured = spectral_peak(&step_response(&helical, 0.0, 80.0, 1 << 17, h), h, predicted);
    let error = (measured - predicted).abs() / predicted;
    println!(
        "helical, rolling: FFT peak {measured:.1} Hz, √(k̄/m_e)/2π = {predicted:.1} Hz, error {:.2} %",
        100.0 * error
    );
    assert!(error < 0.05);

    let spur = lumped(&pair("kurokawa_spur.toml"));
    let mid_load = 310.0 / spur.base_radius_1_m;
    let params = LumpedParameters::defaults(&spur);
    let m_e = gearfmu::dynamics::lumped::equivalent_mesh_mass(&spur, &params);
    let n = spur.drive_pairs.len();
    for pairs in [1, 2] {
        // The middle of the longest run of samples with this many pairs in contact.
        let (mut best, mut run_start, mut best_len) = (0, 0, 0);
        for i in 0..2 * n {
            if spur.drive_pairs[i % n] != pairs {
                run_start = i + 1;
            } else if i + 1 - run_start > best_len {
                best_len = i + 1 - run_start;
                best = run_start + best_len / 2;
            }
        }
        let xi = spur.base_pitch_m * (best % n) as f64 / n as f64;
        let theta_1 = (xi - spur.roll_offset_m) / spur.base_radius_1_m;
        let k = spur.drive.evaluate(spur.drive.static_deflection(mid_load, xi), xi).stiffness_n_per_m;
        let predicted = (k / m_e).sqrt() / (2.0 * std::f64::consts::PI);
        let measured = spectral_peak(&step_response(&spur, theta_1, 0.0, 1 << 16, h), h, predicted);
        let error = (measured - predicted).abs() / predicted;
        println!(
            "spur, at rest, {pairs} pair(s): FFT peak {measured:.1} Hz, √(k/m_e)/2π = {predicted:.1} Hz, error {:.2} %",
            100.0 * error
        );
        assert!(error < 0.05);
    }
}

/// Energy: input work = kinetic + elastic + dissipated, to integrator accuracy, when the mesh
/// force derives from V = ½K(ξ)δ² (see dynamics::lumped). The seed example keeps contact.
#[test]
fn energy_balance_closes_within_0_1_percent() {
    for name in PAIRS {
        let p = pair(name);
        let mesh = lumped(&p);
        let model = LumpedModel::with_defaults(&mesh);
        let h = 1e-6;
        let mut s = LumpedState::default();
        let mut motor_work = 0.0;
        let mut min_force = f64::MAX;
        for k in 0..25_000 {
            let t = k as f64 * h;
            let torques = [seed_torque(t + 0.5 * h), -20.0 * s.omega_2];
            let before = s;
            s = model.rk4_step(&s, torques, h);
            motor_work += torques[0] * 0.5 * (before.omega_1 + s.omega_1) * h;
            if t > 1e-3 {
                min_force = min_force.min(model.mesh_state(&s).force_n);
            }
        }
        let mesh_state = model.mesh_state(&s);
        let stored = model.kinetic_energy(&s) + mesh_state.potential_j + s.dissipated_j;
        let residual = s.input_work_j - stored;
        println!(
            "{name}: input {:.5} J, kinetic {:.5} J, elastic {:.3e} J, damping {:.3e} J, residual {:.2e} J ({:.4} % of motor work {motor_work:.4} J); min force after 1 ms {min_force:.1} N",
            s.input_work_j, model.kinetic_energy(&s), mesh_state.potential_j, s.dissipated_j, residual, 100.0 * residual.abs() / motor_work
        );
        assert!(min_force > 0.0, "{name}: contact was lost, the balance would not apply");
        assert!(residual.abs() < 1e-3 * motor_work, "{name}: residual {residual} J");
    }
}

/// Backlash: unloaded gears with a relative speed bounce off the drive flank, lose contact
/// (force 0 while −j < δ < 0), cross the backlash and hit the coast flank (force < 0, δ < −j).
#[test]
fn unloaded_mesh_loses_contact_and_hits_the_back_flank() {
    let p = pair("kurokawa_spur.toml");
    let mesh = lumped(&p);
    let model = LumpedModel::with_defaults(&mesh);
    // Gear 1 0.5 % faster than the kinematic ratio: the drive flanks close, then rebound.
    let omega_2 = 10.0;
    let mut s = LumpedState {
        omega_2,
        omega_1: 1.005 * omega_2 * mesh.base_radius_2_m / mesh.base_radius_1_m,
        ..Default::default()
    };
    let (mut drive, mut free, mut coast) = (0, 0, 0);
    let mut free_force_max: f64 = 0.0;
    for _ in 0..200_000 {
        s = model.rk4_step(&s, [0.0, 0.0], 1e-6);
        let m = model.mesh_state(&s);
        if m.transmission_error_m > 0.0 {
            drive += 1;
            assert!(m.force_n >= 0.0);
        } else if m.transmission_error_m < -mesh.backlash_m {
            coast += 1;
            assert!(m.force_n <= 0.0, "coast flank force must push back (negative)");
        } else {
            free += 1;
            free_force_max = free_force_max.max(m.force_n.abs());
            assert_eq!(m.pairs_in_contact, 0);
        }
    }
    println!("steps in drive contact {drive}, free flight {free}, coast contact {coast}");
    assert!(drive > 0 && free > 0 && coast > 0);
    assert_eq!(free_force_max, 0.0);
}

/// Under the seed load, the number of pairs in contact alternates between 1 and 2 for the spur
/// pair with duty (ε_α − 1) in double contact, a closed-form check of the contact tables.
#[test]
fn spur_double_contact_share_equals_contact_ratio_minus_one() {
    let p = pair("kurokawa_spur.toml");
    let mesh = lumped(&p);
    let double = mesh.drive_pairs.iter().filter(|&&n| n == 2).count() as f64 / mesh.drive_pairs.len() as f64;
    let single = mesh.drive_pairs.iter().filter(|&&n| n == 1).count() as f64 / mesh.drive_pairs.len() as f64;
    println!("double-contact share {double:.4}, ε_α − 1 = {:.4}", p.transverse_contact_ratio - 1.0);
    assert!((double - (p.transverse_contact_ratio - 1.0)).abs() < 2.0 / mesh.drive_pairs.len() as f64);
    assert!((single + double - 1.0).abs() < 1e-12);
}
