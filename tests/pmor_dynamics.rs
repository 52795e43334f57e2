//! The PMOR-Hertz dynamic model (design §4.5) against independent references: the FE model it
//! was reduced from (inertia, eigenfrequencies), the closed-form steady state of the seed's
//! example 3, the PMOR-Hertz statics it must reproduce in the slow limit, and conservation of
//! energy. One reduced pair (default spur mesh, default build options) serves every test.

#[allow(dead_code)]
mod common;

use gearfmu::contact::hertz::ApproachLaw;
use gearfmu::contact::mesh_kinematics::PairPlacement;
use gearfmu::dynamics::pmor::equations::{gear_terms, interval_gram, Damping, GearTerms};
use gearfmu::dynamics::pmor::integrator::Integrator;
use gearfmu::dynamics::pmor::model::PmorModel;
use gearfmu::dynamics::pmor::quasi_static::Condensation;
use gearfmu::dynamics::pmor::{linear, PmorDynamics, PmorState};
use gearfmu::fe::clamped_gear::ClampedGear;
use gearfmu::fe::eigen;
use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::fe::hex8::Formulation;
use gearfmu::rom::build_cache::{build_dynamic_model_reusing, BuildCache};
use gearfmu::rom::dynamic_reductor::{build_dynamic_model, DynamicBuildOptions, DynamicBuildReport};
use gearfmu::rom::sweep::{Method, ReducedPair};
use std::f64::consts::PI;
use std::sync::OnceLock;

struct Fixture {
    model: PmorModel,
    report: DynamicBuildReport,
    place: PairPlacement,
    /// Static STE (m) of the PMOR-Hertz statics at 185 and 370 N·m, θ₂ = (k + ½)/40 pitch.
    statics: Vec<Vec<f64>>,
    /// The same at 185 N·m with tooth friction μ = `FRICTION_STATICS_MU` (`rom::statics`).
    statics_with_friction: Vec<f64>,
    /// The lumped mesh law tabulated from the separately reduced statics (spur fixture only).
    lumped_law: Option<gearfmu::rom::static_mesh_law::StaticMeshLaw>,
}

const STATIC_TORQUES: [f64; 2] = [185.0, 370.0];
const FRICTION_STATICS_MU: f64 = 0.05;
const STATIC_ANGLES: usize = 40;

/// The reduced pair of an example spec on its own mesh, with the PMOR-Hertz statics of the same
/// pair reduced separately (the reference: `fmu-build ste` with the ROM's depth and p_en).
/// Through the build cache where GEARFMU_BUILD_CACHE is set (scripts/test.sh): the spur pair's
/// model is `fmi_c_api`'s too, and a run of unchanged code builds none of them again.
fn build_fixture(file: &str, lumped_mesh_law: bool) -> Fixture {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(file);
    let spec = gearfmu::gear::PairSpec::load(&path).unwrap();
    let pair = gearfmu::gear::GearPair::from_spec(&spec).unwrap();
    let options = DynamicBuildOptions { lumped_mesh_law, ..Default::default() };
    let (model, report) = build_dynamic_model_reusing(&pair, &spec.mesh, &options, |_| {}).unwrap();
    let method = Method::PmorHertz { depth_m: options.depth_m, p_en: options.p_en, law: ApproachLaw::Weber };
    let reduced = ReducedPair::build(&pair, &spec.mesh, method, |_, _| {}).unwrap();
    let cases = reduced.sweep(&STATIC_TORQUES, STATIC_ANGLES, 1.0);
    let statics = (0..STATIC_TORQUES.len())
        .map(|t| (0..STATIC_ANGLES).map(|k| cases[t * STATIC_ANGLES + k].as_ref().unwrap().ste_m).collect())
        .collect();
    let statics_with_friction = reduced
        .sweep_with_friction(&STATIC_TORQUES[..1], STATIC_ANGLES, 1.0, FRICTION_STATICS_MU)
        .into_iter()
        .map(|c| c.unwrap().ste_m)
        .collect();
    let place = PairPlacement::new(&model.pair);
    let lumped_law = lumped_mesh_law.then(|| {
        use gearfmu::rom::static_mesh_law::{drive_law_from_statics, force_levels, FORCE_LEVELS, TABLE_ROWS};
        let statics = reduced.static_model().unwrap();
        drive_law_from_statics(&pair, &statics, &force_levels(&pair, FORCE_LEVELS), TABLE_ROWS, |_| {}).unwrap()
    });
    Fixture { model, report, place, statics, statics_with_friction, lumped_law }
}

/// The default spur pair (`examples/kurokawa_spur.toml`, the default mesh): every test's.
fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| build_fixture("kurokawa_spur.toml", true))
}

/// The spur pair with a long tip relief near the Harris optimum at 185 N·m and a light lead
/// crowning (`examples/kurokawa_spur_relieved.toml`, issue 27), on the default mesh.
fn relieved_fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| build_fixture("kurokawa_spur_relieved.toml", false))
}

/// The helical pair on its spec's mesh (8 axial slices): the static limit's second pair.
fn helical_fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| build_fixture("kurokawa_helical.toml", false))
}

fn base_radii(m: &PmorModel) -> [f64; 2] {
    [m.pair.gear1.base_radius_m, m.pair.gear2.base_radius_m]
}

fn te(m: &PmorModel, s: &PmorState) -> f64 {
    let rb = base_radii(m);
    rb[0] * s.theta[0] - rb[1] * s.theta[1]
}

/// Closed forms and the FE model: (Gx)ᵀM(Gx) is the gear's polar inertia, which the profile
/// integral gives independently of the mesh (0.1 %); Φ is the FE's lowest fixed-bore modes
/// (an independent eigen solve with another subspace size agrees to 1e-6); span Φ is invariant
/// under the one-tooth rotation (whole clusters kept) and R = ΦᵀMP⁻¹Φ is orthogonal; the shapes
/// are M-orthogonal to Φ (Eq. 14) and one pitch on equal the rotated first (to the SVD basis'
/// own lack of cyclic symmetry, < 2 %).
#[test]
fn reduced_gears_match_the_fe_model_and_close_periodically() {
    let f = fixture();
    let pair = common::kurokawa_spur();
    for i in 0..2 {
        let g = &f.model.gears[i];
        let (fe_inertia, exact) = f.report.polar_inertia_kgm2[i];
        assert!(((fe_inertia - exact) / exact).abs() < 1e-3, "gear {i}: {fe_inertia} vs {exact}");
        assert!(f.report.invariance_residual[i] < 1e-6, "gear {i}: {}", f.report.invariance_residual[i]);
        let r = &g.pitch_map;
        let orthogonality = (r.transpose() * r - nalgebra::DMatrix::identity(g.modes(), g.modes())).amax();
        assert!(orthogonality < 1e-6, "gear {i}: RᵀR − I = {orthogonality}");
        assert!(f.report.residualization[i] < 1e-8, "gear {i}: ΦᵀMS = {}", f.report.residualization[i]);
        assert!(f.report.closure_residual[i] < 2e-2, "gear {i}: closure {}", f.report.closure_residual[i]);
        eprintln!(
            "gear {}: inertia FE {fe_inertia:.6e} / profile {exact:.6e}; invariance {:.1e}; closure {:.1e}",
            i + 1,
            f.report.invariance_residual[i],
            f.report.closure_residual[i]
        );
        // Independent eigen solve (probe of n_k + 2 instead of n_k + 6 vectors).
        let gear = if i == 0 { &pair.gear1 } else { &pair.gear2 };
        let fe = ClampedGear::new(&pair, gear, &MeshSpec::default(), Formulation::IncompatibleModes);
        let modes = eigen::lowest_modes(&fe.stiffness, &fe.mass(), g.modes() + 2, 1e-12, 400, |_, _| {}).unwrap();
        for (j, lam) in g.eigenvalues.iter().enumerate() {
            assert!(((lam - modes.eigenvalues[j]) / lam).abs() < 1e-6, "gear {i} mode {j}");
        }
        // Φ's frequencies in the reduced model: the Φ block of (VᵀKV, VᵀMV) at a frozen angle.
        let st = g.stencil(f.model.interpolation, 0.37 * g.pitch_rad()).unwrap();
        let n_e = g.elastic_size();
        let mut terms = GearTerms::new(g);
        gear_terms(
            g,
            &st,
            &interval_gram(g, st.a0),
            &vec![0.0; n_e],
            0.0,
            &vec![0.0; n_e],
            Damping { modes_ratio: 0.0, shapes_ratio: 0.0 },
            &mut terms,
        );
        let m_phi = terms.mass.view((1, 1), (g.modes(), g.modes())).into_owned();
        let k_phi = nalgebra::DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&g.eigenvalues));
        let l = m_phi.cholesky().unwrap().l();
        let li = l.try_inverse().unwrap();
        let mut reduced: Vec<f64> =
            nalgebra::SymmetricEigen::new(&li * k_phi * li.transpose()).eigenvalues.iter().copied().collect();
        reduced.sort_by(f64::total_cmp);
        for (j, lam) in reduced.iter().enumerate() {
            assert!(
                ((lam - modes.eigenvalues[j]) / lam).abs() < 1e-6,
                "gear {i}: reduced mode {j} {lam} vs FE {}",
                modes.eigenvalues[j]
            );
        }
    }
}

/// Static limit (evidence: the PMOR-Hertz statics, `fmu-build ste`, of the same pair and
/// options, reduced separately): T₁ = 370 N·m, gear 2 speed-held at 0.5 rad/s by a brake that
/// balances the torque, strong modal damping (10 % on Φ, 20 % on the shapes: five to twenty
/// times the defaults; stronger damping, 30 % / 50 %, put real eigenvalues beyond RK4's reach
/// at its default step, `linear::LinearizedPair::stability_limit_s` gave 1.9 µs). The mesh
/// frequency, 2.5 Hz, is 1/1500 of the mesh mode's, so inertia shifts the DTE by 4e-7 of itself.
/// Over one whole mesh cycle the DTE reproduces the STE within 2 % of the mean and 5 % of the
/// peak-to-peak. 370 N·m lies above the ROM's torque level (250): the shapes extrapolate.
fn static_limit(name: &str, f: &Fixture) {
    static_limit_at(name, f, 1)
}

/// The static limit at `STATIC_TORQUES[level]`.
fn static_limit_at(name: &str, f: &Fixture, level: usize) {
    let dynamics = PmorDynamics::new(&f.model, &f.place, f.model.damping(0.1, 0.2), [0.0; 2]);
    let table = &f.statics[level];
    let dte = slow_run_dte(f, &dynamics, STATIC_TORQUES[level], table, 0.5);
    assert_reproduces_the_statics(&format!("{name}: static limit at {} N·m", STATIC_TORQUES[level]), &dte, table);
}

/// The DTE of a run at gear 2's speed `w2` (rad/s) over one mesh cycle, torque T₁ on gear 1 and
/// a brake holding gear 2's speed (its mean the lossless reaction, the rest a feedback), sampled
/// at the statics' angles θ₂ = (k + ½)/40 pitch; started at the mean of `table`, the statics it
/// is compared with.
fn slow_run_dte(f: &Fixture, dynamics: &PmorDynamics, torque: f64, table: &[f64], w2: f64) -> Vec<f64> {
    let m = &f.model;
    let rb = base_radii(m);
    let mean_static = table.iter().sum::<f64>() / table.len() as f64;
    let pitch2 = 2.0 * PI / m.pair.gear2.teeth as f64;
    let theta2_start = -0.2 * pitch2;
    let mut s = m.initial_state([(rb[1] * theta2_start + mean_static) / rb[0], theta2_start], [w2 * rb[1] / rb[0], w2]);
    let h = m.max_step_s;
    let brake = |s: &PmorState| -torque * rb[1] / rb[0] - 20.0 * (s.omega[1] - w2);
    // (θ₂, DTE) along the run; then the DTE at the statics' own angles, so that both curves are
    // sampled alike (a table interpolated between samples would cut the peaks).
    let mut record: Vec<(f64, f64)> = Vec::new();
    while s.theta[1] < pitch2 * 1.01 {
        let load = brake(&s);
        dynamics.advance(&mut s, [torque, load], h, h).unwrap();
        if s.theta[1] >= -0.01 * pitch2 {
            record.push((s.theta[1], te(m, &s)));
        }
    }
    let at = |theta2: f64| {
        let k = record.partition_point(|r| r.0 < theta2).clamp(1, record.len() - 1);
        let (a, b) = (record[k - 1], record[k]);
        a.1 + (b.1 - a.1) * (theta2 - a.0) / (b.0 - a.0)
    };
    (0..STATIC_ANGLES).map(|k| at(pitch2 * (k as f64 + 0.5) / STATIC_ANGLES as f64)).collect()
}

/// Tooth friction in the static limit (evidence: the PMOR-Hertz statics with friction,
/// `rom::statics`, of the same pair reduced separately: the friction loads the statics put on
/// the teeth are built from `ReducedGear`'s flank rows, not from the dynamics' sliding rows).
/// μ = 0.05 at 185 N·m; a run at 2 rad/s on gear 2 (10 Hz mesh frequency, 1/300 of the mesh
/// mode), with and without friction. Friction's change of the DTE over the mesh cycle must be
/// the statics' change of the STE: its mean within 10 %, and pointwise within a quarter of the
/// change's peak. Measured: mean −0.0682 µm against −0.0689 µm; pointwise within 0.003 µm but
/// just after the two contact changes, where the mesh mode rings (the frictionless DTE leaves
/// its STE there too) and friction's damping changes the ringing: 0.025 µm against a peak
/// change of 0.105 µm. Not at the static limit's 0.5 rad/s: there the flanks slide at under
/// 10 mm/s, and v_ε must stay far below the sliding for the run to be Coulomb's, which the
/// statics are. v_ε = 1.5 mm/s here against up to 36 mm/s of sliding: Coulomb's law but within
/// ±4 % of the path around the pitch point.
#[test]
fn slow_run_with_tooth_friction_reproduces_the_friction_statics() {
    use gearfmu::dynamics::mesh_friction::SlidingFriction;
    let f = fixture();
    let frictionless = PmorDynamics::new(&f.model, &f.place, f.model.damping(0.1, 0.2), [0.0; 2]);
    let mut with_friction = PmorDynamics::new(&f.model, &f.place, f.model.damping(0.1, 0.2), [0.0; 2]);
    with_friction.friction = Some(SlidingFriction { coefficient: FRICTION_STATICS_MU, regularization_m_per_s: 1.5e-3 });
    let torque = STATIC_TORQUES[0];
    let w2 = 2.0;
    let dte_0 = slow_run_dte(f, &frictionless, torque, &f.statics[0], w2);
    let dte_mu = slow_run_dte(f, &with_friction, torque, &f.statics_with_friction, w2);
    let ste_0 = &f.statics[0];
    let ste_mu = &f.statics_with_friction;
    let change_dynamic: Vec<f64> = dte_mu.iter().zip(&dte_0).map(|(a, b)| a - b).collect();
    let change_static: Vec<f64> = ste_mu.iter().zip(ste_0).map(|(a, b)| a - b).collect();
    for k in 0..STATIC_ANGLES {
        eprintln!(
            "k {k:2}: STE {:.4} → {:.4} µm ({:+.4}), DTE {:.4} → {:.4} µm ({:+.4})",
            ste_0[k] * 1e6,
            ste_mu[k] * 1e6,
            change_static[k] * 1e6,
            dte_0[k] * 1e6,
            dte_mu[k] * 1e6,
            change_dynamic[k] * 1e6
        );
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (mean_dynamic, mean_static) = (mean(&change_dynamic), mean(&change_static));
    let peak = change_static.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let worst = change_dynamic.iter().zip(&change_static).fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
    eprintln!(
        "friction's change, mean over the cycle: DTE {:+.4} µm, STE {:+.4} µm; pointwise worst {:.4} µm against a peak of {:.4} µm",
        mean_dynamic * 1e6,
        mean_static * 1e6,
        worst * 1e6,
        peak * 1e6
    );
    assert!((mean_dynamic / mean_static - 1.0).abs() <= 0.1, "mean change");
    assert!(worst <= 0.25 * peak, "pointwise change");
}

/// A TE curve against the statics' over a mesh cycle: mean within 2 %, peak-to-peak within 5 %
/// (the static limit's bounds), printed either way.
fn assert_reproduces_the_statics(label: &str, got: &[f64], ste: &[f64]) {
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let p2p = |v: &[f64]| v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min);
    let (mg, ms, pg, ps) = (mean(got), mean(ste), p2p(got), p2p(ste));
    eprintln!(
        "{label}: mean {:.4} µm vs STE {:.4} µm ({:+.2} %); p-p {:.4} vs {:.4} µm ({:+.2} %)",
        mg * 1e6,
        ms * 1e6,
        (mg / ms - 1.0) * 100.0,
        pg * 1e6,
        ps * 1e6,
        (pg / ps - 1.0) * 100.0
    );
    assert!((mg / ms - 1.0).abs() < 0.02, "{label}: mean");
    assert!((pg / ps - 1.0).abs() < 0.05, "{label}: p-p");
}

#[test]
fn slow_run_reproduces_the_static_transmission_error() {
    static_limit("spur", fixture());
}

/// The same for the helical pair on its own mesh (8 slices, 3 tooth pairs in contact part of the
/// cycle, tip-corner contact at the ends of each contact line).
#[test]
fn slow_run_reproduces_the_static_transmission_error_of_the_helical_pair() {
    static_limit("helical", helical_fixture());
}

/// Example 3 of the seed (paper Sect. 6.2): 185 N·m on gear 1 after a 5 ms haversine ramp,
/// viscous 20 N·m·s/rad on gear 2, from rest. We use the text's figures (185 N·m, 20 N·m·s/rad:
/// the steady ω₂ = 185·(z₂/z₁)/20 = 13.65 rad/s it states as "about 13.63"); Table 9's 190 and
/// 110 would give 2.55 rad/s, contradicting it. Evidence: the power balance's closed-form steady
/// speed (0.5 %), and the statics: the DTE's mean over the last mesh cycle is the STE's at 185 N·m
/// (3 %; the dynamic increment at 13.6 rad/s, 67 Hz mesh frequency against ~3 kHz, is small).
#[test]
fn example_3_reaches_the_closed_form_speed_and_the_static_mean() {
    let f = fixture();
    let m = &f.model;
    let started = std::time::Instant::now();
    let run = example_3(m);
    let wall = started.elapsed().as_secs_f64();
    let z = [m.pair.gear1.teeth as f64, m.pair.gear2.teeth as f64];
    let w2_steady = 185.0 * z[1] / z[0] / 20.0;
    let w2 = run.omega2_end;
    let mean_dte = run.dte_mean_m();
    let mean_ste = f.statics[0].iter().sum::<f64>() / f.statics[0].len() as f64;
    eprintln!("example 3: ω₂(25 ms) = {w2:.4} rad/s (closed form {w2_steady:.4}); mean DTE over the last mesh cycle {:.4} µm, STE at 185 N·m {:.4} µm; {:.1} s wall for {} {} steps",
        mean_dte * 1e6, mean_ste * 1e6, wall, run.steps, m.integrator.name());
    assert!((w2 / w2_steady - 1.0).abs() < 5e-3);
    assert!((mean_dte / mean_ste - 1.0).abs() < 0.03);
}

/// One run of example 3 (185 N·m after a 5 ms haversine, 20 N·m·s/rad on gear 2, 25 ms) on a
/// reduced pair at its own max_step.
struct Example3 {
    steps: usize,
    omega2_end: f64,
    /// The DTE at every step over the last whole mesh cycle of gear 2 (m).
    dte_last_cycle: Vec<f64>,
}

impl Example3 {
    fn dte_mean_m(&self) -> f64 {
        self.dte_last_cycle.iter().sum::<f64>() / self.dte_last_cycle.len() as f64
    }

    fn dte_peak_to_peak_m(&self) -> f64 {
        let (lo, hi) = self.dte_last_cycle.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        hi - lo
    }
}

fn example_3(m: &PmorModel) -> Example3 {
    let place = PairPlacement::new(&m.pair);
    let dynamics = PmorDynamics::new(m, &place, m.damping(m.modal_damping_ratio, m.shape_damping_ratio), [0.0; 2]);
    let mut s = m.initial_state([0.0, 0.0], [0.0, 0.0]);
    let h = m.max_step_s;
    let steps = (25e-3 / h) as usize;
    let mut record = Vec::with_capacity(steps);
    for k in 0..steps {
        let t = k as f64 * h;
        let tau1 = if t < 5e-3 { 185.0 * 0.5 * (1.0 - (PI * t / 5e-3).cos()) } else { 185.0 };
        let load = -20.0 * s.omega[1];
        dynamics.advance(&mut s, [tau1, load], h, h).unwrap();
        record.push((s.theta[1], te(m, &s)));
    }
    let pitch2 = 2.0 * PI / m.pair.gear2.teeth as f64;
    let last = record.last().unwrap().0;
    let dte_last_cycle = record.iter().filter(|r| r.0 > last - pitch2).map(|r| r.1).collect();
    Example3 { steps, omega2_end: s.omega[1], dte_last_cycle }
}

/// The load-sharing shapes (`rom::sharing`), evidence by convergence in modelling choices that
/// should not matter: the torque the static shapes are taken at, and the angular samples. With
/// one static shape per sample the split of the load between the pairs in mesh is frozen at
/// that torque's. Example 3 runs at 185 N·m, and with 40 samples its DTE peak-to-peak (the
/// ringing after each pair's entry) moves by several per cent between shapes taken at 185 and
/// at 250 N·m (the control, asserted > 3 %, so that the test can fail). With the sharing shape
/// the default build (20 samples, 250 N·m) and one with 40 samples at 185 N·m agree within 1 %.
#[test]
fn dte_peak_to_peak_follows_the_load_not_the_rom_torque_with_sharing_shapes() {
    let f = fixture();
    assert_eq!(f.model.info.rom_torques_nm, vec![250.0]);
    assert_eq!(f.model.info.sharing_shapes, 1);
    assert_eq!(f.model.gears[0].samples, 20);
    let pair = common::kurokawa_spur();
    let build = |torque: f64, sharing_shapes: usize| {
        let options =
            DynamicBuildOptions { rom_torques_nm: vec![torque], sharing_shapes, angles: 40, ..Default::default() };
        build_dynamic_model(&pair, &MeshSpec::default(), &options, |_| {}).unwrap().0
    };
    let pp = |m: &PmorModel| example_3(m).dte_peak_to_peak_m();
    let with = [pp(&f.model), pp(&build(185.0, 1))];
    let without = [pp(&build(250.0, 0)), pp(&build(185.0, 0))];
    let change = |v: [f64; 2]| v[1] / v[0] - 1.0;
    eprintln!(
        "example 3 DTE p-p: with the sharing shape, 20 samples at 250 N·m {:.4} µm, 40 at 185 N·m {:.4} µm ({:+.2} %); without, 40 samples at 250 / 185 N·m {:.4} / {:.4} µm ({:+.2} %)",
        with[0] * 1e6,
        with[1] * 1e6,
        100.0 * change(with),
        without[0] * 1e6,
        without[1] * 1e6,
        100.0 * change(without)
    );
    assert!(change(with).abs() < 0.01);
    assert!(change(without).abs() > 0.03);
}

/// Back-flank contact, static (evidence: the PMOR-Hertz statics, through the symmetry of the
/// pair). A half turn about the line of centres maps the pair onto itself with its coast flanks
/// on its drive flanks (`PairPlacement::half_turn_angles`), so under a reversed torque the coast
/// TE at θ₂ is −j − STE(θ₂′), j the backlash and θ₂′ the half-turned angle: the drive statics
/// at another angle. The reduced pair's static equilibrium under −185 N·m reproduces it over a
/// whole mesh cycle within the static limit's bounds (2 % of the mean, 5 % of the p-p), and its
/// drive equilibrium at +185 N·m, the control, reproduces STE(θ₂) alike. This checks the coast
/// flank rows, the coast shapes (built in the half-turned pose and turned back) and the half
/// turn's tooth and section maps in one go: a tooth off by one would leave the coast flank
/// without its global deflection (a far stiffer mesh).
#[test]
fn reversed_torque_rests_on_the_coast_flanks_at_the_mirrored_static_te() {
    use gearfmu::dynamics::pmor::linear::static_equilibrium;
    let f = fixture();
    let m = &f.model;
    let dynamics = PmorDynamics::new(m, &f.place, m.damping(0.01, 0.05), [0.0; 2]);
    let torque = STATIC_TORQUES[0];
    let backlash = m.pair.backlash_loa_m;
    let pitch2 = m.gears[1].pitch_rad();
    let turn2 = f.place.half_turn_angles([0.0, 0.0])[1]; // θ₂′ = −θ₂ + turn2
    let ste = &f.statics[0];
    let (mut coast, mut drive) = (Vec::new(), Vec::new());
    for k in 0..STATIC_ANGLES {
        let theta2_turned = pitch2 * (k as f64 + 0.5) / STATIC_ANGLES as f64;
        let theta2 = (turn2 - theta2_turned).rem_euclid(pitch2);
        let (s, _) = static_equilibrium(&dynamics, theta2, -torque, -backlash - ste[k]).unwrap();
        let out = dynamics.outputs(&s).unwrap();
        assert!(out.contact.normal_force_n < 0.0, "the load must rest on the coast flanks");
        coast.push(-backlash - te(m, &s));
        let (s, _) = static_equilibrium(&dynamics, theta2_turned, torque, ste[k]).unwrap();
        drive.push(te(m, &s));
    }
    for (name, got) in [("coast (mirrored)", &coast), ("drive (control)", &drive)] {
        assert_reproduces_the_statics(&format!("{name} at {torque} N·m"), got, ste);
    }
}

/// Rattle conserves energy (evidence: a first integral of the exact flow, as above). No
/// damping, no torque: the gears turn together (50 rad/s) with a relative speed of 5 cm/s along
/// the line of action, so over 40 ms the teeth fly across the backlash, strike the coast flanks,
/// fly back and strike the drive flanks, ten times, crossing ten pitches. With point loads,
/// T + U + W stays constant within 1e-4 of the total and within 1e-2 of the relative motion's
/// energy ½·m_eq·v² that every impact converts into elastic and contact energy and back.
/// Measured drift: 2.3e-5 / 1.0e-6 / 6.8e-8 J at h = 1 / 0.5 / 0.25 µs, 3.3e-2 / 1.5e-3 / 9.8e-5
/// of the relative motion (5.1e-7 J at 0.5 µs since each gear's contact point is its own
/// crossing of the line of action): the named term is RK4's own damping of the high modes that
/// every impact rings (it falls as h⁴ and the energy only decreases, in free flight), so the test
/// runs at 0.5 µs. With the load-sharing shapes (a stiffer top mode, 101 kHz) 7.5e-5 / 3.0e-6 /
/// 9.0e-8 J at 1 / 0.5 / 0.25 µs, 1.1e-1 / 4.4e-3 / 1.3e-4 of the relative motion. (Before the tooth thinning was put into the half-turned pose as a turn of gear 1,
/// it was an offset of the gap, and the tip-corner and conjugate contacts met 0.1 µm apart at
/// the hand-over on the coast flanks: a jump of 3e-5 J that did not shrink with h.)
#[test]
fn rattle_across_the_backlash_conserves_energy() {
    use gearfmu::dynamics::pmor::contact::Loading;
    let f = fixture();
    let m = &f.model;
    let rb = base_radii(m);
    let mut dynamics = PmorDynamics::new(m, &f.place, m.damping(0.0, 0.0), [0.0; 2]);
    dynamics.loading = Loading::Point;
    let (j1, j2) = (m.gears[0].polar_inertia_kgm2, m.gears[1].polar_inertia_kgm2);
    let m_eq = 1.0 / (rb[0] * rb[0] / j1 + rb[1] * rb[1] / j2);
    // Common speed 50 rad/s on gear 2; the relative speed v along the LOA shared so that the
    // angular momentum of the relative motion is zero (v = r_b1·Δω₁ − r_b2·Δω₂).
    let (w2, v) = (50.0, -0.05);
    let dw = [v * m_eq * rb[0] / j1, -v * m_eq * rb[1] / j2];
    let mut s = m.initial_state([0.0, 0.0], [w2 * rb[1] / rb[0] + dw[0], w2 + dw[1]]);
    let relative_j = 0.5 * m_eq * v * v;
    let e0 = dynamics.outputs(&s).unwrap().total_energy_j();
    let (mut drift, mut flanks, mut k) = (0.0_f64, [0usize; 2], 0);
    // RATTLE_STEP_S reruns it at another step (the h⁴ scaling above).
    let h = std::env::var("RATTLE_STEP_S").ok().and_then(|v| v.parse().ok()).unwrap_or(5e-7);
    let steps = (0.04 / h) as usize;
    while k < steps {
        dynamics.rk4_step(&mut s, [0.0, 0.0], h).unwrap();
        k += 1;
        if k % 20 == 0 {
            let o = dynamics.outputs(&s).unwrap();
            drift = drift.max((o.total_energy_j() - e0).abs());
            if o.contact.normal_force_n > 0.0 {
                flanks[0] += 1;
            } else if o.contact.normal_force_n < 0.0 {
                flanks[1] += 1;
            }
        }
    }
    eprintln!(
        "rattle: {k} steps, {:.1} ms; total {e0:.4} J, relative motion {relative_j:.3e} J; max drift {drift:.3e} J ({:.2e} of total, {:.2e} of the relative motion); samples on drive / coast flanks {flanks:?}",
        k as f64 * h * 1e3,
        drift / e0,
        drift / relative_j
    );
    assert!(flanks[0] > 0 && flanks[1] > 0, "the teeth must strike both flanks");
    assert!(drift < 1e-4 * e0 && drift < 1e-2 * relative_j);
}

/// Conservation of energy (evidence: a first integral of the exact flow). No damping; the pair
/// turns at 100 rad/s (gear 2) and is kept in mesh by a balanced pair of constant torques
/// (τ₂ = −τ₁·r_b2/r_b1, conservative: their potential −Στᵢθᵢ joins the balance); it starts off
/// equilibrium, so the mesh vibrates, and runs 10 mesh cycles: 400 sample crossings and 10 pitch
/// re-anchorings per gear. With point loads (the contact force exactly the gradient of the
/// potential W(α)) T + U + W − Στθ stays within 1e-4 of the total and within 1e-3 of the
/// vibration energy (elastic + contact) it sloshes (measured 9.3e-8 and 9.0e-5; 2.6e-7 and
/// 2.5e-4 while T kept the rotation of the deformation, θ̇·GVη). With the default Hertz band the
/// load is not the gradient of the point gap: that named term leaves a drift of 1.2e-2 of the
/// vibration energy (measured and bounded here), which goes when it is treated exactly (the
/// point-load run): 130× less.
///
/// What the point-load run kept halved with the step (2.6e-5 J at 0.25 µs, 1.3e-5 J at
/// 0.125 µs, measured with θ̇·GVη in T): RK4 stepping over the kinks of W — the bilinear flank field's rows, the onset of
/// contact, the radius of curvature's slope at the hand-over to the tip corner. Until each gear's
/// contact point was its own crossing of the line of action (`section_contact`), the hand-over
/// from conjugate to tip-corner contact also jumped W, the two candidates meeting ≈ TE²/2ρ apart
/// under the rigid overlap TE (7e-9 m at 18 µm; 6.8e-5 J in all, not shrinking with h).
///
/// The tip corners touch with their rounded edges (`tip_edge_radius_mm`, 0.6 mm here): the
/// corner's radius blends C¹ from the involute's to the edge's after the hand-over
/// (`mesh_kinematics::corner_radius`). With a step there instead (measured before the blend: a
/// drift of 1e-3 of the total, the whole vibration energy) this test fails: the radius's jump at
/// fixed approach is a jump of W.
#[test]
fn undamped_pair_conserves_energy_over_ten_mesh_cycles() {
    use gearfmu::dynamics::pmor::contact::Loading;
    let f = fixture();
    let m = &f.model;
    let point = undamped_energy_drift(m, &f.place, 2.5e-7, Loading::Point, Integrator::Rk4, Condensation::None);
    let (drift, vib, e0, anchors) = (point.deviation, point.vibration, point.e0, point.anchors);
    let band = undamped_energy_drift(m, &f.place, 2.5e-7, Loading::HertzBand, Integrator::Rk4, Condensation::None);
    let (drift_band, vib_band) = (band.deviation, band.vibration);
    eprintln!("energy (point loads): total {e0:.4} J, peak vibration energy {vib:.3e} J, max drift {drift:.3e} J ({:.2e} of total, {:.2e} of vibration); anchors {anchors:?}",
        drift / e0.abs(), drift / vib);
    eprintln!(
        "energy (Hertz band): max drift {drift_band:.3e} J ({:.2e} of total, {:.2e} of vibration)",
        drift_band / e0.abs(),
        drift_band / vib_band
    );
    assert!(anchors[1] >= 10);
    assert!(drift < 1e-4 * e0.abs() && drift < 1e-3 * vib);
    assert!(drift_band < 1e-4 * e0.abs() && drift_band < 3e-2 * vib_band);
    assert!(drift < drift_band / 10.0, "the band is the named term: point loads must remove most of the drift");
}

/// The energy test's run: no damping, 100 rad/s on gear 2, balanced constant torques, off
/// equilibrium by 6 µm, ten mesh cycles; energy sampled every whole number of steps nearest
/// 12.5 µs (at least one): about 160 samples per mesh cycle at every step.
fn undamped_energy_drift(
    m: &PmorModel,
    place: &PairPlacement,
    h: f64,
    loading: gearfmu::dynamics::pmor::contact::Loading,
    integrator: Integrator,
    condensation: Condensation,
) -> EnergyRun {
    let rb = base_radii(m);
    let torques = [200.0, -200.0 * rb[1] / rb[0]];
    let w2 = 100.0;
    let pitch2 = 2.0 * PI / m.pair.gear2.teeth as f64;
    let mut dynamics = PmorDynamics::new(m, place, m.damping(0.0, 0.0), [0.0; 2]);
    dynamics.loading = loading;
    dynamics.integrator = integrator;
    dynamics.set_condensation(condensation);
    let mut s = dynamics.start_state([6e-6 / rb[0], 0.0], [w2 * rb[1] / rb[0], w2], torques).unwrap();
    let energy = |s: &PmorState| {
        let o = dynamics.outputs(s).unwrap();
        (
            o.total_energy_j() - torques[0] * s.theta[0] - torques[1] * s.theta[1],
            o.elastic_j + o.contact_j,
            o.contact.pairs_in_contact,
        )
    };
    let (e0, _, mut sections) = energy(&s);
    let mut contact_changes = 0;
    let (mut deviation, mut vib): (f64, f64) = (0.0, 0.0);
    // (θ₂, E) at every sample, for the cycle means.
    let mut samples = vec![(s.theta[1], e0)];
    let steps = (12.5e-6 / h).round().max(1.0) as usize;
    while s.theta[1] < 10.0 * pitch2 {
        match integrator {
            Integrator::Rk4 => (0..steps).for_each(|_| dynamics.rk4_step(&mut s, torques, h).unwrap()),
            // `steps` steps of h exactly (the bound a hair above h, so that ceil gives them).
            Integrator::Verlet => dynamics.verlet_advance(&mut s, torques, steps as f64 * h, h * (1.0 + 1e-9)).unwrap(),
            // As the FMU runs it (`advance`: the time stepper's solve tolerance).
            Integrator::DiscreteGradient => {
                dynamics.advance(&mut s, torques, steps as f64 * h, h * (1.0 + 1e-9)).unwrap()
            }
        }
        let (e, v, now) = energy(&s);
        deviation = deviation.max((e - e0).abs());
        vib = vib.max(v);
        samples.push((s.theta[1], e));
        contact_changes += usize::from(now != sections);
        sections = now;
    }
    // The cycle-mean energy: the oscillation inside a mesh cycle (a symplectic integrator's
    // bounded (ωh)² error) averages out of it; what the kinks of W leave behind (the bilinear
    // flank field, contact onsets, each an O(h²) jump of Verlet's shadow energy) does not.
    let cycle_mean = |from: f64| {
        let inside: Vec<f64> =
            samples.iter().filter(|(t, _)| *t >= from && *t < from + pitch2).map(|&(_, e)| e).collect();
        inside.iter().sum::<f64>() / inside.len() as f64
    };
    // Against the first cycle's mean: E₀ is one instant of the oscillation, so |Ē − E₀| carries
    // the shadow energy's offset, (ωh)²-sized, as well as any drift.
    let first = cycle_mean(0.0);
    let cycle_offset = (0..10).map(|k| (cycle_mean(k as f64 * pitch2) - e0).abs()).fold(0.0, f64::max);
    let secular_drift = (1..10).map(|k| (cycle_mean(k as f64 * pitch2) - first).abs()).fold(0.0, f64::max);
    EnergyRun {
        deviation,
        cycle_offset,
        secular_drift,
        trend: linear_trend(&samples),
        vibration: vib,
        e0,
        anchors: s.anchor,
        contact_changes,
    }
}

/// The change over the run of the least-squares line through the samples (θ₂, E).
fn linear_trend(samples: &[(f64, f64)]) -> f64 {
    let n = samples.len() as f64;
    let (tm, em) = samples.iter().fold((0.0, 0.0), |(a, b), &(t, e)| (a + t / n, b + e / n));
    let (stt, ste) = samples.iter().fold((0.0, 0.0), |(a, b), &(t, e)| (a + (t - tm).powi(2), b + (t - tm) * (e - em)));
    ste / stt * (samples[samples.len() - 1].0 - samples[0].0)
}

/// What an undamped run gives: the largest |E − E₀| over the run, the largest |Ē − E₀| of the
/// energy's mean over a mesh cycle (`cycle_offset`), the largest change of that mean from the
/// first cycle's over the next nine (`secular_drift`), the peak vibration energy (elastic +
/// contact), E₀ and the final pitch anchors.
struct EnergyRun {
    deviation: f64,
    cycle_offset: f64,
    secular_drift: f64,
    /// The energy drift as molecular dynamics defines it: the least-squares line through every
    /// sample E(θ₂), its change over the whole run (J). A bounded oscillation leaves it near
    /// zero; a secular gain or loss does not.
    trend: f64,
    /// Samples at which the number of tooth pairs in contact changed (entering, leaving).
    contact_changes: usize,
    vibration: f64,
    e0: f64,
    anchors: [i64; 2],
}

/// The pair with the build's damping, stepped by velocity Verlet, and Verlet's default step
/// (0.6 of its stability limit on the linearized pair, `linear::default_step`).
fn verlet_at_its_default_step(f: &Fixture, condensation: Condensation) -> (PmorDynamics<'_>, f64) {
    let m = &f.model;
    let mut verlet = PmorDynamics::new(m, &f.place, m.damping(m.modal_damping_ratio, m.shape_damping_ratio), [0.0; 2]);
    verlet.integrator = Integrator::Verlet;
    verlet.set_condensation(condensation);
    let h = linear::default_step(&verlet).unwrap().max_step_s;
    (verlet, h)
}

/// Velocity Verlet (`--integrator verlet`) at its own default step, 0.6 of its stability limit
/// on the linearized pair (evidence: the same first integral as above, point loads).
///
/// The integrator's order, on the full pair (`Condensation::None`, every coordinate with its
/// inertia): its energy error is a bounded oscillation of size (ωh)² in the modes that ring,
/// not a drift, so quartering the step divides it by about sixteen (asserted ≥ 9) — checked
/// from a quarter of the default step to a sixteenth, where the stiffest mode (the shapes
/// against the contact, ≈ 100 kHz) has ωh ≤ 0.27 (measured 4.6e-3 J at 1.7 µs, 5.1e-4 J at
/// 0.85 µs, 2.9e-4 J at 0.43 µs, 5.3e-5 J at 0.21 µs, 1.5e-5 J at 0.11 µs).
///
/// The shipped configuration (quasi-static shapes, hub and body modes above 3 × the mesh mode;
/// its default step 18.9 µs here, ω·h ≈ 0.45 for the mesh mode): within 1e-4 of the total
/// (measured 1.9e-5 with point loads, 2.1e-5 with the default Hertz band), 2.0e-2 and 2.3e-2 of
/// the peak vibration energy. That is Verlet's bounded energy oscillation, about (ωh)²/4 of the
/// energy of a mode that rings: a quarter of the step divides it by 32 (point loads) and 12
/// (band), asserted ≥ 4. (At the earlier default, 7.5 µs with every body mode dynamic, it was
/// 2.6e-3 with the band.)
///
/// Averaged over each mesh cycle, which takes the oscillation out, the energy still moves from
/// cycle to cycle: the largest change of the cycle mean from the first cycle's over the next
/// nine is 1.1e-2 of the peak vibration energy with the band and 7.4e-3 with point loads at the
/// default step; a quarter of the step takes it to 1.35e-3 and 4.0e-4 (ratios 9 and 21,
/// asserted ≥ 4: the integrator's error, second order, not the model's). What causes it is the
/// kinks of W: each node of the bilinear flank field the contact point crosses, and each contact
/// onset, is a jump of Verlet's shadow energy of order h². The 1e-3 of the vibration
/// energy is met by point loads at a quarter of the default step, not at the default step.
///
/// Where the jumps come from (measured 2026-11-26, every step's energy dumped over 40 cycles):
/// at the default step this undamped run drifts into rattle — the mesh mode, shifted by
/// Verlet's (ωh)²/24 ≈ 0.8 %, meets a mesh harmonic — and loses contact (187 of 4290 steps with
/// no tooth pair loaded); the largest moves of the smoothed energy, ≈ 1e-2 of the peak
/// vibration energy each, sit at those impacts. At a quarter of the step the teeth never
/// separate. Over 40 cycles the least-squares trend is 4.1e-2 (band) at the default step and
/// 3.1e-3 at a quarter of it. Re-taking a step in which a tooth pair enters or leaves contact as
/// 8 shorter steps (tried, not kept) took the quarter step's 40-cycle trend to 1.0e-4 but made
/// the default step's worse (6.8e-2): at ωh ≈ 0.45 the change of step is itself a jump of the
/// shadow energy, (ωh)²-sized.
#[test]
fn velocity_verlet_keeps_the_energy_at_the_default_step() {
    use gearfmu::dynamics::pmor::contact::Loading;
    let f = fixture();
    let m = &f.model;
    let (_, h) = verlet_at_its_default_step(f, Condensation::None);
    let drift_at = |h: f64| {
        undamped_energy_drift(m, &f.place, h, Loading::Point, Integrator::Verlet, Condensation::None).deviation
    };
    let (drift_quarter, drift_sixteenth) = (drift_at(0.25 * h), drift_at(h / 16.0));
    eprintln!(
        "velocity Verlet energy, full pair (point loads): default step {:.2} µs; at a quarter of it {drift_quarter:.3e} J, at a sixteenth {drift_sixteenth:.3e} J (ratio {:.1})",
        h * 1e6,
        drift_quarter / drift_sixteenth
    );
    assert!(
        drift_quarter / drift_sixteenth > 9.0,
        "second order: quartering the step must divide the error by about sixteen"
    );
    let (_, h) = verlet_at_its_default_step(f, Condensation::QuasiStatic);
    let drift_at =
        |h: f64| undamped_energy_drift(m, &f.place, h, Loading::Point, Integrator::Verlet, Condensation::QuasiStatic);
    let shipped = drift_at(h);
    let (drift, vib, e0, anchors) = (shipped.deviation, shipped.vibration, shipped.e0, shipped.anchors);
    let shipped_quarter = drift_at(0.25 * h);
    let drift_quarter = shipped_quarter.deviation;
    eprintln!(
        "velocity Verlet energy, shipped (quasi-static, point loads): at {:.2} µs max |E − E₀| {drift:.3e} J ({:.2e} of total, {:.2e} of the peak vibration energy); at a quarter of the step {drift_quarter:.3e} J (ratio {:.1})",
        h * 1e6,
        drift / e0.abs(),
        drift / vib,
        drift / drift_quarter
    );
    assert!(anchors[1] >= 10);
    assert!(drift < 1e-4 * e0.abs(), "within the issue's 1e-4 of the total");
    assert!(drift / drift_quarter > 4.0, "a quarter of the step must divide the error by at least four");
    // And with the default Hertz band: its named term (`undamped_pair_conserves_energy_over_ten_mesh_cycles`).
    let band = undamped_energy_drift(m, &f.place, h, Loading::HertzBand, Integrator::Verlet, Condensation::QuasiStatic);
    let (drift_band, vib_band) = (band.deviation, band.vibration);
    eprintln!(
        "velocity Verlet energy, shipped (quasi-static, Hertz band): at {:.2} µs max |E − E₀| {drift_band:.3e} J ({:.2e} of total, {:.2e} of the peak vibration energy); cycle-mean drift (largest |Ē_k − Ē_1| over ten cycles) {:.3e} J ({:.2e} of the peak vibration energy); point loads {:.3e} J ({:.2e})",
        h * 1e6,
        drift_band / e0.abs(),
        drift_band / vib_band,
        band.secular_drift,
        band.secular_drift / vib_band,
        shipped.secular_drift,
        shipped.secular_drift / vib
    );
    eprintln!(
        "  cycle means against E₀ (the shadow energy's offset with the drift): band {:.2e}, point loads {:.2e} of the peak vibration energy; least-squares trend over the run: band {:.2e}, point loads {:.2e}",
        band.cycle_offset / vib_band,
        shipped.cycle_offset / vib,
        band.trend / vib_band,
        shipped.trend / vib
    );
    let band_quarter =
        undamped_energy_drift(m, &f.place, 0.25 * h, Loading::HertzBand, Integrator::Verlet, Condensation::QuasiStatic);
    eprintln!(
        "  at a quarter of the step: band max |E − E₀| {:.3e} J (ratio {:.1}), drift {:.2e} of the peak vibration energy (ratio {:.1}); point loads drift {:.2e} (ratio {:.1})",
        band_quarter.deviation,
        drift_band / band_quarter.deviation,
        band_quarter.secular_drift / band_quarter.vibration,
        band.secular_drift / band_quarter.secular_drift,
        shipped_quarter.secular_drift / shipped_quarter.vibration,
        shipped.secular_drift / shipped_quarter.secular_drift
    );
    assert!(drift_band < 1e-4 * e0.abs());
    // What |E − E₀| and the cycle means' drift are: the integrator's second-order error (a
    // quarter of the step divides them by at least four), not the model's: a force that is not
    // the gradient of the potential would leave a drift that does not shrink with the step.
    assert!(
        drift_band / band_quarter.deviation > 4.0,
        "a quarter of the step must divide the band's error by at least four"
    );
    assert!(band.secular_drift / band_quarter.secular_drift > 4.0, "the band's cycle-mean drift must be second order");
    assert!(shipped.secular_drift / shipped_quarter.secular_drift > 4.0, "the cycle-mean drift must be second order");
}

/// Velocity Verlet's energy balance with damping and a net torque (evidence: the balance law
/// E + D − W = E₀, with D and W the integrator's own work integrals). The default damping (1 % on
/// Φ, 5 % on the shapes), gear 1 driven at 200 N·m against 80 % of the balancing torque, so the
/// pair accelerates; off equilibrium by 6 µm, so the mesh and the shapes ring; three mesh cycles.
/// Verlet books the damping's and the torques' work as the trapezoid of its own forces on its own
/// displacement Δq: the kinetic energy's change over a step is then that work up to a term that
/// telescopes, and the residual is the scheme's second-order oscillation (halving the step
/// divides it by about four, asserted ≥ 3). Booking η̇ᵀDη̇ at the predicted velocity v* instead
/// (as first written) created up to 3 % of the energy in play at the soak's rattle impacts.
#[test]
fn velocity_verlet_books_damping_and_input_work_in_the_energy_balance() {
    let f = fixture();
    let m = &f.model;
    let (verlet, h) = verlet_at_its_default_step(f, Condensation::None);
    let rb = base_radii(m);
    let torques = [200.0, -0.8 * 200.0 * rb[1] / rb[0]];
    let pitch2 = 2.0 * PI / m.pair.gear2.teeth as f64;
    let run = |h: f64| -> (f64, f64, f64, f64) {
        let mut s = verlet.start_state([6e-6 / rb[0], 0.0], [100.0 * rb[1] / rb[0], 100.0], torques).unwrap();
        let e0 = verlet.outputs(&s).unwrap().total_energy_j();
        let (mut worst, mut vib): (f64, f64) = (0.0, 0.0);
        while s.theta[1] < 3.0 * pitch2 {
            verlet.verlet_advance(&mut s, torques, 50.0 * h, h * (1.0 + 1e-9)).unwrap();
            let o = verlet.outputs(&s).unwrap();
            worst = worst.max((o.total_energy_j() + s.dissipated_j - s.input_work_j - e0).abs());
            vib = vib.max(o.elastic_j + o.contact_j);
        }
        (worst, vib, e0, s.dissipated_j)
    };
    let (residual, vib, e0, dissipated) = run(h);
    let (residual_half, _, _, _) = run(0.5 * h);
    eprintln!(
        "velocity Verlet balance (damped, driven): at {:.2} µs max |E + D − W − E₀| {residual:.3e} J ({:.2e} of the total, {:.2e} of the peak vibration energy; dissipated {dissipated:.3e} J); at half the step {residual_half:.3e} J (ratio {:.2})",
        h * 1e6,
        residual / e0,
        residual / vib,
        residual / residual_half
    );
    assert!(dissipated > 0.0);
    assert!(residual < 1e-4 * e0, "within the issue's 1e-4 of the total");
    assert!(residual / residual_half > 3.0, "second order: halving the step must divide the residual by about four");
    // The shipped configuration (quasi-static shapes and hub) at its own default step.
    let (verlet, h) = verlet_at_its_default_step(f, Condensation::QuasiStatic);
    let mut s = verlet.start_state([6e-6 / rb[0], 0.0], [100.0 * rb[1] / rb[0], 100.0], torques).unwrap();
    let e0 = verlet.outputs(&s).unwrap().total_energy_j();
    let mut worst: f64 = 0.0;
    while s.theta[1] < 3.0 * pitch2 {
        verlet.advance(&mut s, torques, 50.0 * h, h * (1.0 + 1e-9)).unwrap();
        let o = verlet.outputs(&s).unwrap();
        worst = worst.max((o.total_energy_j() + s.dissipated_j - s.input_work_j - e0).abs());
    }
    eprintln!(
        "velocity Verlet balance, shipped (quasi-static) at {:.2} µs: max |E + D − W − E₀| {worst:.3e} J ({:.2e} of the total); dissipated {:.3e} J",
        h * 1e6,
        worst / e0,
        s.dissipated_j
    );
    assert!(s.dissipated_j > 0.0);
    assert!(worst < 1e-4 * e0, "within the issue's 1e-4 of the total");
}

/// Regression guard: an angle a hair below a pitch boundary (ϑ rounds to the pitch itself) used
/// to make the pitch anchor oscillate forever; the fmpy drivetrain demo hung on it at t = 0.
#[test]
fn a_start_on_a_pitch_boundary_steps() {
    let f = fixture();
    let m = &f.model;
    let dynamics = PmorDynamics::new(m, &f.place, m.damping(0.01, 0.05), [0.0; 2]);
    for theta in [-1e-20, -0.0, 1e-300, -1e-300] {
        let mut s = m.initial_state([theta, theta], [0.0, 0.0]);
        dynamics.rk4_step(&mut s, [0.0, -0.0], 2e-6).unwrap();
        assert_eq!(
            s.anchor,
            [
                (s.theta[0] / m.gears[0].pitch_rad()).floor() as i64,
                (s.theta[1] / m.gears[1].pitch_rad()).floor() as i64
            ]
        );
    }
}

/// The contact's angle forces are the gradient of the contact potential (evidence: a central
/// difference of W = Σ P·α − W*(P) itself, at fixed η): −∂W/∂θᵢ by the closed form on conjugate
/// contact (rigid arm, the point sliding along the deformed flank, the shapes turning with the
/// gear, the radii of curvature travelling) and by differences at tip corners. States along a
/// whole mesh cycle of a loaded run, so η is far from zero and every contact kind occurs.
#[test]
fn contact_angle_forces_are_the_gradient_of_the_contact_potential() {
    angle_forces_against_the_potential(1.0);
}

/// The same on the coast flanks: the torque reversed, the load across the backlash.
#[test]
fn coast_contact_angle_forces_are_the_gradient_of_the_contact_potential() {
    angle_forces_against_the_potential(-1.0);
}

fn angle_forces_against_the_potential(sign: f64) {
    let f = fixture();
    let m = &f.model;
    let rb = base_radii(m);
    let dynamics = PmorDynamics::new(m, &f.place, m.damping(m.modal_damping_ratio, m.shape_damping_ratio), [0.0; 2]);
    let torque = sign * 370.0;
    let mean_static = f.statics[1].iter().sum::<f64>() / f.statics[1].len() as f64;
    let mean_static = if sign > 0.0 { mean_static } else { -m.pair.backlash_loa_m - mean_static };
    let pitch2 = 2.0 * PI / m.pair.gear2.teeth as f64;
    let w2 = 50.0;
    let mut s = m.initial_state([mean_static / rb[0], 0.0], [w2 * rb[1] / rb[0], w2]);
    let (mut checked, mut kinks, mut worst) = (0, 0, 0.0_f64);
    let mut k = 0;
    while s.theta[1] < pitch2 {
        let brake = -torque * rb[1] / rb[0] - 20.0 * (s.omega[1] - w2);
        dynamics.rk4_step(&mut s, [torque, brake], 2e-6).unwrap();
        k += 1;
        if k % 40 != 0 {
            continue;
        }
        let at = dynamics.outputs(&s).unwrap();
        if at.contact.normal_force_n == 0.0 {
            continue; // the start's rebound
        }
        assert!(at.contact.normal_force_n * sign > 0.0, "the load must rest on the flanks the torque closes");
        for i in 0..2 {
            let slope = |h: f64| {
                let mut up = s.clone();
                up.theta[i] += h;
                let mut down = s.clone();
                down.theta[i] -= h;
                (dynamics.outputs(&up).unwrap().contact_j - dynamics.outputs(&down).unwrap().contact_j) / (2.0 * h)
            };
            // Scale: the mesh torque on the gear.
            let scale = rb[i] * at.contact.normal_force_n.abs();
            let (coarse, fine) = (slope(1e-7), slope(2.5e-8));
            // W is only piecewise smooth: the flank field is bilinear between node rows, so its
            // slope jumps where a contact point crosses a row. Where the two differences
            // disagree the state sits on such a kink and has no gradient to compare.
            if (coarse - fine).abs() > 1e-6 * scale {
                kinks += 1;
                continue;
            }
            let force = at.contact.force[i][0];
            let error = (force + coarse).abs() / scale;
            worst = worst.max(error);
            assert!(
                error < 1e-5,
                "gear {} at θ₂ = {:.5}: F_θ {force:.6} N·m, −∂W/∂θ {:.6} N·m",
                i + 1,
                s.theta[1],
                -coarse
            );
            checked += 1;
        }
    }
    eprintln!(
        "angle forces against −∂W/∂θ: {checked} checks, worst {worst:.2e} of the mesh torque; {kinks} states on a kink of W skipped"
    );
    assert!(checked > 40 && kinks * 10 < checked);
}

/// Linear dynamics (evidence: the linearized ROM's eigenvalues against a time run of the full
/// nonlinear model). At 185 N·m the pair sits in static equilibrium (gear 2 at 0.3 pitch); a
/// balanced torque step of +2 % (both gears, the reaction from the new equilibrium) starts it
/// vibrating, undamped. Linear theory splits the DTE's response into modes, a_k = d·φ_k ·
/// (ψ_kᵀΔq)/(ψ_kᵀφ_k) with φ, ψ the right and left eigenvectors of −∂q̈/∂q and Δq the static
/// change; the mode with the largest a_k is the mesh mode. The DTE's spectrum over 20 ms peaks
/// at its frequency within 2 %.
#[test]
fn torque_step_rings_at_the_linearized_mesh_mode() {
    use gearfmu::dynamics::pmor::linear::static_equilibrium;
    let f = fixture();
    let m = &f.model;
    let dynamics = PmorDynamics::new(m, &f.place, m.damping(0.0, 0.0), [0.0; 2]);
    let theta2 = 0.3 * m.gears[1].pitch_rad();
    let torque = 185.0;
    let (s0, _) = static_equilibrium(&dynamics, theta2, torque, 15e-6).unwrap();
    let (s1, t2_1) = static_equilibrium(&dynamics, theta2, 1.02 * torque, te(m, &s0)).unwrap();
    let mode = gearfmu::dynamics::pmor::linear::mesh_mode(&dynamics, theta2, torque).unwrap();
    let (mesh_mode, share) = (mode.frequency_hz, mode.dte_share);
    // The nonlinear run.
    let h = 0.5 * m.max_step_s;
    let steps = (20e-3 / h) as usize;
    let mut s = s0.clone();
    let mut dte = Vec::with_capacity(steps);
    for _ in 0..steps {
        dynamics.rk4_step(&mut s, [1.02 * torque, t2_1], h).unwrap();
        dte.push(te(m, &s));
    }
    let mean = dte.iter().sum::<f64>() / steps as f64;
    let pad = 16 * steps.next_power_of_two();
    let mut buffer: Vec<rustfft::num_complex::Complex<f64>> = (0..pad)
        .map(|k| {
            let v = if k < steps { (dte[k] - mean) * (1.0 - (2.0 * PI * k as f64 / steps as f64).cos()) } else { 0.0 };
            rustfft::num_complex::Complex::new(v, 0.0)
        })
        .collect();
    rustfft::FftPlanner::new().plan_fft_forward(pad).process(&mut buffer);
    let bin = 1.0 / (pad as f64 * h);
    let peak = (1..pad / 2).max_by(|&i, &j| buffer[i].norm().total_cmp(&buffer[j].norm())).unwrap() as f64 * bin;
    eprintln!(
        "torque step at {torque} N·m: mesh mode {:.1} Hz carries {:.0} % of the modal DTE amplitude; DTE spectrum peak {:.1} Hz ({:+.2} %); run DTE mean change {:.3} µm vs static {:.3} µm",
        mesh_mode,
        100.0 * share,
        peak,
        (peak / mesh_mode - 1.0) * 100.0,
        (mean - te(m, &s0)) * 1e6,
        (te(m, &s1) - te(m, &s0)) * 1e6
    );
    assert!((peak / mesh_mode - 1.0).abs() < 0.02);
    assert!(share > 0.5, "one mode must carry the DTE for the comparison to mean anything");
}

/// Validity (issue 12, item 4, the dynamics' side): the pair pressed ever deeper at rest (η = 0,
/// all the approach in the contact) is refused by the half-width rule (b ≤ h/4,
/// `contact::hertz::MAX_HALF_WIDTH_OVER_DEPTH`) — before the law's own monotone range ends
/// (b ≈ 0.59 h) — with a message that names the rule; a doStep there returns an error.
#[test]
fn contact_beyond_the_half_width_rule_is_an_error() {
    let f = fixture();
    let m = &f.model;
    let rb = base_radii(m);
    let dynamics = PmorDynamics::new(m, &f.place, m.damping(0.01, 0.05), [0.0; 2]);
    let theta2 = 0.3 * m.gears[1].pitch_rad();
    let mut te_m = 10e-6;
    loop {
        let s = m.initial_state([(rb[1] * theta2 + te_m) / rb[0], theta2], [0.0; 2]);
        match dynamics.outputs(&s) {
            Ok(out) => {
                assert!(out.contact.normal_force_n > 0.0);
                te_m += 10e-6;
            }
            Err(message) => {
                eprintln!("refused at an approach of {:.0} µm: {message}", te_m * 1e6);
                assert!(message.contains("half-width") && message.contains("0.25"), "{message}");
                break;
            }
        }
        assert!(te_m < 5e-3, "never refused");
    }
}

/// The fixture's pair with the build's damping and a mesh damper at ratio ζ of the spec.
fn with_mesh_damper(f: &Fixture, zeta: f64) -> PmorDynamics<'_> {
    let m = &f.model;
    let mut d = PmorDynamics::new(m, &f.place, m.damping(m.modal_damping_ratio, m.shape_damping_ratio), [0.0; 2]);
    d.mesh_damping_n_s_per_m =
        m.mesh_damper_n_s_per_m(zeta, [m.gears[0].polar_inertia_kgm2, m.gears[1].polar_inertia_kgm2]);
    d
}

/// The mesh damper (`PmorDynamics::mesh_damping_n_s_per_m`, the FMU's mesh_damping_ratio)
/// gives the mesh mode the damping ratio asked (evidence: the linearized pair's eigenvalues,
/// `linear::mesh_mode`, the mode followed from the damper-free flow as the damper grows) on the
/// average over a mesh cycle (eight positions), within 20 % from ζ = 0.02 to 0.3, at 185 N·m
/// (the build calibrates at ζ = 0.05 under the reference mesh force). Per position the ratio follows the contact zone, as any viscous mesh damper's does:
/// higher in single contact, where the mesh is softer (measured +33 %), lower in double
/// (−15 %). The damper acts on the loaded sections' approach velocity, so without the build's
/// gain (`PmorModel::mesh_damper_gain`, about 2.1 here) it would give about half the ratio: the teeth's
/// own bending, which it leaves out, carries the rest of the mesh mode's relative motion.
#[test]
fn the_mesh_damper_damps_the_mesh_mode_at_about_the_ratio_asked() {
    let f = fixture();
    let m = &f.model;
    let torque = 185.0;
    let dynamics = |zeta: f64| with_mesh_damper(f, zeta);
    eprintln!("the build's damper gain g = {:.3}", m.mesh_damper_gain);
    let positions: Vec<f64> = (0..8).map(|j| (j as f64 + 0.5) / 8.0 * m.gears[1].pitch_rad()).collect();
    let ratios = |zeta: f64| -> Vec<(f64, f64, f64)> {
        let d = dynamics(zeta);
        positions
            .iter()
            .map(|&theta2| {
                let mode = linear::mesh_mode(&d, theta2, torque).unwrap();
                (mode.frequency_hz, mode.damping_ratio, mode.dte_share)
            })
            .collect()
    };
    let without = ratios(0.0);
    for &(frequency_hz, ratio, share) in &without {
        assert!(share > 0.5, "one mode carries the DTE ({frequency_hz:.0} Hz: {share})");
        assert!(ratio < 0.01, "without the damper the mesh mode is lightly damped ({ratio})");
    }
    for zeta in [0.02, 0.05, 0.1, 0.3] {
        let added: Vec<f64> = ratios(zeta).iter().zip(&without).map(|(w, o)| w.1 - o.1).collect();
        let mean = added.iter().sum::<f64>() / added.len() as f64;
        let per_position: Vec<String> = added
            .iter()
            .zip(&without)
            .map(|(a, o)| format!("{:.0} Hz {:+.0} %", o.0, 100.0 * (a / zeta - 1.0)))
            .collect();
        eprintln!(
            "asked ζ = {zeta}: the damper adds {mean:.4} over the cycle ({:+.1} %); per position {}",
            100.0 * (mean / zeta - 1.0),
            per_position.join(", ")
        );
        assert!((mean / zeta - 1.0).abs() < 0.2, "the damper adds ζ {mean:.4} to the mesh mode, asked {zeta}");
    }
}

/// The quasi-static condensation damps the mesh mode as the full pair does (evidence: the full
/// pair, every coordinate with its inertia, linearized at the same mesh damper c, ζ = 0.05 of the
/// spec, at eight positions of a mesh cycle under 185 N·m). The condensed coordinates — the
/// shapes, the hub and the body modes above the cut-off — move with the slow motion through
/// their equilibrium, and the mesh damper's approach rate and the modal damping see that rate
/// (`damp_the_fast_motion`). Without the condensed body modes' rate the damper saw a larger
/// approach rate than the full pair's: at the same c the default's ζ was 8 % above the full
/// pair's here (20 % on the small helical pair, 1.7–2.1 × at the explicit integrator's 3 × cut-off),
/// and each build's own calibration of c then made the two FMUs of one spec different pairs
/// (issue 38). Measured 2026-11-28: within 0.1 % per position at the default cut-off, +7 % at 3 ×
/// (its mesh mode 1.4 % stiffer).
#[test]
fn the_condensed_pair_damps_the_mesh_mode_as_the_full_pair_does() {
    let f = fixture();
    let m = &f.model;
    let torque = 185.0;
    let ratios = |condensation: Condensation| -> Vec<f64> {
        let mut d = with_mesh_damper(f, 0.05);
        d.set_condensation(condensation);
        (0..8)
            .map(|j| {
                let theta2 = (j as f64 + 0.5) / 8.0 * m.gears[1].pitch_rad();
                linear::mesh_mode(&d, theta2, torque).unwrap().damping_ratio
            })
            .collect()
    };
    let full = ratios(Condensation::None);
    let condensed = ratios(Condensation::QuasiStatic);
    for (k, (c, f)) in condensed.iter().zip(&full).enumerate() {
        eprintln!("position {k}: ζ condensed {c:.5}, full {f:.5} ({:+.2} %)", 100.0 * (c / f - 1.0));
        assert!(
            (c / f - 1.0).abs() < 0.02,
            "position {k}: the condensed pair's ζ {c:.5} against the full pair's {f:.5}"
        );
    }
}

/// Velocity Verlet books the mesh damper's work like the modal damping's (evidence: the
/// first integral E + D − W, as `velocity_verlet_books_damping_and_input_work_in_the_energy_balance`,
/// with a heavy mesh damper, ζ = 0.3, from a start in the backlash: free flight, the impact, load).
#[test]
fn velocity_verlet_books_the_mesh_damper_in_the_energy_balance() {
    let f = fixture();
    let m = &f.model;
    let (mut verlet, undamped_h) = verlet_at_its_default_step(f, Condensation::QuasiStatic);
    let rb = base_radii(m);
    let inertia = [m.gears[0].polar_inertia_kgm2, m.gears[1].polar_inertia_kgm2];
    verlet.mesh_damping_n_s_per_m = m.mesh_damper_n_s_per_m(0.3, inertia);
    // The step follows the damped pair (as the FMU's stability check does for a
    // mesh_damping_ratio other than the build's).
    let h = linear::default_step(&verlet).unwrap().max_step_s;
    let torques = [200.0, -0.8 * 200.0 * rb[1] / rb[0]];
    let pitch2 = 2.0 * PI / m.pair.gear2.teeth as f64;
    // A gap of 10 µm to start: free flight (about 65 µs under these torques), the impact (the
    // damper switching on with contact), then the loaded mesh; sampled every whole number of
    // steps nearest 10 µs (at least one), so that the free flight is sampled at any step.
    let mut s = verlet.start_state([-10e-6 / rb[0], 0.0], [100.0 * rb[1] / rb[0] + 0.05, 100.0], torques).unwrap();
    let e0 = verlet.outputs(&s).unwrap().total_energy_j();
    let (mut worst, mut unloaded): (f64, usize) = (0.0, 0);
    while s.theta[1] < 3.0 * pitch2 {
        let steps = (10e-6 / h).round().max(1.0);
        verlet.verlet_advance(&mut s, torques, steps * h, h * (1.0 + 1e-9)).unwrap();
        let o = verlet.outputs(&s).unwrap();
        worst = worst.max((o.total_energy_j() + s.dissipated_j - s.input_work_j - e0).abs());
        unloaded += (o.contact.pairs_in_contact == 0) as usize;
    }
    eprintln!(
        "velocity Verlet with the mesh damper (ζ 0.3) at {:.2} µs (undamped default {:.2} µs): max |E + D − W − E₀| {worst:.3e} J ({:.2e} of the total), dissipated {:.3e} J, {unloaded} samples without contact",
        h * 1e6,
        undamped_h * 1e6,
        worst / e0,
        s.dissipated_j
    );
    assert!(s.dissipated_j > 0.0);
    assert!(unloaded > 0, "the run must pass through free flight");
    assert!(worst < 1e-4 * e0, "within the issue's 1e-4 of the total");
}

/// The port a master couples to carries the gear's whole inertia (closed form: a free rigid
/// body, ω(t) = T·t/J). Gear 1 sits in the middle of the backlash, out of contact, and a torque
/// steps on at its bore; from 100 µs to 200 µs (6 to 12 periods of its 59 kHz hub mode) the
/// port's speed is T·t/J₁ to terms of second order in η (measured 3e-9: Jω is the angular
/// momentum), and its angle T·t²/2J₁. With every coordinate's inertia (`Condensation::None`)
/// the bore — the floating frame, carrying about 2 % of the inertia on its own — rings about
/// that line with the hub mode: the reason the port is not the bore. With the hub direction
/// quasi-static (the default) the hub mode is gone: the bore follows the port through the web's
/// static twist (within 1e-3 here). Also φ̇ = ω of the port, by central differences along the
/// run (the pair a master integrates).
#[test]
fn the_port_accelerates_as_the_rigid_gear_and_its_angle_integrates_its_speed() {
    use gearfmu::dynamics::pmor::quasi_static::Condensation;
    let f = fixture();
    let m = &f.model;
    let rb = base_radii(m);
    let j1 = m.gears[0].polar_inertia_kgm2;
    for condensation in [Condensation::None, Condensation::QuasiStatic] {
        let mut dynamics =
            PmorDynamics::new(m, &f.place, m.damping(m.modal_damping_ratio, m.shape_damping_ratio), [0.0; 2]);
        dynamics.set_condensation(condensation);
        let (torque, h) = (5.0, 2e-7);
        let mut s = dynamics.start_state([-0.5 * m.pair.backlash_loa_m / rb[0], 0.0], [0.0; 2], [torque, 0.0]).unwrap();
        assert_eq!(dynamics.outputs(&s).unwrap().contact.pairs_in_contact, 0, "the start must be out of contact");
        let (mut port_error, mut bore_error, mut rate_error): (f64, f64, f64) = (0.0, 0.0, 0.0);
        let start_angle = dynamics.port(0, &s).unwrap().0;
        let mut previous = dynamics.port(0, &s).unwrap();
        let steps = 1000;
        for k in 1..=steps {
            let before = previous;
            dynamics.advance(&mut s, [torque, 0.0], h, h).unwrap();
            let now = dynamics.port(0, &s).unwrap();
            // Central difference of the angle at the step's middle against the mean of the speeds.
            let rate = (now.0 - before.0) / h;
            rate_error = rate_error.max((rate - 0.5 * (now.1 + before.1)).abs());
            previous = now;
            let t = k as f64 * h;
            if t >= 100e-6 {
                let rigid = torque * t / j1;
                port_error = port_error.max((now.1 / rigid - 1.0).abs());
                bore_error = bore_error.max((s.omega[0] / rigid - 1.0).abs());
            }
        }
        assert_eq!(dynamics.outputs(&s).unwrap().contact.pairs_in_contact, 0, "the run must stay out of contact");
        let t = steps as f64 * h;
        let angle = dynamics.port(0, &s).unwrap().0 - start_angle;
        eprintln!(
            "{condensation:?}: port speed within {port_error:.2e} of T·t/J (bore {bore_error:.2e}); angle {angle:.4e} rad against T·t²/2J {:.4e}; |φ̇ − ω| ≤ {rate_error:.2e} rad/s",
            torque * t * t / (2.0 * j1)
        );
        assert!(port_error < 1e-6, "the port must move as the rigid body");
        match condensation {
            Condensation::None => {
                assert!(bore_error > 0.01, "the bore rings with the hub mode (else this test proves nothing)")
            }
            Condensation::QuasiStatic => assert!(bore_error < 1e-3, "no hub mode: the bore follows the port"),
        }
        assert!((angle / (torque * t * t / (2.0 * j1)) - 1.0).abs() < 0.01);
        assert!(rate_error < 1e-3 * torque * t / j1, "the port's angle must integrate its speed");
    }
}

/// The mesh damper never pulls the teeth together and only dissipates (evidence: the sign of
/// the contact force and of the damper's power at every step). The rattle of
/// `rattle_across_the_backlash_conserves_energy` with the mesh damper at ζ = 0.3: the teeth
/// strike both flanks and separate again at 0.05 m/s, so the approach velocity is negative
/// on every separation, where a damper on the rigid frames' velocity (this model's before
/// issue 24) pulled with c·α̇ while the elastic force vanished. Each section's damper force is
/// bounded below by its elastic force, so the mesh force keeps the sign of the flank that
/// carries it, and the booked dissipation never decreases.
#[test]
fn the_mesh_damper_never_pulls_and_only_dissipates() {
    let f = fixture();
    let m = &f.model;
    let rb = base_radii(m);
    let (j1, j2) = (m.gears[0].polar_inertia_kgm2, m.gears[1].polar_inertia_kgm2);
    let mut dynamics =
        PmorDynamics::new(m, &f.place, m.damping(m.modal_damping_ratio, m.shape_damping_ratio), [0.0; 2]);
    dynamics.mesh_damping_n_s_per_m = m.mesh_damper_n_s_per_m(0.3, [j1, j2]);
    dynamics.integrator = Integrator::Verlet;
    let h = linear::default_step(&dynamics).unwrap().max_step_s;
    let m_eq = 1.0 / (rb[0] * rb[0] / j1 + rb[1] * rb[1] / j2);
    let (w2, v) = (50.0, -0.05);
    let dw = [v * m_eq * rb[0] / j1, -v * m_eq * rb[1] / j2];
    let mut s = m.initial_state([0.0, 0.0], [w2 * rb[1] / rb[0] + dw[0], w2 + dw[1]]);
    let (mut separations, mut flanks, mut previous_dissipated) = (0, [0usize; 2], 0.0);
    let mut previous_force = 0.0;
    for _ in 0..(0.02 / h) as usize {
        dynamics.verlet_advance(&mut s, [0.0, 0.0], h, h * (1.0 + 1e-9)).unwrap();
        let c = dynamics.outputs(&s).unwrap().contact;
        let elastic = c.normal_force_n - c.damper_force_n;
        assert!(c.damper_power_w >= 0.0, "the damper's power {} W is negative", c.damper_power_w);
        assert!(
            c.normal_force_n * elastic >= 0.0,
            "mesh force {} N against elastic {elastic} N: the damper pulls",
            c.normal_force_n
        );
        assert!(s.dissipated_j >= previous_dissipated - 1e-12, "the booked dissipation decreased");
        previous_dissipated = s.dissipated_j;
        if previous_force != 0.0 && c.normal_force_n == 0.0 {
            separations += 1;
        }
        if c.normal_force_n > 0.0 {
            flanks[0] += 1;
        } else if c.normal_force_n < 0.0 {
            flanks[1] += 1;
        }
        previous_force = c.normal_force_n;
    }
    eprintln!(
        "damped rattle: {separations} separations, steps on drive / coast flanks {flanks:?}, dissipated {:.3e} J",
        s.dissipated_j
    );
    assert!(separations >= 2 && flanks[0] > 0 && flanks[1] > 0, "the teeth must strike both flanks and separate");
}

/// Example 3 as a master couples it: 185 N·m after a 5 ms haversine ramp, a viscous brake of
/// 20 N·m·s/rad fed back from the port's speed each 20 µs, 25 ms from `s`. Returns the DTE over
/// 20–25 ms, sampled each 20 µs: mean, RMS about the mean and peak-to-peak (m).
fn example_3_coupled_dte(m: &PmorModel, d: &PmorDynamics, s: &mut PmorState, max_step_s: f64) -> [f64; 3] {
    let comm = 2e-5;
    let mut dte = Vec::new();
    for k in 0..1250 {
        let t = k as f64 * comm;
        let tau = 185.0 * if t < 5e-3 { 0.5 * (1.0 - (PI * t / 5e-3).cos()) } else { 1.0 };
        let w2 = d.port(1, s).unwrap().1;
        d.advance(s, [tau, -20.0 * w2], comm, max_step_s).unwrap();
        dte.push(te(m, s));
    }
    let tail = &dte[1000..];
    let mean = tail.iter().sum::<f64>() / tail.len() as f64;
    let rms = (tail.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / tail.len() as f64).sqrt();
    let pp = tail.iter().cloned().fold(f64::MIN, f64::max) - tail.iter().cloned().fold(f64::MAX, f64::min);
    [mean, rms, pp]
}

/// The quasi-static condensation (`quasi_static`) against the full reduced pair on the same
/// model (evidence: the full model, every coordinate with its inertia, as reference). Example 3
/// (185 N·m haversine ramp 5 ms, viscous brake 20 N·m·s/rad fed back from the port's speed each
/// 20 µs): the DTE over 20–25 ms (mean, RMS about the mean, peak-to-peak, sampled each 20 µs)
/// within 1 % of the full model's at its default step, while velocity Verlet's stability limit
/// on the condensed pair, linearized at the model's checked load, is at least twice the full
/// pair's: the shapes against the contact and the hub mode no longer bound it, the mesh mode
/// and the retained body modes do (measured on the default spur pair at 1000 N·m: 33.4 µs,
/// highest mode 9.3 kHz, against 3.0 µs and 99.5 kHz). The body-mode cut-off's share of that:
/// with every body mode dynamic (the condensation before the cut-off, 12.2 µs and 23.9 kHz on
/// the default spur pair) the DTE is within 1 % too, and the cut-off's limit is at least twice
/// that one. Also the energy balance of the condensed run (E + D − W − E₀ within 1e-4 of the
/// work put in).
#[test]
fn the_quasi_static_condensation_keeps_example_3s_dte_at_a_longer_step() {
    use gearfmu::dynamics::pmor::quasi_static::Condensation;
    let f = fixture();
    let m = &f.model;
    let inertia = [m.gears[0].polar_inertia_kgm2, m.gears[1].polar_inertia_kgm2];
    let run = |condensation: Condensation, cutoff_hz: Option<f64>| {
        let mut d = PmorDynamics::new(m, &f.place, m.damping(m.modal_damping_ratio, m.shape_damping_ratio), [0.0; 2]);
        d.set_condensation(condensation);
        if let Some(cutoff_hz) = cutoff_hz {
            d.set_quasi_static_cutoff(cutoff_hz);
        }
        d.mesh_damping_n_s_per_m = m.mesh_damper_n_s_per_m(0.05, inertia);
        let step = linear::default_step(&d).unwrap();
        let mut s = d.start_state([0.0; 2], [0.0; 2], [0.0; 2]).unwrap();
        let e0 = d.outputs(&s).unwrap().total_energy_j();
        let figures = example_3_coupled_dte(m, &d, &mut s, step.max_step_s);
        let balance = d.outputs(&s).unwrap().total_energy_j() + s.dissipated_j - s.input_work_j - e0;
        (step, figures, balance / s.input_work_j)
    };
    let (full_step, full, full_balance) = run(Condensation::None, None);
    let (qs_step, qs, qs_balance) = run(Condensation::QuasiStatic, None);
    let (every_step, every, every_balance) = run(Condensation::QuasiStatic, Some(f64::INFINITY));
    eprintln!(
        "quasi-static, every body mode dynamic: limit {:.2} µs (top {:.0} Hz), DTE mean/rms/p-p {:.4}/{:.4}/{:.4} µm, balance {every_balance:.1e}",
        every_step.stability_limit_s * 1e6,
        every_step.natural_frequencies_hz.last().unwrap(),
        every[0] * 1e6,
        every[1] * 1e6,
        every[2] * 1e6,
    );
    eprintln!(
        "full: limit {:.2} µs (top {:.0} Hz), DTE mean/rms/p-p {:.4}/{:.4}/{:.4} µm, balance {full_balance:.1e}; quasi-static: limit {:.2} µs (top {:.0} Hz), {:.4}/{:.4}/{:.4} µm, balance {qs_balance:.1e}",
        full_step.stability_limit_s * 1e6,
        full_step.natural_frequencies_hz.last().unwrap(),
        full[0] * 1e6,
        full[1] * 1e6,
        full[2] * 1e6,
        qs_step.stability_limit_s * 1e6,
        qs_step.natural_frequencies_hz.last().unwrap(),
        qs[0] * 1e6,
        qs[1] * 1e6,
        qs[2] * 1e6,
    );
    for k in 0..3 {
        assert!((qs[k] / full[k] - 1.0).abs() < 0.01, "DTE figure {k}: {} against {}", qs[k], full[k]);
        assert!((every[k] / full[k] - 1.0).abs() < 0.01, "DTE figure {k}: {} against {}", every[k], full[k]);
    }
    assert!(qs_step.stability_limit_s > 2.0 * full_step.stability_limit_s);
    assert!(qs_step.stability_limit_s > 2.0 * every_step.stability_limit_s);
    assert!(qs_balance.abs() < 1e-4 && full_balance.abs() < 1e-4 && every_balance.abs() < 1e-4);
}

/// Tooth friction on the condensed pair against the full reduced pair (issue 42; evidence: the
/// full model, every coordinate with its inertia and its own rate, where friction acts on the
/// contact shapes and body modes directly and slides the flanks with their rates, as reference
/// for the condensation's route: the fast rates from the equilibrium, the fast loads carried
/// through its tangent). Example 3 as above with μ = 0.05 and without (v_ε 20 mm/s in both): what
/// friction changes in the DTE over 20–25 ms (mean, RMS about the mean, peak-to-peak) agrees
/// within 5 % of the change. Measured: mean +0.0496 µm full, +0.0487 condensed; RMS +0.1985,
/// +0.1978; p-p +0.0515, +0.0513.
#[test]
fn the_condensed_pair_carries_tooth_friction_as_the_full_pair_does() {
    use gearfmu::dynamics::mesh_friction::SlidingFriction;
    let f = fixture();
    let m = &f.model;
    let inertia = [m.gears[0].polar_inertia_kgm2, m.gears[1].polar_inertia_kgm2];
    let run = |condensation: Condensation, mu: f64| {
        let mut d = PmorDynamics::new(m, &f.place, m.damping(m.modal_damping_ratio, m.shape_damping_ratio), [0.0; 2]);
        d.set_condensation(condensation);
        d.mesh_damping_n_s_per_m = m.mesh_damper_n_s_per_m(0.05, inertia);
        if mu > 0.0 {
            d.friction = Some(SlidingFriction { coefficient: mu, regularization_m_per_s: 2e-2 });
        }
        // The full pair by RK4 at a quarter microsecond: within the band friction is a damper of
        // μF/v_ε on the contact shapes' light modal masses, too stiff for the default step.
        let max_step_s = match condensation {
            Condensation::None => {
                d.integrator = Integrator::Rk4;
                2.5e-7
            }
            _ => linear::default_step(&d).unwrap().max_step_s,
        };
        let mut s = d.start_state([0.0; 2], [0.0; 2], [0.0; 2]).unwrap();
        example_3_coupled_dte(m, &d, &mut s, max_step_s)
    };
    let (full, full_mu) = (run(Condensation::None, 0.0), run(Condensation::None, 0.05));
    let (qs, qs_mu) = (run(Condensation::QuasiStatic, 0.0), run(Condensation::QuasiStatic, 0.05));
    let names = ["mean", "rms", "p-p"];
    for k in 0..3 {
        let (d_full, d_qs) = (full_mu[k] - full[k], qs_mu[k] - qs[k]);
        eprintln!(
            "DTE {}: full {:.4} → {:.4} µm ({:+.4}), condensed {:.4} → {:.4} µm ({:+.4})",
            names[k],
            full[k] * 1e6,
            full_mu[k] * 1e6,
            d_full * 1e6,
            qs[k] * 1e6,
            qs_mu[k] * 1e6,
            d_qs * 1e6
        );
    }
    for k in 0..3 {
        let (d_full, d_qs) = (full_mu[k] - full[k], qs_mu[k] - qs[k]);
        assert!(d_full.abs() > 1e-8, "friction moves the DTE's {} ({d_full:e} m)", names[k]);
        assert!((d_qs - d_full).abs() <= 0.05 * d_full.abs(), "friction's change of the DTE's {}", names[k]);
    }
}

/// The lumped FMU's mesh law from the PMOR-Hertz build's own statics (`--lumped-fmu`, issue 26:
/// no second reduction when both FMUs are built) is the law a lumped-only build tabulates from
/// its own reduction (evidence: the same statics by two routes, `ReducedPair` and the dynamic
/// build): equal to the last bit, force levels, deflections and tooth-pair counts.
#[test]
fn the_builds_lumped_mesh_law_is_the_one_a_separate_reduction_gives() {
    let f = fixture();
    let from_build = f.report.lumped_mesh_law.as_ref().expect("asked for by the fixture");
    let separate = f.lumped_law.as_ref().unwrap();
    assert_eq!(from_build, separate);
    let pairs_separate = &separate.pairs;
    assert!(pairs_separate.contains(&1) && pairs_separate.contains(&2));
}

/// Flank modifications in the dynamics (issue 27; evidence: the PMOR-Hertz statics of the same
/// relieved pair, reduced separately). The relief enters the dynamic contact's rigid gap as it
/// enters the statics': at 185 N·m (the relief's design load, where it flattens the STE) and at
/// 370 N·m (where the relieved zones carry load) the slow run reproduces the relieved STE over a
/// mesh cycle within the static limit's bounds. Measured: mean +0.12 %, p-p +0.07 % at 185 N·m;
/// −0.07 % and −0.33 % at 370 N·m.
#[test]
fn slow_run_of_the_relieved_pair_reproduces_its_static_transmission_error() {
    let f = relieved_fixture();
    static_limit_at("relieved spur", f, 0);
    static_limit_at("relieved spur", f, 1);
}

/// Conservation of energy with a flank modification (evidence: the first integral, as in
/// `undamped_pair_conserves_energy_over_ten_mesh_cycles`, point loads). The relief is a ramp of
/// the rigid gap along each flank: the contact's angle forces must carry its slope dδ/dρ
/// (`PairPlacement::conjugate_modification_slopes`), else the relief's ramp does work the
/// balance does not book. Bound as for the unmodified pair: 1e-3 of the vibration energy.
/// Measured: 1.1e-4 of it (1.2e-5 J); with the slope left out of the angle forces, 1.1e-1 (the
/// control, run by hand: this test then fails by a factor of 100).
#[test]
fn undamped_relieved_pair_conserves_energy_over_ten_mesh_cycles() {
    use gearfmu::dynamics::pmor::contact::Loading;
    let f = relieved_fixture();
    let run = undamped_energy_drift(&f.model, &f.place, 2.5e-7, Loading::Point, Integrator::Rk4, Condensation::None);
    eprintln!(
        "energy, relieved pair (point loads): total {:.4} J, peak vibration energy {:.3e} J, max drift {:.3e} J ({:.2e} of vibration); anchors {:?}",
        run.e0, run.vibration, run.deviation, run.deviation / run.vibration, run.anchors
    );
    assert!(run.anchors[1] >= 10);
    assert!(run.deviation < 1e-4 * run.e0.abs() && run.deviation < 1e-3 * run.vibration);
}

/// The shipped configuration's energy (issue 24; evidence: the first integral of the undamped
/// pair under balancing torques, E − τ·θ): the default integrator, the energy-conserving discrete
/// gradient, at its default step (velocity Verlet's, 18.9 µs here) with the default Hertz band,
/// run as the FMU runs it (`advance`), over ten pitches of gear 2 with tooth pairs entering and
/// leaving: the largest |E − E₀| ≤ 1e-3 of the peak vibration energy. Velocity Verlet at the
/// same step, beside it, loses 2e-2 (its shadow energy jumps at each contact event): the test
/// would fail on it. Measured: 1.0e-5 (DG) against 2.3e-2 (Verlet).
#[test]
fn the_shipped_discrete_gradient_keeps_the_undamped_energy_within_1e_3_of_the_vibration_energy() {
    use gearfmu::dynamics::pmor::contact::Loading;
    let f = fixture();
    let m = &f.model;
    let (_, h) = verlet_at_its_default_step(f, Condensation::QuasiStatic);
    let shipped = undamped_energy_drift(
        m,
        &f.place,
        h,
        Loading::HertzBand,
        Integrator::DiscreteGradient,
        Condensation::QuasiStatic,
    );
    let verlet =
        undamped_energy_drift(m, &f.place, h, Loading::HertzBand, Integrator::Verlet, Condensation::QuasiStatic);
    eprintln!(
        "undamped energy at {:.2} µs, Hertz band, ten pitches ({} contact changes): discrete gradient max |E − E₀| {:.3e} J = {:.2e} of the peak vibration energy (trend {:.2e}); velocity Verlet {:.3e} J = {:.2e} (trend {:.2e})",
        h * 1e6,
        shipped.contact_changes,
        shipped.deviation,
        shipped.deviation / shipped.vibration,
        shipped.trend / shipped.vibration,
        verlet.deviation,
        verlet.deviation / verlet.vibration,
        verlet.trend / verlet.vibration
    );
    assert!(shipped.anchors[1] >= 10, "ten pitches");
    assert!(shipped.contact_changes >= 10, "tooth pairs enter and leave");
    assert!(shipped.deviation <= 1e-3 * shipped.vibration, "the issue's bound");
    assert!(verlet.deviation > 5.0 * shipped.deviation, "the test tells the integrators apart");
}

/// The discrete gradient's energy balance with damping and a net torque (evidence: E + D − W =
/// E₀ with D and W the step's own work integrals, and D ≥ 0 step by step): the default damping
/// and mesh damper (ζ 0.05), gear 1 driven at 200 N·m against 80 % of the balancing torque, off
/// equilibrium by 6 µm, three mesh cycles at the default step, as the FMU runs it.
#[test]
fn the_discrete_gradient_books_damping_and_input_work_in_the_energy_balance() {
    let f = fixture();
    let m = &f.model;
    let (base, h) = verlet_at_its_default_step(f, Condensation::QuasiStatic);
    let (gain, _) = linear::mesh_damper_gain(&base).unwrap();
    let mut dynamics = base.with_mesh_damper(gain);
    dynamics.integrator = Integrator::DiscreteGradient;
    let rb = base_radii(m);
    let torques = [200.0, -0.8 * 200.0 * rb[1] / rb[0]];
    let pitch2 = 2.0 * PI / m.pair.gear2.teeth as f64;
    let mut s = dynamics.start_state([6e-6 / rb[0], 0.0], [100.0 * rb[1] / rb[0], 100.0], torques).unwrap();
    let e0 = dynamics.outputs(&s).unwrap().total_energy_j();
    let (mut worst, mut vib, mut dissipated): (f64, f64, f64) = (0.0, 0.0, 0.0);
    while s.theta[1] < 3.0 * pitch2 {
        dynamics.advance(&mut s, torques, 5.0 * h, h * (1.0 + 1e-9)).unwrap();
        assert!(s.dissipated_j >= dissipated - 1e-12 * e0, "dissipation is never negative");
        dissipated = s.dissipated_j;
        let o = dynamics.outputs(&s).unwrap();
        worst = worst.max((o.total_energy_j() + s.dissipated_j - s.input_work_j - e0).abs());
        vib = vib.max(o.elastic_j + o.contact_j);
    }
    eprintln!(
        "discrete gradient balance (damped, driven) at {:.2} µs: max |E + D − W − E₀| {worst:.3e} J ({:.2e} of the peak vibration energy); dissipated {dissipated:.3e} J",
        h * 1e6,
        worst / vib
    );
    assert!(dissipated > 0.0);
    assert!(worst <= 1e-3 * vib, "the balance closes to the iteration's tolerance");
}

/// Tooth friction in the discrete gradient (issue 42; evidence: E + D − W = E₀, a conservation
/// law, with D the step's booked dissipation, friction's included, and friction's own tally
/// D_f = ∫Σf·v dt never decreasing): μ = 0.05, no mesh damper (the bodies' modal damping only),
/// v_ε as the FMU sets it at this step, gear 1 driven at 200 N·m against 80 % of the balancing
/// torque from 100 rad/s, three mesh cycles. Friction acts on the bore angles and the teeth's
/// elastic coordinates (the fast ones through their equilibrium): the pair loses μ·H_V-scale
/// power, D_f is most of D, and the balance closes as without friction.
#[test]
fn the_discrete_gradient_books_tooth_friction_in_the_energy_balance() {
    use gearfmu::dynamics::mesh_friction::{regularization_for_pair_m_per_s, SlidingFriction};
    let f = fixture();
    let m = &f.model;
    let (mut dynamics, h) = verlet_at_its_default_step(f, Condensation::QuasiStatic);
    dynamics.integrator = Integrator::DiscreteGradient;
    let p = &m.pair;
    let inertia = [m.gears[0].polar_inertia_kgm2, m.gears[1].polar_inertia_kgm2];
    let eps = regularization_for_pair_m_per_s(p, 0.05, inertia, h, 1.0);
    dynamics.friction = Some(SlidingFriction { coefficient: 0.05, regularization_m_per_s: eps });
    let rb = base_radii(m);
    let torques = [200.0, -0.8 * 200.0 * rb[1] / rb[0]];
    let pitch2 = 2.0 * PI / m.pair.gear2.teeth as f64;
    let mut s = dynamics.start_state([6e-6 / rb[0], 0.0], [100.0 * rb[1] / rb[0], 100.0], torques).unwrap();
    let e0 = dynamics.outputs(&s).unwrap().total_energy_j();
    let (mut worst, mut vib, mut friction): (f64, f64, f64) = (0.0, 0.0, 0.0);
    let mut powers = Vec::new();
    while s.theta[1] < 3.0 * pitch2 {
        dynamics.advance(&mut s, torques, 5.0 * h, h * (1.0 + 1e-9)).unwrap();
        assert!(s.friction_dissipated_j >= friction, "friction's dissipation never decreases");
        friction = s.friction_dissipated_j;
        let o = dynamics.outputs(&s).unwrap();
        powers.push(o.contact.friction_power_w);
        worst = worst.max((o.total_energy_j() + s.dissipated_j - s.input_work_j - e0).abs());
        vib = vib.max(o.elastic_j + o.contact_j);
    }
    eprintln!(
        "discrete gradient with friction (μ 0.05, v_ε {eps:.3e} m/s) at {:.2} µs: max |E + D − W − E₀| {worst:.3e} J \
         ({:.2e} of the peak vibration energy); dissipated {:.3e} J, of it friction {friction:.3e} J; friction power \
         {:.1} … {:.1} W",
        h * 1e6,
        worst / vib,
        s.dissipated_j,
        powers.iter().cloned().fold(f64::INFINITY, f64::min),
        powers.iter().cloned().fold(0.0, f64::max)
    );
    assert!(friction > 0.0 && friction <= s.dissipated_j * (1.0 + 1e-6), "friction is part of the booked dissipation");
    assert!(friction > 0.5 * s.dissipated_j, "without a mesh damper friction is most of it");
    assert!(worst <= 1e-3 * vib, "the balance closes to the iteration's tolerance");
}

/// Tooth friction's direction on the flanks (issue 42), against closed forms. (1) Each flank
/// node's transverse tangent (`FlankGrid::transverse_tangent`) is a unit vector in the flank's
/// tangent plane, and a turn of the gear moves the node along it by the involute's radius of
/// curvature √(r² − r_b²) per radian. (2) Friction's rows on the elastic coordinates see a turn of
/// the rim as the floating frame's turn: the fixed-interface modes' share of the rigid rotation
/// field, Φ·c with c = M_ΦΦ⁻¹·b (b = (Gx)ᵀMΦ, the field's mass-weighted projection), moves each
/// loaded section's flank points as a turn of the gear does. So c's approach (the normal rows) is
/// the approach slope ∂α/∂θ times the share of the turn the modes carry there, and c's sliding
/// (the tangent rows, with their orientation and sign) is the rigid arm (u on gear 1,
/// −(T₁T₂ − u) on gear 2, `mesh_friction`'s closed form) times the same share — to within what
/// the modes' fit of the turn leaves: the share along the normal varies by 5 % between sections,
/// so the sliding is asked within 3 % of the base radius (the approach slope's size). A tangent
/// oriented the wrong way would miss by twice the arm over r_b, 0.2 or more on these pairs.
/// Contacts below the stored flank's lowest row (the helical pair's path starts 2 mm below it
/// on gear 1) take that row's band, whose arm is longer than the contact's: reported, not asked.
#[test]
fn friction_acts_along_the_flank_tangent_and_sees_a_turn_of_the_rim_as_the_rigid_arms() {
    use gearfmu::contact::mesh_kinematics::Flank;
    use gearfmu::dynamics::mesh_friction::SlidingFriction;
    for (name, f) in [("spur", fixture()), ("helical", helical_fixture())] {
        let m = &f.model;
        let rb = base_radii(m);
        // (1) The tangent at every node of both flanks of both gears.
        let mut arm_error = 0.0_f64;
        let mut arm_range = [[f64::INFINITY, 0.0_f64]; 2];
        for i in 0..2 {
            for flank in [Flank::Drive, Flank::Coast] {
                let grid = &m.gears[i].flank(flank).grid;
                for k in 0..grid.len() {
                    let t = grid.transverse_tangent(k);
                    let n = grid.nodes[k].1;
                    let [x, y] = grid.node_xy[k];
                    assert!((t[0].hypot(t[1]) - 1.0).abs() < 1e-12 && t[2] == 0.0);
                    assert!((t[0] * n[0] + t[1] * n[1]).abs() < 1e-12, "in the tangent plane");
                    // A turn moves the node by e_z × x per radian.
                    let arm = -y * t[0] + x * t[1];
                    let involute = (x * x + y * y - rb[i] * rb[i]).sqrt();
                    arm_error = arm_error.max((arm.abs() - involute).abs() / involute);
                    arm_range[i] = [arm_range[i][0].min(arm.abs()), arm_range[i][1].max(arm.abs())];
                }
            }
        }
        assert!(arm_error < 1e-6, "{name}: a node's arm along the tangent is the involute's ρ ({arm_error:e})");
        // (2) The rows of loaded sections at eight positions over a pitch.
        let mut d = PmorDynamics::new(m, &f.place, m.damping(m.modal_damping_ratio, m.shape_damping_ratio), [0.0; 2]);
        d.set_condensation(Condensation::QuasiStatic);
        d.friction = Some(SlidingFriction { coefficient: 0.05, regularization_m_per_s: 1e-3 });
        let torque = m.info.rom_torques_nm[0];
        let loa = m.pair.loa_length_m();
        let (mut checked, mut worst, mut worst_below) = ([0; 2], 0.0_f64, 0.0_f64);
        let mut share_range = [f64::INFINITY, 0.0_f64];
        // The drive flanks, and the coast flanks (the torque reversed, gear 1 turned back across
        // the backlash): there the tangent's orientation and the rows' sign both turn.
        for (flank, sign) in [(0, 1.0), (1, -1.0)] {
            for k in 0..8 {
                let theta2 = (k as f64 + 0.5) / 8.0 * 2.0 * PI / m.pair.gear2.teeth as f64;
                // Gear 1 pressed 20 µm into the flanks along the line of action.
                let along = if flank == 0 { 20e-6 } else { -m.pair.backlash_loa_m - 20e-6 };
                let t = [sign * torque, -sign * torque * rb[1] / rb[0]];
                let s = d.start_state([(along + theta2 * rb[1]) / rb[0], theta2], [0.0; 2], t).unwrap();
                // The condensed right-hand side solves the fast coordinates and keeps the rows.
                let (_, out) = d.rhs(&d.pack(&s), s.anchor, s.torques_nm).unwrap();
                for section in &out.contact.sections {
                    assert_eq!(section.flank_sign, sign, "the flanks pressed are the ones asked for");
                    for i in 0..2 {
                        let g = &m.gears[i];
                        let n_k = g.modes();
                        let c = g.phi_phi.clone().cholesky().unwrap().solve(&g.gx_phi);
                        let on_c = |row: &[f64]| row[1..1 + n_k].iter().zip(c.iter()).map(|(r, c)| r * c).sum::<f64>();
                        let normal_share = on_c(&section.rows[i]) / section.rows[i][0];
                        let arm = if i == 0 { section.point_m } else { -(loa - section.point_m) };
                        // The sliding the turn makes against the rigid arm's at the normal's share,
                        // over the approach slope (≈ r_b): near a gear's root the arm is short.
                        let miss = ((on_c(&section.sliding_rows[i]) - normal_share * arm) / section.rows[i][0]).abs();
                        if arm.abs() < arm_range[i][0] {
                            worst_below = worst_below.max(miss);
                            continue;
                        }
                        worst = worst.max(miss);
                        share_range = [share_range[0].min(normal_share), share_range[1].max(normal_share)];
                        checked[flank] += 1;
                    }
                }
            }
        }
        eprintln!(
            "{name}: node arms within {arm_error:.1e} of the involute's; {checked:?} section rows (drive, coast), the modes carry \
             {:.4} … {:.4} of a turn along the normal, the sliding within {worst:.4} r_b of the rigid arm's at \
             that share ({worst_below:.4} below the flank's lowest row)",
            share_range[0], share_range[1]
        );
        assert!(checked.iter().all(|&c| c >= 16));
        assert!(share_range[0] > 0.8, "the fixed-interface modes carry the rim's turn at the flanks");
        assert!(worst < 0.03, "the tangent rows see the turn as the rigid arms do");
    }
}

/// Issue 38, at the mesh resonance: the Kurokawa spur pair at a 2.9 kHz mesh frequency (gear 2 at
/// 588 rad/s), a constant T₁ = 185 N·m against a viscous brake fed back from w₂ once per 20 µs
/// call, as a master runs it, over 30 mesh cycles with contact loss. Before the speed bound the
/// default step (one 20 µs step per call) turned gear 2 by 0.0118 rad, past the stored samples'
/// one-interval reach beyond its pitch (Δϑ = 0.0101 rad), and the call failed in the first
/// cycles. Evidence: the step bound's closed form Δϑ/(2|ω|), the mean speed the brake balances
/// (closed form: c·ω₂* = T₁·z₂/z₁), and the energy balance E + D − W = E₀ (a conservation law) at
/// speed, through contact loss and the re-engagements, on the driven and damped pair.
#[test]
fn at_the_mesh_resonance_the_default_pair_steps_with_the_speed_and_keeps_its_energy_balance() {
    let f = fixture();
    let m = &f.model;
    let inertia = [m.gears[0].polar_inertia_kgm2, m.gears[1].polar_inertia_kgm2];
    let mut d = PmorDynamics::new(m, &f.place, m.damping(m.modal_damping_ratio, m.shape_damping_ratio), [0.0; 2]);
    d.mesh_damping_n_s_per_m = m.mesh_damper_n_s_per_m(0.05, inertia);
    let z = [m.gears[0].teeth as f64, m.gears[1].teeth as f64];
    let mesh_hz = 2900.0;
    let w2 = 2.0 * PI * mesh_hz / z[1];
    let w1 = w2 * z[1] / z[0];
    let torque = 185.0;
    let c = torque * z[1] / (z[0] * w2);
    let mut s = d.start_state([0.0; 2], [w1, w2], [torque, -c * w2]).unwrap();
    let bound = d.angular_step_bound_s(&s);
    let closed_form = (0..2).map(|i| m.gears[i].sample_step_rad() / (2.0 * s.omega[i].abs())).fold(f64::MAX, f64::min);
    assert!((bound / closed_form - 1.0).abs() < 1e-12, "{bound:e} against {closed_form:e}");
    assert!(bound < 1e-5, "the bound {bound:e} s must be below the 20 µs default at this speed");
    let e0 = d.outputs(&s).unwrap().total_energy_j();
    let (comm, cycles) = (2e-5, 30.0);
    let calls = (cycles / mesh_hz / comm).round() as usize;
    let (mut w2_tail, mut lost, mut n_tail, mut peak_stored) = (0.0, 0, 0, 0.0f64);
    for k in 0..calls {
        let port_w2 = d.port(1, &s).unwrap().1;
        d.advance(&mut s, [torque, -c * port_w2], comm, 2e-5).unwrap_or_else(|e| panic!("call {k}: {e}"));
        let out = d.outputs(&s).unwrap();
        lost += (out.contact.pairs_in_contact == 0) as usize;
        peak_stored = peak_stored.max(out.elastic_j + out.contact_j);
        if k >= calls / 2 {
            w2_tail += d.port(1, &s).unwrap().1;
            n_tail += 1;
        }
    }
    let out = d.outputs(&s).unwrap();
    let balance = out.total_energy_j() + s.dissipated_j - s.input_work_j - e0;
    let w2_mean = w2_tail / n_tail as f64;
    eprintln!(
        "2.9 kHz: bound {:.2} µs, {lost} of {calls} calls end with no contact, mean ω₂ {:+.2e} of its target, balance {:.2e} of the peak elastic energy ({:.3e} J), dissipated {:.3e} J",
        bound * 1e6,
        w2_mean / w2 - 1.0,
        balance / peak_stored,
        peak_stored,
        s.dissipated_j
    );
    assert!(lost > 0, "the resonance must lose contact here (else the test does not cover re-engagement)");
    assert!((w2_mean / w2 - 1.0).abs() < 0.01, "mean ω₂ {w2_mean} against {w2}");
    // The discrete gradient closes each step's balance to 1e-7 of the elastic energy (its
    // Newton tolerance): over the run's 1500 steps the sum stays far below 1e-3 of it.
    assert!(balance.abs() < 1e-3 * peak_stored, "energy balance {balance:e} J against {peak_stored:e} J stored");
}

/// The build cache (evidence: the build itself, run again). An entry read back is the model and
/// report the build made, bit for bit; another option is another entry; an entry that does not
/// read back (cut short, or zeroed past its digest) is built again and replaced, never taken.
#[test]
fn the_build_cache_returns_what_the_build_makes() {
    let dir = std::env::temp_dir().join(format!("gearfmu-build-cache-test-{}", std::process::id()));
    let cache = BuildCache::new(&dir);
    let pair = common::kurokawa_spur();
    let mesh = MeshSpec::default();
    // A small basis: the cache stores whatever the build makes; its size does not matter here.
    // No memory limit: the schedule (and so the report's bytes) may not follow MemAvailable
    // between the builds compared below.
    let options =
        DynamicBuildOptions { modes: 6, angles: 8, memory_limit_bytes: Some(f64::INFINITY), ..Default::default() };
    let heard = std::sync::Mutex::new(Vec::<String>::new());
    let listen = |m: String| heard.lock().unwrap().push(m);
    let reused = |heard: &std::sync::Mutex<Vec<String>>| heard.lock().unwrap().iter().any(|m| m.starts_with("reused"));

    // An entry of other code (another digest) and a file that is no entry.
    std::fs::create_dir_all(&dir).unwrap();
    let stale = dir.join("pmor-0000000000000000-0123.postcard");
    let other_file = dir.join("notes.txt");
    std::fs::write(&stale, b"a model of other code").unwrap();
    std::fs::write(&other_file, b"kept").unwrap();

    let built = cache.build_dynamic_model(&pair, &mesh, &options, listen).unwrap();
    assert!(!reused(&heard), "an empty cache cannot reuse");
    let entry = cache.entry(&pair, &mesh, &options);
    assert!(entry.is_file(), "the build stores its entry");
    assert!(!stale.exists(), "storing removes the entries of other code");
    assert!(other_file.exists(), "and nothing else");
    let read_back = cache.build_dynamic_model(&pair, &mesh, &options, listen).unwrap();
    assert!(reused(&heard), "the second build of the same model reads the entry");
    assert_eq!(read_back.0, built.0, "the model read back is the one built");
    assert_eq!(format!("{:?}", read_back.1), format!("{:?}", built.1), "the report read back is the one built");

    // The memory limit is no part of the key (it decides the schedule only); any input is: the
    // angular samples, the mesh, the pair by one ulp.
    assert_eq!(cache.entry(&pair, &mesh, &DynamicBuildOptions { memory_limit_bytes: None, ..options.clone() }), entry);
    let other = DynamicBuildOptions { angles: 10, ..options.clone() };
    assert_ne!(cache.entry(&pair, &mesh, &other), entry);
    let finer = MeshSpec { elements_in_rim: mesh.elements_in_rim + 1, ..mesh };
    assert_ne!(cache.entry(&pair, &finer, &options), entry);
    let mut wider = pair.clone();
    wider.face_width_m = f64::from_bits(pair.face_width_m.to_bits() + 1); // one ulp wider
    assert_ne!(cache.entry(&wider, &mesh, &options), entry);

    // An entry cut short, or of the right length but zeroed past its digest (a crash's leftover),
    // is built again (the same model) and replaced by a whole one.
    let whole = std::fs::read(&entry).unwrap();
    let mut zeroed = whole.clone();
    zeroed[32..].fill(0);
    for damaged in [whole[..whole.len() / 2].to_vec(), zeroed] {
        std::fs::write(&entry, &damaged).unwrap();
        heard.lock().unwrap().clear();
        let rebuilt = cache.build_dynamic_model(&pair, &mesh, &options, listen).unwrap();
        assert!(!reused(&heard), "a damaged entry is not taken");
        assert_eq!(rebuilt.0, built.0);
        assert_eq!(std::fs::read(&entry).unwrap(), whole, "the damaged entry is replaced by the whole one");
    }
    std::fs::remove_dir_all(&dir).ok();
}
