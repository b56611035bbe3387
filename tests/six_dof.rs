//! The four-bearing 6-DOF stage and the floating-body dynamics under it:
//! equivalence with the 1-DOF stage when the bearings are identical, rigid-body
//! checks against closed form, the exact Jacobian against central differences,
//! and eigenvalues shared with the 1-DOF model.

use fistage_analysis::modal_analysis;
use fistage_model::{EquilibriumKind, EvaluationPath, Inputs, Model, ReferenceSample, StateKind};
use fistage_sim::{AdaptiveEngine, Engine, Excitation, ScenarioExcitation, SimSettings};
use fistage_tests::{CART_PENDULUM, FREE_BODY, SplitMix, load, model_from, run, still};
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

/// A stuck LuGre contact conserves z minus its displacement (z' = v at zero
/// slip): one zero eigenvalue per stuck bearing, flagged neutral, and none
/// when every bearing slips.
#[test]
fn each_stuck_bearing_adds_one_neutral_mode() {
    for (file, bearings) in [
        ("scenarios/paper/fig05b_fi.toml", 1),
        ("scenarios/coupling/mismatch_fc20_fig05b.toml", 4),
    ] {
        let loaded = load(file);
        let inputs = ScenarioExcitation::from_scenario(&loaded.scenario).inputs(0.0);
        for (kind, neutral) in [
            (EquilibriumKind::Sticking, bearings),
            (EquilibriumKind::Slipping, 0),
        ] {
            let analysis = modal_analysis(&loaded.model, &inputs, kind, &loaded.model.zero_state())
                .expect("modes");
            assert_eq!(analysis.neutral, neutral, "{file} {kind:?}");
            let flagged: Vec<_> = analysis.modes.iter().filter(|m| m.neutral).collect();
            assert_eq!(flagged.len(), neutral, "{file} {kind:?}");
            for mode in flagged {
                assert!(mode.real.abs() < 1e-9 && mode.imag == 0.0, "{mode:?}");
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
    let body = &model.bodies()[0];
    let poses = model.body_poses(x);
    let rotation = poses[0].0;
    let nq = model.layout().nq;
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
    let nq = model.layout().nq;
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
    let trajectory = AdaptiveEngine::NATIVE
        .simulate(
            &model,
            &x0,
            &still(),
            &settings,
            &mut fistage_sim::no_progress,
        )
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
    let nq = model.layout().nq;
    let body = &model.bodies()[0];
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
        let actuator = &model.actuators()[0];
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
            for (i, kind) in model.layout().kinds.iter().enumerate() {
                use fistage_model::StateKind::*;
                x[i] = match kind {
                    Translation => rng.range(-1e-4, 1e-4),
                    Angle => rng.range(-1e-3, 1e-3),
                    Quaternion => x[i],
                    LinearVelocity => rng.range(-0.03, 0.03),
                    AngularVelocity => rng.range(-0.1, 0.1),
                    Bristle => rng.range(-2e-6, 2e-6),
                    ErrorIntegral => rng.range(-1e-5, 1e-5),
                    CompensatorBristle => rng.range(-2e-6, 2e-6),
                    CompensatorDeflection => rng.range(-1e-4, 1e-4),
                    CompensatorVelocity => rng.range(-0.03, 0.03),
                    CompensatorForce | ObserverState => rng.range(-5.0, 5.0),
                };
            }
            if let Some(q0) = model.layout().index("table.qw") {
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
                let h = 1e-6 * model.layout().nominal[col];
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
                        model.layout().names[row],
                        model.layout().names[col],
                        exact[(row, col)]
                    );
                }
            }
        }
    }
}

/// Three floating bodies (the plate on a rotated joint frame with a welded
/// bracket, the carriage and a puck on unrotated ones) and three rail bodies (one on a
/// turned rail), coupled by isolators with every kind of end as parent and as
/// child: floating to rail, with and without attach rotations and sharing
/// their relative rotation through rail ends and through floating ends;
/// floating to floating; world to floating; rail to rail; world to rail and
/// rail to world; rail to floating; one floating parent with identical attach
/// rotations toward a rail and toward a floating body (which must not share). Friction on rails and on both floating
/// bodies; sensors and actuators on both kinds of body.
const ROOTED: &str = r#"<robot name="rooted" xmlns:fistage="urn:fistage:urdf:1">
  <link name="world"/>
  <link name="plate"><inertial><origin xyz="0.01 -0.02 0.03" rpy="0.2 -0.1 0.4"/><mass value="3.0"/>
    <inertia ixx="0.02" ixy="0.001" ixz="-0.002" iyy="0.03" iyz="0.0005" izz="0.04"/></inertial></link>
  <joint name="plate" type="floating"><origin xyz="0.1 0 0.05" rpy="0.1 0.2 -0.3"/><parent link="world"/><child link="plate"/></joint>
  <link name="bracket"><inertial><origin xyz="0 0 -0.01"/><mass value="0.3"/>
    <inertia ixx="1e-4" ixy="0" ixz="0" iyy="2e-4" iyz="0" izz="2e-4"/></inertial></link>
  <joint name="bracket" type="fixed"><origin xyz="0 0.02 -0.01" rpy="0 0 0.3"/><parent link="plate"/><child link="bracket"/></joint>
  <link name="carriage"><inertial><origin xyz="0.005 0 0.01"/><mass value="1.5"/>
    <inertia ixx="0.004" ixy="0" ixz="0.0003" iyy="0.005" iyz="0" izz="0.006"/></inertial></link>
  <joint name="carriage" type="floating"><origin xyz="-0.1 0.02 0.04"/><parent link="world"/><child link="carriage"/></joint>
  <link name="puck"><inertial><mass value="0.4"/><inertia ixx="2e-4" ixy="0" ixz="0" iyy="3e-4" iyz="0" izz="4e-4"/></inertial></link>
  <joint name="puck" type="floating"><origin xyz="-0.15 -0.05 0.04"/><parent link="world"/><child link="puck"/></joint>
  <link name="shoe_a"><inertial><mass value="0.2"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial></link>
  <joint name="rail_a" type="prismatic"><origin xyz="0.1 0.05 0"/><parent link="world"/><child link="shoe_a"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <link name="shoe_b"><inertial><mass value="0.25"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial></link>
  <joint name="rail_b" type="prismatic"><origin xyz="0.1 -0.05 0" rpy="0 0.1 0.5"/><parent link="world"/><child link="shoe_b"/><axis xyz="0.6 0.8 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <link name="shoe_c"><inertial><mass value="0.15"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial></link>
  <joint name="rail_c" type="prismatic"><origin xyz="-0.1 0.05 0"/><parent link="world"/><child link="shoe_c"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <fistage:isolator name="iso_a" parent="plate" child="shoe_a">
    <origin xyz="0.05 0.05 -0.02"/><stiffness xyz="1e4 3e6 3e6" rpy="200 200 200"/><damping xyz="1 10 10" rpy="0.1 0.1 0.1"/></fistage:isolator>
  <fistage:isolator name="iso_c" parent="plate" child="shoe_c">
    <origin xyz="-0.05 0.05 -0.02"/><stiffness xyz="2e4 1e6 2e6" rpy="300 100 200"/><damping xyz="2 5 10" rpy="0.2 0.1 0.3"/></fistage:isolator>
  <fistage:isolator name="iso_b" parent="bracket" child="shoe_b">
    <origin xyz="0.01 -0.06 0.01" rpy="0.1 0 0.2"/><stiffness xyz="1e4 2e6 3e6" rpy="100 200 300"/><damping xyz="1 2 3" rpy="0.1 0.2 0.3"/></fistage:isolator>
  <fistage:isolator name="iso_pc" parent="plate" child="carriage">
    <origin xyz="-0.1 0 0.01" rpy="0 0.3 0"/><stiffness xyz="5e3 5e4 5e4" rpy="50 60 70"/><damping xyz="3 4 5" rpy="0.3 0.4 0.5"/></fistage:isolator>
  <fistage:isolator name="iso_wc" parent="world" child="carriage">
    <origin xyz="-0.12 0.03 0.05" rpy="0 0.2 0.1"/><stiffness xyz="1e3 2e3 3e3" rpy="10 20 30"/><damping xyz="1 1 1" rpy="0.1 0.1 0.1"/></fistage:isolator>
  <fistage:isolator name="iso_pc2" parent="plate" child="carriage">
    <origin xyz="-0.08 0.03 0.0" rpy="0 0.3 0"/><stiffness xyz="4e3 3e4 6e4" rpy="40 30 20"/><damping xyz="2 3 4" rpy="0.2 0.3 0.4"/></fistage:isolator>
  <fistage:isolator name="iso_wa" parent="world" child="shoe_a">
    <origin xyz="0.12 0.05 0.01" rpy="0.1 -0.2 0"/><stiffness xyz="500 1e3 2e3" rpy="5 6 7"/><damping xyz="0.5 1 1" rpy="0.1 0.1 0.1"/></fistage:isolator>
  <fistage:isolator name="iso_cw" parent="shoe_c" child="world">
    <origin xyz="0.01 0 0.02"/><stiffness xyz="700 800 900" rpy="8 9 10"/><damping xyz="0.7 0.8 0.9" rpy="0.1 0.1 0.1"/></fistage:isolator>
  <fistage:isolator name="iso_bc" parent="shoe_b" child="carriage">
    <origin xyz="-0.05 0.02 0.03" rpy="0 0 -0.4"/><stiffness xyz="2e3 3e3 4e3" rpy="20 30 40"/><damping xyz="1 2 3" rpy="0.1 0.2 0.3"/></fistage:isolator>
  <fistage:isolator name="iso_cs" parent="carriage" child="shoe_c">
    <origin xyz="0.02 0.01 -0.03"/><stiffness xyz="1e3 2e3 3e3" rpy="10 20 30"/><damping xyz="1 1 1" rpy="0.1 0.1 0.1"/></fistage:isolator>
  <fistage:isolator name="iso_cp" parent="carriage" child="puck">
    <origin xyz="-0.03 -0.04 0"/><stiffness xyz="3e3 2e3 1e3" rpy="30 20 10"/><damping xyz="1 1 1" rpy="0.1 0.1 0.1"/></fistage:isolator>
  <fistage:isolator name="iso_ab" parent="shoe_a" child="shoe_b">
    <origin xyz="0 -0.05 0" rpy="0.2 0 0"/><stiffness xyz="1e3 1e3 1e3" rpy="10 10 10"/><damping xyz="1 1 1" rpy="0.1 0.1 0.1"/></fistage:isolator>
  <fistage:friction name="friction_a" link="shoe_a"><origin xyz="0 0 -0.007"/><axis xyz="1 0 0"/>
    <lugre sigma0="5.5e5" sigma1="59.25" sigma2="3.55" f_c="1.275" f_s="1.625" v_s="0.0167"/></fistage:friction>
  <fistage:friction name="friction_b" link="shoe_b"><origin xyz="0 0 -0.007"/><axis xyz="0.6 0.8 0"/>
    <lugre sigma0="4e5" sigma1="50" sigma2="3" f_c="1" f_s="1.4" v_s="0.02"/></fistage:friction>
  <fistage:friction name="friction_carriage" link="carriage"><origin xyz="0.01 0.02 -0.03"/><axis xyz="1 0 0"/>
    <lugre sigma0="3e5" sigma1="40" sigma2="2" f_c="0.8" f_s="1.1" v_s="0.01"/></fistage:friction>
  <fistage:friction name="friction_plate" link="plate"><origin xyz="0.02 -0.03 -0.02"/><axis xyz="0 1 0"/>
    <lugre sigma0="2e5" sigma1="30" sigma2="1" f_c="0.5" f_s="0.7" v_s="0.015"/></fistage:friction>
  <fistage:actuator name="drive" link="bracket"><origin xyz="0.02 0 0.01"/><axis xyz="1 0.1 0"/></fistage:actuator>
  <fistage:actuator name="push" link="shoe_b"><origin xyz="0 0 0"/><axis xyz="0.6 0.8 0"/></fistage:actuator>
  <fistage:sensor name="encoder" link="plate"><origin xyz="0.03 -0.01 0.02"/><axis xyz="1 0 0"/></fistage:sensor>
  <fistage:sensor name="rail_encoder" link="shoe_b"><origin xyz="0.01 0 0"/><axis xyz="0.6 0.8 0"/></fistage:sensor>
</robot>"#;

/// The rooted-bodies fast path gives the general recursive dynamics' state
/// derivative at random states (large rotations, unnormalised quaternions,
/// fast spins), with the servo on a floating body and on a rail body.
#[test]
fn rooted_fast_path_matches_the_general_dynamics() {
    let servo = |sensor: &str, actuator: &str, k_i: f64| {
        format!(
            "[controller]\nsensor = \"{sensor}\"\nactuator = \"{actuator}\"\nk = 5e4\nc = 80\nk_i = {k_i}\n"
        )
    };
    for controller in [
        servo("encoder", "drive", 2e5),
        servo("rail_encoder", "push", 2e5),
        servo("encoder", "push", 0.0),
        servo("encoder", "drive", 2e5)
            + "[compensation]\nkind = \"lugre\"\nelement = \"friction_a\"\n[dob]\nbandwidth = 30.0\nnominal_mass = 2.0\n",
        servo("rail_encoder", "push", 0.0)
            + "[compensation]\nkind = \"dahl\"\nelement = \"friction_b\"\nisolator = \"static\"\nerror = { sigma = 0.3 }\n",
        String::new(),
    ] {
        let model = model_from(
            ROOTED,
            &format!("robot = \"x\"\nduration = 1\n{controller}"),
        );
        assert_eq!(model.evaluation_path(), EvaluationPath::RootedBodies);
        let mut ws = model.workspace();
        let mut rng = SplitMix(23);
        let n = model.n_states();
        let (mut fast, mut general) = (vec![0.0; n], vec![0.0; n]);
        for _ in 0..300 {
            let x: Vec<f64> = model
                .layout()
                .kinds
                .iter()
                .map(|kind| match kind {
                    StateKind::Quaternion => rng.range(-1.2, 1.2),
                    StateKind::AngularVelocity => rng.range(-3.0, 3.0),
                    StateKind::LinearVelocity => rng.range(-0.1, 0.1),
                    StateKind::Bristle => rng.range(-5e-6, 5e-6),
                    _ => rng.range(-0.01, 0.01),
                })
                .collect();
            let inputs = Inputs {
                reference: ReferenceSample {
                    position: rng.range(-0.01, 0.01),
                    velocity: rng.range(-0.02, 0.02),
                },
                servo_force: rng.range(-1.0, 1.0),
                platform_velocity: rng.range(-0.03, 0.03),
            };
            model.rhs(&x, &inputs, &mut fast, &mut ws);
            model.rhs_general(&x, &inputs.values(), &mut general, &mut ws);
            // Round-off of an entry scales with the largest entry of its kind.
            let kinds = &model.layout().kinds;
            let scale = |kind: StateKind| {
                general
                    .iter()
                    .zip(kinds)
                    .filter(|(_, k)| **k == kind)
                    .fold(0.0f64, |m, (v, _)| m.max(v.abs()))
            };
            for (i, (a, b)) in fast.iter().zip(&general).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-10 * a.abs().max(b.abs()) + 1e-13 * scale(kinds[i]),
                    "{}: fast path {a} vs general {b}",
                    model.layout().names[i]
                );
            }
        }
    }
}

/// The four-bearing stage and the free body take the rooted fast path; a
/// body on a body does not.
#[test]
fn evaluation_paths_follow_the_structure() {
    assert_eq!(
        load("scenarios/coupling/friction20_traverse.toml")
            .model
            .evaluation_path(),
        EvaluationPath::RootedBodies
    );
    assert_eq!(free_body().evaluation_path(), EvaluationPath::RootedBodies);
    assert_eq!(
        load("scenarios/paper/fig05b_fi.toml")
            .model
            .evaluation_path(),
        EvaluationPath::ConstantJacobian
    );
    let pendulum = model_from(CART_PENDULUM, "robot = \"x\"\nduration = 1\n");
    assert_eq!(pendulum.evaluation_path(), EvaluationPath::General);
    // The general path compiles too, and its machine code gives its numbers.
    let native = fistage_codegen::machine_code(&pendulum, fistage_codegen::Function::Rhs)
        .expect("the general path compiles");
    let mut rng = SplitMix(11);
    let inputs = fistage_model::InputValues {
        reference_position: 0.0,
        reference_velocity: 0.0,
        servo_force: 0.3,
        platform_velocity: 0.0,
    };
    let n = pendulum.n_states();
    let mut ws = pendulum.workspace();
    for _ in 0..50 {
        let x: Vec<f64> = pendulum
            .zero_state()
            .iter()
            .map(|zero| zero + rng.range(-0.01, 0.01))
            .collect();
        let (mut compiled, mut generic) = (vec![0.0; n], vec![0.0; n]);
        pendulum.rhs_of(&x, &inputs, &mut generic, &mut ws);
        if native.rhs(&x, &inputs, &mut compiled).is_ok() {
            assert_eq!(compiled, generic);
        }
    }
    let wheel = r#"<robot name="wheel"><link name="world"/>
      <link name="wheel"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.02"/></inertial></link>
      <joint name="spin" type="continuous"><parent link="world"/><child link="wheel"/><axis xyz="0 0 1"/></joint>
    </robot>"#;
    let wheel = model_from(wheel, "robot = \"x\"\nduration = 1\n");
    assert_eq!(wheel.evaluation_path(), EvaluationPath::General);
}
