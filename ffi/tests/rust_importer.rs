//! A second, independent importer: fmu-runner (crates.io, its own bindings
//! and FMU unpacking) runs the same FMU with the same communication steps
//! as FMPy, and the outputs agree.

use crate::support;

use std::collections::HashMap;

use fmu_runner::{Fmu, FmuInstance, fmi2Type};

/// Runs the FMU in fmu-runner with 1 ms steps at `tolerance`, as FMPy is asked to;
/// rows of (time, outputs...).
fn run_in_fmu_runner(
    fmu: &std::path::Path,
    outputs: &[&str],
    stop: f64,
    tolerance: f64,
) -> Vec<Vec<f64>> {
    let library = Fmu::unpack(fmu)
        .expect("fmu-runner unpacks the FMU")
        .load(fmi2Type::fmi2CoSimulation)
        .expect("fmu-runner loads the library");
    let instance = FmuInstance::instantiate(&library, false).expect("fmi2Instantiate");
    let variables = instance.lib.variables();
    let signals: Vec<_> = outputs
        .iter()
        .map(|name| variables.get(*name).expect("variable in the description"))
        .collect();
    instance
        .setup_experiment(0.0, None, Some(tolerance))
        .expect("fmi2SetupExperiment");
    instance
        .enter_initialization_mode()
        .expect("fmi2EnterInitializationMode");
    instance
        .exit_initialization_mode()
        .expect("fmi2ExitInitializationMode");
    let step = 1e-3;
    let steps = (stop / step).round() as usize;
    let sample = |t: f64| -> Vec<f64> {
        let values: HashMap<_, f64> = instance.get_reals(&signals).expect("fmi2GetReal");
        std::iter::once(t)
            .chain(signals.iter().map(|s| values[s]))
            .collect()
    };
    let mut rows = vec![sample(0.0)];
    // Communication points k * step, step sizes their differences: the
    // sequence FMPy's simulate_fmu uses, so both importers make the same calls.
    let mut t = 0.0;
    for k in 0..steps {
        let next = (k + 1) as f64 * step;
        instance.do_step(t, next - t, true).expect("fmi2DoStep");
        t = next;
        rows.push(sample(t));
    }
    rows
}

#[test]
fn fmu_runner_and_fmpy_agree() {
    if !support::fmpy_available("fmu_runner_and_fmpy_agree") {
        return;
    }
    for (scenario, stop, outputs) in [
        (
            "scenarios/paper/fig05b_fi.toml",
            1.0,
            vec!["encoder.position", "bearing_friction.force", "drive.force"],
        ),
        (
            "scenarios/coupling/friction20_traverse.toml",
            0.3,
            vec!["table.x", "table.yaw", "friction_fl.force"],
        ),
    ] {
        let name = std::path::Path::new(scenario)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("stage");
        let folder = support::scratch(&format!("rust_importer_{name}"));
        let fmu = support::fmu(scenario, &folder);
        let csv = folder.join("fmpy.csv");
        support::fmpy_simulate(&fmu, &csv, stop, &outputs);
        let (names, fmpy_rows) = support::read_csv(&csv);
        let rust_rows = run_in_fmu_runner(&fmu, &outputs, stop, support::SIMULATION_RTOL);
        assert_eq!(fmpy_rows.len(), rust_rows.len(), "{name}: same samples");
        for (j, output) in outputs.iter().enumerate() {
            let column = names.iter().position(|n| n == output).expect("FMPy column");
            let fmpy: Vec<f64> = fmpy_rows.iter().map(|r| r[column]).collect();
            let rust: Vec<f64> = rust_rows.iter().map(|r| r[j + 1]).collect();
            let scale = fmpy.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
            let difference = fmpy
                .iter()
                .zip(&rust)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            let identical = fmpy.iter().zip(&rust).filter(|(a, b)| a == b).count();
            println!(
                "{name} {output}: max |fmu-runner - FMPy| = {difference:.3e} ({identical}/{} samples identical)",
                fmpy.len()
            );
            assert!(
                difference <= 1e-12 * scale,
                "{name} {output}: importers differ by {difference:e} (scale {scale:e})"
            );
        }
    }
}
