//! The lumped model against independent references: a power balance (steady speed), ISO 6336-1
//! mesh stiffness, the mesh natural frequency √(k̄/m_e), conservation of energy, and the
//! kinematics of backlash (contact loss, back-flank contact).

use gearfmu::closed_forms::iso6336;
use gearfmu::dynamics::lumped::{mesh_natural_frequency_hz, LumpedMesh, LumpedModel, LumpedParameters, LumpedState};
use gearfmu::gear::{GearPair, HertzContact, PairSpec};
use rustfft::{num_complex::Complex, FftPlanner};
use std::f64::consts::PI;
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
/// potential-energy teeth with Yang & Lin's linearized contact. The load-dependent Weber contact
/// (the default) is printed beside it: over the whole pitch it is softer than c_γα (0.76 / 0.80),
/// because c_γα's double-contact zone is 1.75 × c′; the Weber law is asserted against ISO where
/// the standard's single stiffness c′ applies, in the test below.
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

/// The shipped law (potential-energy teeth + Weber contact) against ISO 6336-1's single stiffness
/// c′ (method B, the q′ series with C_M, C_B and E/E_st; the implementation reproduces ISO/TR
/// 6336-30's worked example to its printed digits, tests/iso6336.rs), where c′ applies: the
/// single-contact zone of the spur pair, at ISO's loads (≥ 100 N/mm). Its mean over c_γα is not
/// the comparison: c_γα = c′(0.75ε_α + 0.25) assumes a double-contact zone 1.75× as stiff, which
/// the Weber contact is not (two half loads are softer per newton), see BENCHMARKS.md.
///
/// Measured (mean of F/δ over the 394 single-contact rows of 1024): 0.794 × c′ at 100 N/mm,
/// 0.809 at 200, 0.825 at 392, 0.847 at 1000. The law does NOT agree with c′: it is 15–21 %
/// soft in single contact, where PMOR-Hertz (FE) is within 4 % of c′ (0.961 at 392 N/mm,
/// pmor_hertz_statics) and 14 % stiffer than this law at the same positions. A likely cause, not
/// settled here: at the pitch point the law's pair compliance is 0.0803 (potential-energy teeth)
/// + 0.0199 (Weber, referred to half the tooth thickness, ≈ 4.7 mm) mm·µm/N, while the FE global
/// part at h = 3 mm (body included) is 0.0759 on the paper-like mesh (fe_tooth) and Weber to
/// 3 mm 0.0173. The potential-energy teeth match the FE line-load total (which holds the local
/// deformation as far as the mesh resolves it), so Weber's approach may count part of that local
/// deformation a second time. A finding of this test, reported in issue 12, not tuned away.
///
/// So the assertion is a guard, one-sided on the measured side: the law may not move further from
/// c′ than measured − 3 % (the table interpolates to 0.5 %; c′ is exact arithmetic), and may not
/// come out stiffer than c′ + 5 % (ISO's own C_M = 0.8 is a measured-versus-theoretical factor;
/// FE lands at 0.96–1.0 × c′, BENCHMARKS.md). A fix of the overlap passes it.
#[test]
fn weber_law_single_contact_stiffness_against_iso_6336_c_prime_is_17_percent_soft() {
    let p = pair_with("kurokawa_spur.toml", HertzContact::Weber);
    let c_prime = iso6336::single_stiffness(&p);
    let mesh = lumped(&p);
    let n = mesh.drive.rows();
    let rows: Vec<usize> = (0..n).filter(|&i| mesh.drive_pairs_under(0)[i] == 1).collect();
    let b_mm = p.face_width_m * 1e3;
    for (specific_load, measured) in [(100.0, 0.794), (200.0, 0.809), (392.0, 0.825), (1000.0, 0.847)] {
        let force = specific_load * b_mm;
        // ISO's "mean value" convention for c_γα applied to the single zone: the mean over the
        // zone's positions of the secant stiffness F/δ(F, ξ), per face width.
        let single = rows
            .iter()
            .map(|&i| force / (mesh.drive.static_deflection(force, mesh.base_pitch_m * i as f64 / n as f64) * 1e6))
            .sum::<f64>()
            / rows.len() as f64
            / b_mm;
        let ratio = single / c_prime;
        println!(
            "{specific_load} N/mm: single-contact zone ({} of {n} rows) {single:.3} N/(mm·µm), ISO c′ {c_prime:.3}, ratio {ratio:.3}",
            rows.len()
        );
        assert!(ratio > measured - 0.03 && ratio < 1.05, "{specific_load} N/mm: single zone / ISO c′ = {ratio}");
    }
}

/// Spur geometry written out from examples/kurokawa_spur.toml (m 6 mm, α 20°, z 21/31, addendum
/// 1·m, no profile shift, standard centre distance, E 200 GPa, ν 0.3, b 15 mm): textbook formulas
/// only, nothing from the crate's geometry.
struct TextbookSpur {
    m: f64,
    alpha: f64,
    z: [f64; 2],
    rb: [f64; 2],
    ra: [f64; 2],
    /// Length T₁T₂ of the line of action, a·sin α.
    loa: f64,
    /// u of the start of active contact A (from T₁): T₁T₂ − √(r_a2² − r_b2²).
    u_a: f64,
    /// Base pitch π m cos α.
    pb: f64,
}

impl TextbookSpur {
    fn new(p: &GearPair) -> Self {
        assert_eq!((p.gear1.teeth, p.gear2.teeth), (21, 31), "the spec changed: update the numbers here");
        let (m, alpha, z) = (6e-3, 20f64.to_radians(), [21.0, 31.0]);
        let rb = z.map(|z| m * z / 2.0 * alpha.cos());
        let ra = z.map(|z| m * (z / 2.0 + 1.0));
        let loa = m * (z[0] + z[1]) / 2.0 * alpha.sin();
        let u_a = loa - (ra[1] * ra[1] - rb[1] * rb[1]).sqrt();
        TextbookSpur { m, alpha, z, rb, ra, loa, u_a, pb: PI * m * alpha.cos() }
    }

    /// ε_α = (√(r_a1² − r_b1²) + √(r_a2² − r_b2²) − a·sin α)/p_b.
    fn contact_ratio(&self) -> f64 {
        ((self.ra[0].powi(2) - self.rb[0].powi(2)).sqrt() + (self.ra[1].powi(2) - self.rb[1].powi(2)).sqrt() - self.loa)
            / self.pb
    }

    /// Half the chordal tooth thickness of gear i at radius r (the depth Weber's approach is
    /// referred to in the lumped law): r·sin ψ, ψ = π/(2z) + inv α − inv α_r, cos α_r = r_b/r.
    fn half_thickness(&self, i: usize, r: f64) -> f64 {
        let inv = |a: f64| a.tan() - a;
        let psi = PI / (2.0 * self.z[i]) + inv(self.alpha) - inv((self.rb[i] / r).acos());
        r * psi.sin()
    }
}

/// Weber's approach of two steel cylinders, written out from the formula (Weber 1921; design
/// §4.3), both bodies E, ν, referred to depths h₁, h₂:
/// δ = Σᵢ 2P(1−ν²)/(π l E)·[ln(2hᵢ/b) − ν/(2(1−ν))], b = √(4PR/(π l E*)), 1/R = 1/ρ₁ + 1/ρ₂,
/// E* = E/(2(1−ν²)).
fn weber_approach(force: f64, length: f64, e: f64, nu: f64, rho: [f64; 2], depth: [f64; 2]) -> f64 {
    let r = 1.0 / (1.0 / rho[0] + 1.0 / rho[1]);
    let e_star = e / (2.0 * (1.0 - nu * nu));
    let b = (4.0 * force * r / (PI * length * e_star)).sqrt();
    let a = 2.0 * force * (1.0 - nu * nu) / (PI * length * e);
    depth.iter().map(|h| a * ((2.0 * h / b).ln() - nu / (2.0 * (1.0 - nu)))).sum()
}

/// Where a single tooth pair carries the whole load (spur, single-contact zone), the mesh law
/// must be the teeth (linear in F) in series with Weber's line contact. Independent reference:
/// Weber's approach written out above on textbook geometry (ρ₁ = u, ρ₂ = a sin α − u, depths
/// from the involute's tooth thickness), none of the crate's contact or geometry code. What is
/// left, δ_law(F) − δ_Weber(F), must then be linear in F: the same compliance per newton at every
/// load from 25 to 1000 N/mm, while the Weber part alone falls by 38 % per newton over that range
/// (measured: remainder 0.08030 → 0.08035 mm·µm/N, Weber 0.02797 → 0.01728 mm·µm/N).
/// The teeth's own compliance is the potential-energy method's, checked against FE in fe_tooth.
/// And the stiffness is load-dependent: the secant stiffness grows with load.
#[test]
fn weber_mesh_law_is_linear_teeth_in_series_with_weber_written_out_and_stiffens_with_load() {
    let p = pair_with("kurokawa_spur.toml", HertzContact::Weber);
    let t = TextbookSpur::new(&p);
    let mesh = lumped(&p);
    let n = mesh.drive.rows();
    // The middle of the single-contact zone by the textbook kinematics: a roll ξ (from A) in
    // ((ε_α − 1)p_b, p_b) has one pair in contact, at u = u_A + ξ.
    let eps = t.contact_ratio();
    let roll = t.pb * (eps - 1.0 + 0.5 * (2.0 - eps));
    let row = (roll / t.pb * n as f64).round() as usize;
    assert_eq!(mesh.drive_pairs_under(0)[row], 1, "the table has one pair at the middle of the single-contact zone");
    let roll = t.pb * row as f64 / n as f64;
    let u = t.u_a + roll;
    let rho = [u, t.loa - u];
    let radius = [t.rb[0].hypot(rho[0]), t.rb[1].hypot(rho[1])];
    let depth = [t.half_thickness(0, radius[0]), t.half_thickness(1, radius[1])];
    let (e, nu, b) = (200e9, 0.3, 15e-3);
    assert_eq!((p.youngs_modulus_pa, p.poisson_ratio, p.face_width_m), (e, nu, b));
    println!(
        "u = {:.4} mm (module {} mm): ρ {:.3} / {:.3} mm, depth h {:.3} / {:.3} mm",
        u * 1e3,
        t.m * 1e3,
        rho[0] * 1e3,
        rho[1] * 1e3,
        depth[0] * 1e3,
        depth[1] * 1e3
    );
    let mut remainder = Vec::new();
    let mut previous_secant = 0.0;
    for specific_load in [25.0, 100.0, 400.0, 1000.0] {
        let force = specific_load * 1e3 * b;
        let law = mesh.drive.static_deflection(force, roll);
        let weber = weber_approach(force, b, e, nu, rho, depth);
        // mm·µm/N per face width.
        let teeth = (law - weber) / force * b * 1e9;
        println!(
            "{specific_load} N/mm: δ law {:.4} µm, Weber written out {:.4} µm ({:.5} mm·µm/N), remainder {teeth:.5} mm·µm/N",
            law * 1e6,
            weber * 1e6,
            weber / force * b * 1e9
        );
        remainder.push(teeth);
        let secant = mesh.drive.mean_secant_stiffness(force);
        assert!(secant > previous_secant, "secant stiffness must grow with load");
        previous_secant = secant;
    }
    // The law interpolates linearly between force levels (dense where the contact is most
    // nonlinear), to 0.5 % of δ; over the teeth's share of δ (≥ 75 % here) that is < 0.7 %.
    let mean = remainder.iter().sum::<f64>() / remainder.len() as f64;
    for (r, load) in remainder.iter().zip([25, 100, 400, 1000]) {
        assert!((r / mean - 1.0).abs() < 0.007, "{load} N/mm: remainder {r} vs mean {mean} mm·µm/N: not linear");
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
    let n = spur.drive.rows();
    for pairs in [1, 2] {
        // The middle of the longest run of samples with this many pairs in contact.
        let (mut best, mut run_start, mut best_len) = (0, 0, 0);
        for i in 0..2 * n {
            if spur.drive_pairs_under(0)[i % n] != pairs {
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
            assert_eq!(model.pairs_in_contact(&s), 0);
        }
    }
    println!("steps in drive contact {drive}, free flight {free}, coast contact {coast}");
    assert!(drive > 0 && free > 0 && coast > 0);
    assert_eq!(free_force_max, 0.0);
}

/// The number of pairs in contact alternates between 1 and 2 for the spur pair with duty
/// (ε_α − 1) in double contact; ε_α from the textbook formula written out here (tip and base
/// radii, centre distance), not from the path ends the table is built on.
#[test]
fn spur_double_contact_share_equals_textbook_contact_ratio_minus_one() {
    let p = pair("kurokawa_spur.toml");
    let eps = TextbookSpur::new(&p).contact_ratio();
    let mesh = lumped(&p);
    let double = mesh.drive_pairs_under(0).iter().filter(|&&n| n == 2).count() as f64 / mesh.drive.rows() as f64;
    let single = mesh.drive_pairs_under(0).iter().filter(|&&n| n == 1).count() as f64 / mesh.drive.rows() as f64;
    println!("double-contact share {double:.4}, textbook ε_α − 1 = {:.4}", eps - 1.0);
    assert!((double - (eps - 1.0)).abs() < 2.0 / mesh.drive.rows() as f64);
    assert!((single + double - 1.0).abs() < 1e-12);
}

/// The lumped mesh law from the FE statics (issue 26; evidence: the PMOR-Hertz statics on the
/// same coarse mesh, solved at positions and loads the table does not hold). Gear 2 held at 40
/// positions over a pitch, T₁ = 22, 185 and 370 N·m (the table's levels lie elsewhere): the law's
/// static deflection at each case's roll position r_b1·θ₁ + ξ₀ and force T₁/r_b1 has the
/// statics' mean within 1 % and peak-to-peak within 5 % (measured −0.1 to −0.5 % and −0.2 to
/// −1.0 % on the 4/8/4 mesh), and the analytic law (the no-FE estimate) is shown for contrast:
/// its mean is as close, its peak-to-peak 1.8–1.9 × the statics'.
/// The Kurokawa spur pair's PMOR-Hertz reduction on the coarse mesh and the lumped mesh whose
/// law its statics tabulate.
fn fe_fed_spur() -> (GearPair, gearfmu::rom::sweep::ReducedPair, LumpedMesh) {
    use gearfmu::contact::hertz::ApproachLaw;
    use gearfmu::rom::static_mesh_law::{drive_law_from_statics, force_levels, FORCE_LEVELS, TABLE_ROWS};
    use gearfmu::rom::sweep::{Method, ReducedPair};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join("kurokawa_spur.toml");
    let spec = PairSpec::load(&path).unwrap();
    let p = GearPair::from_spec(&spec).unwrap();
    let depth_m = gearfmu::rom::reductor::contact_depth_m(&p);
    let method = Method::PmorHertz { depth_m, p_en: gearfmu::rom::svd::DEFAULT_P_EN, law: ApproachLaw::Weber };
    let reduced = ReducedPair::build(&p, &spec.mesh, method, |_, _| {}).unwrap();
    let levels = force_levels(&p, FORCE_LEVELS);
    let table = drive_law_from_statics(&p, &reduced.static_model().unwrap(), &levels, TABLE_ROWS, |_| {}).unwrap();
    assert_eq!(table.capped, None, "the statics solve every level up to the top");
    let (law, pairs, spread) = (table.law, table.pairs, table.spread);
    let fe = LumpedMesh::from_drive_law(&p, gearfmu::dynamics::lumped::MeshLawSource::FeStatics, law, pairs, spread);
    (p, reduced, fe)
}

#[test]
fn fe_fed_mesh_law_reproduces_the_pmor_hertz_statics() {
    let (p, reduced, fe) = fe_fed_spur();
    let analytic = lumped(&p);
    let (rb1, roll_offset) = (p.gear1.base_radius_m, fe.roll_offset_m);
    for torque in [22.0, 185.0, 370.0] {
        let cases: Vec<_> = reduced.sweep(&[torque], 40, 1.0).into_iter().map(|c| c.unwrap()).collect();
        let stats = |v: &[f64]| {
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let (lo, hi) = v.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
            (mean, hi - lo)
        };
        let (ste_mean, ste_pp) = stats(&cases.iter().map(|c| c.ste_m).collect::<Vec<_>>());
        let on = |m: &LumpedMesh| {
            let at: Vec<f64> = cases
                .iter()
                .map(|c| m.drive.static_deflection(torque / rb1, rb1 * c.theta_rad[0] + roll_offset))
                .collect();
            stats(&at)
        };
        let ((mean, pp), (an_mean, an_pp)) = (on(&fe), on(&analytic));
        eprintln!(
            "T₁ {torque} N·m: statics mean {:.3} µm p-p {:.3} µm; FE-fed law {:.3} / {:.3} µm; analytic law {:.3} / {:.3} µm",
            ste_mean * 1e6,
            ste_pp * 1e6,
            mean * 1e6,
            pp * 1e6,
            an_mean * 1e6,
            an_pp * 1e6
        );
        assert!((mean / ste_mean - 1.0).abs() < 0.01);
        assert!((pp / ste_pp - 1.0).abs() < 0.05);
        assert!(an_pp / ste_pp > 1.5, "the contrast: the analytic law's peak-to-peak");
    }
}

/// Tooth friction in the FE-fed lumped law (issue 42; evidence: the PMOR-Hertz statics with
/// friction, `rom::statics`, at positions the table does not hold). μ = 0.05 at 185 N·m, 40
/// positions over a pitch. The lumped pair's static equilibrium with friction, turning forward
/// (ω₁ = 50 rad/s: the flanks slide far faster than v_ε but within microns of the pitch point):
/// its mesh force F solves T₁ = r_b1·F + (friction's torque on gear 1 from the contact spread),
/// and its deflection is the law's at F and λ = μ. Friction's change of the STE against the
/// statics': its mean within 10 % and pointwise within a quarter of its largest (measured: mean
/// −0.0732 against −0.0689 µm, pointwise within 0.007 µm against a peak of 0.105 µm). For
/// contrast, the same with the law's elastic share off (λ = 0: friction's torques only, the
/// lumped model before the share was tabulated) is printed: in single contact it moves the STE
/// by ±0.33 µm (±1.8 %), where the statics move it by under 0.04 µm — the deformation that turns
/// the gear about its axis sees the torque, not how it splits between normal force and friction.
#[test]
fn fe_fed_mesh_law_carries_tooth_friction_as_the_friction_statics_do() {
    let (p, reduced, fe) = fe_fed_spur();
    let (rb1, roll_offset) = (p.gear1.base_radius_m, fe.roll_offset_m);
    let (torque, mu, omega_1) = (185.0, 0.05, 50.0);
    let without: Vec<_> = reduced.sweep(&[torque], 40, 1.0).into_iter().map(|c| c.unwrap()).collect();
    let with: Vec<_> = reduced.sweep_with_friction(&[torque], 40, 1.0, mu).into_iter().map(|c| c.unwrap()).collect();
    // The lumped equilibrium at roll ξ with friction's elastic share λ = μ·sense.
    let lumped_ste = |roll: f64, sense: f64| -> f64 {
        let params =
            LumpedParameters { friction_coefficient: mu, rolling_sense: sense, ..LumpedParameters::defaults(&fe) };
        let model = LumpedModel::new(&fe, params);
        let mut force = torque / rb1;
        let mut delta = 0.0;
        for _ in 0..50 {
            delta = fe.drive.static_deflection_with_friction(force, roll, model.friction_share());
            let theta_1 = (roll - roll_offset) / rb1;
            let state = LumpedState {
                theta_1,
                omega_1,
                theta_2: (rb1 * theta_1 - delta) / fe.base_radius_2_m,
                omega_2: omega_1 * rb1 / fe.base_radius_2_m,
                ..Default::default()
            };
            let mesh = model.mesh_state(&state);
            let friction = model.friction(&mesh, &state);
            let next = (torque + friction.torque_nm[0]) / rb1;
            if (next - force).abs() <= 1e-12 * force {
                break;
            }
            force = next;
        }
        delta
    };
    let (mut change_statics, mut change_lumped, mut change_torques_only) = (Vec::new(), Vec::new(), Vec::new());
    for (c0, c1) in without.iter().zip(&with) {
        let roll = rb1 * c0.theta_rad[0] + roll_offset;
        let lumped_0 = fe.drive.static_deflection(torque / rb1, roll);
        change_statics.push(c1.ste_m - c0.ste_m);
        change_lumped.push(lumped_ste(roll, 1.0) - lumped_0);
        change_torques_only.push(lumped_ste(roll, 0.0) - lumped_0);
        eprintln!(
            "θ₂ {:.5} rad, {} pair(s): friction's change of the STE, statics {:+.4} µm, lumped {:+.4} µm, lumped without the elastic share {:+.4} µm",
            c0.theta_rad[1],
            c0.pairs_in_contact,
            change_statics.last().unwrap() * 1e6,
            change_lumped.last().unwrap() * 1e6,
            change_torques_only.last().unwrap() * 1e6,
        );
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let worst = |v: &[f64]| v.iter().zip(&change_statics).fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
    let peak = change_statics.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    eprintln!(
        "mean change: statics {:+.4} µm, lumped {:+.4} µm, without the share {:+.4} µm; pointwise worst {:.4} / {:.4} µm against a peak of {:.4} µm",
        mean(&change_statics) * 1e6,
        mean(&change_lumped) * 1e6,
        mean(&change_torques_only) * 1e6,
        worst(&change_lumped) * 1e6,
        worst(&change_torques_only) * 1e6,
        peak * 1e6
    );
    assert!((mean(&change_lumped) / mean(&change_statics) - 1.0).abs() <= 0.1, "mean change");
    assert!(worst(&change_lumped) <= 0.25 * peak, "pointwise change");
}
