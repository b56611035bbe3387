//! Any bytes as a scenario file, assembled with the shipped 1-DOF stage: a
//! clear error or a model, never a panic.
#![no_main]

use std::path::Path;
use std::sync::OnceLock;

use fistage_model::{RobotSpec, Scenario, assemble};
use libfuzzer_sys::fuzz_target;

fn robot() -> &'static RobotSpec {
    static ROBOT: OnceLock<RobotSpec> = OnceLock::new();
    ROBOT.get_or_init(|| {
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/stage_1dof_fi.urdf");
        RobotSpec::from_file(&file).expect("the shipped robot loads")
    })
}

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data)
        && let Ok(scenario) = Scenario::from_str(text, Path::new("fuzz.toml"))
    {
        let _ = assemble(robot().clone(), &scenario);
    }
});
