//! Every example spec runs on its own defaults (issue 12, item 1): a newcomer's first command on
//! any example must not be an error. The statics with `fmu-build ste`'s defaults (PMOR-Hertz,
//! h = 3 mm, p_en = `rom::svd::DEFAULT_P_EN`, Weber) on the spec's own mesh, at the heaviest load of the paper's
//! Table 4 / Table 7, three positions over a pitch. Regression guard (what it checks is that the
//! spec's mesh carries its contact at the default depth, and that the answer is a number in the
//! range the committed results show).

use gearfmu::contact::hertz::ApproachLaw;
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::rom::sweep::{Method, ReducedPair};

fn run_on_defaults(file: &str, torque_nm: f64) -> f64 {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples").join(file);
    let spec = PairSpec::load(&path).unwrap();
    let pair = GearPair::from_spec(&spec).unwrap();
    let method = Method::PmorHertz { depth_m: 3e-3, p_en: gearfmu::rom::svd::DEFAULT_P_EN, law: ApproachLaw::Weber };
    let reduced = ReducedPair::build(&pair, &spec.mesh, method, |_, _| {})
        .unwrap_or_else(|e| panic!("{file} on its defaults: {e}"));
    let cases = reduced.sweep(&[torque_nm], 3, 1.0);
    let ste: Vec<f64> = cases.iter().map(|c| c.as_ref().unwrap().ste_m).collect();
    eprintln!("{file}: STE at {torque_nm} N·m: {:?} µm", ste.iter().map(|v| v * 1e6).collect::<Vec<_>>());
    ste.iter().sum::<f64>() / ste.len() as f64
}

#[test]
fn spur_example_runs_on_its_defaults() {
    let mean = run_on_defaults("kurokawa_spur.toml", 370.25);
    assert!(mean > 20e-6 && mean < 40e-6, "mean STE {mean}");
}

#[test]
fn helical_example_runs_on_its_defaults() {
    let mean = run_on_defaults("kurokawa_helical.toml", 917.7);
    assert!(mean > 20e-6 && mean < 40e-6, "mean STE {mean}");
}
