//! The names of the files in an FMU's `resources/` folder, which packaging
//! writes and an instance reads.

/// The scenario's name inside `resources/`.
pub const SCENARIO_FILE: &str = "scenario.toml";
/// The robot's name inside `resources/`.
pub const ROBOT_FILE: &str = "robot.urdf";
/// A CSV reference's name inside `resources/`.
pub const REFERENCE_FILE: &str = "reference.csv";
