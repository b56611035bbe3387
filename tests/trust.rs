//! Stability verdicts the numerics can back, and none they cannot: at very
//! stiff parameters (servo gains of 1e12, a bearing of 1e-9 kg) the
//! Jacobian's norm reaches 1e12 to 1e15, where a relative "neutral"
//! threshold used to hide the growing bearing mode and report "stable".

use fistage_analysis::{ModalAnalysis, Verdict, modal_analysis};
use fistage_model::{EquilibriumKind, Inputs, Scenario, assemble};
use fistage_tests::path;

/// The paper's FI stage at 20 mm/s with the servo or bearing changed.
fn analyse(controller: &str, overrides: &str, kind: EquilibriumKind) -> ModalAnalysis {
    let robot_file = path("robots/stage_1dof_fi.urdf");
    let text = format!(
        "robot = {:?}\nduration = 1.0\n[platform]\nvelocity = 0.02\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\n{controller}\n{overrides}",
        robot_file.display().to_string()
    );
    let scenario = Scenario::from_str(&text, &path("scenarios/stiff.toml")).expect("scenario");
    let robot = fistage_model::RobotSpec::from_file(&robot_file).expect("robot");
    let (_, model) = assemble(robot, &scenario).expect("model");
    let inputs = Inputs {
        platform_velocity: 0.02,
        ..Inputs::default()
    };
    modal_analysis(&model, &inputs, kind, &model.zero_state()).expect("equilibrium")
}

/// A verdict of "stable" never stands beside a growing mode in the table,
/// and every number of the analysis is finite.
fn assert_honest(analysis: &ModalAnalysis, case: &str) {
    assert!(analysis.max_real_part.is_finite(), "{case}");
    for mode in &analysis.modes {
        assert!(mode.real.is_finite() && mode.imag.is_finite(), "{case}");
        if analysis.verdict == Verdict::Stable {
            assert!(
                mode.real < 0.0 || mode.neutral,
                "{case}: stable beside a growing mode {} {:+}i",
                mode.real,
                mode.imag
            );
        }
    }
    assert_eq!(analysis.stable, analysis.verdict == Verdict::Stable);
    assert_eq!(
        analysis.undetermined_reason.is_some(),
        analysis.verdict == Verdict::Undetermined
    );
}

#[test]
fn stiff_servos_show_the_growing_bearing_mode() {
    // The shipped gains: the slipping equilibrium is stable (the stage is bistable).
    let shipped = analyse("k = 6e4\nc = 100.0", "", EquilibriumKind::Slipping);
    assert_honest(&shipped, "shipped");
    assert_eq!(shipped.verdict, Verdict::Stable);
    // A 1e12 N/m servo freezes the table; the bearing's own stick-slip mode
    // (Re +31.6 1/s, as in the free bearing) is what decides, and it grows.
    for controller in ["k = 1e12\nc = 100.0", "k = 1e12\nc = 1e9"] {
        let stiff = analyse(controller, "", EquilibriumKind::Slipping);
        assert_honest(&stiff, controller);
        assert_eq!(stiff.verdict, Verdict::Unstable, "{controller}");
        assert!(
            (stiff.max_real_part - 31.59).abs() < 0.1,
            "{controller}: {}",
            stiff.max_real_part
        );
    }
    let integral = analyse(
        "k = 6e4\nc = 100.0\nk_i = 1e12",
        "",
        EquilibriumKind::Slipping,
    );
    assert_honest(&integral, "k_i = 1e12");
}

#[test]
fn a_verdict_the_residuals_cannot_back_is_undetermined() {
    let tiny = "[overrides.bearing]\nmass = 1e-9\n";
    for kind in [EquilibriumKind::Sticking, EquilibriumKind::Slipping] {
        let analysis = analyse("k = 6e4\nc = 100.0", tiny, kind);
        assert_honest(&analysis, "bearing of 1e-9 kg");
        assert_ne!(analysis.verdict, Verdict::Stable, "{kind:?}");
    }
}

/// A native run whose step size collapses stops after one window of steps
/// with the reason, instead of burning its whole step budget first. (The
/// implicit-explicit engine, which solves the bristles exactly at each stage,
/// is not bounded by sigma0 and runs this model.)
#[test]
fn a_collapsing_step_size_fails_fast() {
    let robot_file = path("robots/stage_1dof_fi.urdf");
    let text = format!(
        "robot = {:?}\nduration = 5.0\n[solver]\nengine = \"native\"\n[platform]\nvelocity = 0.02\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 6e4\nc = 100.0\n[overrides.bearing_friction]\nsigma0 = 1e12\n",
        robot_file.display().to_string()
    );
    let scenario = Scenario::from_str(&text, &path("scenarios/stiff.toml")).expect("scenario");
    let robot = fistage_model::RobotSpec::from_file(&robot_file).expect("robot");
    let (robot, model) = assemble(robot, &scenario).expect("model");
    let loaded = fistage_model::Loaded {
        scenario,
        robot,
        model,
    };
    let error = fistage_sim::run_scenario(&loaded, &mut fistage_sim::no_progress)
        .expect_err("cannot succeed");
    let message = error.to_string();
    assert!(message.contains("step size collapsed"), "{message}");
}
