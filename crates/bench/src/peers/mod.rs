//! Peers of the native engines in `fistage bench --peers`: CVODE's BDF and
//! Adams methods (SUNDIALS, opened at run time) and SciPy's `solve_ivp`
//! (through the Python package's plant, where a Python with fistage and
//! SciPy is at hand). Each peer integrates the same model from the same
//! start, with the same tolerances and the same output grid, so the table
//! rows compare integrators, not models.

pub mod cvode;
pub mod scipy;

/// The environment variable that hides every optional component the bench
/// can use (CVODE, a Python with fistage and SciPy, FMPy), as on a machine
/// that has none of them: `.ci/run` sets it for one pass of the tests that
/// use them, so that their SKIPPED paths are run too.
pub const HIDE_OPTIONAL: &str = "FISTAGE_HIDE_OPTIONAL";

/// Why an optional component is not looked for, when [`HIDE_OPTIONAL`] is
/// set to anything but empty or `0`.
pub fn hidden() -> Option<String> {
    std::env::var(HIDE_OPTIONAL)
        .ok()
        .filter(|value| !value.is_empty() && value != "0")
        .map(|value| format!("hidden ({HIDE_OPTIONAL}={value})"))
}

use fistage_model::Loaded;
use fistage_sim::{ScenarioExcitation, SimSettings, StepCounts, Trajectory, initial_state};

use crate::timing::{median, thread_cpu_time};

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

/// CVODE BDF and Adams on one model at one tolerance, timed one run at a
/// time so that the bench can alternate them with its own runs (a drift of
/// the machine's speed then falls on every contender alike).
pub struct CvodeTimer<'a> {
    cvode: &'a cvode::Cvode,
    loaded: &'a Loaded,
    x0: Vec<f64>,
    excitation: ScenarioExcitation,
    settings: SimSettings,
    methods: Vec<MethodTimes>,
}

/// The runs of one method so far.
struct MethodTimes {
    method: cvode::CvodeMethod,
    walls: Vec<f64>,
    cpus: Vec<f64>,
    last: Option<cvode::CvodeRun>,
    failure: Option<String>,
}

impl<'a> CvodeTimer<'a> {
    /// BDF and Adams on `loaded` at `rtol`.
    pub fn new(cvode: &'a cvode::Cvode, loaded: &'a Loaded, rtol: f64) -> anyhow::Result<Self> {
        Ok(Self {
            cvode,
            loaded,
            x0: initial_state(&loaded.model, &loaded.scenario)?,
            excitation: ScenarioExcitation::from_scenario(&loaded.scenario),
            settings: SimSettings {
                rtol,
                ..SimSettings::from_scenario(&loaded.scenario)
            },
            methods: [cvode::CvodeMethod::Bdf, cvode::CvodeMethod::Adams]
                .into_iter()
                .map(|method| MethodTimes {
                    method,
                    walls: Vec::new(),
                    cpus: Vec::new(),
                    last: None,
                    failure: None,
                })
                .collect(),
        })
    }

    /// One timed run of each method that has not failed.
    pub fn round(&mut self) {
        for times in &mut self.methods {
            if times.failure.is_some() {
                continue;
            }
            let (wall, cpu) = (std::time::Instant::now(), thread_cpu_time());
            match self.cvode.simulate(
                times.method,
                &self.loaded.model,
                &self.x0,
                &self.excitation,
                &self.settings,
            ) {
                Ok(run) => {
                    times.cpus.push(thread_cpu_time() - cpu);
                    times.walls.push(wall.elapsed().as_secs_f64());
                    times.last = Some(run);
                }
                Err(e) => times.failure = Some(e),
            }
        }
    }

    /// Each method's median times and last run, or why it did not run.
    pub fn finish(self) -> Vec<Result<PeerRun, PeerSkipped>> {
        self.methods
            .into_iter()
            .map(|mut times| match (times.last, times.failure) {
                (Some(run), None) => Ok(PeerRun {
                    family: times.method.label().to_string(),
                    method: format!("{} ({} Jacobians)", times.method.label(), run.jacobians)
                        .replace(" (0 Jacobians)", ""),
                    wall_s: median(&mut times.walls),
                    cpu_s: median(&mut times.cpus),
                    counts: run.counts,
                    steps_known: true,
                    trajectory: run.trajectory,
                }),
                (_, failure) => Err(PeerSkipped {
                    method: times.method.label().to_string(),
                    reason: failure.unwrap_or_else(|| "no run".into()),
                }),
            })
            .collect()
    }
}
