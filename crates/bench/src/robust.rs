//! `fistage bench --robust`: the cost of a tolerance analysis of the
//! four-bearing stage (`scenarios/robust/four_bearing_population.toml`):
//! 10 000 linear samples and 1 000 simulated 2 s samples, and of the
//! simulated 40 x 40 stability sweep of `scenarios/bench/fig06b_40x40.toml`,
//! each on one and on two threads, side by side. Samples and points are
//! computed as `fistage robust` and `fistage sweep` compute them, without
//! writing files.

use std::path::Path;
use std::time::Instant;

use fistage_analysis::assess::Analyses;
use fistage_analysis::robust::RobustSpec;
use fistage_analysis::sweep::{SweepSpec, run_points};
use fistage_model::RobotSpec;

/// The sweep timed after the tolerance analysis.
const SWEEP: &str = "scenarios/bench/fig06b_40x40.toml";

/// One timed case: (label, samples, analysis, simulated duration).
const CASES: [(&str, usize, Analyses, Option<f64>); 2] = [
    ("linear", 10_000, Analyses::Linear, None),
    (
        "simulated, 2 s each",
        1_000,
        Analyses::Simulation,
        Some(2.0),
    ),
];

/// Prints the Markdown table.
pub fn robust_table(scenario: &Path) -> anyhow::Result<()> {
    let loaded = fistage_model::load(scenario)?;
    let robot_file = RobotSpec::from_file(&loaded.scenario.robot)?;
    println!("Tolerance analysis of {} (wall time):", scenario.display());
    println!();
    println!(
        "| samples | analysis | 1 thread [s] | 2 threads [s] | speed-up | samples/s (2 threads) |"
    );
    println!("|---:|---|---:|---:|---:|---:|");
    for (label, samples, analysis, duration) in CASES {
        let mut spec =
            RobustSpec::from_scenario(&loaded.scenario, &robot_file, Some(samples), None)?;
        spec.assessment.analysis = analysis;
        spec.assessment.duration = duration;
        let indices: Vec<usize> = (0..samples).collect();
        let (one, two) = one_and_two_threads("samples", |threads| {
            spec.run(&loaded, &robot_file, &indices, threads, &|_, _| {})
        })?;
        print_row(samples, label, one, two);
    }
    sweep_row(Path::new(SWEEP))
}

/// Wall seconds of `compute` on one and on two threads, which must give
/// the same `items`.
fn one_and_two_threads<T: PartialEq>(
    items: &str,
    compute: impl Fn(usize) -> T,
) -> anyhow::Result<(f64, f64)> {
    let time = |threads: usize| {
        let start = Instant::now();
        let results = compute(threads);
        (start.elapsed().as_secs_f64(), results)
    };
    let (one, first) = time(1);
    let (two, second) = time(2);
    anyhow::ensure!(
        first == second,
        "one and two threads gave different {items}"
    );
    Ok((one, two))
}

fn print_row(items: usize, label: &str, one: f64, two: f64) {
    println!(
        "| {items} | {label} | {one:.2} | {two:.2} | {:.2} | {:.0} |",
        one / two,
        items as f64 / two
    );
}

/// The sweep's points on one and on two threads.
fn sweep_row(scenario: &Path) -> anyhow::Result<()> {
    let loaded = fistage_model::load(scenario)?;
    let robot_file = RobotSpec::from_file(&loaded.scenario.robot)?;
    let spec = SweepSpec::from_scenario(&loaded.scenario)?;
    let indices: Vec<usize> = (0..spec.len()).collect();
    let (one, two) = one_and_two_threads("sweep points", |threads| {
        run_points(&loaded, &robot_file, &spec, &indices, threads, &|_, _| {})
    })?;
    let label = format!("sweep `{}`", scenario.display());
    print_row(spec.len(), &label, one, two);
    Ok(())
}
