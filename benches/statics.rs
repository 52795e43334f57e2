//! Cost of a static contact case, PMOR-Hertz against the penalty baseline ("standard PMOR"), as
//! the flank is refined to the paper's 53 rows (`cargo bench --bench statics`; issue 12, item 3).
//!
//! One process, one thread (the sweep's rayon is not used): for 8, 16, 24 and 53 uniform rows
//! along the profile (4 across the tooth, 4 in the rim, 4 slices — the Kurokawa spur pair) both
//! reductions are built on the same mesh and solved at Table 4's 22 and 392 N/mm over a mesh
//! cycle, each by both solvers:
//! - `condensed` (the default: active set on the contact forces, a loaded-tooth-contact
//!   analysis), all positions;
//! - `dense` (Newton on every reduced coordinate, the solver the paper's ratio was measured with
//!   here before), on the first few positions only — at 53 rows it takes seconds per case.
//!
//! The ratio that means something is baseline-condensed over PMOR-Hertz-condensed: both solved as
//! well as we can. The mean and peak-to-peak STE per method are printed beside, so that a speed-up
//! is never read without the accuracy it buys.

use gearfmu::contact::hertz::ApproachLaw;
use gearfmu::fe::gear_mesh::{MeshSpec, ProfileGrading};
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::rom::statics::Solver;
use gearfmu::rom::sweep::{Method, ReducedPair};
use std::time::Instant;

const TORQUES_NM: [f64; 2] = [20.79, 370.251];
const ANGLES: usize = 41;

/// Mean seconds per case and (mean, peak-to-peak) STE in µm per torque.
fn time_cases(reduced: &ReducedPair, solver: Solver, angles: usize) -> (f64, Vec<(f64, f64)>) {
    let model = reduced.static_model().unwrap();
    let pitch = 2.0 * std::f64::consts::PI / reduced.pair.gear2.teeth as f64;
    let mut seconds = 0.0;
    let mut stats = Vec::new();
    for torque in TORQUES_NM {
        let mut ste = Vec::new();
        for k in 0..angles {
            let theta2 = pitch * (k as f64 + 0.5) / angles as f64;
            let start = Instant::now();
            let case = model.solve_with(theta2, torque, solver).unwrap();
            seconds += start.elapsed().as_secs_f64();
            ste.push(case.ste_m * 1e6);
        }
        let mean = ste.iter().sum::<f64>() / ste.len() as f64;
        let (lo, hi) = ste.iter().fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        stats.push((mean, hi - lo));
    }
    (seconds / (angles * TORQUES_NM.len()) as f64, stats)
}

fn main() {
    let spec = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
    let pair = GearPair::from_spec(&PairSpec::load(&spec).unwrap()).unwrap();
    let rows: Vec<usize> = std::env::var("STATICS_BENCH_ROWS")
        .map(|v| {
            v.split(',').map(|r| r.trim().parse().expect("STATICS_BENCH_ROWS: comma-separated row counts")).collect()
        })
        .unwrap_or_else(|_| vec![8, 16, 24, 53]);
    println!(
        "| rows | loadable nodes (gear 1 / 2) | PMOR-Hertz n_sv | build PMOR-Hertz / CMS (s) | \
         per case (ms): PMOR-Hertz condensed | PMOR-Hertz dense | penalty condensed | penalty dense | \
         baseline / PMOR-Hertz (condensed) | baseline dense / condensed | \
         PMOR-Hertz mean, p-p 22 / 392 N/mm (µm) | penalty mean, p-p 22 / 392 N/mm (µm) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for &n in &rows {
        let mesh =
            MeshSpec { elements_along_profile: n, profile_grading: ProfileGrading::Uniform, ..MeshSpec::default() };
        let hertz = Method::PmorHertz { depth_m: 3e-3, p_en: gearfmu::rom::svd::DEFAULT_P_EN, law: ApproachLaw::Weber };
        let start = Instant::now();
        let pmor = ReducedPair::build(&pair, &mesh, hertz, |_, _| {}).unwrap();
        let build_pmor = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let cms = ReducedPair::build(&pair, &mesh, Method::Penalty { factor: 100.0 }, |_, _| {}).unwrap();
        let build_cms = start.elapsed().as_secs_f64();
        // The dense solver on a few positions: its cost grows as (n₁ + n₂)³.
        let dense_angles = if n > 30 { 1 } else { 4 };
        let (pmor_condensed, pmor_ste) = time_cases(&pmor, Solver::Condensed, ANGLES);
        let (pmor_dense, _) = time_cases(&pmor, Solver::Dense, dense_angles);
        let (cms_condensed, cms_ste) = time_cases(&cms, Solver::Condensed, ANGLES);
        let (cms_dense, _) = time_cases(&cms, Solver::Dense, dense_angles);
        let nsv = pmor.compression.as_ref().map(|c| format!("{} / {}", c[0].n_sv, c[1].n_sv)).unwrap_or_default();
        let fmt = |s: &[(f64, f64)]| format!("{:.3}, {:.3} / {:.3}, {:.3}", s[0].0, s[0].1, s[1].0, s[1].1);
        println!(
            "| {n} | {} / {} | {nsv} | {build_pmor:.1} / {build_cms:.1} | {:.2} | {:.1} | {:.2} | {:.1} | {:.1} | {:.0} | {} | {} |",
            cms.gears[0].size(),
            cms.gears[1].size(),
            pmor_condensed * 1e3,
            pmor_dense * 1e3,
            cms_condensed * 1e3,
            cms_dense * 1e3,
            cms_condensed / pmor_condensed,
            cms_dense / cms_condensed,
            fmt(&pmor_ste),
            fmt(&cms_ste),
        );
    }
}
