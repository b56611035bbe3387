//! How a run is integrated ([`SimSettings`]), how it can fail
//! ([`SimError`]), the checks every engine makes before it starts, and the
//! uniform output grid.

use fistage_model::{Model, Scenario};
use thiserror::Error;

/// How to integrate.
#[derive(Debug, Clone, PartialEq)]
pub struct SimSettings {
    /// End time, s (the run starts at 0).
    pub t_end: f64,
    /// Output sample interval, s.
    pub sample_interval: f64,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance of state i is `rtol * atol_scale * nominal_i`.
    pub atol_scale: f64,
    /// Largest step, s.
    pub max_step: Option<f64>,
    /// Largest number of accepted plus rejected steps.
    pub max_steps: u64,
}

impl SimSettings {
    /// Settings from a scenario file.
    pub fn from_scenario(scenario: &Scenario) -> Self {
        Self {
            t_end: scenario.duration,
            sample_interval: 1.0 / scenario.sample_rate,
            rtol: scenario.solver.rtol,
            atol_scale: scenario.solver.atol_scale,
            max_step: scenario.solver.max_step,
            max_steps: scenario.solver.max_steps,
        }
    }
}

/// Why a simulation failed. Each names the simulated time.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SimError {
    /// The step size fell below round-off level.
    #[error("step size underflow at t = {t:.9} s (h = {h:.3e} s){}", cause_text(.non_finite))]
    StepSizeUnderflow {
        /// Time reached, s.
        t: f64,
        /// Step size, s.
        h: f64,
        /// Name of the first state that became non-finite, if that was the cause.
        non_finite: Option<String>,
    },
    /// The caller stopped the run (its progress callback said stop).
    #[error("stopped at t = {t:.6} s by the caller")]
    Cancelled {
        /// Time reached, s.
        t: f64,
    },
    /// The step budget ran out.
    #[error(
        "gave up at t = {t:.6} s after {steps} steps (raise solver.max_steps or loosen solver.rtol)"
    )]
    TooManySteps {
        /// Time reached, s.
        t: f64,
        /// Steps taken.
        steps: u64,
    },
    /// The step size collapsed: at its recent pace the run would need far
    /// more steps than its budget.
    #[error(
        "the step size collapsed to {h:.3e} s at t = {t:.6} s: at this pace the run to t = {t_end:e} s (its duration) needs about {projected:.3e} steps, more than four times solver.max_steps = {max_steps} (the model changes faster than the tolerance allows there: check its parameters and duration, or loosen solver.rtol)"
    )]
    StepSizeCollapse {
        /// Time reached, s.
        t: f64,
        /// Where the run was to end, s.
        t_end: f64,
        /// Mean step over the last window, s.
        h: f64,
        /// Steps the run would need at that pace.
        projected: f64,
        /// The budget.
        max_steps: u64,
    },
    /// The engine a scenario names is not in this build.
    #[error(
        "the {engine} engine is not in this build of fistage (its `{feature}` feature is off: build with the default features)"
    )]
    EngineNotBuilt {
        /// The engine's scenario name.
        engine: &'static str,
        /// The cargo feature that brings it.
        feature: &'static str,
    },
    /// A fixed-step engine would need more steps than the budget allows.
    #[error(
        "the fixed step dt = {dt:.3e} s needs {steps:.3e} steps, more than solver.max_steps = {max_steps} (raise rapier.dt or solver.max_steps, or shorten the run)"
    )]
    FixedStepBudget {
        /// The step, s.
        dt: f64,
        /// Steps the run needs.
        steps: f64,
        /// The budget.
        max_steps: u64,
    },
    /// The initial state is not finite or has the wrong length.
    #[error("invalid initial state: {0}")]
    InvalidInitialState(String),
    /// Settings out of range.
    #[error("invalid settings: {0}")]
    InvalidSettings(String),
    /// A fixed-step engine produced a non-finite state.
    #[error(
        "state \"{state}\" became non-finite at t = {t:.9} s (the fixed step rapier.dt = {dt:.3e} s is too long for this model)"
    )]
    NonFinite {
        /// Time reached, s.
        t: f64,
        /// The fixed step, s.
        dt: f64,
        /// Name of the first non-finite state.
        state: String,
    },
}

fn cause_text(non_finite: &Option<String>) -> String {
    match non_finite {
        Some(name) => format!(": state \"{name}\" became non-finite"),
        None => ": the solution changes faster than the tolerance allows".into(),
    }
}

pub(crate) fn check_settings(
    model: &Model,
    x0: &[f64],
    settings: &SimSettings,
) -> Result<(), SimError> {
    if x0.len() != model.n_states() {
        return Err(SimError::InvalidInitialState(format!(
            "{} entries for {} states",
            x0.len(),
            model.n_states()
        )));
    }
    if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
        return Err(SimError::InvalidInitialState(format!(
            "\"{}\" is {}",
            model.layout().names[i],
            x0[i]
        )));
    }
    let positive = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(SimError::InvalidSettings(format!(
                "{name} must be > 0, got {}",
                fistage_model::rule::show(v)
            )))
        }
    };
    positive("t_end", settings.t_end)?;
    positive("sample_interval", settings.sample_interval)?;
    positive("rtol", settings.rtol)?;
    positive("atol_scale", settings.atol_scale)?;
    if let Some(h) = settings.max_step {
        positive("max_step", h)?;
    }
    Ok(())
}

/// Sample times k * dt for k = 0..=N with N dt <= t_end (plus t_end itself when
/// it is not on the grid).
pub fn sample_times(t_end: f64, dt: f64) -> Vec<f64> {
    let n = (t_end / dt * (1.0 + 1e-12)).floor() as usize;
    let mut times: Vec<f64> = (0..=n).map(|k| k as f64 * dt).collect();
    if let Some(&last) = times.last()
        && t_end - last > 1e-9 * dt
    {
        times.push(t_end);
    }
    times
}
