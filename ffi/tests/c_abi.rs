//! The shared library's C face: exactly the 44 FMI 2.0 symbols (common,
//! Model Exchange and Co-Simulation) and the 75 of FMI 3.0, and generated
//! headers that agree, function by function, with the official FMI 2.0 and
//! 3.0 headers as FMPy ships them.

use crate::support;

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

/// The FMI 3.0 functions.
const FMI3_FUNCTIONS: [&str; 75] = [
    "fmi3GetVersion",
    "fmi3SetDebugLogging",
    "fmi3InstantiateModelExchange",
    "fmi3InstantiateCoSimulation",
    "fmi3InstantiateScheduledExecution",
    "fmi3FreeInstance",
    "fmi3EnterInitializationMode",
    "fmi3ExitInitializationMode",
    "fmi3EnterEventMode",
    "fmi3Terminate",
    "fmi3Reset",
    "fmi3GetFloat64",
    "fmi3SetFloat64",
    "fmi3GetFloat32",
    "fmi3SetFloat32",
    "fmi3GetInt8",
    "fmi3SetInt8",
    "fmi3GetUInt8",
    "fmi3SetUInt8",
    "fmi3GetInt16",
    "fmi3SetInt16",
    "fmi3GetUInt16",
    "fmi3SetUInt16",
    "fmi3GetInt32",
    "fmi3SetInt32",
    "fmi3GetUInt32",
    "fmi3SetUInt32",
    "fmi3GetInt64",
    "fmi3SetInt64",
    "fmi3GetUInt64",
    "fmi3SetUInt64",
    "fmi3GetBoolean",
    "fmi3SetBoolean",
    "fmi3GetString",
    "fmi3SetString",
    "fmi3GetBinary",
    "fmi3SetBinary",
    "fmi3GetClock",
    "fmi3SetClock",
    "fmi3GetNumberOfVariableDependencies",
    "fmi3GetVariableDependencies",
    "fmi3GetFMUState",
    "fmi3SetFMUState",
    "fmi3FreeFMUState",
    "fmi3SerializedFMUStateSize",
    "fmi3SerializeFMUState",
    "fmi3DeserializeFMUState",
    "fmi3GetDirectionalDerivative",
    "fmi3GetAdjointDerivative",
    "fmi3EnterConfigurationMode",
    "fmi3ExitConfigurationMode",
    "fmi3GetIntervalDecimal",
    "fmi3GetIntervalFraction",
    "fmi3GetShiftDecimal",
    "fmi3GetShiftFraction",
    "fmi3SetIntervalDecimal",
    "fmi3SetIntervalFraction",
    "fmi3SetShiftDecimal",
    "fmi3SetShiftFraction",
    "fmi3EvaluateDiscreteStates",
    "fmi3UpdateDiscreteStates",
    "fmi3EnterContinuousTimeMode",
    "fmi3CompletedIntegratorStep",
    "fmi3SetTime",
    "fmi3SetContinuousStates",
    "fmi3GetContinuousStateDerivatives",
    "fmi3GetEventIndicators",
    "fmi3GetContinuousStates",
    "fmi3GetNominalsOfContinuousStates",
    "fmi3GetNumberOfEventIndicators",
    "fmi3GetNumberOfContinuousStates",
    "fmi3EnterStepMode",
    "fmi3GetOutputDerivatives",
    "fmi3DoStep",
    "fmi3ActivateModelPartition",
];

#[test]
fn library_exports_exactly_the_fmi2_and_fmi3_functions() {
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
    let mut expected: Vec<String> = (FMI2_FUNCTIONS.iter().chain(&FMI3_FUNCTIONS))
        .map(|s| s.to_string())
        .collect();
    expected.sort();
    assert_eq!(exported, expected);
}

/// Compiles `source` (each of `functions` assigned to its official type)
/// with the official headers under -Werror, links it to the library and
/// runs it (it checks the version string).
fn compiles_against_the_official_headers(source: &str, functions: &[&str], program: &str) {
    let root = support::root();
    let folder = support::scratch(program);
    let source = root.join("ffi/tests/c").join(source);
    let text = std::fs::read_to_string(&source).expect("C source");
    for name in functions {
        assert!(
            text.contains(&format!("CHECK({name})")),
            "{name} is checked"
        );
    }
    let library = support::library();
    let program = folder.join(program);
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
        "the header does not agree with the official types:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let run = Command::new(&program)
        .env("LD_LIBRARY_PATH", library.parent().expect("library folder"))
        .status()
        .expect("run the C program");
    assert!(
        run.success(),
        "the version through the library is the standard's"
    );
}

#[test]
fn header_matches_the_official_function_types_under_werror() {
    if !support::fmpy_available("header_matches_the_official_function_types_under_werror") {
        return;
    }
    compiles_against_the_official_headers("assign_types.c", &FMI2_FUNCTIONS, "assign_types");
}

#[test]
fn fmi3_header_matches_the_official_function_types_under_werror() {
    if !support::fmpy_available("fmi3_header_matches_the_official_function_types_under_werror") {
        return;
    }
    compiles_against_the_official_headers(
        "assign_types_fmi3.c",
        &FMI3_FUNCTIONS,
        "assign_types_fmi3",
    );
}
