//! Stability analysis against independent checks: the paper's Routh-Hurwitz
//! test (corrected) against the eigenvalues of fistage's Jacobian, linear
//! against simulated verdicts on the Fig. 6 grids, the paper's claims about
//! those grids, and the largest Lyapunov exponent on a limit cycle and on the
//! irregular k_i = 5e6 motion of Fig. 12.

use fistage_analysis::lyapunov::{LyapunovSettings, largest_lyapunov};
use fistage_analysis::modal_analysis;
use fistage_analysis::routh::{RigidStage, rigid_slipping};
use fistage_analysis::sweep::{SweepSpec, run_points};
use fistage_model::{EquilibriumKind, LugreParams, RobotSpec};
use fistage_sim::{Excitation, ScenarioExcitation};
use fistage_tests::load;

/// The corrected Routh-Hurwitz conditions give the same verdict as the
/// eigenvalues at every point of a (k, c, x_p') grid, and the corrected
/// coefficients are those of the Jacobian's characteristic polynomial. The
/// conditions as printed in the paper disagree at some points.
#[test]
fn corrected_routh_hurwitz_equals_eigenvalues() {
    let base = load("scenarios/paper/fig06a_rigid_vp20.toml");
    let mut printed_disagreements = 0;
    let mut points = 0;
    let mut stable_points = 0;
    for &vp in &[0.005, 0.02, 0.05] {
        for i in 0..12 {
            for j in 0..12 {
                let k = 1e4 * 100f64.powf(i as f64 / 11.0);
                let c = 10.0 * 50f64.powf(j as f64 / 11.0);
                let mut scenario = base.scenario.clone();
                scenario.platform_velocity = vp;
                if let Some(controller) = scenario.controller.as_mut() {
                    controller.k = k;
                    controller.c = c;
                }
                let (_, model) =
                    fistage_model::assemble(base.robot.clone(), &scenario).expect("model");
                let inputs = ScenarioExcitation::from_scenario(&scenario).inputs(0.0);
                let modes = modal_analysis(
                    &model,
                    &inputs,
                    EquilibriumKind::Slipping,
                    &model.zero_state(),
                )
                .expect("modes");
                let test = rigid_slipping(&RigidStage {
                    mass: model.bodies()[0].mass,
                    k,
                    c,
                    lugre: LugreParams::paper_table1(),
                    platform_velocity: vp,
                });
                assert_eq!(
                    test.stable, modes.stable,
                    "k = {k}, c = {c}, x_p' = {vp}: Routh-Hurwitz vs eigenvalues"
                );
                // Characteristic polynomial of J: lambda^3 - tr lambda^2 + m2 lambda - det.
                let j = &modes.jacobian;
                let trace = j.trace();
                let minors = j[(0, 0)] * j[(1, 1)] - j[(0, 1)] * j[(1, 0)] + j[(0, 0)] * j[(2, 2)]
                    - j[(0, 2)] * j[(2, 0)]
                    + j[(1, 1)] * j[(2, 2)]
                    - j[(1, 2)] * j[(2, 1)];
                let det = j.determinant();
                let w = test.omega_n;
                let expected = [-trace / w, minors / (w * w), -det / (w * w * w)];
                for (a, b) in test.coefficients.iter().zip(expected) {
                    assert!(
                        (a - b).abs() <= 1e-8 * b.abs().max(1.0),
                        "coefficient {a} vs {b} at k = {k}, c = {c}"
                    );
                }
                points += 1;
                stable_points += usize::from(test.stable);
                printed_disagreements += usize::from(test.stable_as_printed != test.stable);
            }
        }
    }
    println!(
        "Routh-Hurwitz: {stable_points} of {points} points stable; the printed conditions disagree at {printed_disagreements}"
    );
    assert!(
        stable_points > 0 && stable_points < points,
        "the grid must cross the boundary"
    );
    assert!(
        printed_disagreements > 0,
        "the printed form should be distinguishable on this grid"
    );
}

fn sweep(file: &str, points: usize) -> Vec<fistage_analysis::sweep::PointResult> {
    let loaded = load(file);
    let mut spec = SweepSpec::from_scenario(&loaded.scenario).expect("sweep");
    for axis in &mut spec.axes {
        axis.points = points;
    }
    spec.duration = Some(2.0);
    let robot = RobotSpec::from_file(&loaded.scenario.robot).expect("robot");
    let indices: Vec<usize> = (0..spec.len()).collect();
    run_points(&loaded, &robot, &spec, &indices, 2, &|_, _| {})
}

/// On the Fig. 6 grids the linear and simulated verdicts agree except at
/// bistable points (stable equilibrium, run from rest oscillating); never is a
/// linearly unstable equilibrium settled on in simulation. Without FI raising
/// c stabilises at every k; with FI the stable region is smaller.
#[test]
fn fig06_linear_and_simulated_verdicts_agree_except_bistable() {
    let rigid = sweep("scenarios/paper/fig06a_rigid_vp20.toml", 8);
    let fi = sweep("scenarios/paper/fig06b_fi_vp20.toml", 8);
    for point in rigid.iter().chain(&fi) {
        let (linear, simulated) = (
            point.stable_linear.expect("linear"),
            point.stable_sim.expect("simulated"),
        );
        assert!(
            linear || !simulated,
            "linearly unstable but settled at {:?}",
            point.parameters
        );
        assert_eq!(point.bistable, Some(linear && !simulated));
    }
    // Rigid: along c (the second axis) stability, once reached, persists, at every k.
    for k_index in 0..8 {
        let column: Vec<bool> = (0..8)
            .map(|c_index| rigid[c_index * 8 + k_index].stable_sim == Some(true))
            .collect();
        let first_stable = column.iter().position(|s| *s).expect("some c stabilises");
        assert!(
            column[first_stable..].iter().all(|s| *s),
            "k index {k_index}: {column:?}"
        );
    }
    let count = |points: &[fistage_analysis::sweep::PointResult]| {
        points.iter().filter(|p| p.stable_sim == Some(true)).count()
    };
    println!(
        "Fig. 6 at 8 x 8: rigid {} stable, FI {} stable",
        count(&rigid),
        count(&fi)
    );
    assert!(
        count(&fi) < count(&rigid),
        "the FI stable region is smaller"
    );
}

/// Fig. 12: the Lyapunov exponent is near zero on the k_i = 1e6 limit cycle
/// (and on Fig. 5b's), and clearly positive for the irregular k_i = 5e6 motion.
/// Measured over 10 s; the values hold to about 0.01 1/s when the separation
/// or the tolerance changes 10x (see the module doc of `lyapunov`).
#[test]
fn lyapunov_exponent_separates_limit_cycle_from_chaos() {
    let settings = LyapunovSettings {
        duration: 10.0,
        ..LyapunovSettings::default()
    };
    let exponent = |file: &str| largest_lyapunov(&load(file), &settings).expect("exponent");
    let cycle = exponent("scenarios/paper/fig12_ki1e6.toml");
    let fig05 = exponent("scenarios/paper/fig05b_fi.toml");
    let chaos = exponent("scenarios/paper/fig12_ki5e6.toml");
    println!(
        "largest Lyapunov exponent: k_i = 1e6 {cycle:.3} 1/s, Fig. 5b {fig05:.3} 1/s, k_i = 5e6 {chaos:.3} 1/s"
    );
    assert!(cycle.abs() < 1.0, "limit cycle exponent {cycle}");
    assert!(fig05.abs() < 1.0, "limit cycle exponent {fig05}");
    assert!(chaos > 4.0, "chaotic exponent {chaos}");
}

/// `spread.friction` mismatches the four bearings evenly around the file's
/// value (fl +s, fr +s/3, rl -s/3, rr -s), keeping the mean.
#[test]
fn spread_parameter_mismatches_the_bearings() {
    use fistage_analysis::sweep::apply_parameter;
    let loaded = load("scenarios/coupling/symmetric_traverse.toml");
    let mut scenario = loaded.scenario.clone();
    let mut robot = RobotSpec::from_file(&scenario.robot).expect("robot");
    apply_parameter(&mut scenario, &mut robot, "spread.friction", 0.3).expect("spread");
    let names: Vec<&str> = robot.frictions.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(
        names,
        ["friction_fl", "friction_fr", "friction_rl", "friction_rr"]
    );
    for (friction, factor) in robot.frictions.iter().zip([1.3, 1.1, 0.9, 0.7]) {
        assert!((friction.lugre.f_c - 1.275 * factor).abs() < 1e-12);
        assert!((friction.lugre.f_s - 1.625 * factor).abs() < 1e-12);
        assert!((friction.lugre.sigma0 - 5.5e5 * factor).abs() < 1e-6);
        assert_eq!(friction.lugre.v_s, 0.0167);
    }
    let mut robot = RobotSpec::from_file(&scenario.robot).expect("robot");
    assert!(apply_parameter(&mut scenario, &mut robot, "spread.mu", 0.3).is_err());
}
