//! The four-bearing 6-DOF stage and the floating-body dynamics under it:
//! equivalence with the 1-DOF stage when the bearings are identical, rigid-body
//! checks against closed form, the exact Jacobian against central differences,
//! and eigenvalues shared with the 1-DOF model.

use fistage_analysis::modal_analysis;
use fistage_model::{EquilibriumKind, Inputs, Model};
use fistage_sim::{Engine, Excitation, NativeEngine, ScenarioExcitation, SimSettings};
use fistage_tests::{FREE_BODY, SplitMix, load, model_from, run, still};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// Identical bearings at the centre-of-mass height: the table's x follows the
/// 1-DOF FI stage of Fig. 5b to solver tolerance, and the other five table
/// coordinates stay at zero to round-off. The comparison covers the first
/// second: the in-phase stick-slip cycle is unstable to the anti-phase bearing
/// modes (see the modal test below), so round-off eventually grows into yaw.
#[test]
fn symmetric_stage_reproduces_the_one_dof_stage() {
    let mut six = load("scenarios/coupling/symmetric_fig05b.toml");
    let mut one = load("scenarios/paper/fig05b_fi.toml");
    for loaded in [&mut six, &mut one] {
        loaded.scenario.duration = 1.0;
        loaded.scenario.window = [0.0, 1.0];
        loaded.scenario.solver.rtol = 1e-10;
    }
    let (six_run, one_run) = (run(&six), run(&one));
    let x6 = six_run.signals.column("table.x").expect("table.x");
    let x1 = one_run.signals.column("table_x.q").expect("table_x.q");
    let size = x1.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let worst = x6
        .iter()
        .zip(x1)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0_f64, f64::max);
    assert!(
        worst < 1e-7 * size,
        "table x differs by {worst:e} m (size {size:e})"
    );
    for (signal, bound) in [
        ("table.y", 1e-15),
        ("table.z", 1e-15),
        ("table.roll", 1e-13),
        ("table.pitch", 1e-13),
        ("table.yaw", 1e-13),
    ] {
        let values = six_run.signals.column(signal).expect("signal");
        let largest = values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(largest < bound, "{signal} reaches {largest:e}");
    }
    // Each bearing moves like the 1-DOF bearing.
    let xb = one_run.signals.column("bearing_x.q").expect("bearing");
    for rail in ["rail_fl.q", "rail_fr.q", "rail_rl.q", "rail_rr.q"] {
        let q = six_run.signals.column(rail).expect("rail");
        let worst = q
            .iter()
            .zip(xb)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0_f64, f64::max);
        assert!(worst < 1e-7 * size * 3.0, "{rail} differs by {worst:e}");
    }
}

/// The symmetric stage's eigenvalues contain the 1-DOF FI stage's, at both
/// equilibria; the extra ones at the slipping equilibrium include three
/// anti-phase bearing modes that the servo cannot damp, unstable at 45 Hz.
#[test]
fn symmetric_stage_contains_the_one_dof_eigenvalues() {
    let six = load("scenarios/coupling/symmetric_fig05b.toml");
    let one = load("scenarios/paper/fig05b_fi.toml");
    let inputs = ScenarioExcitation::from_scenario(&one.scenario).inputs(0.0);
    for kind in [EquilibriumKind::Sticking, EquilibriumKind::Slipping] {
        let small =
            modal_analysis(&one.model, &inputs, kind, &one.model.zero_state()).expect("1-DOF");
        let large =
            modal_analysis(&six.model, &inputs, kind, &six.model.zero_state()).expect("6-DOF");
        for mode in &small.modes {
            let found = large.modes.iter().any(|m| {
                let distance = ((m.real - mode.real).powi(2) + (m.imag - mode.imag).powi(2)).sqrt();
                distance <= 1e-6 * mode.frequency_hz.max(1e-3) * 2.0 * std::f64::consts::PI
            });
            assert!(
                found,
                "{kind:?}: 1-DOF eigenvalue {} + {}i missing",
                mode.real, mode.imag
            );
        }
        if kind == EquilibriumKind::Slipping {
            assert!(small.stable, "the 1-DOF slipping equilibrium is stable");
            let unstable: Vec<_> = large.modes.iter().filter(|m| m.real > 0.0).collect();
            assert_eq!(unstable.len(), 3, "three anti-phase bearing modes");
            for mode in unstable {
                assert!(
                    (mode.frequency_hz - 45.0).abs() < 0.5,
                    "{}",
                    mode.frequency_hz
                );
                assert!(
                    mode.share("table.x") < 1e-6,
                    "the table does not move along x"
                );
            }
        }
    }
}

fn free_body() -> Model {
    model_from(
        FREE_BODY,
        "robot = \"x\"\nduration = 1\ngravity = [0, 0, 0]\n",
    )
}

/// World angular momentum about the centre of mass and kinetic energy of the free body.
fn momentum_and_energy(model: &Model, x: &[f64]) -> (Vector3<f64>, f64) {
    let body = &model.bodies[0];
    let poses = model.body_poses(x);
    let rotation = poses[0].0;
    let nq = model.layout.nq;
    // Velocities are in the joint frame; the joint frame's rotation is the joint origin's.
    let joint = body.joint.origin_rotation;
    let omega = joint * Vector3::new(x[nq + 3], x[nq + 4], x[nq + 5]);
    let origin_velocity = joint * Vector3::new(x[nq], x[nq + 1], x[nq + 2]);
    let r = rotation * body.com;
    let com_velocity = origin_velocity + omega.cross(&r);
    let inertia: Matrix3<f64> = rotation * body.inertia * rotation.transpose();
    let momentum = inertia * omega;
    let energy = 0.5 * body.mass * com_velocity.norm_squared() + 0.5 * omega.dot(&momentum);
    (momentum, energy)
}

/// A body tumbling about a non-principal axis with no forces keeps its angular
/// momentum (in the world) and its kinetic energy, while its angular velocity
/// wanders.
#[test]
fn torque_free_tumbling_conserves_momentum_and_energy() {
    let model = free_body();
    let nq = model.layout.nq;
    let mut x0 = model.zero_state();
    x0[nq..nq + 6].copy_from_slice(&[0.01, -0.02, 0.03, 3.0, -7.0, 5.0]);
    let settings = SimSettings {
        t_end: 3.0,
        sample_interval: 1e-2,
        rtol: 1e-11,
        atol_scale: 1e-2,
        max_step: None,
        max_steps: 10_000_000,
    };
    let trajectory = NativeEngine
        .simulate(&model, &x0, &still(), &settings, &mut |_| {})
        .expect("runs");
    let (l0, e0) = momentum_and_energy(&model, &x0);
    let mut omega_change = 0.0_f64;
    for k in 0..trajectory.len() {
        let x = trajectory.state(k);
        let (l, e) = momentum_and_energy(&model, x);
        assert!(
            (l - l0).norm() < 1e-8 * l0.norm(),
            "momentum drifts by {:e} at sample {k}",
            (l - l0).norm()
        );
        assert!((e - e0).abs() < 1e-8 * e0, "energy drifts by {:e}", e - e0);
        omega_change = omega_change.max(
            (Vector3::new(x[nq + 3], x[nq + 4], x[nq + 5]) - Vector3::new(3.0, -7.0, 5.0)).norm(),
        );
    }
    assert!(
        omega_change > 1.0,
        "the body must actually tumble (change {omega_change})"
    );
    // The quaternion stays a unit quaternion.
    let q = trajectory.last_state();
    let norm = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
    assert!((norm - 1.0).abs() < 1e-8, "quaternion norm {norm}");
}

/// A known force at a known point of a body at rest: the centre of mass
/// accelerates at F / m and the body turns at I^-1 (r x F).
#[test]
fn free_body_under_known_force_and_torque() {
    let model = free_body();
    let nq = model.layout.nq;
    let body = &model.bodies[0];
    let mut rng = SplitMix(5);
    for _ in 0..10 {
        // A random attitude, at rest.
        let attitude = UnitQuaternion::from_euler_angles(
            rng.range(-3.0, 3.0),
            rng.range(-1.5, 1.5),
            rng.range(-3.0, 3.0),
        );
        let mut x = model.zero_state();
        x[3..7].copy_from_slice(&[attitude.w, attitude.i, attitude.j, attitude.k]);
        let inputs = Inputs {
            servo_force: rng.range(-5.0, 5.0),
            ..Inputs::default()
        };
        let mut dx = vec![0.0; model.n_states()];
        let mut ws = model.workspace();
        model.rhs(&x, &inputs, &mut dx, &mut ws);
        let poses = model.body_poses(&x);
        let (rotation, origin) = poses[0];
        let actuator = &model.actuators[0];
        let force = actuator.axis * inputs.servo_force;
        let r_force = rotation * actuator.point;
        let r_com = rotation * body.com;
        let inertia = rotation * body.inertia * rotation.transpose();
        let alpha_expected =
            inertia.try_inverse().expect("inertia") * (r_force - r_com).cross(&force);
        let joint = body.joint.origin_rotation;
        let alpha = joint * Vector3::new(dx[nq + 3], dx[nq + 4], dx[nq + 5]);
        let origin_accel = joint * Vector3::new(dx[nq], dx[nq + 1], dx[nq + 2]);
        // At rest the centre of mass accelerates at a_origin + alpha x r_com.
        let com_accel = origin_accel + alpha.cross(&r_com);
        assert!(
            (com_accel - force / body.mass).norm() < 1e-12 * (1.0 + force.norm()),
            "{com_accel} vs {}",
            force / body.mass
        );
        assert!(
            (alpha - alpha_expected).norm() < 1e-10 * (1.0 + alpha_expected.norm()),
            "{alpha} vs {alpha_expected}"
        );
        let _ = origin;
    }
}

/// The dual-number Jacobian equals central differences of the right-hand side
/// at random states of the 6-DOF stage (moving, rotated, bristles loaded) and
/// of the 1-DOF stages.
#[test]
fn jacobian_matches_central_differences() {
    let mut rng = SplitMix(17);
    for file in [
        "scenarios/coupling/friction20_traverse.toml",
        "scenarios/coupling/drive_offset_p2p.toml",
        "scenarios/paper/fig12_ki1e6.toml",
    ] {
        let loaded = load(file);
        let model = &loaded.model;
        for _ in 0..3 {
            let mut x = model.zero_state();
            for (i, kind) in model.layout.kinds.iter().enumerate() {
                use fistage_model::StateKind::*;
                x[i] = match kind {
                    Translation => rng.range(-1e-4, 1e-4),
                    Angle => rng.range(-1e-3, 1e-3),
                    Quaternion => x[i],
                    LinearVelocity => rng.range(-0.03, 0.03),
                    AngularVelocity => rng.range(-0.1, 0.1),
                    Bristle => rng.range(-2e-6, 2e-6),
                    ErrorIntegral => rng.range(-1e-5, 1e-5),
                };
            }
            if let Some(q0) = model.layout.index("table.qw") {
                let q = UnitQuaternion::from_euler_angles(0.01, -0.02, 0.03);
                x[q0..q0 + 4].copy_from_slice(&[q.w, q.i, q.j, q.k]);
            }
            let inputs = Inputs {
                platform_velocity: 0.013,
                ..Inputs::default()
            };
            let exact = model.jacobian(&x, &inputs);
            let mut ws = model.workspace();
            let n = model.n_states();
            let (mut plus, mut minus) = (vec![0.0; n], vec![0.0; n]);
            for col in 0..n {
                let h = 1e-6 * model.layout.nominal[col];
                let mut xp = x.clone();
                xp[col] += h;
                let mut xm = x.clone();
                xm[col] -= h;
                model.rhs_general(&xp, &inputs.values(), &mut plus, &mut ws);
                model.rhs_general(&xm, &inputs.values(), &mut minus, &mut ws);
                for row in 0..n {
                    let numeric = (plus[row] - minus[row]) / (2.0 * h);
                    let scale = exact.column(col).amax().max(exact.row(row).amax()) * 1e-7 + 1e-9;
                    assert!(
                        (exact[(row, col)] - numeric).abs() <= scale,
                        "{file}: d {} / d {}: dual {} vs central {numeric}",
                        model.layout.names[row],
                        model.layout.names[col],
                        exact[(row, col)]
                    );
                }
            }
        }
    }
}
