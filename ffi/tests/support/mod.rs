//! Shared set-up of the FMU tests: the Python environment with FMPy, FMUs
//! built from shipped scenarios with the library this build made, and
//! running the Python helper scripts.
#![allow(dead_code)] // each test binary uses a different part

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The cdylib of this build (beside the test binary, in `target/<profile>/deps`).
pub fn library() -> PathBuf {
    let exe = std::env::current_exe().expect("test binary path");
    fistage_fmi::package::default_library_locations(&exe)
        .into_iter()
        .chain(
            exe.parent()
                .and_then(Path::parent)
                .map(|p| p.join("libfistage_fmi.so")),
        )
        .find(|p| p.is_file())
        .expect("libfistage_fmi.so is built beside the tests")
}

/// Whether `.ci/run` asked for every system-dependent test to run
/// (`FISTAGE_SYSTEM_TESTS=required`): then a missing tool fails the test.
/// Hidden components ([`optional_hidden`]) are never required.
pub fn system_tests_required() -> bool {
    optional_hidden().is_none()
        && std::env::var("FISTAGE_SYSTEM_TESTS").is_ok_and(|v| v == "required")
}

/// Why the optional components (FMPy, fmutool) are not looked for:
/// `FISTAGE_HIDE_OPTIONAL` set to anything but empty or `0`, as `.ci/run`
/// sets it for one pass that runs every SKIPPED path of a bare machine.
pub fn optional_hidden() -> Option<String> {
    std::env::var("FISTAGE_HIDE_OPTIONAL")
        .ok()
        .filter(|value| !value.is_empty() && value != "0")
        .map(|value| format!("hidden (FISTAGE_HIDE_OPTIONAL={value})"))
}

/// The python of the environment with FMPy: `FISTAGE_PYTHON` if set (as
/// `.ci/run` sets it), else the environment `.ci/run` makes under `target/`.
/// Tests never make it themselves.
fn find_python() -> Option<PathBuf> {
    if optional_hidden().is_some() {
        return None;
    }
    if let Some(python) = std::env::var_os("FISTAGE_PYTHON") {
        return Some(PathBuf::from(python));
    }
    let venv = root().join("target/fmi-venv/bin/python");
    venv.is_file().then_some(venv)
}

/// Whether a test that needs FMPy can run. Without the environment it says
/// SKIPPED and why, unless `.ci/run` requires it, when the test fails.
pub fn fmpy_available(test: &str) -> bool {
    if find_python().is_some() {
        return true;
    }
    let why = optional_hidden().map_or_else(
        || "no FMPy environment (set FISTAGE_PYTHON, or run `bash ffi/tests/python/env.sh target/fmi-venv` as .ci/run does)".to_string(),
        |why| format!("FMPy {why}"),
    );
    assert!(!system_tests_required(), "{test}: {why}");
    println!("SKIPPED {test}: {why}");
    false
}

/// The python of the FMPy environment (see [`fmpy_available`]).
pub fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| find_python().expect("the FMPy environment (checked by fmpy_available)"))
}

/// A fresh scratch folder under `target/fmi-tests/<name>`.
pub fn scratch(name: &str) -> PathBuf {
    let dir = root().join("target/fmi-tests").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch folder");
    dir
}

/// Builds the FMI 2.0 FMU of a shipped scenario into `folder`.
pub fn fmu(scenario: &str, folder: &Path) -> PathBuf {
    fmu_version(scenario, folder, fistage_fmi::FmiVersion::Fmi2)
}

/// Builds the FMU of a shipped scenario for the FMI standard `version` into `folder`.
pub fn fmu_version(scenario: &str, folder: &Path, version: fistage_fmi::FmiVersion) -> PathBuf {
    let bytes = fistage_fmi::build_fmu_version(&root().join(scenario), &library(), version)
        .expect("build FMU");
    let stem = Path::new(scenario)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("stage");
    let path = folder.join(format!("{stem}.fmu"));
    std::fs::write(&path, bytes).expect("write FMU");
    path
}

/// Runs `ffi/tests/python/<script>` with arguments; returns its standard output.
pub fn run_python(script: &str, args: &[&str]) -> String {
    run_python_file(&root().join("ffi/tests/python").join(script), args)
}

/// [`run_python`] on any script of the repository (an example, say).
pub fn run_python_file(script: &Path, args: &[&str]) -> String {
    let output = Command::new(python())
        .arg(script)
        .args(args)
        .output()
        .expect("run python");
    assert!(
        output.status.success(),
        "{} failed:\n{}\n{}",
        script.display(),
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// Simulates an FMU in FMPy (`simulate_fmu`, 1 ms steps) into a CSV of the outputs.
pub fn fmpy_simulate(fmu: &Path, csv: &Path, stop: f64, outputs: &[&str]) {
    fmpy_simulate_as(fmu, csv, stop, outputs, "CoSimulation");
}

/// The relative tolerance the FMPy simulations ask for: the shipped
/// scenarios' own, so that they can be compared with the native run.
pub const SIMULATION_RTOL: f64 = 1e-8;

/// [`fmpy_simulate`] through `interface` (`CoSimulation`, or
/// `ModelExchange` with FMPy's CVode), at [`SIMULATION_RTOL`].
pub fn fmpy_simulate_as(fmu: &Path, csv: &Path, stop: f64, outputs: &[&str], interface: &str) {
    run_python(
        "fmpy_checks.py",
        &[
            "simulate",
            fmu.to_str().unwrap_or_default(),
            csv.to_str().unwrap_or_default(),
            "--stop",
            &stop.to_string(),
            "--step",
            "0.001",
            "--outputs",
            &outputs.join(","),
            "--interface",
            interface,
            "--rtol",
            &SIMULATION_RTOL.to_string(),
        ],
    );
}

/// The FMPy `c-code` folder with the official FMI headers.
pub fn fmi_headers() -> PathBuf {
    let out = Command::new(python())
        .args([
            "-c",
            "import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), 'c-code'))",
        ])
        .output()
        .expect("ask FMPy for its headers");
    PathBuf::from(String::from_utf8_lossy(&out.stdout).trim())
}

/// Reads a CSV with a header row into (names, rows).
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).expect("read CSV");
    let mut lines = text.lines();
    let names = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().expect("number")).collect())
        .collect();
    (names, rows)
}
