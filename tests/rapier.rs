//! The rapier engine against the native engine: the same steady-state
//! statistics on the paper's Fig. 5b stage and on the symmetric and a
//! mismatched four-bearing stage, with a difference that shrinks with the
//! step; the same torque-free tumbling; and the colliders only rapier has (a
//! hard stop, a loose payload) checked against physics computed independently.

use fistage_model::Loaded;
use fistage_sim::{
    AdaptiveEngine, Engine, RapierEngine, RunOutput, ScenarioExcitation, SimSettings, run_scenario,
};
use fistage_tests::{CART_PENDULUM, FREE_BODY, load, model_from, run, settings, still};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

fn with_engine(loaded: &Loaded, engine: &str, dt: Option<f64>) -> RunOutput {
    let mut loaded = loaded.clone();
    loaded.scenario.solver.engine = engine.parse().expect("engine name");
    loaded.scenario.rapier.dt = dt;
    run_scenario(&loaded, &mut fistage_sim::no_progress).expect("run")
}

/// Relative differences (peak-to-peak, mean) of a signal between two runs.
fn differences(a: &RunOutput, b: &RunOutput, signal: &str) -> (f64, f64) {
    let (sa, sb) = (
        fistage_tests::stats(a, signal),
        fistage_tests::stats(b, signal),
    );
    (
        (sa.peak_to_peak - sb.peak_to_peak).abs() / sb.peak_to_peak,
        (sa.mean - sb.mean).abs() / sb.mean.abs().max(1e-30),
    )
}

#[test]
fn fig05b_statistics_agree_and_converge_with_the_step() {
    let mut loaded = load("scenarios/paper/fig05b_fi.toml");
    loaded.scenario.solver.rtol = 1e-10;
    let native = run(&loaded);
    let coarse = with_engine(&loaded, "rapier", Some(2e-5));
    let fine = with_engine(&loaded, "rapier", Some(1e-5));
    let (p2p_coarse, mean_coarse) = differences(&coarse, &native, "encoder.position");
    let (p2p_fine, mean_fine) = differences(&fine, &native, "encoder.position");
    println!(
        "dt 2e-5: p2p {p2p_coarse:.2e} mean {mean_coarse:.2e}; dt 1e-5: p2p {p2p_fine:.2e} mean {mean_fine:.2e}"
    );
    assert!(
        p2p_fine < 5e-3 && mean_fine < 2e-4,
        "rapier at 1e-5 s: {p2p_fine:e}, {mean_fine:e}"
    );
    // First order: halving the step about halves the difference.
    assert!(
        p2p_fine < 0.7 * p2p_coarse,
        "{p2p_fine:e} vs {p2p_coarse:e}"
    );
    assert!(
        mean_fine < 0.7 * mean_coarse,
        "{mean_fine:e} vs {mean_coarse:e}"
    );
}

#[test]
fn four_bearing_stage_statistics_agree() {
    let mut symmetric = load("scenarios/coupling/symmetric_fig05b.toml");
    symmetric.scenario.solver.rtol = 1e-10;
    // Two seconds: slipping, the four bearings' antisymmetric modes are
    // unstable (`fistage modes`: Re +31.6 1/s), so any round-off difference
    // between the bearings grows into yaw; after about 2.5 s the two
    // engines' limit cycles differ in phase by round-off, not by physics.
    symmetric.scenario.duration = 2.0;
    symmetric.scenario.window = [1.0, 2.0];
    let native = run(&symmetric);
    let rapier = with_engine(&symmetric, "rapier", Some(1e-5));
    let (p2p, mean) = differences(&rapier, &native, "encoder.position");
    println!("symmetric_fig05b: p2p {p2p:.2e} mean {mean:.2e}");
    assert!(p2p < 3e-3 && mean < 5e-4, "symmetric: {p2p:e}, {mean:e}");

    let mut mismatched = load("scenarios/coupling/friction20_traverse.toml");
    mismatched.scenario.solver.rtol = 1e-10;
    let native = run(&mismatched);
    let rapier = with_engine(&mismatched, "rapier", Some(5e-6));
    let (p2p, mean) = differences(&rapier, &native, "controller.error");
    let (_, yaw_mean) = differences(&rapier, &native, "table.yaw");
    println!("friction20_traverse: error p2p {p2p:.2e} mean {mean:.2e}, yaw mean {yaw_mean:.2e}");
    assert!(p2p < 2e-2 && mean < 1e-4, "mismatched: {p2p:e}, {mean:e}");
    assert!(yaw_mean < 5e-3, "yaw excited by the mismatch: {yaw_mean:e}");
}

/// World angular momentum about the centre of mass, from the state.
fn momentum(model: &fistage_model::Model, x: &[f64]) -> Vector3<f64> {
    let body = &model.bodies()[0];
    let rotation = model.body_poses(x)[0].0;
    let nq = model.layout().nq;
    let omega = body.joint.origin_rotation * Vector3::new(x[nq + 3], x[nq + 4], x[nq + 5]);
    let inertia: Matrix3<f64> = rotation * body.inertia * rotation.transpose();
    inertia * omega
}

#[test]
fn tumbling_body_conserves_momentum_and_agrees_with_native() {
    let model = model_from(
        FREE_BODY,
        "robot = \"x\"\nduration = 1\ngravity = [0, 0, 0]\n",
    );
    let nq = model.layout().nq;
    let mut x0 = model.zero_state();
    x0[nq..nq + 6].copy_from_slice(&[0.01, -0.02, 0.03, 3.0, -7.0, 5.0]);
    let still = still();
    let settings = SimSettings {
        atol_scale: 1e-2,
        ..settings(1.0, 1e-2, 1e-11)
    };
    let native = AdaptiveEngine::NATIVE
        .simulate(
            &model,
            &x0,
            &still,
            &settings,
            &mut fistage_sim::no_progress,
        )
        .expect("native");
    let mut rapier_engine = RapierEngine::default();
    rapier_engine.settings.dt = Some(1e-5);
    let rapier = rapier_engine
        .simulate(
            &model,
            &x0,
            &still,
            &settings,
            &mut fistage_sim::no_progress,
        )
        .expect("rapier");
    let l0 = momentum(&model, &x0);
    let mut drift: f64 = 0.0;
    for k in 0..rapier.len() {
        drift = drift.max((momentum(&model, rapier.state(k)) - l0).norm() / l0.norm());
    }
    let attitude = |x: &[f64]| UnitQuaternion::from_matrix(&model.body_poses(x)[0].0);
    let angle = attitude(rapier.last_state()).angle_to(&attitude(native.last_state()));
    let omega = |x: &[f64]| Vector3::new(x[nq + 3], x[nq + 4], x[nq + 5]);
    let omega_difference = (omega(rapier.last_state()) - omega(native.last_state())).norm();
    let omega_change = (omega(native.last_state()) - omega(&x0)).norm();
    println!(
        "rapier tumbling: momentum drift {drift:.2e}, attitude difference {angle:.2e} rad, omega difference {omega_difference:.2e} rad/s (omega changes by {omega_change:.2})"
    );
    assert!(omega_change > 1.0, "the body tumbles");
    assert!(drift < 1e-4, "angular momentum drifts by {drift:e}");
    assert!(angle < 1e-3, "attitudes differ by {angle:e} rad after 1 s");
    assert!(
        omega_difference < 1e-3 * omega(&x0).norm(),
        "{omega_difference:e}"
    );
}

#[test]
fn hard_stop_holds_the_table_where_native_runs_past() {
    let loaded = load("scenarios/rapier/stop_crash.toml");
    let upper = loaded.scenario.rapier.stops[0].upper.expect("upper stop");
    let crashed = run(&loaded);
    let stats = fistage_tests::stats(&crashed, "table_x.q");
    let mut free = loaded.clone();
    free.scenario.rapier.stops.clear();
    free.scenario.solver.engine = fistage_model::EngineKind::Native;
    let free_stats = fistage_tests::stats(&run(&free), "table_x.q");
    let position = crashed.signals.column("table_x.q").expect("signal");
    let peak = position.iter().cloned().fold(f64::MIN, f64::max);
    println!(
        "stop at {upper:e} m: peak {peak:e} m, settled {:e} m; without the stop {:e} m",
        stats.mean, free_stats.mean
    );
    assert!(
        free_stats.mean > 1.5 * upper,
        "the move goes past the stop without it"
    );
    // Held at the stop, pressed into it by the servo by at most tens of micrometres.
    assert!(
        stats.mean > upper && stats.mean < upper + 3e-5,
        "{}",
        stats.mean
    );
    assert!(peak < upper + 5e-5, "peak {peak:e}");
    // The native engine refuses a scenario with colliders instead of ignoring them.
    let mut native = loaded.clone();
    native.scenario.solver.engine = fistage_model::EngineKind::Native;
    let error =
        run_scenario(&native, &mut fistage_sim::no_progress).expect_err("native refuses colliders");
    assert!(error.to_string().contains("rapier.stop"), "{error}");
}

/// Final slip of a Coulomb block on a platform moving with velocity `v(t)`
/// (samples at interval `dt`): the block's velocity follows the platform's
/// while that needs at most `mu g`, and changes at `mu g` otherwise.
fn coulomb_slip(platform_velocity: &[f64], dt: f64, mu_g: f64) -> f64 {
    let substeps = 200;
    let h = dt / substeps as f64;
    let (mut block, mut slip) = (platform_velocity[0], 0.0);
    for pair in platform_velocity.windows(2) {
        for k in 0..substeps {
            let v = pair[0] + (pair[1] - pair[0]) * (k as f64 + 0.5) / substeps as f64;
            let needed = (v - block) / h;
            block += needed.clamp(-mu_g, mu_g) * h;
            slip += (v - block) * h;
        }
    }
    slip
}

#[test]
fn payload_stays_put_with_friction_and_slides_as_coulomb_predicts_without() {
    let held = load("scenarios/rapier/payload_p2p.toml");
    let output = run(&held);
    let slip = fistage_tests::stats(&output, "payload.slip").mean;
    let sink = fistage_tests::stats(&output, "payload.sink").mean;
    println!("mu 0.5: slip {slip:e} m, sink {sink:e} m");
    assert!(
        slip < 2e-6,
        "peak acceleration 0.58 m/s^2 < mu g: the payload stays ({slip:e})"
    );
    assert!(
        sink > 0.0 && sink < 1e-5,
        "resting contact compliance {sink:e}"
    );

    let mut slippery = held.clone();
    let mu = 0.02;
    if let Some(payload) = slippery.scenario.rapier.payload.as_mut() {
        payload.friction = mu;
    }
    let output = run(&slippery);
    let slip = fistage_tests::stats(&output, "payload.slip").mean;
    let table_velocity = output.signals.column("table.vx").expect("table.vx");
    let dt = output.signals.times[1] - output.signals.times[0];
    let g = slippery.scenario.gravity[2].abs();
    let predicted = coulomb_slip(table_velocity, dt, mu * g).abs();
    println!("mu {mu}: slip {slip:e} m, Coulomb block on the table's motion {predicted:e} m");
    assert!(predicted > 5e-5, "the move needs more than mu g");
    assert!(
        (slip - predicted).abs() < 0.05 * predicted,
        "rapier {slip:e} vs Coulomb {predicted:e}"
    );
}

/// A revolute joint below a prismatic one, with a point mass (zero inertia
/// about its centre): rapier swings at the closed-form frequency
/// w^2 = g (M + m) / (M L) and keeps the horizontal momentum.
#[test]
fn pendulum_on_a_cart_swings_at_the_closed_form_frequency() {
    let model = model_from(CART_PENDULUM, "robot = \"x\"\nduration = 1\n");
    let (cart, bob, length, g): (f64, f64, f64, f64) = (3.0, 0.7, 0.4, 9.81);
    let omega = (g * (cart + bob) / (cart * length)).sqrt();
    let amplitude = 1e-3;
    let mut x0 = model.zero_state();
    x0[1] = amplitude;
    let still = still();
    let settings = settings(2.0, 1e-3, 1e-8);
    let mut engine = RapierEngine::default();
    engine.settings.dt = Some(1e-5);
    let trajectory = engine
        .simulate(
            &model,
            &x0,
            &still,
            &settings,
            &mut fistage_sim::no_progress,
        )
        .expect("rapier");
    let (mut worst_angle, mut worst_momentum) = (0.0_f64, 0.0_f64);
    for (k, &t) in trajectory.times.iter().enumerate() {
        let x = trajectory.state(k);
        worst_angle = worst_angle.max((x[1] - amplitude * (omega * t).cos()).abs());
        let momentum = (cart + bob) * x[2] - bob * length * x[1].cos() * x[3];
        worst_momentum = worst_momentum.max(momentum.abs());
    }
    println!(
        "rapier pendulum on cart: angle error {worst_angle:.2e} rad, momentum {worst_momentum:.2e}"
    );
    assert!(
        worst_angle < 1e-2 * amplitude,
        "angle deviates by {worst_angle} rad"
    );
    assert!(worst_momentum < 1e-9, "momentum drifts by {worst_momentum}");
}

const CARRIER: &str = r#"<robot name="carrier">
  <link name="world"/>
  <link name="platform"><inertial><origin xyz="0.02 -0.01 0.03"/><mass value="2.0"/>
    <inertia ixx="0.02" ixy="0.001" ixz="0" iyy="0.03" iyz="-0.002" izz="0.04"/></inertial></link>
  <link name="slider"><inertial><origin xyz="0 0.01 0"/><mass value="0.5"/>
    <inertia ixx="1e-3" ixy="0" ixz="0" iyy="2e-3" iyz="0" izz="2e-3"/></inertial></link>
  <joint name="float" type="floating"><parent link="world"/><child link="platform"/></joint>
  <joint name="slide" type="prismatic"><origin xyz="0.1 0 0.05"/><parent link="platform"/><child link="slider"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"#;

/// A floating platform carrying a prismatic slider (a joint below a floating
/// body, an impulse joint in rapier), started moving and turning: rapier
/// follows the native engine.
#[test]
fn moving_free_root_with_a_jointed_child_follows_native() {
    let model = model_from(
        CARRIER,
        "robot = \"x\"\nduration = 1\ngravity = [0, 0, 0]\n",
    );
    let nq = model.layout().nq;
    let mut x0 = model.zero_state();
    let slide = model.layout().index("slide.q").expect("slide.q");
    let slide_rate = model.layout().index("slide.v").expect("slide.v");
    x0[slide] = 0.01;
    x0[slide_rate] = 0.05;
    x0[nq..nq + 6].copy_from_slice(&[0.1, 0.02, -0.03, 0.3, -0.2, 0.5]);
    let still = still();
    let settings = SimSettings {
        atol_scale: 1e-2,
        ..settings(0.5, 1e-2, 1e-11)
    };
    let native = AdaptiveEngine::NATIVE
        .simulate(
            &model,
            &x0,
            &still,
            &settings,
            &mut fistage_sim::no_progress,
        )
        .expect("native");
    let mut engine = RapierEngine::default();
    engine.settings.dt = Some(1e-5);
    let rapier = engine
        .simulate(
            &model,
            &x0,
            &still,
            &settings,
            &mut fistage_sim::no_progress,
        )
        .expect("rapier");
    let (a, b) = (rapier.last_state(), native.last_state());
    let position = (Vector3::new(a[0], a[1], a[2]) - Vector3::new(b[0], b[1], b[2])).norm();
    let slider = (a[slide] - b[slide]).abs();
    println!(
        "free root after 0.5 s: platform {position:.2e} m apart, slider {slider:.2e} m apart (moved {:.3e} m)",
        (b[slide] - x0[slide]).abs()
    );
    assert!(
        (Vector3::new(b[0], b[1], b[2])).norm() > 0.04,
        "the platform moves"
    );
    assert!(
        position < 1e-5,
        "platform positions differ by {position:e} m"
    );
    assert!(slider < 1e-5, "slider positions differ by {slider:e} m");
}

/// A run whose length is not a whole number of output intervals ends with a
/// sample at exactly its end time, as the native engine's does.
#[test]
fn off_grid_end_time_gets_its_own_sample() {
    let loaded = load("scenarios/paper/fig05b_fi.toml");
    let model = &loaded.model;
    let x0 = fistage_sim::initial_state(model, &loaded.scenario).expect("initial state");
    let excitation = ScenarioExcitation::from_scenario(&loaded.scenario);
    let settings = settings(0.01005, 1e-3, 1e-8);
    let mut engine = RapierEngine::default();
    engine.settings.dt = Some(2e-4);
    let rapier = engine
        .simulate(
            model,
            &x0,
            &excitation,
            &settings,
            &mut fistage_sim::no_progress,
        )
        .expect("rapier");
    let native = AdaptiveEngine::NATIVE
        .simulate(
            model,
            &x0,
            &excitation,
            &settings,
            &mut fistage_sim::no_progress,
        )
        .expect("native");
    assert_eq!(rapier.times, native.times);
    assert_eq!(rapier.times.last().copied(), Some(0.01005));
    // 50 steps of 0.2 ms, then one of 0.05 ms.
    assert_eq!(rapier.stats.counts.steps, 51);
}
