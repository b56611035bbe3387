//! The shared library's C face: exactly the 44 FMI 2.0 symbols (common,
//! Model Exchange and Co-Simulation), and a generated header that agrees, function by function, with
//! the official FMI 2.0 headers as FMPy ships them.

mod support;

use std::process::Command;

/// The FMI 2.0 functions (common, Model Exchange and Co-Simulation).
const FMI2_FUNCTIONS: [&str; 44] = [
    "fmi2GetTypesPlatform",
    "fmi2GetVersion",
    "fmi2SetDebugLogging",
    "fmi2Instantiate",
    "fmi2FreeInstance",
    "fmi2SetupExperiment",
    "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode",
    "fmi2Terminate",
    "fmi2Reset",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
    "fmi2GetFMUstate",
    "fmi2SetFMUstate",
    "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize",
    "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
    "fmi2EnterEventMode",
    "fmi2NewDiscreteStates",
    "fmi2EnterContinuousTimeMode",
    "fmi2CompletedIntegratorStep",
    "fmi2SetTime",
    "fmi2SetContinuousStates",
    "fmi2GetDerivatives",
    "fmi2GetEventIndicators",
    "fmi2GetContinuousStates",
    "fmi2GetNominalsOfContinuousStates",
];

#[test]
fn library_exports_exactly_the_44_fmi2_functions() {
    let output = Command::new("nm")
        .args(["-D", "--defined-only"])
        .arg(support::library())
        .output()
        .expect("run nm");
    assert!(output.status.success());
    let mut exported: Vec<String> = String::from_utf8_lossy(&output.stdout)
        .lines()
        .filter_map(|line| {
            let fields: Vec<&str> = line.split_whitespace().collect();
            (fields.len() == 3 && fields[1] == "T").then(|| fields[2].to_string())
        })
        .collect();
    exported.sort();
    let mut expected: Vec<String> = FMI2_FUNCTIONS.iter().map(|s| s.to_string()).collect();
    expected.sort();
    assert_eq!(exported, expected);
}

#[test]
fn header_matches_the_official_function_types_under_werror() {
    if !support::fmpy_available("header_matches_the_official_function_types_under_werror") {
        return;
    }
    let root = support::root();
    let folder = support::scratch("c_abi");
    let source = root.join("ffi/tests/c/assign_types.c");
    let text = std::fs::read_to_string(&source).expect("C source");
    for name in FMI2_FUNCTIONS {
        assert!(
            text.contains(&format!("CHECK({name})")),
            "{name} is checked"
        );
    }
    let library = support::library();
    let program = folder.join("assign_types");
    let output = Command::new("cc")
        .args(["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror"])
        .arg("-I")
        .arg(support::fmi_headers())
        .arg("-I")
        .arg(root.join("ffi/include"))
        .arg(&source)
        .arg("-o")
        .arg(&program)
        .arg(&library)
        .output()
        .expect("run the C compiler");
    assert!(
        output.status.success(),
        "the header does not agree with the official FMI 2.0 types:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let run = Command::new(&program)
        .env("LD_LIBRARY_PATH", library.parent().expect("library folder"))
        .status()
        .expect("run the C program");
    assert!(
        run.success(),
        "fmi2GetVersion through the library returns \"2.0\""
    );
}
