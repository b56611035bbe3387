//! The exported FMUs in FMPy, the independent reference importer: they
//! validate with no findings, simulate like `fistage run` (the same library
//! call), take an external controller from Python, roll back bit for bit, and
//! give directional derivatives equal to finite differences. `fmutool -check`
//! (fmu-manipulation-toolbox) finds nothing either.

mod support;

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use fistage_sim::run_scenario;

/// `fistage run` of a shipped scenario, shortened to `duration`: signal name -> samples.
fn native_run(scenario: &str, duration: f64) -> HashMap<String, Vec<f64>> {
    let mut loaded = fistage_model::load(&support::root().join(scenario)).expect("scenario loads");
    loaded.scenario.duration = duration;
    loaded.scenario.signals = None;
    let output = run_scenario(&loaded, &mut fistage_sim::no_progress).expect("native run");
    let table = output.signals;
    table.names.into_iter().zip(table.columns).collect()
}

fn column(names: &[String], rows: &[Vec<f64>], name: &str) -> Vec<f64> {
    let index = names.iter().position(|n| n == name).expect("column exists");
    rows.iter().map(|row| row[index]).collect()
}

fn peak_to_peak(values: &[f64]) -> f64 {
    let max = values.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let min = values.iter().cloned().fold(f64::INFINITY, f64::min);
    max - min
}

fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "same sample count");
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn validate(fmu: &Path) -> usize {
    let report: serde_json::Value = serde_json::from_str(&support::run_python(
        "fmpy_checks.py",
        &["validate", fmu.to_str().unwrap_or_default()],
    ))
    .expect("JSON");
    let problems = report["problems"].as_array().expect("problem list");
    assert!(problems.is_empty(), "FMPy finds problems: {problems:?}");
    report["variables"].as_u64().unwrap_or_default() as usize
}

/// Simulates in FMPy through `interface` with the given outputs; compares
/// each with the native run.
fn simulate_and_compare(
    scenario: &str,
    name: &str,
    stop: f64,
    outputs: &[&str],
    (interface, relative): (&str, f64),
) {
    let folder = support::scratch(&format!("{name}-{interface}"));
    let fmu = support::fmu(scenario, &folder);
    let n_variables = validate(&fmu);
    assert!(n_variables > outputs.len());
    let csv = folder.join("fmpy.csv");
    support::fmpy_simulate_as(&fmu, &csv, stop, outputs, interface);
    let (names, rows) = support::read_csv(&csv);
    let native = native_run(scenario, stop);
    for output in outputs {
        let fmpy = column(&names, &rows, output);
        let reference = &native[*output];
        let scale = peak_to_peak(reference).max(1e-12);
        let difference = max_difference(&fmpy, reference);
        println!(
            "{name} {interface} {output}: max |FMPy - native| = {difference:.3e} (p2p {scale:.3e})"
        );
        assert!(
            difference <= relative * scale,
            "{output}: FMPy and fistage run differ by {difference:e} (p2p {scale:e})"
        );
    }
}

#[test]
fn fig05b_fi_validates_and_simulates_like_fistage_run() {
    if !support::fmpy_available("fig05b_fi_validates_and_simulates_like_fistage_run") {
        return;
    }
    simulate_and_compare(
        "scenarios/paper/fig05b_fi.toml",
        "fig05b_fi",
        5.0,
        &[
            "encoder.position",
            "bearing_x.q",
            "bearing_friction.force",
            "drive.force",
        ],
        ("CoSimulation", 1e-4),
    );
}

/// Model Exchange: FMPy's CVode integrates the unit's derivatives (the
/// stiff bristle state included) and reproduces the native run.
#[test]
fn fig05b_fi_model_exchange_in_fmpy_cvode_matches_fistage_run() {
    if !support::fmpy_available("fig05b_fi_model_exchange_in_fmpy_cvode_matches_fistage_run") {
        return;
    }
    simulate_and_compare(
        "scenarios/paper/fig05b_fi.toml",
        "fig05b_fi",
        5.0,
        &["encoder.position", "bearing_x.q", "bearing_friction.force"],
        ("ModelExchange", 1e-3),
    );
}

#[test]
fn six_dof_stage_validates_and_simulates_like_fistage_run() {
    if !support::fmpy_available("six_dof_stage_validates_and_simulates_like_fistage_run") {
        return;
    }
    simulate_and_compare(
        "scenarios/coupling/friction20_traverse.toml",
        "friction20_traverse",
        0.5,
        &[
            "table.x",
            "table.yaw",
            "table.pitch",
            "rail_fl.q",
            "friction_rr.force",
            "isolator_fl.dx",
        ],
        ("CoSimulation", 1e-4),
    );
}

/// Model Exchange on the four-bearing 6-DOF table: CVode integrates the
/// quaternion, the isolators and four bristle states like the native run.
#[test]
fn six_dof_stage_model_exchange_in_fmpy_cvode_matches_fistage_run() {
    if !support::fmpy_available("six_dof_stage_model_exchange_in_fmpy_cvode_matches_fistage_run") {
        return;
    }
    simulate_and_compare(
        "scenarios/coupling/friction20_traverse.toml",
        "friction20_traverse",
        0.5,
        &["table.x", "table.yaw", "table.pitch", "friction_rr.force"],
        ("ModelExchange", 1e-3),
    );
}

/// The servo in Python through the force input, gains zero inside. Holding the
/// force over a step is a first-order method: the difference to the internal
/// servo must shrink with the communication step.
#[test]
fn external_controller_converges_to_the_internal_one() {
    if !support::fmpy_available("external_controller_converges_to_the_internal_one") {
        return;
    }
    let scenario = "scenarios/paper/fig05b_fi.toml";
    let folder = support::scratch("external_controller");
    let fmu = support::fmu(scenario, &folder);
    let native = native_run(scenario, 1.0);
    let reference = &native["encoder.position"];
    let scale = peak_to_peak(reference);
    let mut errors = Vec::new();
    for step in ["2e-4", "1e-4", "5e-5"] {
        let csv = folder.join(format!("external_{step}.csv"));
        support::run_python(
            "fmpy_checks.py",
            &[
                "external",
                fmu.to_str().unwrap_or_default(),
                csv.to_str().unwrap_or_default(),
                "--stop",
                "1.0",
                "--step",
                step,
                "--sample",
                "0.001",
                "--k",
                "6e4",
                "--c",
                "100",
                "--outputs",
                "encoder.position",
            ],
        );
        let (names, rows) = support::read_csv(&csv);
        let error = max_difference(&column(&names, &rows, "encoder.position"), reference);
        println!("external servo, h = {step} s: max error {error:.3e} m (p2p {scale:.3e} m)");
        errors.push(error);
    }
    assert!(
        errors[1] < 0.8 * errors[0] && errors[2] < 0.8 * errors[1],
        "errors {errors:?} do not shrink with the step"
    );
    assert!(
        errors[2] < 0.05 * scale,
        "errors {errors:?} against p2p {scale}"
    );
}

#[test]
fn rollback_repeats_the_trajectory_bit_for_bit() {
    if !support::fmpy_available("rollback_repeats_the_trajectory_bit_for_bit") {
        return;
    }
    for (scenario, name) in [
        ("scenarios/paper/fig05b_fi.toml", "rollback_1dof"),
        (
            "scenarios/coupling/friction20_traverse.toml",
            "rollback_6dof",
        ),
    ] {
        let folder = support::scratch(name);
        let fmu = support::fmu(scenario, &folder);
        let report: serde_json::Value = serde_json::from_str(&support::run_python(
            "fmpy_checks.py",
            &["rollback", fmu.to_str().unwrap_or_default()],
        ))
        .expect("JSON");
        let first = &report["first"];
        assert_eq!(first.as_array().map(Vec::len), Some(100));
        assert_eq!(&report["again"], first, "{name}: set FMU state and re-step");
        assert_eq!(
            &report["through_bytes"], first,
            "{name}: serialise, deserialise, set and re-step"
        );
        // The steps after the save point do change the outputs.
        assert_ne!(first[0], first[99]);
    }
}

#[test]
fn directional_derivatives_equal_central_differences() {
    if !support::fmpy_available("directional_derivatives_equal_central_differences") {
        return;
    }
    let folder = support::scratch("derivatives");
    let fmu = support::fmu("scenarios/paper/fig05b_fi.toml", &folder);
    let report: serde_json::Value = serde_json::from_str(&support::run_python(
        "fmpy_checks.py",
        &["derivatives", fmu.to_str().unwrap_or_default()],
    ))
    .expect("JSON");
    let outputs = report["outputs"].as_array().expect("outputs");
    let mut nonzero = 0;
    for (i, input) in report["inputs"]
        .as_array()
        .expect("inputs")
        .iter()
        .enumerate()
    {
        for (j, output) in outputs.iter().enumerate() {
            let exact = report["exact"][i][j].as_f64().expect("number");
            let central = report["central"][i][j].as_f64().expect("number");
            assert!(
                (exact - central).abs() <= 1e-6 * exact.abs().max(1.0),
                "d {output} / d {input}: exact {exact}, central difference {central}"
            );
            if exact != 0.0 {
                nonzero += 1;
            }
        }
    }
    // Reference, velocity reference, force and platform velocity all act on some output.
    assert!(nonzero >= 7, "only {nonzero} non-zero derivatives");
}

#[test]
fn fmutool_check_finds_nothing() {
    if !support::fmpy_available("fmutool_check_finds_nothing") {
        return;
    }
    let folder = support::scratch("fmutool");
    for scenario in [
        "scenarios/paper/fig05b_fi.toml",
        "scenarios/coupling/symmetric_traverse.toml",
    ] {
        let fmu = support::fmu(scenario, &folder);
        let fmutool = support::python().with_file_name("fmutool");
        let output = Command::new(&fmutool)
            .arg("-input")
            .arg(&fmu)
            .arg("-check")
            .output()
            .expect("run fmutool");
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        );
        assert!(output.status.success(), "fmutool failed:\n{text}");
        assert!(text.contains("compliant with FMI-2.0"), "{text}");
        assert!(text.contains("No semantic error"), "{text}");
        assert!(
            !text
                .lines()
                .any(|l| l.starts_with("ERROR") || l.starts_with("WARNING")),
            "{text}"
        );
    }
}
