//! The summary of a run, as `summary.json` holds it and the Python package
//! gives it: the scenario, the steady-state window, the solver's
//! statistics, the tracking metrics (with a servo) and each signal's
//! statistics over the window.

use fistage_model::Loaded;

use crate::metrics::SignalSummary;
use crate::run::RunOutput;

#[derive(serde::Serialize)]
struct SummaryFile<'a> {
    scenario: String,
    title: &'a str,
    robot: String,
    duration_s: f64,
    window_s: [f64; 2],
    rtol: f64,
    solver: &'a crate::SolverStats,
    /// With a servo: RMS error, peak errors at reference reversals, settling times.
    #[serde(skip_serializing_if = "Option::is_none")]
    tracking: Option<&'a crate::TrackingMetrics>,
    signals: serde_json::Map<String, serde_json::Value>,
}

#[derive(serde::Serialize)]
struct SignalEntry<'a> {
    unit: &'a str,
    mean: f64,
    peak_to_peak: f64,
    rms: f64,
    min: f64,
    max: f64,
    std: f64,
}

impl<'a> From<&'a SignalSummary> for SignalEntry<'a> {
    fn from(s: &'a SignalSummary) -> Self {
        Self {
            unit: &s.unit,
            mean: s.stats.mean,
            peak_to_peak: s.stats.peak_to_peak,
            rms: s.stats.rms,
            min: s.stats.min,
            max: s.stats.max,
            std: s.stats.std,
        }
    }
}

/// The summary document of a run of `loaded`, to serialise (keys in the
/// order of `summary.json`).
pub fn document<'a>(loaded: &'a Loaded, output: &'a RunOutput) -> impl serde::Serialize + 'a {
    let scenario = &loaded.scenario;
    let mut signals = serde_json::Map::new();
    for s in &output.summary {
        signals.insert(s.name.clone(), serde_json::json!(SignalEntry::from(s)));
    }
    SummaryFile {
        scenario: scenario.file.display().to_string(),
        title: &scenario.title,
        robot: scenario.robot.display().to_string(),
        duration_s: scenario.duration,
        window_s: scenario.window,
        rtol: scenario.solver.rtol,
        solver: &output.trajectory.stats,
        tracking: output.tracking.as_ref(),
        signals,
    }
}
