//! Physics checks of the general assembly against closed-form results:
//! passivity of LuGre + isolator without servo, the steady-state friction curve
//! reached in simulation, a two-level prismatic tree, a pendulum on a cart (the
//! rotating, general path), and fixed-joint merging.

use fistage_model::{Inputs, assemble};
use fistage_sim::{AdaptiveEngine, Engine, Excitation, ScenarioExcitation};
use fistage_tests::{CART_PENDULUM, SplitMix, load, model_from, settings, still};

/// With no servo and no platform motion, kinetic + isolator + bristle energy
/// never increases (LuGre is dissipative while |z| <= g(v)).
#[test]
fn energy_never_increases_without_servo() {
    let loaded = load("scenarios/paper/fig05b_fi.toml");
    let mut scenario = loaded.scenario.clone();
    scenario.controller = None;
    let (_, model) = assemble(loaded.robot.clone(), &scenario).unwrap();
    let names = &model.layout().names;
    let index = |n: &str| names.iter().position(|s| s == n).unwrap();
    let mut rng = SplitMix(3);
    for _ in 0..4 {
        let mut x0 = model.zero_state();
        x0[index("table_x.q")] = rng.range(-2e-4, 2e-4);
        x0[index("table_x.v")] = rng.range(-0.08, 0.08);
        x0[index("bearing_x.v")] = rng.range(-0.08, 0.08);
        let trajectory = AdaptiveEngine::NATIVE
            .simulate(
                &model,
                &x0,
                &still(),
                &settings(0.5, 1e-4, 1e-10),
                &mut fistage_sim::no_progress,
            )
            .unwrap();
        let mut ws = model.workspace();
        let energies: Vec<f64> = (0..trajectory.len())
            .map(|k| model.stored_energy(trajectory.state(k), &mut ws))
            .collect();
        let initial = energies[0];
        assert!(initial > 1e-4, "test must start with energy, got {initial}");
        for (k, pair) in energies.windows(2).enumerate() {
            assert!(
                pair[1] <= pair[0] + 1e-9 * initial,
                "energy rose from {} to {} at t = {}",
                pair[0],
                pair[1],
                trajectory.times[k + 1]
            );
        }
        // And friction does dissipate: most of the energy is gone.
        assert!(energies[energies.len() - 1] < 0.2 * initial);
    }
}

/// A bearing pulled along at constant velocity by a stiff servo settles on
/// the steady-state friction force of Eq. 30.
#[test]
fn sliding_contact_reaches_eq30() {
    let loaded = load("scenarios/paper/fig05b_rigid.toml");
    let lugre = fistage_model::LugreParams::paper_table1();
    for platform_velocity in [-0.05, -0.004, 0.001, 0.0167, 0.03] {
        let excitation = ScenarioExcitation {
            reference: Default::default(),
            platform_velocity,
            servo_force: 0.0,
        };
        let model = &loaded.model;
        let trajectory = AdaptiveEngine::NATIVE
            .simulate(
                model,
                &model.zero_state(),
                &excitation,
                &settings(1.0, 1e-3, 1e-9),
                &mut fistage_sim::no_progress,
            )
            .unwrap();
        let mut ws = model.workspace();
        model.evaluate(trajectory.last_state(), &excitation.inputs(1.0), &mut ws);
        let force = ws.elements.friction_force[0];
        let slip = ws.elements.slip_velocity[0];
        assert!(
            (slip + platform_velocity).abs() < 1e-9,
            "stage must be at rest, slip {slip}"
        );
        let expected = lugre.steady_state_force(-platform_velocity);
        assert!(
            (force - expected).abs() < 1e-6 * expected.abs(),
            "v_p = {platform_velocity}: friction {force} vs Eq. 30 {expected}"
        );
        // The servo holds the friction: k x = -f_f at rest.
        let x = trajectory.last_state()[0];
        assert!((6e4 * x + force).abs() < 1e-6 * force.abs());
    }
}

const TWO_LEVEL: &str = r#"<robot name="two_level" xmlns:fistage="urn:fistage:urdf:1">
  <link name="world"/>
  <link name="carriage"><inertial><mass value="2.0"/><inertia ixx="1e-3" ixy="0" ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link>
  <link name="slider"><inertial><origin xyz="0.01 0.02 0.03"/><mass value="0.5"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <joint name="carriage_x" type="prismatic"><parent link="world"/><child link="carriage"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="slider_x" type="prismatic"><origin xyz="0 0 0.1" rpy="0 0 0"/><parent link="carriage"/><child link="slider"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <fistage:isolator name="ground_spring" parent="world" child="carriage"><stiffness xyz="800 0 0"/></fistage:isolator>
  <fistage:isolator name="slider_spring" parent="carriage" child="slider"><origin xyz="0 0 0.1"/><stiffness xyz="200 0 0"/></fistage:isolator>
</robot>"#;

/// A carriage on a prismatic joint carrying a second prismatic body, springs to
/// the world and between the two: free vibration equals the closed-form modal
/// solution of M x'' + K x = 0 in absolute coordinates.
#[test]
fn two_level_prismatic_tree_matches_modal_solution() {
    let model = model_from(
        TWO_LEVEL,
        "robot = \"x\"\nduration = 1.0\ngravity = [0, 0, -9.81]\n",
    );
    assert_eq!(model.layout().names[..2], ["carriage_x.q", "slider_x.q"]);
    let (m1, m2, k1, k2): (f64, f64, f64, f64) = (2.0, 0.5, 800.0, 200.0);
    // Modes of [[k1 + k2, -k2], [-k2, k2]] against diag(m1, m2).
    let a = m1 * m2;
    let b = -(m1 * k2 + m2 * (k1 + k2));
    let c = k1 * k2;
    let root = (b * b - 4.0 * a * c).sqrt();
    let omegas = [
        ((-b - root) / (2.0 * a)).sqrt(),
        ((-b + root) / (2.0 * a)).sqrt(),
    ];
    // Mode shape (1, r) with (k1 + k2 - m1 w^2) - k2 r = 0.
    let shapes: Vec<f64> = omegas.iter().map(|w| (k1 + k2 - m1 * w * w) / k2).collect();
    // Start at x1 = 1 mm, x2 = 0 (relative joint q2 = x2 - x1 = -1 mm), at rest.
    let (x1_0, x2_0) = (1e-3, 0.0);
    // x = A1 (1, r1) cos w1 t + A2 (1, r2) cos w2 t
    let amplitude2 = (x2_0 - shapes[0] * x1_0) / (shapes[1] - shapes[0]);
    let amplitude1 = x1_0 - amplitude2;
    let mut x0 = model.zero_state();
    x0[0] = x1_0;
    x0[1] = x2_0 - x1_0;
    let trajectory = AdaptiveEngine::NATIVE
        .simulate(
            &model,
            &x0,
            &still(),
            &settings(1.0, 1e-3, 1e-11),
            &mut fistage_sim::no_progress,
        )
        .unwrap();
    let mut worst = 0.0_f64;
    for (k, &t) in trajectory.times.iter().enumerate() {
        let x = trajectory.state(k);
        let (c1, c2) = ((omegas[0] * t).cos(), (omegas[1] * t).cos());
        let x1 = amplitude1 * c1 + amplitude2 * c2;
        let x2 = amplitude1 * shapes[0] * c1 + amplitude2 * shapes[1] * c2;
        worst = worst.max((x[0] - x1).abs()).max((x[0] + x[1] - x2).abs());
    }
    assert!(
        worst < 1e-11,
        "largest deviation from closed form {worst} m"
    );
}

/// A point-mass pendulum on a free cart (revolute joint below a prismatic one:
/// the general, rotating path). Small swings oscillate at
/// w^2 = g (M + m) / (M L), and the cart's horizontal momentum is conserved.
#[test]
fn pendulum_on_free_cart_matches_closed_form() {
    let model = model_from(CART_PENDULUM, "robot = \"x\"\nduration = 1.0\n");
    let (cart, bob, length, g): (f64, f64, f64, f64) = (3.0, 0.7, 0.4, 9.81);
    let omega = (g * (cart + bob) / (cart * length)).sqrt();
    let amplitude = 1e-3;
    let mut x0 = model.zero_state();
    x0[1] = amplitude;
    // Start with zero horizontal momentum: the cart's offset does not matter.
    let t_end = 3.0;
    let trajectory = AdaptiveEngine::NATIVE
        .simulate(
            &model,
            &x0,
            &still(),
            &settings(t_end, 1e-3, 1e-11),
            &mut fistage_sim::no_progress,
        )
        .unwrap();
    let mut worst_angle = 0.0_f64;
    let mut worst_momentum = 0.0_f64;
    for (k, &t) in trajectory.times.iter().enumerate() {
        let x = trajectory.state(k);
        worst_angle = worst_angle.max((x[1] - amplitude * (omega * t).cos()).abs());
        // Bob at x_cart - L sin(theta): momentum (M + m) v_cart - m L cos(theta) theta'.
        let momentum = (cart + bob) * x[2] - bob * length * x[1].cos() * x[3];
        worst_momentum = worst_momentum.max(momentum.abs());
    }
    // Nonlinear terms are O(amplitude^3): relative 1e-6 of the amplitude.
    assert!(
        worst_angle < 2e-3 * amplitude,
        "angle deviates by {worst_angle} rad"
    );
    assert!(
        worst_momentum < 1e-12,
        "momentum drifts by {worst_momentum}"
    );
}

const MERGED: &str = r#"<robot name="merged" xmlns:fistage="urn:fistage:urdf:1">
  <link name="world"/>
  <link name="base"><inertial><origin xyz="0.1 0 0"/><mass value="1.0"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link>
  <link name="bracket"><inertial><origin xyz="0 0.05 0" rpy="0 0 1.5707963267948966"/><mass value="2.0"/><inertia ixx="0.004" ixy="0" ixz="0" iyy="0.003" iyz="0" izz="0.002"/></inertial></link>
  <link name="tip"><inertial><mass value="0.5"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <joint name="spin" type="continuous"><parent link="world"/><child link="base"/><axis xyz="0 0 1"/></joint>
  <joint name="weld1" type="fixed"><origin xyz="0.2 0 0"/><parent link="base"/><child link="bracket"/></joint>
  <joint name="weld2" type="fixed"><origin xyz="0 0.3 0" rpy="0 0 1.5707963267948966"/><parent link="bracket"/><child link="tip"/></joint>
  <fistage:actuator name="push" link="tip"><origin xyz="0.1 0 0"/><axis xyz="0 1 0"/></fistage:actuator>
</robot>"#;

/// Fixed joints merge links into one body with mass, centre of mass and inertia
/// combined about the merged frame, and elements on a merged link act at the
/// right place: a force on the tip spins the body at tau / I_zz(pivot).
#[test]
fn fixed_joints_merge_inertia_correctly() {
    let model = model_from(MERGED, "robot = \"x\"\nduration = 1.0\n");
    assert_eq!(model.bodies().len(), 1);
    let body = &model.bodies()[0];
    assert_eq!(body.links, ["base", "bracket", "tip"]);
    // Centres of mass in the base frame: base (0.1, 0, 0), bracket (0.2, 0.05, 0), tip (0.2, 0.3, 0).
    let parts = [(1.0, [0.1, 0.0]), (2.0, [0.2, 0.05]), (0.5, [0.2, 0.3])];
    let mass: f64 = parts.iter().map(|p| p.0).sum();
    let com_x = parts.iter().map(|p| p.0 * p.1[0]).sum::<f64>() / mass;
    let com_y = parts.iter().map(|p| p.0 * p.1[1]).sum::<f64>() / mass;
    assert!((body.mass - 3.5).abs() < 1e-12);
    assert!((body.com.x - com_x).abs() < 1e-12 && (body.com.y - com_y).abs() < 1e-12);
    // Bracket inertia rotated 90 degrees about z swaps ixx and iyy.
    let own_zz = 0.03 + 0.002;
    let izz_about_com = own_zz
        + parts
            .iter()
            .map(|(m, c)| m * ((c[0] - com_x).powi(2) + (c[1] - com_y).powi(2)))
            .sum::<f64>();
    assert!((body.inertia[(2, 2)] - izz_about_com).abs() < 1e-12);
    let ixx_about_com = 0.01
        + 0.003
        + parts
            .iter()
            .map(|(m, c)| m * (c[1] - com_y).powi(2))
            .sum::<f64>();
    assert!(
        (body.inertia[(0, 0)] - ixx_about_com).abs() < 1e-12,
        "{}",
        body.inertia
    );
    // The tip frame is the bracket frame (base + (0.2, 0, 0)) moved by (0, 0.3, 0) and
    // turned 90 degrees about z. The actuator point (0.1, 0, 0) in the tip frame is
    // (0.2, 0.4, 0) in the base frame, and its axis (0, 1, 0) is (-1, 0, 0):
    // torque about z per newton = 0.2 * 0 - 0.4 * (-1) = 0.4 N m.
    let izz_pivot = izz_about_com + mass * (com_x * com_x + com_y * com_y);
    let mut ws = model.workspace();
    let mut dx = vec![0.0; model.n_states()];
    let inputs = Inputs {
        servo_force: 2.0,
        ..Inputs::default()
    };
    model.rhs(&model.zero_state(), &inputs, &mut dx, &mut ws);
    let expected = 2.0 * 0.4 / izz_pivot;
    assert!((dx[1] - expected).abs() < 1e-12, "{} vs {expected}", dx[1]);
}

/// Staircase tracking of the rigid stage (Table 1 friction): a PD servo
/// stops each 50 um step short by a stiction offset of order f / k (here
/// micrometres), so no step settles into +-50 nm; integral action removes the
/// offset and every step settles, later for a weaker integral gain.
#[test]
fn integral_action_lets_staircase_steps_settle() {
    let settle = |k_i: f64| {
        let text = format!(
            "robot = {:?}\nduration = 1.6\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 1e6\nc = 2000\nk_i = {k_i:?}\n\
             [reference]\nkind = \"staircase\"\nstep = 50e-6\nmove_time = 0.05\ndwell = 0.35\nsteps = 4\n",
            fistage_tests::path("robots/stage_1dof_rigid.urdf")
                .display()
                .to_string()
        );
        let loaded = fistage_tests::load_text(&text);
        let output =
            fistage_sim::run_scenario(&loaded, &mut fistage_sim::no_progress).expect("run");
        output
            .tracking
            .expect("a servo")
            .settling
            .expect("a staircase")
    };
    let pd = settle(0.0);
    assert_eq!((pd.unsettled, pd.times.values.len()), (4, 0), "{pd:?}");
    let strong = settle(5e8);
    let weak = settle(1e8);
    assert_eq!(strong.unsettled, 0, "{strong:?}");
    assert_eq!(weak.unsettled, 0, "{weak:?}");
    let (s, w) = (
        strong.times.mean.expect("mean"),
        weak.times.mean.expect("mean"),
    );
    println!("mean settling: k_i = 5e8: {s:.4} s, k_i = 1e8: {w:.4} s");
    assert!(s < w && s > 0.0, "{s} vs {w}");
}

/// The sensors' readings from the kinematics alone (what a population's
/// verdict reads at every sample) equal those of the whole evaluation, on
/// the one-axis FI stage and the 6-DOF four-bearing stage, at states away
/// from the zero configuration.
#[test]
fn sensor_readings_from_the_kinematics_equal_the_whole_evaluations() {
    for file in [
        "scenarios/paper/fig05b_fi.toml",
        "scenarios/coupling/friction20_traverse.toml",
    ] {
        let loaded = fistage_tests::load(file);
        let model = &loaded.model;
        let mut ws = model.workspace();
        let mut rng = fistage_tests::SplitMix(11);
        let mut readings = vec![f64::NAN; model.sensors().len()];
        for _ in 0..50 {
            let x: Vec<f64> = (model.zero_state().iter())
                .map(|x0| x0 + rng.range(-1e-2, 1e-2))
                .collect();
            model.evaluate(&x, &fistage_model::Inputs::default(), &mut ws);
            let whole = ws.elements.sensor_position.clone();
            model.sensor_positions(&x, &mut readings, &mut ws);
            assert_eq!(readings, whole, "{file}");
            assert!(whole.iter().any(|r| r.abs() > 1e-4), "{file}: {whole:?}");
        }
    }
}
