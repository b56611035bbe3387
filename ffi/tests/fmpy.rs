//! The exported FMUs in FMPy, the independent reference importer: they
//! validate with no findings, simulate like `fistage run` (the same library
//! call), take an external controller from Python, roll back bit for bit, and
//! give directional derivatives equal to finite differences. `fmutool -check`
//! (fmu-manipulation-toolbox) finds nothing either.

use crate::support;

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use fistage_fmi::FmiVersion;
use fistage_sim::run_scenario;

/// `fistage run` of a shipped scenario, shortened to `duration`: signal name -> samples.
fn native_run(scenario: &str, duration: f64) -> HashMap<String, Vec<f64>> {
    let mut loaded = fistage_model::load(&support::root().join(scenario)).expect("scenario loads");
    loaded.scenario.duration = duration;
    loaded.scenario.signals = None;
    let output = run_scenario(&loaded, &mut fistage_sim::no_progress).expect("native run");
    let table = output.signals;
    let mut signals: HashMap<String, Vec<f64>> =
        table.names.into_iter().zip(table.columns).collect();
    signals.insert("time".into(), table.times);
    signals
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
    simulate_and_compare_version(
        scenario,
        name,
        stop,
        outputs,
        (interface, relative, FmiVersion::Fmi2),
    );
}

/// [`simulate_and_compare`] for an FMU of the FMI standard `version`.
fn simulate_and_compare_version(
    scenario: &str,
    name: &str,
    stop: f64,
    outputs: &[&str],
    (interface, relative, version): (&str, f64, FmiVersion),
) {
    let folder = support::scratch(&format!("{name}-{interface}-{version:?}"));
    let fmu = support::fmu_version(scenario, &folder, version);
    let n_variables = validate(&fmu);
    assert!(n_variables > outputs.len());
    let csv = folder.join("fmpy.csv");
    support::fmpy_simulate_as(&fmu, &csv, stop, outputs, interface);
    let (names, mut rows) = support::read_csv(&csv);
    // Model Exchange results repeat the time of each event (before and
    // after it): keep the row after.
    let time = column(&names, &rows, "time");
    let mut k = 0;
    rows.retain(|_| {
        k += 1;
        time.get(k).is_none_or(|next| *next != time[k - 1])
    });
    let native = native_run(scenario, stop);
    for output in outputs {
        let fmpy = column(&names, &rows, output);
        let reference = &native[*output];
        let scale = peak_to_peak(reference).max(1e-12);
        let difference = max_difference(&fmpy, reference);
        println!(
            "{name} {version:?} {interface} {output}: max |FMPy - native| = {difference:.3e} (p2p {scale:.3e})"
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

/// FMI 3.0, both interfaces: FMPy validates the FMU and simulates Fig. 5b
/// through its Co-Simulation and, with CVode, its Model Exchange like the
/// native run.
#[test]
fn fig05b_fi_fmi3_in_both_interfaces_matches_fistage_run() {
    if !support::fmpy_available("fig05b_fi_fmi3_in_both_interfaces_matches_fistage_run") {
        return;
    }
    for (interface, relative) in [("CoSimulation", 1e-4), ("ModelExchange", 1e-3)] {
        simulate_and_compare_version(
            "scenarios/paper/fig05b_fi.toml",
            "fig05b_fi",
            5.0,
            &["encoder.position", "bearing_x.q", "bearing_friction.force"],
            (interface, relative, FmiVersion::Fmi3),
        );
    }
}

/// FMI 3.0 on the four-bearing 6-DOF traverse, both interfaces.
#[test]
fn six_dof_stage_fmi3_in_both_interfaces_matches_fistage_run() {
    if !support::fmpy_available("six_dof_stage_fmi3_in_both_interfaces_matches_fistage_run") {
        return;
    }
    for (interface, relative) in [("CoSimulation", 1e-4), ("ModelExchange", 1e-3)] {
        simulate_and_compare_version(
            "scenarios/coupling/friction20_traverse.toml",
            "friction20_traverse",
            0.5,
            &["table.x", "table.yaw", "friction_rr.force"],
            (interface, relative, FmiVersion::Fmi3),
        );
    }
}

/// A user's first try: `simulate_fmu(fmu, fmi_type=...)` with FMPy's
/// defaults and the description's default experiment, FMI 2.0 and 3.0, runs
/// through both interfaces and gives Fig. 5b's limit cycle (69.26 um peak to
/// peak in the second half) as `fistage run` does.
#[test]
fn fmpy_defaults_give_the_fig05b_limit_cycle() {
    if !support::fmpy_available("fmpy_defaults_give_the_fig05b_limit_cycle") {
        return;
    }
    let scenario = "scenarios/paper/fig05b_fi.toml";
    let native = native_run(scenario, 5.0);
    let time = &native["time"];
    let window: Vec<f64> = (time.iter().zip(&native["encoder.position"]))
        .filter(|(t, _)| **t >= 2.5)
        .map(|(_, x)| *x)
        .collect();
    let reference = peak_to_peak(&window);
    assert!(
        (reference - 69.26e-6).abs() < 0.01e-6,
        "native {reference:e}"
    );
    for version in [FmiVersion::Fmi2, FmiVersion::Fmi3] {
        let folder = support::scratch(&format!("defaults-{version:?}"));
        let fmu = support::fmu_version(scenario, &folder, version);
        let printed = support::run_python(
            "fmpy_checks.py",
            &[
                "defaults",
                fmu.to_str().unwrap_or_default(),
                "--from",
                "2.5",
            ],
        );
        let report: serde_json::Value = serde_json::from_str(&printed).expect("JSON");
        for interface in ["CoSimulation", "ModelExchange"] {
            let p2p = report[interface].as_f64().expect("peak to peak");
            println!(
                "{version:?} {interface} with FMPy's defaults: {:.3} um",
                p2p * 1e6
            );
            // FMPy samples Model Exchange every 10 ms, Co-Simulation every
            // millisecond: the sampled peak is a little below the true one.
            assert!(
                (p2p / reference - 1.0).abs() < 2e-4,
                "{version:?} {interface}: {p2p:e} against {reference:e}"
            );
        }
    }
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

/// Model Exchange with time events: the minimum-jerk move of the p2p
/// scenario starts and ends at reference breakpoints, which the unit
/// announces through fmi2NewDiscreteStates.
#[test]
fn point_to_point_model_exchange_handles_the_time_events() {
    if !support::fmpy_available("point_to_point_model_exchange_handles_the_time_events") {
        return;
    }
    simulate_and_compare(
        "scenarios/coupling/symmetric_p2p.toml",
        "symmetric_p2p",
        0.3,
        &["table.x", "controller.error"],
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

/// The PD controller of `ffi/ssp/` compiled against the official FMI 2.0
/// headers and packed as an FMU of its own (gains zero until a system sets
/// them).
fn controller_fmu(folder: &Path) -> Vec<u8> {
    use std::io::Write;
    let root = support::root();
    let library = folder.join("pd_controller.so");
    let output = Command::new("cc")
        .args(["-std=c99", "-Wall", "-Werror", "-shared", "-fPIC", "-O2"])
        .arg("-I")
        .arg(support::fmi_headers())
        .arg(root.join("ffi/ssp/pd_controller.c"))
        .arg("-o")
        .arg(&library)
        .output()
        .expect("run the C compiler");
    assert!(
        output.status.success(),
        "the controller does not compile against the official headers:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default();
    let description = std::fs::read(root.join("ffi/ssp/pd_controller.xml")).expect("description");
    zip.start_file("modelDescription.xml", options)
        .expect("entry");
    zip.write_all(&description).expect("write");
    zip.start_file("binaries/linux64/pd_controller.so", options)
        .expect("entry");
    zip.write_all(&std::fs::read(&library).expect("library"))
        .expect("write");
    zip.finish().expect("archive").into_inner()
}

/// Whether the FMU environment's python has libcosimpy (the second SSP
/// importer): SKIPPED without it, unless `.ci/run` requires it.
fn libcosim_available(test: &str) -> bool {
    let found = Command::new(support::python())
        .args(["-c", "import libcosimpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        let why = "the FMU environment has no libcosimpy (ffi/tests/python/requirements.txt)";
        assert!(!support::system_tests_required(), "{test}: {why}");
        println!("SKIPPED {test} in libcosim: {why}");
    }
    found
}

/// The plant in a system of FMUs: [`fistage_fmi::ssp::build_ssp`] (what
/// `fistage ssp` runs) packs the Fig. 5b FMU with the PD controller FMU of
/// `ffi/ssp/`, connected by variable name. The system's parameter bindings
/// switch the plant's own servo off and give the controller its gains
/// (they start at zero), so a binding that does not arrive breaks the loop.
/// FMPy's SSP master and libcosim (`ffi/ssp/run_ssp.py`) exchange values
/// once per communication step (the force is a step late and held), so
/// each converges to `fistage run` at first order as the step halves.
#[test]
fn an_ssp_system_runs_in_two_importers_and_converges_to_the_native_run() {
    use fistage_fmi::ssp::{ComponentFile, Connection, Endpoint, ParameterValue, SystemSpec};
    let test = "an_ssp_system_runs_in_two_importers_and_converges_to_the_native_run";
    if !support::fmpy_available(test) {
        return;
    }
    let folder = support::scratch("ssp_system");
    let at = |text: &str| Endpoint::parse(text).expect("endpoint");
    let connect = |from: &str, to: &str| Connection {
        from: at(from),
        to: at(to),
    };
    let set = |name: &str, value: &str| ParameterValue {
        at: at(name),
        value: value.into(),
    };
    let plant =
        std::fs::read(support::fmu("scenarios/paper/fig05b_fi.toml", &folder)).expect("plant FMU");
    let spec = SystemSpec {
        name: "servo_loop".into(),
        components: vec![
            ComponentFile {
                name: "plant".into(),
                fmu: plant,
            },
            ComponentFile {
                name: "controller".into(),
                fmu: controller_fmu(&folder),
            },
        ],
        connections: vec![
            connect("controller.force", "plant.servo_force"),
            connect("plant.encoder.position", "controller.position"),
            connect("plant.encoder.velocity", "controller.velocity"),
        ],
        parameters: vec![
            set("plant.controller.k", "0"),
            set("plant.controller.c", "0"),
            set("controller.k", "6e4"),
            set("controller.c", "100"),
        ],
        stop_time: Some(0.5),
    };
    let ssp = folder.join("servo_loop.ssp");
    std::fs::write(&ssp, fistage_fmi::ssp::build_ssp(&spec).expect("package")).expect("write");
    let stop = 0.5;
    let native = native_run("scenarios/paper/fig05b_fi.toml", stop);
    let reference = &native["encoder.position"];
    let scale = peak_to_peak(reference);
    let mut importers = vec!["fmpy"];
    if libcosim_available(test) {
        importers.push("libcosim");
    }
    let script = support::root().join("ffi/ssp/run_ssp.py");
    for importer in importers {
        let mut errors = Vec::new();
        for step in ["2e-4", "1e-4", "5e-5"] {
            let csv = folder.join(format!("{importer}_{step}.csv"));
            support::run_python_file(
                &script,
                &[
                    ssp.to_str().unwrap_or_default(),
                    csv.to_str().unwrap_or_default(),
                    "--importer",
                    importer,
                    "--stop",
                    &stop.to_string(),
                    "--step",
                    step,
                ],
            );
            let (names, rows) = support::read_csv(&csv);
            let time = column(&names, &rows, "time");
            let position = column(&names, &rows, "plant.encoder.position");
            // The native run's samples are every millisecond.
            let every = (1e-3 / step.parse::<f64>().expect("step")).round() as usize;
            assert!(
                (time[every - 1] - 1e-3).abs() < 1e-9,
                "{importer}: first sample at {}",
                time[every - 1]
            );
            let sampled: Vec<f64> = (every - 1..position.len())
                .step_by(every)
                .map(|k| position[k])
                .collect();
            let error = max_difference(&sampled, &reference[1..=sampled.len()]);
            println!(
                "SSP in {importer}, h = {step} s: max error {error:.3e} m (p2p {scale:.3e} m)"
            );
            errors.push(error);
        }
        for pair in errors.windows(2) {
            let ratio = pair[0] / pair[1];
            assert!(
                (1.5..3.0).contains(&ratio),
                "{importer}: halving the step divides the error by {ratio:.2} (errors {errors:?}): not first order"
            );
        }
        assert!(
            errors[2] < 0.05 * scale,
            "{importer}: errors {errors:?} against p2p {scale}"
        );
    }
}

/// Many instances at once: 64 instances of the Fig. 5b FMU, each with its
/// own servo damping, stepped on eight threads together by the Python
/// example `python/examples/fmu_parallel_instances.py` (FMPy), each equal bit
/// for bit, at every step, to the same instance run alone; the dampings make
/// 64 different trajectories.
#[test]
fn parallel_instances_equal_their_serial_runs_bit_for_bit() {
    if !support::fmpy_available("parallel_instances_equal_their_serial_runs_bit_for_bit") {
        return;
    }
    let folder = support::scratch("parallel_instances");
    let fmu = support::fmu("scenarios/paper/fig05b_fi.toml", &folder);
    let example = support::root().join("python/examples/fmu_parallel_instances.py");
    let report: serde_json::Value = serde_json::from_str(&support::run_python_file(
        &example,
        &[fmu.to_str().unwrap_or_default(), "--json", "--stop", "0.2"],
    ))
    .expect("JSON");
    assert_eq!(report["instances"], 64);
    assert_eq!(report["threads"], 8);
    assert_eq!(report["differing"], serde_json::json!([]), "{report}");
    assert_eq!(report["serial"], report["parallel"]);
    assert_eq!(report["distinct_trajectories"], 64);
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
    let cases = [
        ("scenarios/paper/fig05b_fi.toml", FmiVersion::Fmi2, "2.0"),
        (
            "scenarios/coupling/symmetric_traverse.toml",
            FmiVersion::Fmi2,
            "2.0",
        ),
        ("scenarios/paper/fig05b_fi.toml", FmiVersion::Fmi3, "3.0"),
        (
            "scenarios/coupling/symmetric_traverse.toml",
            FmiVersion::Fmi3,
            "3.0",
        ),
    ];
    for (scenario, version, standard) in cases {
        let fmu = support::fmu_version(scenario, &folder, version);
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
        assert!(
            text.contains(&format!("compliant with FMI-{standard}")),
            "{text}"
        );
        assert!(text.contains("No semantic error"), "{text}");
        assert!(
            !text
                .lines()
                .any(|l| l.starts_with("ERROR") || l.starts_with("WARNING")),
            "{text}"
        );
    }
}
