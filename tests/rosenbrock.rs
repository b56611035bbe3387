//! The linearly implicit engine (ROS34PW2): it agrees with the explicit
//! engine, converges under a tighter tolerance, and keeps its step count when
//! the isolators' stiff directions are made a hundred times stiffer, where
//! the explicit engine's step count explodes.

use fistage_model::{Loaded, assemble};
use fistage_sim::RunOutput;
use fistage_tests::{load, run_with as with, stats};

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn agrees_with_the_explicit_engine_and_converges() {
    let loaded = load("scenarios/paper/fig05b_fi.toml");
    let reference = with(&loaded, "native", 1e-10);
    let target = stats(&reference, "encoder.position");
    let mut differences = Vec::new();
    for rtol in [1e-5, 1e-7] {
        let run = with(&loaded, "rosenbrock", rtol);
        let s = stats(&run, "encoder.position");
        let difference =
            relative(s.peak_to_peak, target.peak_to_peak).max(relative(s.mean, target.mean));
        println!("rosenbrock rtol {rtol:e}: statistics differ by {difference:.2e}");
        differences.push(difference);
    }
    assert!(differences[1] < 1e-4, "{differences:?}");
    assert!(differences[1] < differences[0], "{differences:?}");
}

#[test]
fn stiff_isolators_leave_its_step_count_alone() {
    let base = load("scenarios/coupling/friction20_traverse.toml");
    let mut robot = base.robot.clone();
    for isolator in &mut robot.isolators {
        for k in &mut isolator.stiffness[1..] {
            *k *= 100.0;
        }
    }
    let (robot, model) = assemble(robot, &base.scenario).expect("stiff model");
    let stiff = Loaded {
        scenario: base.scenario.clone(),
        robot,
        model,
    };
    let explicit_soft = with(&base, "native", 1e-6);
    let implicit_soft = with(&base, "rosenbrock", 1e-6);
    let explicit = with(&stiff, "native", 1e-6);
    let implicit = with(&stiff, "rosenbrock", 1e-6);
    let steps = |run: &RunOutput| run.trajectory.stats.counts.steps as f64;
    println!(
        "steps: native {} -> {}, rosenbrock {} -> {}",
        steps(&explicit_soft),
        steps(&explicit),
        steps(&implicit_soft),
        steps(&implicit)
    );
    assert!(steps(&explicit) > 5.0 * steps(&explicit_soft));
    assert!(steps(&implicit) < 1.1 * steps(&implicit_soft));
    assert!(steps(&implicit) < steps(&explicit) / 4.0);
    for signal in ["controller.error", "table.yaw"] {
        let (a, b) = (stats(&implicit, signal), stats(&explicit, signal));
        println!(
            "{signal}: p2p {:.5e} vs {:.5e}, mean {:.5e} vs {:.5e}",
            a.peak_to_peak, b.peak_to_peak, a.mean, b.mean
        );
        assert!(
            relative(a.peak_to_peak, b.peak_to_peak) < 5e-3,
            "{signal} p2p"
        );
        assert!(relative(a.mean, b.mean) < 1e-4, "{signal} mean");
    }
}
