//! `fistage bench --population`: what a simulated population costs per
//! stage, the figure the population work is judged by. Three populations,
//! each as `fistage robust` or `fistage sweep` computes it (no files):
//!
//! - (a) the 1-DOF FI population of `scenarios/robust/fig05b_simulated.toml`
//!   (4 000 stages, 2 s each at rtol 1e-6; k_j, f_S and sigma0 spread);
//! - (b) the four-bearing population of
//!   `scenarios/robust/four_bearing_population.toml`, judged by simulation
//!   (2 s each);
//! - (c) the simulated 40 x 40 sweep of `scenarios/bench/fig06b_40x40.toml`.
//!
//! Each on one thread and on two: stages per CPU-second (the process's CPU
//! time, so a second thread's work counts), and the two threads' wall-time
//! speed-up over one. The two runs must give the same results.

use std::path::Path;
use std::time::Instant;

use fistage_analysis::assess::Analyses;
use fistage_analysis::robust::RobustSpec;
use fistage_analysis::sweep::{SweepSpec, run_points};
use fistage_model::RobotSpec;

use crate::timing::process_cpu_time;

/// Wall and CPU seconds of one computation.
struct Cost {
    wall: f64,
    cpu: f64,
}

/// `compute` on `threads` threads: its cost and its results.
fn costed<T>(threads: usize, compute: &impl Fn(usize) -> T) -> (Cost, T) {
    let (wall, cpu) = (Instant::now(), process_cpu_time());
    let results = compute(threads);
    let cost = Cost {
        wall: wall.elapsed().as_secs_f64(),
        cpu: process_cpu_time() - cpu,
    };
    (cost, results)
}

/// One row: the population on one thread, then on two (same results).
fn row<T: PartialEq>(
    label: &str,
    stages: usize,
    compute: impl Fn(usize) -> T,
) -> anyhow::Result<()> {
    let (one, first) = costed(1, &compute);
    let (two, second) = costed(2, &compute);
    anyhow::ensure!(
        first == second,
        "{label}: one and two threads gave different results"
    );
    let n = stages as f64;
    println!(
        "| {label} | {stages} | {:.0} | {:.0} | {:.2} |",
        n / one.cpu,
        n / two.cpu,
        one.wall / two.wall
    );
    Ok(())
}

/// A `[robust]` population of `scenario` judged by simulation: `samples`
/// stages of `duration` s (the scenario's when `None`).
fn robust_row(
    label: &str,
    scenario: &Path,
    samples: Option<usize>,
    duration: Option<f64>,
) -> anyhow::Result<()> {
    let loaded = fistage_model::load(scenario)?;
    let robot = RobotSpec::from_file(&loaded.scenario.robot)?;
    let mut spec = RobustSpec::from_scenario(&loaded.scenario, &robot, samples, None)?;
    spec.assessment.analysis = Analyses::Simulation;
    if duration.is_some() {
        spec.assessment.duration = duration;
    }
    let indices: Vec<usize> = (0..spec.samples).collect();
    row(label, indices.len(), |threads| {
        spec.run(&loaded, &robot, &indices, threads, &|_, _| {})
    })
}

/// Prints the Markdown table.
pub fn population_table() -> anyhow::Result<()> {
    println!("Simulated populations, stages per CPU-second (process CPU time, all threads):");
    println!();
    println!("| population | stages | 1 thread | 2 threads | 2-thread wall speed-up |");
    println!("|---|---:|---:|---:|---:|");
    robust_row(
        "(a) 1-DOF FI, `fig05b_simulated.toml`, 2 s",
        Path::new("scenarios/robust/fig05b_simulated.toml"),
        None,
        None,
    )?;
    robust_row(
        "(b) four bearings, `four_bearing_population.toml`, 2 s",
        Path::new("scenarios/robust/four_bearing_population.toml"),
        Some(200),
        Some(2.0),
    )?;
    let sweep = Path::new("scenarios/bench/fig06b_40x40.toml");
    let loaded = fistage_model::load(sweep)?;
    let robot = RobotSpec::from_file(&loaded.scenario.robot)?;
    let spec = SweepSpec::from_scenario(&loaded.scenario)?;
    let indices: Vec<usize> = (0..spec.len()).collect();
    row(
        "(c) 40 x 40 sweep, `fig06b_40x40.toml`",
        indices.len(),
        |threads| run_points(&loaded, &robot, &spec, &indices, threads, &|_, _| {}),
    )
}
