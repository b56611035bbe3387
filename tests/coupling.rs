//! Mode coupling grows with bearing mismatch: traverses of the four-bearing
//! stage with the friction of the bearings (f_C, f_S, sigma0 together) spread
//! by 0, 10, 20 and 50% (left bearings above the mean, right below, front above
//! rear). Measured: yaw and pitch of the table during the traverse, and at the
//! slipping equilibrium (a) the yaw that the table-x modes carry, as yaw times
//! the 50 mm half bearing spacing over x, and (b) the share of table-x kinetic
//! energy in the bearing-dominated modes (zero when the bearings are alike,
//! because the anti-phase bearing modes then leave the table still along x). `cargo test --release --test integration coupling -- --nocapture` prints
//! the table quoted in the README.

use fistage_analysis::modal_analysis;
use fistage_model::{EquilibriumKind, Override, assemble};
use fistage_sim::{Excitation, ScenarioExcitation};
use fistage_tests::{load, run, stats};

const PATTERN: [(&str, f64); 4] = [
    ("fl", 1.0),
    ("fr", -1.0 / 3.0),
    ("rl", 1.0 / 3.0),
    ("rr", -1.0),
];

struct Row {
    spread: f64,
    yaw_mean: f64,
    yaw_p2p: f64,
    pitch_p2p: f64,
    error_p2p: f64,
    yaw_per_x: f64,
    x_in_bearing_modes: f64,
}

fn measure(spread: f64) -> Row {
    let base = load("scenarios/coupling/symmetric_traverse.toml");
    let mut scenario = base.scenario.clone();
    for (bearing, weight) in PATTERN {
        let factor = 1.0 + spread * weight;
        for (key, value) in [("f_c", 1.275), ("f_s", 1.625), ("sigma0", 5.5e5)] {
            scenario.overrides.push(Override {
                target: format!("friction_{bearing}"),
                key: key.into(),
                value: value * factor,
            });
        }
    }
    let (robot, model) = assemble(base.robot.clone(), &scenario).expect("model");
    let loaded = fistage_model::Loaded {
        scenario,
        robot,
        model,
    };
    let output = run(&loaded);
    let yaw = stats(&output, "table.yaw");
    let pitch = stats(&output, "table.pitch");
    let error = stats(&output, "controller.error");
    let mut inputs = ScenarioExcitation::from_scenario(&loaded.scenario).inputs(0.0);
    inputs.platform_velocity = -loaded.scenario.reference.traverse_velocity();
    inputs.reference = Default::default();
    let modes = modal_analysis(
        &loaded.model,
        &inputs,
        EquilibriumKind::Slipping,
        &loaded.model.zero_state(),
    )
    .expect("modes");
    let magnitude = |m: &fistage_analysis::Mode, c: &str| {
        m.participation
            .iter()
            .find(|p| p.coordinate == c)
            .map_or(0.0, |p| p.magnitude)
    };
    let yaw_per_x = modes
        .modes
        .iter()
        .filter(|m| m.oscillatory && m.share("table.x") > 0.1)
        .map(|m| magnitude(m, "table.yaw") * 0.05 / magnitude(m, "table.x"))
        .fold(0.0, f64::max);
    let x_in_bearing_modes = modes
        .modes
        .iter()
        .filter(|m| m.oscillatory && m.dominant.starts_with("bearing"))
        .map(|m| m.share("table.x"))
        .fold(0.0, f64::max);
    Row {
        spread,
        yaw_mean: yaw.mean,
        yaw_p2p: yaw.peak_to_peak,
        pitch_p2p: pitch.peak_to_peak,
        error_p2p: error.peak_to_peak,
        yaw_per_x,
        x_in_bearing_modes,
    }
}

#[test]
fn coupling_grows_with_friction_mismatch() {
    let rows: Vec<Row> = [0.0, 0.1, 0.2, 0.5].iter().map(|&s| measure(s)).collect();
    println!(
        "| spread | yaw mean (µrad) | yaw p2p (µrad) | pitch p2p (µrad) | x error p2p (µm) | yaw x 50 mm / x in table-x modes | table-x share of bearing modes |"
    );
    println!("|---|---|---|---|---|---|---|");
    for r in &rows {
        println!(
            "| ±{:.0}% | {:.4} | {:.4} | {:.4} | {:.3} | {:.2e} | {:.2e} |",
            100.0 * r.spread,
            r.yaw_mean * 1e6,
            r.yaw_p2p * 1e6,
            r.pitch_p2p * 1e6,
            r.error_p2p * 1e6,
            r.yaw_per_x,
            r.x_in_bearing_modes
        );
    }
    // Identical bearings: no mean yaw, and the bearing modes leave table x still.
    assert!(rows[0].yaw_mean.abs() < 1e-9, "{}", rows[0].yaw_mean);
    assert!(
        rows[0].x_in_bearing_modes < 1e-6,
        "{}",
        rows[0].x_in_bearing_modes
    );
    // Mismatch yaws the table and couples x with yaw and the bearing modes, more with more mismatch.
    for pair in rows.windows(2) {
        assert!(
            pair[1].yaw_mean.abs() > pair[0].yaw_mean.abs(),
            "mean yaw grows with the spread"
        );
        assert!(
            pair[1].yaw_per_x > pair[0].yaw_per_x,
            "yaw in the x modes grows with the spread"
        );
        assert!(
            pair[1].x_in_bearing_modes > pair[0].x_in_bearing_modes,
            "x in the bearing modes grows"
        );
    }
    assert!(
        rows[3].yaw_mean.abs() > 1e-7,
        "50% spread yaws by {}",
        rows[3].yaw_mean
    );
}
