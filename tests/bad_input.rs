//! Bad robot and scenario files fail with a message naming the file, the
//! element or key, and the reason.

use std::path::{Path, PathBuf};

use fistage_model::{LoadError, RobotSpec, Scenario, assemble};
use fistage_tests::path;

fn shipped_robot() -> String {
    std::fs::read_to_string(path("robots/stage_1dof_fi.urdf")).expect("robot")
}

fn robot_error(xml: &str) -> String {
    match RobotSpec::from_str(xml, Path::new("robots/bad.urdf")) {
        Ok(robot) => {
            let scenario = Scenario::from_str("robot = \"x\"\nduration = 1\n", Path::new("s.toml"))
                .expect("scenario");
            assemble(robot, &scenario)
                .expect_err("must fail")
                .to_string()
        }
        Err(e) => e.to_string(),
    }
}

fn scenario_error(toml: &str) -> String {
    let robot = RobotSpec::from_str(&shipped_robot(), Path::new("robots/stage_1dof_fi.urdf"))
        .expect("robot");
    match Scenario::from_str(toml, Path::new("scenarios/bad.toml")) {
        Ok(scenario) => assemble(robot, &scenario)
            .expect_err("must fail")
            .to_string(),
        Err(e) => e.to_string(),
    }
}

fn assert_mentions(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(message.contains(part), "message {message:?} lacks {part:?}");
    }
}

#[test]
fn negative_mass_is_named() {
    let xml = shipped_robot().replacen("<mass value=\"0.5\"/>", "<mass value=\"-0.5\"/>", 1);
    let e = robot_error(&xml);
    assert_eq!(
        e,
        "robots/bad.urdf: link \"bearing\": mass must be >= 0, got -0.5"
    );
}

#[test]
fn non_positive_sigma0_is_named() {
    let xml = shipped_robot().replace("sigma0=\"2.2e6\"", "sigma0=\"0\"");
    let e = robot_error(&xml);
    assert_mentions(
        &e,
        &[
            "robots/bad.urdf",
            "friction \"bearing_friction\"",
            "sigma0 must be > 0, got 0",
        ],
    );
    let e =
        scenario_error("robot = \"x\"\nduration = 1\n[overrides.bearing_friction]\nsigma0 = -3\n");
    assert_eq!(
        e,
        "scenarios/bad.toml: overrides.bearing_friction.sigma0: sigma0 must be > 0, got -3"
    );
}

#[test]
fn friction_on_a_missing_link_is_named() {
    let xml = shipped_robot().replace(
        "<fistage:friction name=\"bearing_friction\" link=\"bearing\">",
        "<fistage:friction name=\"bearing_friction\" link=\"bearng\">",
    );
    let e = robot_error(&xml);
    assert_mentions(
        &e,
        &[
            "robots/bad.urdf",
            "friction \"bearing_friction\"",
            "link \"bearng\" does not exist",
        ],
    );
}

#[test]
fn missing_elements_are_named() {
    let xml = shipped_robot().replace("<axis xyz=\"1 0 0\"/>\n    <lugre", "<lugre");
    assert_mentions(
        &robot_error(&xml),
        &["friction \"bearing_friction\"", "missing <axis"],
    );
    let xml = shipped_robot().replace(
        "<lugre sigma0=\"2.2e6\" sigma1=\"237\"",
        "<lugre sigma0=\"2.2e6\"",
    );
    assert_mentions(
        &robot_error(&xml),
        &[
            "friction \"bearing_friction\"",
            "missing attribute \"sigma1\"",
        ],
    );
    let e = scenario_error(
        "robot = \"x\"\nduration = 1\n[controller]\nsensor = \"encodr\"\nactuator = \"drive\"\nk = 1\nc = 1\n",
    );
    assert_mentions(
        &e,
        &[
            "scenarios/bad.toml",
            "controller.sensor",
            "no sensor named \"encodr\"",
            "encoder",
        ],
    );
    let e = scenario_error("robot = \"x\"\n");
    assert_mentions(&e, &["scenarios/bad.toml", "missing field `duration`"]);
    let e = scenario_error(
        "robot = \"x\"\nduration = 1\n[controller]\nsensor = \"encoder\"\nk = 1\nc = 1\n",
    );
    assert_mentions(&e, &["scenarios/bad.toml", "missing field `actuator`"]);
    let xml = shipped_robot().replace("<link name=\"world\"/>", "");
    assert_mentions(
        &robot_error(&xml),
        &["robots/bad.urdf", "no link named \"world\""],
    );
}

#[test]
fn unknown_keys_are_named() {
    let e = scenario_error(
        "robot = \"x\"\nduration = 1\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 1\nc = 1\nkd = 3\n",
    );
    assert_mentions(&e, &["scenarios/bad.toml", "kd"]);
    let e = scenario_error("robot = \"x\"\nduration = 1\n[overrides.bearing_friction]\nmu = 0.3\n");
    assert_mentions(&e, &["overrides.bearing_friction.mu", "sigma0, sigma1"]);
    let e = scenario_error("robot = \"x\"\nduration = 1\n[overrides.no_such_bearing]\nf_c = 3\n");
    assert_mentions(
        &e,
        &["overrides.no_such_bearing", "no element or link named"],
    );
    let xml = shipped_robot().replace(
        "<stiffness xyz=\"40000 0 0\" rpy=\"0 0 0\"/>",
        "<stiffness xyz=\"40000 0 0\" rpy=\"0 0 0\" units=\"N/m\"/>",
    );
    assert_mentions(
        &robot_error(&xml),
        &["isolator \"isolator\"", "unknown attribute \"units\""],
    );
    let xml = shipped_robot()
        .replace(
            "<fistage:sensor name=\"encoder\"",
            "<fistage:probe name=\"encoder\"",
        )
        .replace("</fistage:sensor>", "</fistage:probe>");
    assert_mentions(&robot_error(&xml), &["fistage:probe", "unknown element"]);
}

#[test]
fn malformed_files_are_named_with_position() {
    let xml = shipped_robot().replace("</robot>", "");
    let e = robot_error(&xml);
    assert_mentions(&e, &["robots/bad.urdf", "malformed XML"]);
    let e = scenario_error("robot = \"x\"\nduration = = 1\n");
    assert_mentions(&e, &["scenarios/bad.toml", "line 2"]);
}

#[test]
fn missing_files_and_bad_trees_are_named() {
    let dir = std::env::temp_dir().join(format!("fistage-bad-input-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let scenario: PathBuf = dir.join("s.toml");
    std::fs::write(&scenario, "robot = \"missing.urdf\"\nduration = 1\n").expect("write");
    let e = fistage_model::load(&scenario).expect_err("must fail");
    assert!(matches!(e, LoadError::Io { .. }));
    assert_mentions(&e.to_string(), &["missing.urdf", "cannot read"]);
    std::fs::remove_dir_all(&dir).ok();

    // A link not connected to the world.
    let xml = shipped_robot().replace(
        "<parent link=\"world\"/>\n    <child link=\"bearing\"/>",
        "<parent link=\"bearing\"/>\n    <child link=\"bearing\"/>",
    );
    let e = robot_error(&xml);
    assert_mentions(&e, &["link \"bearing\""]);
    // A moving link without mass.
    let xml = shipped_robot().replacen("<mass value=\"1.0\"/>", "<mass value=\"0\"/>", 1);
    assert_mentions(&robot_error(&xml), &["link \"table\"", "no mass"]);
}

#[test]
fn unknown_output_signal_is_named_before_the_run() {
    let mut loaded = fistage_tests::load("scenarios/paper/fig05b_fi.toml");
    loaded.scenario.signals = Some(vec!["encoder.position".into(), "encoder.jerk".into()]);
    loaded.scenario.duration = 1e6; // would take hours if it ran first
    let error = fistage_sim::run_scenario(&loaded, &mut fistage_sim::no_progress)
        .expect_err("must fail")
        .to_string();
    assert_mentions(
        &error,
        &[
            "fig05b_fi.toml",
            "output.signals",
            "encoder.jerk",
            "encoder.velocity",
        ],
    );
}

/// Names become CSV headers, signal and FMI names: a comma, a quote or an
/// empty name is refused, naming the element.
#[test]
fn unusable_names_are_named() {
    for (from, to, element) in [
        (
            "name=\"bearing_friction\"",
            "name=\"bearing,friction\"",
            "friction \"bearing,friction\"",
        ),
        ("name=\"encoder\"", "name=\"\"", "sensor \"\""),
        ("name=\"drive\"", "name=\"dr&quot;ive\"", "actuator"),
    ] {
        let xml = shipped_robot().replacen(from, to, 1);
        let message = robot_error(&xml);
        assert_mentions(&message, &["robots/bad.urdf", element, "unusable name"]);
    }
}

/// The fistage prefix bound to another namespace is an error, not a file
/// whose isolator and friction silently vanish.
#[test]
fn fistage_prefix_of_another_namespace_is_an_error() {
    let xml = shipped_robot().replace(
        "xmlns:fistage=\"urn:fistage:urdf:1\"",
        "xmlns:fistage=\"urn:vendor:stage\"",
    );
    assert_mentions(&robot_error(&xml), &["robots/bad.urdf", "urn:vendor:stage"]);
}

/// A file nested 20 000 deep is refused before any parser recurses into it.
#[test]
fn deep_nesting_is_refused_before_parsing() {
    let deep = format!(
        "<robot name=\"x\">{}{}</robot>",
        "<a>".repeat(20_000),
        "</a>".repeat(20_000)
    );
    assert_mentions(
        &robot_error(&deep),
        &["robots/bad.urdf", "nested more than"],
    );
}

/// What the adversarial campaign (`tests/adversarial/campaign.py`) found
/// accepted, or refused without naming the culprit, each now a clear error
/// naming the key, element, attribute or line.
#[test]
fn campaign_findings_are_refused_by_name() {
    let base = "robot = \"r.urdf\"\nduration = 1\n";
    for (extra, needles) in [
        (
            "[statistics]\nwindow = [0.1, 0.2, 0.3]\n",
            &["statistics.window", "3 values"][..],
        ),
        ("[overrides.nope]\n", &["overrides.nope", "empty table"]),
        (
            "[overrides.world]\nmass = 1\n",
            &["overrides.world", "does not move"],
        ),
        (
            "[reference]\nkind = \"ramp\"\nvelocity = \"\"\n",
            &["reference.velocity", "must be a number"],
        ),
        (
            "[reference]\nkind = \"ramp\"\nspeed = 1\n",
            &["reference.speed", "unknown key"],
        ),
        (
            "[reference]\nkind = \"step\"\nvalue = 1\n",
            &["reference.time", "missing"],
        ),
        ("[solver]\nrtol = 1e-300\n", &["solver.rtol", "1e-14"]),
        (
            "[solver]\nmax_step = 1e-300\n",
            &["solver.max_step", "at least 1e-18"],
        ),
        (
            "[platform]\nvelocity = 1e300\n",
            &["platform.velocity", "at most 1e18"],
        ),
        (
            "[initial]\n\"bearing_friction.z\" = 1e300\n",
            &["initial.bearing_friction.z", "at most 1e18"],
        ),
    ] {
        let message = scenario_error(&format!("{base}{extra}"));
        assert_mentions(&message, needles);
    }
    let message = scenario_error("robot = \"\"\nduration = 1\n");
    assert_mentions(&message, &["robot", "empty"]);
    for (from, to, needles) in [
        (
            "<joint name=\"table_x\" type=\"prismatic\">",
            "<joint name=\"table_x\" type=\"prismatic\"><limit lower=\"NaN\" upper=\"1\" effort=\"1\" velocity=\"1\"/>",
            &["joint \"table_x\"", "lower=\"NaN\"", "line"][..],
        ),
        (
            "<robot name=\"stage_1dof_fi\"",
            "<robot name=\"\"",
            &["robot", "empty"],
        ),
        (
            "<mass value=\"0.5\"/>",
            "<mass value=\"abc\"/>",
            &["<mass value=\"abc\">", "a finite number"],
        ),
        (
            "<stiffness xyz=\"40000 0 0\" rpy=\"0 0 0\"/>",
            "<stiffness/>",
            &["stiffness", "neither xyz nor rpy"],
        ),
    ] {
        let xml = shipped_robot().replacen(from, to, 1);
        assert!(xml != shipped_robot(), "{from} is in the shipped robot");
        assert_mentions(&robot_error(&xml), needles);
    }
    let misspelt = shipped_robot()
        .replacen("<robot ", "<robbot ", 1)
        .replace("</robot>", "</robbot>");
    assert_mentions(&robot_error(&misspelt), &["root element must be <robot>"]);
    let device = RobotSpec::from_file(Path::new("/dev/zero")).expect_err("a device");
    assert_mentions(&device.to_string(), &["/dev/zero", "not a regular file"]);
}

/// A sweep whose simulated duration per point cannot fit in memory is
/// refused when read (it aborted with a failed allocation).
#[test]
fn a_sweep_duration_beyond_memory_is_refused() {
    let text = format!(
        "robot = {:?}\nduration = 1\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 1e5\nc = 100\n\
         [sweep]\nduration = 1e12\n[[sweep.axis]]\nparameter = \"controller.k\"\nfrom = 1e4\nto = 1e5\npoints = 2\n",
        path("robots/stage_1dof_fi.urdf").display().to_string()
    );
    let scenario = Scenario::from_str(&text, Path::new("sweep.toml")).expect("scenario");
    let error = fistage_analysis::sweep::SweepSpec::from_scenario(&scenario)
        .expect_err("refused")
        .to_string();
    assert_mentions(&error, &["sweep.duration", "samples per point"]);
}

/// A servo whose actuator pushes against its sensor's direction on the same
/// body is positive feedback: refused when the model is built, not found as
/// a collapsing step size half a second into the run.
#[test]
fn a_servo_with_opposite_axes_is_refused() {
    let xml = shipped_robot().replacen(
        "<fistage:actuator name=\"drive\" link=\"table\">\n    <origin xyz=\"0 0 0\"/>\n    <axis xyz=\"1 0 0\"/>",
        "<fistage:actuator name=\"drive\" link=\"table\">\n    <origin xyz=\"0 0 0\"/>\n    <axis xyz=\"-1 0 0\"/>",
        1,
    );
    assert!(xml != shipped_robot(), "the actuator's axis was flipped");
    let robot = RobotSpec::from_str(&xml, Path::new("robots/bad.urdf")).expect("robot");
    let scenario = Scenario::from_str(
        "robot = \"x\"\nduration = 1\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 6e4\nc = 100\n",
        Path::new("s.toml"),
    )
    .expect("scenario");
    let message = assemble(robot, &scenario).expect_err("refused").to_string();
    assert_mentions(
        &message,
        &["controller", "positive feedback", "encoder", "drive"],
    );
}

/// A singular force balance names the coordinate that nothing holds (a rail
/// turned into a hinge leaves its bearing free to swing).
#[test]
fn a_singular_balance_names_the_free_coordinate() {
    let xml = std::fs::read_to_string(path("robots/stage_4fi.urdf"))
        .expect("robot")
        .replacen(
            "<joint name=\"rail_fl\" type=\"prismatic\">",
            "<joint name=\"rail_fl\" type=\"revolute\">",
            1,
        );
    let robot = RobotSpec::from_str(&xml, Path::new("robots/hinge.urdf")).expect("robot");
    let scenario = Scenario::from_str(
        "robot = \"x\"\nduration = 1\nstart = \"static\"\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 6e4\nc = 100\n",
        Path::new("s.toml"),
    )
    .expect("scenario");
    let (_, model) = assemble(robot, &scenario).expect("model");
    let error = fistage_sim::initial_state(&model, &scenario)
        .expect_err("no static equilibrium")
        .to_string();
    assert_mentions(&error, &["singular", "rail_fl"]);
}

/// The circle and staircase references read their keys, and refuse bad ones
/// by name.
#[test]
fn circle_and_staircase_references_are_read_and_checked() {
    let base = "robot = \"r.urdf\"\nduration = 1\n";
    let read =
        |reference: &str| Scenario::from_str(&format!("{base}{reference}"), Path::new("s.toml"));
    let circle =
        read("[reference]\nkind = \"circle\"\nradius = 0.02\ntangential_velocity = 0.05\n")
            .expect("circle");
    assert_eq!(
        circle.reference,
        fistage_model::reference::Reference::Circle {
            radius: 0.02,
            tangential_velocity: 0.05
        }
    );
    let stairs = read(
        "[reference]\nkind = \"staircase\"\nstep = 50e-6\nmove_time = 0.05\ndwell = 0.2\nsteps = 4\nprofile = \"trapezoidal\"\n",
    )
    .expect("staircase");
    assert!((stairs.reference.sample(10.0).position - 200e-6).abs() < 1e-15);
    for (reference, needles) in [
        (
            "[reference]\nkind = \"circle\"\nradius = 0\ntangential_velocity = 0.05\n",
            &["reference.radius"][..],
        ),
        (
            "[reference]\nkind = \"circle\"\nradius = 0.02\n",
            &["reference.tangential_velocity", "missing"],
        ),
        (
            "[reference]\nkind = \"staircase\"\nstep = 1e-6\nmove_time = 0.1\ndwell = 0\nsteps = 2.5\n",
            &["reference.steps", "whole number"],
        ),
        (
            "[reference]\nkind = \"staircase\"\nstep = 1e-6\nmove_time = 0.1\ndwell = 0\nprofile = \"s-curve\"\n",
            &["reference.profile", "s-curve"],
        ),
        (
            "[reference]\nkind = \"staircase\"\nstep = 1e-6\nmove_time = 0.1\ndwell = -1\n",
            &["reference.dwell"],
        ),
    ] {
        let message = read(reference).expect_err("refused").to_string();
        assert_mentions(&message, needles);
    }
}

#[test]
fn a_visual_of_no_size_is_named_and_drawable_visuals_reach_the_model() {
    let robot = std::fs::read_to_string(path("robots/stage_4fi.urdf")).expect("robot");
    let bad = robot.replacen(
        "box size=\"0.15 0.15 0.0165\"",
        "box size=\"0.15 0 0.0165\"",
        1,
    );
    assert_mentions(
        &robot_error(&bad),
        &[
            "robots/bad.urdf",
            "link \"table\" visual 1",
            "positive and finite",
        ],
    );
    // The shipped stage's five boxes, each on the body of its link; a mesh
    // (not drawable) is left out.
    let with_mesh = robot.replacen(
        "<geometry><box size=\"0.15 0.15 0.0165\"/></geometry>\n    </visual>",
        "<geometry><box size=\"0.15 0.15 0.0165\"/></geometry>\n    </visual>\n    <visual><geometry><mesh filename=\"plate.stl\"/></geometry></visual>",
        1,
    );
    let spec = RobotSpec::from_str(&with_mesh, Path::new("robots/stage_4fi.urdf")).expect("robot");
    let scenario =
        Scenario::from_str("robot = \"x\"\nduration = 1\n", Path::new("s.toml")).expect("scenario");
    let (_, model) = assemble(spec, &scenario).expect("model");
    assert_eq!(model.visuals().len(), 5);
    for visual in model.visuals() {
        let fistage_model::Frame::Body(b) = visual.frame else {
            panic!("{} is on the world", visual.link);
        };
        assert_eq!(model.bodies()[b].name, visual.link);
    }
    assert_eq!(
        model.visuals()[0].shape,
        fistage_model::VisualShape::Box([0.15, 0.15, 0.0165])
    );
}
