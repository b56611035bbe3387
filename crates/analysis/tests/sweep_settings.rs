//! Nonsense `[sweep]` settings are errors naming the key, found before a
//! point is computed or a grid allocated: a negative oscillation threshold,
//! an axis swept twice, an axis naming nothing, an axis through negative
//! gains, an empty axis, a spread on a stage with one contact, and a grid too
//! large to hold (10^12 points overflowed the point count before).

use std::path::{Path, PathBuf};

use fistage_analysis::sweep::SweepSpec;
use fistage_model::{RobotSpec, Scenario};

fn robot_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots/stage_1dof_fi.urdf")
}

/// The error of a fig05b-like study with this `[sweep]` table.
fn sweep_error(sweep: &str) -> String {
    let text = format!(
        "robot = {:?}\nduration = 0.5\n[platform]\nvelocity = 0.02\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 1e5\nc = 100\n{sweep}",
        robot_file().display().to_string()
    );
    let scenario = Scenario::from_str(&text, Path::new("sweep.toml")).expect("scenario");
    let robot = RobotSpec::from_file(&scenario.robot).expect("robot");
    match SweepSpec::from_scenario(&scenario) {
        Ok(spec) => spec
            .check_against(&scenario, &robot)
            .expect_err("a nonsense sweep is refused")
            .to_string(),
        Err(e) => e.to_string(),
    }
}

fn axis(parameter: &str, from: f64, to: f64, points: u64) -> String {
    format!(
        "[[sweep.axis]]\nparameter = \"{parameter}\"\nfrom = {from:?}\nto = {to:?}\npoints = {points}\n"
    )
}

#[test]
fn nonsense_sweep_settings_are_named() {
    let gain = axis("controller.k", 1e4, 1e6, 3);
    let cases = [
        (
            format!("[sweep]\noscillation_threshold = -1e-9\n{gain}"),
            "sweep.oscillation_threshold",
        ),
        (format!("[sweep]\n{gain}{gain}"), "swept twice"),
        (
            format!("[sweep]\n{}", axis("overrides.nope.k_x", 1.0, 2.0, 2)),
            "no element or link named \"nope\"",
        ),
        (
            format!("[sweep]\n{}", axis("controller.c", -10.0, 10.0, 3)),
            "sweep.axis[0] (controller.c)",
        ),
        (
            format!("[sweep]\n{}", axis("controller.k", 1.0, 2.0, 0)),
            "points must be >= 1",
        ),
        (
            format!("[sweep]\n{}", axis("spread.friction", -0.1, 0.1, 3)),
            "spreads mismatch friction contacts",
        ),
        (
            format!(
                "[sweep]\n{}{}",
                axis("controller.k", 1e4, 1e6, 1_000_000_000_000),
                axis("controller.c", 1.0, 10.0, 1_000_000_000_000)
            ),
            "at most 1000000",
        ),
        (
            format!(
                "[sweep]\n{}{}",
                axis("controller.k", 1e4, 1e6, 1001),
                axis("controller.c", 1.0, 10.0, 1000)
            ),
            "1001 x 1000 points",
        ),
    ];
    for (sweep, needle) in cases {
        let message = sweep_error(&sweep);
        assert!(message.contains(needle), "{needle:?} not in {message:?}");
    }
}

#[test]
fn a_grid_at_the_limit_is_accepted() {
    let text = format!(
        "robot = {:?}\nduration = 0.5\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 1e5\nc = 100\n[sweep]\n{}{}",
        robot_file().display().to_string(),
        axis("controller.k", 1e4, 1e6, 1000),
        axis("controller.c", 1.0, 10.0, 1000)
    );
    let scenario = Scenario::from_str(&text, Path::new("sweep.toml")).expect("scenario");
    let spec = SweepSpec::from_scenario(&scenario).expect("a million points is allowed");
    assert_eq!(spec.len(), 1_000_000);
}
