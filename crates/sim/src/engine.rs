//! Engines integrate a [`Model`] driven by an [`Excitation`] and return a
//! [`Trajectory`] sampled on a uniform grid. The native engine is the
//! error-controlled Dormand-Prince 5(4) of [`crate::dopri`], the Rosenbrock
//! engine the linearly implicit method of [`crate::rosenbrock`]; both step
//! through the one driver of [`crate::driver`]. Which engine runs is an
//! [`EngineKind`], checked when the scenario is read.

use std::time::Instant;

use fistage_model::{EngineKind, Inputs, Model, Reference, Scenario};
use thiserror::Error;

use crate::dopri::{DormandPrince, Tolerances};
use crate::driver::{Integrating, ModelSystem, drive, tolerances};
use crate::rosenbrock::Rosenbrock;
use crate::trajectory::{SolverStats, Trajectory};

/// What drives the model's inputs over time.
pub trait Excitation: Sync {
    /// The inputs at time t.
    fn inputs(&self, t: f64) -> Inputs;
    /// Times where the inputs jump (the engine restarts there).
    fn breakpoints(&self) -> Vec<f64> {
        Vec::new()
    }
    /// True when the inputs do not depend on time (the engine then reads
    /// them once).
    fn is_constant(&self) -> bool {
        false
    }
}

/// Inputs given by a scenario: its reference, its platform velocity, no external force.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioExcitation {
    /// Servo reference.
    pub reference: Reference,
    /// Counter-surface velocity, m/s.
    pub platform_velocity: f64,
    /// Constant external servo force, N.
    pub servo_force: f64,
}

impl ScenarioExcitation {
    /// The excitation a scenario describes.
    pub fn from_scenario(scenario: &Scenario) -> Self {
        Self {
            reference: scenario.reference.clone(),
            platform_velocity: scenario.platform_velocity,
            servo_force: 0.0,
        }
    }
}

impl Excitation for ScenarioExcitation {
    fn inputs(&self, t: f64) -> Inputs {
        Inputs {
            reference: self.reference.sample(t),
            servo_force: self.servo_force,
            platform_velocity: self.platform_velocity,
        }
    }

    fn breakpoints(&self) -> Vec<f64> {
        self.reference.breakpoints()
    }

    fn is_constant(&self) -> bool {
        matches!(self.reference, Reference::Constant { .. })
    }
}

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
    /// The initial state is not finite or has the wrong length.
    #[error("invalid initial state: {0}")]
    InvalidInitialState(String),
    /// Settings out of range.
    #[error("invalid settings: {0}")]
    InvalidSettings(String),
    /// A fixed-step engine produced a non-finite state.
    #[error(
        "state \"{state}\" became non-finite at t = {t:.9} s (the fixed step is too long for this model)"
    )]
    NonFinite {
        /// Time reached, s.
        t: f64,
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

/// An integration engine.
pub trait Engine {
    /// Which engine this is.
    fn kind(&self) -> EngineKind;

    /// Engine name as used in scenario files.
    fn name(&self) -> &'static str {
        self.kind().name()
    }

    /// Integrates from `x0` at t = 0; `progress` receives the fraction done.
    fn simulate(
        &self,
        model: &Model,
        x0: &[f64],
        excitation: &dyn Excitation,
        settings: &SimSettings,
        progress: &mut dyn FnMut(f64),
    ) -> Result<Trajectory, SimError>;
}

/// Error-controlled explicit Dormand-Prince 5(4) with dense output.
#[derive(Debug, Clone, Copy, Default)]
pub struct NativeEngine;

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
                "{name} must be > 0, got {v}"
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

/// The loop of the adaptive engines: the driver's segments and step budget,
/// uniform samples by interpolation, progress.
fn integrate<I: Integrating>(
    engine: EngineKind,
    model: &Model,
    x0: &[f64],
    excitation: &dyn Excitation,
    settings: &SimSettings,
    progress: &mut dyn FnMut(f64),
    start: impl FnOnce(&mut ModelSystem) -> I,
) -> Result<Trajectory, SimError> {
    check_settings(model, x0, settings)?;
    let started = Instant::now();
    let n = model.n_states();
    let mut workspace = model.workspace();
    let mut system = ModelSystem::new(model, excitation, &mut workspace);
    let times = sample_times(settings.t_end, settings.sample_interval);
    let mut trajectory = Trajectory::with_capacity(n, times.len());
    trajectory.push(0.0, x0);
    let mut next_sample = 1;
    let mut integrator = start(&mut system);
    let mut buffer = vec![0.0; n];
    drive(
        &mut integrator,
        &mut system,
        settings.t_end,
        settings.max_steps,
        |integrator| {
            while next_sample < times.len()
                && times[next_sample] <= integrator.time() * (1.0 + 1e-14)
            {
                integrator.interpolate(times[next_sample], &mut buffer);
                trajectory.push(times[next_sample], &buffer);
                next_sample += 1;
            }
            if integrator.counts().steps.is_multiple_of(2048) {
                progress(integrator.time() / settings.t_end);
            }
        },
    )?;
    progress(1.0);
    trajectory.stats = SolverStats {
        engine: engine.name().to_string(),
        counts: integrator.counts(),
        wall_time_s: started.elapsed().as_secs_f64(),
    };
    Ok(trajectory)
}

fn settings_tolerances(model: &Model, settings: &SimSettings) -> Tolerances {
    tolerances(model, settings.rtol, settings.atol_scale, settings.max_step)
}

impl Engine for NativeEngine {
    fn kind(&self) -> EngineKind {
        EngineKind::Native
    }

    fn simulate(
        &self,
        model: &Model,
        x0: &[f64],
        excitation: &dyn Excitation,
        settings: &SimSettings,
        progress: &mut dyn FnMut(f64),
    ) -> Result<Trajectory, SimError> {
        let tol = settings_tolerances(model, settings);
        integrate(
            self.kind(),
            model,
            x0,
            excitation,
            settings,
            progress,
            |system| DormandPrince::new(system, 0.0, x0, tol),
        )
    }
}

/// The linearly implicit Rosenbrock-W engine (ROS34PW2) with the model's
/// exact Jacobian, reused over a few steps: for stages stiffer than the
/// explicit engine handles economically.
#[derive(Debug, Clone, Copy, Default)]
pub struct RosenbrockEngine;

impl Engine for RosenbrockEngine {
    fn kind(&self) -> EngineKind {
        EngineKind::Rosenbrock
    }

    fn simulate(
        &self,
        model: &Model,
        x0: &[f64],
        excitation: &dyn Excitation,
        settings: &SimSettings,
        progress: &mut dyn FnMut(f64),
    ) -> Result<Trajectory, SimError> {
        let tol = settings_tolerances(model, settings);
        let span = settings.sample_interval.min(settings.t_end);
        integrate(
            self.kind(),
            model,
            x0,
            excitation,
            settings,
            progress,
            |system| Rosenbrock::new(system, 0.0, x0, tol, span),
        )
    }
}

/// The engine of a kind with default settings (the rapier engine without colliders).
pub fn engine_of_kind(kind: EngineKind) -> Box<dyn Engine> {
    match kind {
        EngineKind::Native => Box::new(NativeEngine),
        EngineKind::Rosenbrock => Box::new(RosenbrockEngine),
        EngineKind::Rapier => Box::new(crate::rapier_engine::RapierEngine::default()),
    }
}

/// An engine by name or alias (`native`, `dopri5`, `rosenbrock`, `implicit`, `rapier`).
pub fn engine_by_name(name: &str) -> Option<Box<dyn Engine>> {
    name.parse().ok().map(engine_of_kind)
}

/// The engine a scenario names (`solver.engine` or `engine`), with its settings.
pub fn engine_for(scenario: &Scenario) -> Box<dyn Engine> {
    match scenario.solver.engine {
        EngineKind::Rapier => Box::new(crate::rapier_engine::RapierEngine {
            settings: scenario.rapier.clone(),
        }),
        kind => engine_of_kind(kind),
    }
}
