//! Shared helpers for the cross-crate tests in `tests/`: locating the shipped
//! robots and scenarios, loading them, and running them.

use std::path::{Path, PathBuf};

use fistage_model::{Loaded, Model, RobotSpec, Scenario, assemble};
use fistage_sim::{RunOutput, ScenarioExcitation, SimSettings};

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A path below the repository root.
pub fn path(relative: &str) -> PathBuf {
    root().join(relative)
}

/// Loads a shipped scenario; panics with the loader's message on failure.
pub fn load(relative: &str) -> Loaded {
    fistage_model::load(&path(relative)).unwrap_or_else(|e| panic!("{e}"))
}

/// A scenario written as text (`robot` relative to the repository root)
/// with its robot, loaded; panics with the loader's message on failure.
pub fn load_text(text: &str) -> Loaded {
    let scenario =
        Scenario::from_str(text, &path("scenario.toml")).unwrap_or_else(|e| panic!("{e}"));
    let robot = RobotSpec::from_file(&scenario.robot).unwrap_or_else(|e| panic!("{e}"));
    let (robot, model) = assemble(robot, &scenario).unwrap_or_else(|e| panic!("{e}"));
    Loaded {
        scenario,
        robot,
        model,
    }
}

/// Runs a loaded scenario; panics with the engine's message on failure.
pub fn run(loaded: &Loaded) -> RunOutput {
    fistage_sim::run_scenario(loaded, &mut fistage_sim::no_progress)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Runs a loaded scenario on the engine named `engine` at `rtol`.
pub fn run_with(loaded: &Loaded, engine: &str, rtol: f64) -> RunOutput {
    let mut loaded = loaded.clone();
    loaded.scenario.solver.engine = engine.parse().expect("engine name");
    loaded.scenario.solver.rtol = rtol;
    run(&loaded)
}

/// Largest difference of a signal between two runs on the same grid,
/// relative to the reference's range over the whole run.
pub fn deviation(run: &RunOutput, reference: &RunOutput, signal: &str) -> f64 {
    let column = |r: &RunOutput| r.signals.column(signal).expect("signal").to_vec();
    let (a, b) = (column(run), column(reference));
    assert_eq!(a.len(), b.len());
    let range = b.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - b.iter().cloned().fold(f64::INFINITY, f64::min);
    a.iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / range
}

/// Steady-state peak-to-peak of a signal in a run.
pub fn peak_to_peak(output: &RunOutput, signal: &str) -> f64 {
    stats(output, signal).peak_to_peak
}

/// Steady-state statistics of a signal in a run.
pub fn stats(output: &RunOutput, signal: &str) -> fistage_sim::WindowStats {
    output
        .summary
        .iter()
        .find(|s| s.name == signal)
        .unwrap_or_else(|| panic!("no signal {signal}"))
        .stats
}

/// A small deterministic generator (SplitMix64) for random test states.
pub struct SplitMix(pub u64);

impl SplitMix {
    /// Next value, uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
}

/// A free rigid body with an offset, rotated centre of mass and a full
/// inertia tensor, on a floating joint, with one actuator.
pub const FREE_BODY: &str = r#"<robot name="free" xmlns:fistage="urn:fistage:urdf:1">
  <link name="world"/>
  <link name="block"><inertial><origin xyz="0.01 -0.02 0.005" rpy="0.3 -0.2 0.5"/><mass value="2.0"/>
    <inertia ixx="0.004" ixy="0.0003" ixz="-0.0002" iyy="0.006" iyz="0.0001" izz="0.009"/></inertial></link>
  <joint name="free" type="floating"><origin xyz="0.1 0.2 0.3" rpy="0.1 0.2 0.3"/><parent link="world"/><child link="block"/></joint>
  <fistage:actuator name="thruster" link="block"><origin xyz="0.05 0.01 -0.02"/><axis xyz="0.3 1 0.2"/></fistage:actuator>
</robot>"#;

/// A cart on a prismatic joint carrying a point-mass pendulum on a
/// continuous joint (a revolute joint below a prismatic one).
pub const CART_PENDULUM: &str = r#"<robot name="cart_pendulum">
  <link name="world"/>
  <link name="cart"><inertial><mass value="3.0"/><inertia ixx="1e-2" ixy="0" ixz="0" iyy="1e-2" iyz="0" izz="1e-2"/></inertial></link>
  <link name="rod"><inertial><origin xyz="0 0 -0.4"/><mass value="0.7"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <joint name="cart_x" type="prismatic"><parent link="world"/><child link="cart"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="swing" type="continuous"><origin xyz="0 0 0.05"/><parent link="cart"/><child link="rod"/><axis xyz="0 1 0"/></joint>
</robot>"#;

/// A model from robot XML and scenario TOML text; panics with the loader's message.
pub fn model_from(robot_xml: &str, scenario_toml: &str) -> Model {
    let robot =
        RobotSpec::from_str(robot_xml, Path::new("test.urdf")).unwrap_or_else(|e| panic!("{e}"));
    let scenario =
        Scenario::from_str(scenario_toml, Path::new("test.toml")).unwrap_or_else(|e| panic!("{e}"));
    assemble(robot, &scenario)
        .unwrap_or_else(|e| panic!("{e}"))
        .1
}

/// No reference, no platform motion, no external force.
pub fn still() -> ScenarioExcitation {
    ScenarioExcitation {
        reference: Default::default(),
        platform_velocity: 0.0,
        servo_force: 0.0,
    }
}

/// Integration settings: end time, output interval, relative tolerance.
pub fn settings(t_end: f64, sample_interval: f64, rtol: f64) -> SimSettings {
    SimSettings {
        t_end,
        sample_interval,
        rtol,
        atol_scale: 1.0,
        max_step: None,
        max_steps: 50_000_000,
    }
}
