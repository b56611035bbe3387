//! One scenario run from a loaded study: initial state, engine choice,
//! integration, output signals and steady-state statistics.

use fistage_model::excitation::{ScenarioExcitation, initial_state};
use fistage_model::{EngineKind, LoadError, Loaded, Model, Scenario};
use thiserror::Error;

use crate::metrics::{SignalSummary, summarize};
use crate::select::engine_for;
use crate::settings::{SimError, SimSettings};
use crate::trajectory::{SignalTable, Trajectory};

/// Why a scenario run failed.
#[derive(Debug, Error)]
pub enum RunError {
    /// The scenario asks for something the model does not have.
    #[error(transparent)]
    Scenario(#[from] LoadError),
    /// The integration failed.
    #[error("{file}: simulation failed: {source}")]
    Simulation {
        /// Scenario file.
        file: String,
        /// The engine's error.
        source: SimError,
    },
}

/// Everything a run produces.
#[derive(Debug, Clone)]
pub struct RunOutput {
    /// States on the output grid, with solver statistics.
    pub trajectory: Trajectory,
    /// Output signals selected by the scenario (all when it names none).
    pub signals: SignalTable,
    /// Statistics of the selected signals over the steady-state window.
    pub summary: Vec<SignalSummary>,
    /// Tracking metrics of the servo (every signal is used, selected or not).
    pub tracking: Option<crate::tracking::TrackingMetrics>,
}

/// Every name in `output.signals` must be a signal of the model (checked
/// before integrating, so a typo costs nothing).
fn check_signal_names(model: &Model, scenario: &Scenario) -> Result<(), LoadError> {
    let Some(wanted) = &scenario.signals else {
        return Ok(());
    };
    let missing: Vec<&str> = wanted
        .iter()
        .filter(|name| model.signal_index(name).is_none())
        .map(String::as_str)
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    let available: Vec<&str> = model.signals().iter().map(|s| s.name.as_str()).collect();
    Err(scenario.error(
        "output.signals",
        format!(
            "unknown signal(s) {} (available: {})",
            missing.join(", "),
            available.join(", ")
        ),
    ))
}

/// Everything a run checks before it integrates, so that `fistage check`
/// refuses exactly what `fistage run` would: output signal names, colliders
/// only with the rapier engine and naming joints and links of the model, and
/// the start state (equilibrium, `[initial]` names). Gives the start state.
pub fn validate(loaded: &Loaded) -> Result<Vec<f64>, RunError> {
    let scenario = &loaded.scenario;
    let model = &loaded.model;
    check_signal_names(model, scenario)?;
    let colliders = if !scenario.rapier.stops.is_empty() {
        Some("rapier.stop")
    } else if scenario.rapier.payload.is_some() {
        Some("rapier.payload")
    } else {
        None
    };
    match (scenario.solver.engine, colliders) {
        (EngineKind::Rapier, _) => {
            check_rapier(model, scenario).map_err(|source| RunError::Simulation {
                file: scenario.file.display().to_string(),
                source,
            })?;
        }
        (engine, Some(key)) => {
            return Err(scenario
                .error(
                    key,
                    format!(
                        "colliders need engine = \"rapier\"; the {engine} engine has no contacts"
                    ),
                )
                .into());
        }
        (_, None) => {}
    }
    Ok(initial_state(model, scenario)?)
}

/// The rapier engine's colliders against the model.
#[cfg(feature = "rapier")]
fn check_rapier(model: &Model, scenario: &Scenario) -> Result<(), SimError> {
    crate::rapier_engine::check_colliders(model, &scenario.rapier)
}

/// A build without rapier refuses its engine before anything runs.
#[cfg(not(feature = "rapier"))]
fn check_rapier(_model: &Model, _scenario: &Scenario) -> Result<(), SimError> {
    Err(crate::absent_engine::AbsentEngine::rapier().error())
}

/// Runs a loaded scenario with the engine it names.
pub fn run_scenario(
    loaded: &Loaded,
    progress: &mut crate::engine::Progress<'_>,
) -> Result<RunOutput, RunError> {
    let scenario = &loaded.scenario;
    let model = &loaded.model;
    let x0 = validate(loaded)?;
    let engine = engine_for(scenario);
    let excitation = ScenarioExcitation::from_scenario(scenario);
    let settings = SimSettings::from_scenario(scenario);
    let trajectory = engine
        .simulate(model, &x0, &excitation, &settings, progress)
        .map_err(|source| RunError::Simulation {
            file: scenario.file.display().to_string(),
            source,
        })?;
    let all = trajectory.signals(model, &excitation);
    let tracking = crate::tracking::tracking_metrics(
        &scenario.reference,
        &all,
        scenario.window,
        scenario.settle_window,
    );
    let signals = match &scenario.signals {
        None => all,
        // Names were checked before the run; select cannot miss.
        Some(wanted) => all.select(wanted).unwrap_or_default(),
    };
    let summary = summarize(&signals, scenario.window[0], scenario.window[1]);
    Ok(RunOutput {
        trajectory,
        signals,
        summary,
        tracking,
    })
}
