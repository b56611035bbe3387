//! Properties of the parameter table over arbitrary values: a write succeeds
//! exactly when the entry's rule admits the value, a successful write of an
//! absolute parameter reads back bit for bit, and a refused write changes
//! nothing.

use std::path::Path;
use std::sync::OnceLock;

use fistage_model::{Parameter, RobotSpec, Rule, Scenario};
use proptest::prelude::*;

/// The four-bearing stage: every kind of entry (gains, LuGre, isolators,
/// points, masses, alpha, beta, spreads).
fn study() -> &'static (Scenario, RobotSpec, Vec<Parameter>) {
    static STUDY: OnceLock<(Scenario, RobotSpec, Vec<Parameter>)> = OnceLock::new();
    STUDY.get_or_init(|| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let scenario =
            Scenario::from_file(&root.join("scenarios/coupling/friction20_traverse.toml"))
                .expect("scenario");
        let robot = RobotSpec::from_file(&scenario.robot).expect("robot");
        let all = Parameter::all(&scenario, &robot);
        (scenario, robot, all)
    })
}

fn interesting_value() -> impl Strategy<Value = f64> {
    prop_oneof![
        prop::num::f64::ANY,
        -2.0..2.0f64,
        Just(0.0),
        Just(-0.0),
        Just(f64::INFINITY),
        Just(f64::NAN),
        (1e-12..1e12f64),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn writes_follow_the_rules(pick in 0usize..10_000, value in interesting_value()) {
        let (scenario, robot, all) = study();
        let parameter = &all[pick % all.len()];
        let (mut s, mut r) = (scenario.clone(), robot.clone());
        let before = parameter.read(&s, &r);
        let result = parameter.write(&mut s, &mut r, value);
        prop_assert_eq!(result.is_ok(), parameter.rule().admits(value), "{} = {}", parameter, value);
        match result {
            Ok(()) if !parameter.is_relative() => {
                prop_assert_eq!(parameter.read(&s, &r).to_bits(), value.to_bits());
            }
            Ok(()) => {}
            Err(e) => {
                prop_assert!(e.to_string().contains(parameter.path()), "{}", e);
                prop_assert_eq!(parameter.read(&s, &r).to_bits(), before.to_bits());
            }
        }
        if parameter.rule() != Rule::Finite {
            prop_assert!(!parameter.rule().admits(f64::NAN));
        }
    }

    #[test]
    fn every_path_resolves_to_itself(pick in 0usize..10_000) {
        let (scenario, robot, all) = study();
        let parameter = &all[pick % all.len()];
        let again = Parameter::resolve(parameter.path(), scenario, robot).expect("resolves");
        prop_assert_eq!(&again, parameter);
        prop_assert_eq!(again.unit(), parameter.unit());
    }
}

/// A compensator's parameters may name the element it models:
/// `compensation.<element>.<key>` and `compensation.<element>.error.<key>`
/// reach what `compensation.<key>` and `compensation.error.<key>` reach; an
/// element it does not model names nothing.
#[test]
fn compensation_paths_may_name_the_modelled_element() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut scenario =
        Scenario::from_file(&root.join("scenarios/paper/fig03a_lugre_fi.toml")).expect("scenario");
    let mut robot = RobotSpec::from_file(&scenario.robot).expect("robot");
    for (named, plain, value) in [
        ("compensation.bearing_friction.f_c", "compensation.f_c", 6.0),
        (
            "compensation.bearing_friction.error.sigma0",
            "compensation.error.sigma0",
            0.3,
        ),
    ] {
        let named = Parameter::resolve(named, &scenario, &robot).expect("the element's path");
        let plain = Parameter::resolve(plain, &scenario, &robot).expect("the plain path");
        named
            .write(&mut scenario, &mut robot, value)
            .expect("admissible");
        assert_eq!(plain.read(&scenario, &robot), value, "{named}");
        assert_eq!(named.unit(), plain.unit());
    }
    let error = Parameter::resolve("compensation.table_friction.f_c", &scenario, &robot)
        .expect_err("names nothing");
    assert!(error.to_string().contains("table_friction"), "{error}");
}
