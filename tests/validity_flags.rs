//! Results outside the model's validity are errors, never silent numbers (issue 12, item 4).
//! Each test names the rule and checks that the message does too.

use gearfmu::contact::hertz::{ApproachLaw, MAX_HALF_WIDTH_OVER_DEPTH};
use gearfmu::gear::{GearPair, PairSpec};
use gearfmu::rom::sweep::{Method, ReducedPair};

/// Rule: the Hertz half-width must stay below h/4 (`MAX_HALF_WIDTH_OVER_DEPTH`). 100 × Table 4's
/// heaviest torque (37 kN·m on the spur pair) used to return an STE of 2.33 mm without a word; the
/// paper's own heaviest load (370 N·m) still solves.
#[test]
fn hundred_times_the_table_4_torque_is_refused_by_the_half_width_rule() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
    let spec = PairSpec::load(&path).unwrap();
    let pair = GearPair::from_spec(&spec).unwrap();
    let method = Method::PmorHertz { depth_m: 3e-3, p_en: gearfmu::rom::svd::DEFAULT_P_EN, law: ApproachLaw::Weber };
    let reduced = ReducedPair::build(&pair, &spec.mesh, method, |_, _| {}).unwrap();
    let cases = reduced.sweep(&[370.251, 37025.1], 3, 1.0);
    for case in &cases[..3] {
        let case = case.as_ref().expect("the paper's heaviest load is inside the law's range");
        for e in &case.elements {
            assert!(e.half_width_m <= MAX_HALF_WIDTH_OVER_DEPTH * 3e-3);
        }
    }
    for case in &cases[3..] {
        let message = case.as_ref().expect_err("100 × the torque must be refused");
        eprintln!("{message}");
        assert!(
            message.contains("half-width") && message.contains("0.25") && message.contains("3.000 mm"),
            "{message}"
        );
    }
}
