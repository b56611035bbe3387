//! Any bytes as a robot file: a clear error or a robot, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = fistage_model::RobotSpec::from_str(text, std::path::Path::new("fuzz.urdf"));
    }
});
