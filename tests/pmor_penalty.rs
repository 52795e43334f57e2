//! The standard PMOR reference model (`FlankContact::Penalty`, `--model pmor-penalty`; paper
//! Sects. 4.1 and 5.2): the floating-frame pair with contact shapes from the standard CMS
//! statics and node-to-surface penalty contact. Evidence: the penalty baseline statics on the
//! same mesh, reduced separately (its static equilibria must reproduce them), and conservation
//! of energy (its contact forces must derive from the penalty potential). Coarse mesh (4/8/4),
//! where the penalty law is far from converged: what is tested is that the dynamic model is the
//! same model as its statics, not the method's accuracy (BENCHMARKS §11 compares it with
//! PMOR-Hertz on a mesh where its statics converge).

use gearfmu::contact::mesh_kinematics::PairPlacement;
use gearfmu::dynamics::pmor::integrator::Integrator;
use gearfmu::dynamics::pmor::model::{FlankContact, PmorModel};
use gearfmu::dynamics::pmor::quasi_static::Condensation;
use gearfmu::dynamics::pmor::{linear, PmorDynamics, PmorState};
use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::rom::dynamic_reductor::{build_dynamic_model, DynamicBuildOptions};
use gearfmu::rom::statics::DEFAULT_PENALTY_FACTOR;
use gearfmu::rom::sweep::{Method, ReducedPair};
use std::f64::consts::PI;
use std::sync::OnceLock;

struct Fixture {
    pair: GearPair,
    model: PmorModel,
    place: PairPlacement,
}

const ROM_TORQUE_NM: f64 = 250.0;

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
        let pair = GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap();
        let options = DynamicBuildOptions {
            rom_torques_nm: vec![ROM_TORQUE_NM],
            contact: FlankContact::Penalty { factor: DEFAULT_PENALTY_FACTOR },
            integrator: Integrator::Rk4,
            condensation: Condensation::None,
            ..Default::default()
        };
        let (model, _) = build_dynamic_model(&pair, &MeshSpec::default(), &options, |_| {}).unwrap();
        let place = PairPlacement::new(&pair);
        Fixture { pair, model, place }
    })
}

fn rb(m: &PmorModel) -> [f64; 2] {
    [m.gears[0].base_radius_m, m.gears[1].base_radius_m]
}

fn te(m: &PmorModel, s: &PmorState) -> f64 {
    let r = rb(m);
    r[0] * s.theta[0] - r[1] * s.theta[1]
}

/// Evidence: the penalty baseline statics (`rom::statics`, node-to-surface on standard CMS
/// gears), reduced separately on the same mesh. At the shapes' own samples and torque the
/// static shape lies in the basis, so the dynamic model's equilibrium is the statics' own
/// solution, but for gear 1: its shapes were made at its own sample angle plus the static TE
/// over r_b1 (about 1 % of a sample interval), so at gear 2's sample gear 1's shape is
/// interpolated that far off its sample — and the penalty's shapes, local indentations under
/// the nodes that carry load, change fast between samples: 0.5 % of the STE. Between the samples the
/// basis interpolates the shapes, and the equilibrium is a Galerkin approximation of the
/// statics: within 3 % there on this coarse flank (10 % of the penalty's own peak-to-peak).
#[test]
fn static_equilibria_reproduce_the_penalty_statics() {
    let f = fixture();
    let m = &f.model;
    let reference = ReducedPair::build(
        &f.pair,
        &MeshSpec::default(),
        Method::Penalty { factor: DEFAULT_PENALTY_FACTOR },
        |_, _| {},
    )
    .unwrap();
    let statics = reference.static_model().unwrap();
    let dynamics = PmorDynamics::new(m, &f.place, m.damping(0.0, 0.0), [0.0; 2]);
    let pitch2 = 2.0 * PI / f.pair.gear2.teeth as f64;
    let n = m.gears[1].samples;
    let (mut at_samples, mut between) = (0.0_f64, 0.0_f64);
    for k in 0..n {
        for offset in [0.0, 0.5] {
            let theta2 = (k as f64 + offset) / n as f64 * pitch2;
            let ste = statics.solve(theta2, ROM_TORQUE_NM).unwrap().ste_m;
            let (s, _) = linear::static_equilibrium(&dynamics, theta2, ROM_TORQUE_NM, ste).unwrap();
            let error = (te(m, &s) - ste).abs() / ste;
            if offset == 0.0 {
                at_samples = at_samples.max(error);
            } else {
                between = between.max(error);
            }
        }
    }
    eprintln!("standard PMOR equilibria against the penalty statics: worst {at_samples:.2e} at the samples, {between:.2e} between");
    assert!(at_samples < 5e-3, "at the samples: {at_samples:.2e}");
    assert!(between < 3e-2, "between the samples: {between:.2e}");
}

/// Conservation of energy: undamped (no modal damping, no mesh damper), rolling at 50 rad/s on
/// gear 2 under balanced torques, off equilibrium by 6 µm, across one mesh cycle: the teeth
/// rattle on the stiff penalty (impacts, nodes entering and leaving contact, every shape
/// sample). E = T + U + ½Σkα² − Σ τθ must converge to conservation as RK4 converges: halving the
/// step from a fifth of the linearized limit cuts the drift by ≥ 8 (RK4's h⁴ gives 16 where the
/// flow is smooth; the contact onsets, where ½kα² is only C¹, converge slower), and at a tenth
/// the drift stays below 1 % of the vibration energy. The angle forces are central differences
/// of α at fixed η, so this also checks that they are the potential's gradient: a force that
/// is not would leave a drift that does not converge with the step.
#[test]
fn undamped_standard_pmor_conserves_energy_as_rk4_converges() {
    let f = fixture();
    let m = &f.model;
    let r = rb(m);
    let torques = [ROM_TORQUE_NM, -ROM_TORQUE_NM * r[1] / r[0]];
    let dynamics = PmorDynamics::new(m, &f.place, m.damping(0.0, 0.0), [0.0; 2]);
    let pitch2 = 2.0 * PI / f.pair.gear2.teeth as f64;
    let (rest, _) = linear::static_equilibrium(&dynamics, 0.0, ROM_TORQUE_NM, 20e-6).unwrap();
    let energy = |s: &PmorState| {
        let o = dynamics.outputs(s).unwrap();
        (o.total_energy_j() - torques[0] * s.theta[0] - torques[1] * s.theta[1], o.elastic_j + o.contact_j)
    };
    let drift_at = |h: f64| {
        let w2 = 50.0;
        let mut s = m.initial_state([rest.theta[0] + 6e-6 / r[0], 0.0], [w2 * r[1] / r[0], w2]);
        s.eta = rest.eta.clone();
        let (e0, _) = energy(&s);
        let (mut drift, mut vibration): (f64, f64) = (0.0, 0.0);
        let mut steps = 0;
        while s.theta[1] < pitch2 {
            dynamics.rk4_step(&mut s, torques, h).unwrap();
            steps += 1;
            if steps % 10 == 0 {
                let (e, v) = energy(&s);
                drift = drift.max((e - e0).abs());
                vibration = vibration.max(v);
            }
        }
        eprintln!(
            "standard PMOR, undamped, one mesh cycle at {:.3} µs ({steps} steps): energy drift {drift:.3e} J, {:.2e} of the peak elastic + contact energy {vibration:.3e} J",
            h * 1e6,
            drift / vibration
        );
        (drift, vibration)
    };
    let (coarse, _) = drift_at(0.2 * m.stability_limit_s);
    let (fine, vibration) = drift_at(0.1 * m.stability_limit_s);
    assert!(fine < coarse / 8.0, "halving the step: drift {coarse:.3e} → {fine:.3e} J");
    assert!(fine < 1e-2 * vibration);
}

/// The reference model carries the drive flanks only: a torque that loads the coast flanks is
/// an error that says so, not a pair that falls through its backlash.
#[test]
fn coast_flank_contact_is_refused_with_the_reason() {
    let f = fixture();
    let m = &f.model;
    let r = rb(m);
    let dynamics = PmorDynamics::new(m, &f.place, m.damping(0.01, 0.05), [0.0; 2]);
    let mut s = m.initial_state([-(f.pair.backlash_loa_m + 20e-6) / r[0], 0.0], [0.0; 2]);
    let result = (0..10).try_for_each(|_| dynamics.rk4_step(&mut s, [-200.0, 200.0 * r[1] / r[0]], 1e-7));
    let message = result.expect_err("a pair pressed onto its coast flanks must not step");
    assert!(message.contains("drive-flank contact only"), "{message}");
}
