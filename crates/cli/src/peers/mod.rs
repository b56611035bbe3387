//! Peers of the native engines in `fistage bench --peers`: CVODE's BDF and
//! Adams methods (SUNDIALS, opened at run time) and SciPy's `solve_ivp`
//! (through the Python package's plant, where a Python with fistage and
//! SciPy is at hand). Each peer integrates the same model from the same
//! start, with the same tolerances and the same output grid, so the table
//! rows compare integrators, not models.

pub mod cvode;
pub mod scipy;

use fistage_model::Loaded;
use fistage_sim::{ScenarioExcitation, SimSettings, StepCounts, Trajectory, initial_state};

use crate::bench::{median, thread_cpu_time};

/// One peer's timed run at one tolerance.
pub struct PeerRun {
    /// What ran, as the table shows it.
    pub method: String,
    /// The method without this run's counts: rows of one family are one
    /// peer at several tolerances.
    pub family: String,
    /// Median wall time, s.
    pub wall_s: f64,
    /// Median CPU time of the integration, s.
    pub cpu_s: f64,
    /// Counters of the last run.
    pub counts: StepCounts,
    /// Whether steps and rejections are known (SciPy reports only evaluations).
    pub steps_known: bool,
    /// Samples of the last run.
    pub trajectory: Trajectory,
}

/// A peer that could not run, and why (shown in the table instead of numbers).
pub struct PeerSkipped {
    /// The peer.
    pub method: String,
    /// Why.
    pub reason: String,
}

/// CVODE BDF and Adams on `loaded` at `rtol`, `repeat` runs each (the
/// median is kept); a method that fails says so instead.
pub fn cvode_runs(
    cvode: &cvode::Cvode,
    loaded: &Loaded,
    rtol: f64,
    repeat: usize,
) -> anyhow::Result<Vec<Result<PeerRun, PeerSkipped>>> {
    let x0 = initial_state(&loaded.model, &loaded.scenario)?;
    let excitation = ScenarioExcitation::from_scenario(&loaded.scenario);
    let settings = SimSettings {
        rtol,
        ..SimSettings::from_scenario(&loaded.scenario)
    };
    let mut rows = Vec::new();
    for method in [cvode::CvodeMethod::Bdf, cvode::CvodeMethod::Adams] {
        let mut walls = Vec::with_capacity(repeat);
        let mut cpus = Vec::with_capacity(repeat);
        let mut last = None;
        let mut failure = None;
        for _ in 0..repeat.max(1) {
            let (wall, cpu) = (std::time::Instant::now(), thread_cpu_time());
            match cvode.simulate(method, &loaded.model, &x0, &excitation, &settings) {
                Ok(run) => {
                    cpus.push(thread_cpu_time() - cpu);
                    walls.push(wall.elapsed().as_secs_f64());
                    last = Some(run);
                }
                Err(e) => {
                    failure = Some(e);
                    break;
                }
            }
        }
        rows.push(match (last, failure) {
            (Some(run), None) => Ok(PeerRun {
                family: method.label().to_string(),
                method: format!("{} ({} Jacobians)", method.label(), run.jacobians)
                    .replace(" (0 Jacobians)", ""),
                wall_s: median(&mut walls),
                cpu_s: median(&mut cpus),
                counts: run.counts,
                steps_known: true,
                trajectory: run.trajectory,
            }),
            (_, failure) => Err(PeerSkipped {
                method: method.label().to_string(),
                reason: failure.unwrap_or_else(|| "no run".into()),
            }),
        });
    }
    Ok(rows)
}
