//! Engines integrate a [`Model`] driven by an [`Excitation`] and return a
//! [`Trajectory`] sampled on a uniform grid. [`AdaptiveEngine`] runs any of
//! the ODE layer's error-controlled methods ([`MethodKind`]: Dormand-Prince
//! 5(4), the implicit-explicit pair, DOP853, the classical method,
//! Rosenbrock-W) through the one driver (module `driver`); [`AutoEngine`]
//! picks one of them for the model; the rapier engine lives in
//! [`crate::rapier_engine`]. Which engine runs is an [`EngineKind`],
//! checked when the scenario is read.

use std::ops::ControlFlow;
use std::time::Instant;

use fistage_model::{EngineKind, Inputs, Model, Scenario};

use fistage_ode::{
    AdaptiveMethod, ClassicalRungeKutta, Dop853, DormandPrince, ImexRungeKutta, MethodKind,
    Rosenbrock, Tolerances,
};

use crate::choice::{MethodChoice, choose_method};
use crate::driver::{ModelSystem, drive, slip_floor, tolerances};
use crate::settings::{SimError, SimSettings, check_settings, sample_times};
use crate::trajectory::{SolverStats, Trajectory};
use fistage_model::excitation::Excitation;

/// What an engine tells of a run as it goes: the fraction done, now and
/// then; `ControlFlow::Break` stops the run with [`SimError::Cancelled`].
pub type Progress<'a> = dyn FnMut(f64) -> ControlFlow<()> + 'a;

/// A [`Progress`] that wants nothing and never stops a run.
pub fn no_progress(_fraction: f64) -> ControlFlow<()> {
    ControlFlow::Continue(())
}

/// An integration engine.
pub trait Engine {
    /// Which engine this is.
    fn kind(&self) -> EngineKind;

    /// Engine name as used in scenario files.
    fn name(&self) -> &'static str {
        self.kind().name()
    }

    /// Integrates from `x0` at t = 0; `progress` receives the fraction done
    /// and may stop the run.
    fn simulate(
        &self,
        model: &Model,
        x0: &[f64],
        excitation: &dyn Excitation,
        settings: &SimSettings,
        progress: &mut Progress<'_>,
    ) -> Result<Trajectory, SimError>;
}

/// An error-controlled engine: one of the ODE layer's adaptive methods
/// driven over the model (segments between the inputs' discontinuities,
/// steps that end on the friction law's kinks, uniform samples by dense
/// output).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AdaptiveEngine {
    /// The method.
    pub method: MethodKind,
}

impl AdaptiveEngine {
    /// Dormand-Prince 5(4), the `native` engine of scenario files.
    pub const NATIVE: Self = Self::new(MethodKind::DormandPrince);

    /// The engine of `method`.
    pub const fn new(method: MethodKind) -> Self {
        Self { method }
    }
}

impl Engine for AdaptiveEngine {
    fn kind(&self) -> EngineKind {
        engine_kind_of(self.method)
    }

    fn simulate(
        &self,
        model: &Model,
        x0: &[f64],
        excitation: &dyn Excitation,
        settings: &SimSettings,
        progress: &mut Progress<'_>,
    ) -> Result<Trajectory, SimError> {
        let tol = settings_tolerances(model, settings);
        let run = Run {
            engine: self.kind(),
            model,
            x0,
            excitation,
            settings,
        };
        match self.method {
            MethodKind::DormandPrince => {
                run.integrate(progress, |s| DormandPrince::new(s, 0.0, x0, tol))
            }
            MethodKind::Imex => run.integrate(progress, |s| ImexRungeKutta::new(s, 0.0, x0, tol)),
            MethodKind::Dop853 => run.integrate(progress, |s| Dop853::new(s, 0.0, x0, tol)),
            MethodKind::Classical => {
                run.integrate(progress, |s| ClassicalRungeKutta::new(s, 0.0, x0, tol))
            }
            MethodKind::Rosenbrock => {
                // The first step is a thousandth of a sample interval.
                let span = settings.sample_interval.min(settings.t_end);
                run.integrate(progress, |s| {
                    Rosenbrock::with_initial_span(s, 0.0, x0, tol, span)
                })
            }
        }
    }
}

/// The engine kind (the name in scenario files) of an adaptive method.
pub fn engine_kind_of(method: MethodKind) -> EngineKind {
    match method {
        MethodKind::DormandPrince => EngineKind::Native,
        MethodKind::Imex => EngineKind::Imex,
        MethodKind::Dop853 => EngineKind::Dop853,
        MethodKind::Classical => EngineKind::Rk4,
        MethodKind::Rosenbrock => EngineKind::Rosenbrock,
    }
}

/// One run of an adaptive engine: what it integrates and how.
struct Run<'r> {
    engine: EngineKind,
    model: &'r Model,
    x0: &'r [f64],
    excitation: &'r dyn Excitation,
    settings: &'r SimSettings,
}

impl Run<'_> {
    /// The loop of the adaptive engines: the driver's segments and step
    /// budget, uniform samples by interpolation, progress; `start` starts
    /// the method at the run's first point.
    fn integrate<M>(
        self,
        progress: &mut Progress<'_>,
        start: impl FnOnce(&mut ModelSystem<'_>) -> M,
    ) -> Result<Trajectory, SimError>
    where
        M: for<'s> AdaptiveMethod<ModelSystem<'s>>,
    {
        let Run {
            engine,
            model,
            x0,
            excitation,
            settings,
        } = self;
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
            slip_floor(model, &settings_tolerances(model, settings)),
            |integrator, system| {
                while next_sample < times.len()
                    && times[next_sample] <= integrator.time() * (1.0 + 1e-14)
                {
                    integrator.interpolate(system, times[next_sample], &mut buffer);
                    trajectory.push(times[next_sample], &buffer);
                    next_sample += 1;
                }
                if integrator.counts().steps.is_multiple_of(2048) {
                    progress(integrator.time() / settings.t_end)
                } else {
                    ControlFlow::Continue(())
                }
            },
        )?;
        let _ = progress(1.0);
        trajectory.stats = SolverStats {
            engine: engine.name().to_string(),
            counts: integrator.counts(),
            wall_time_s: started.elapsed().as_secs_f64(),
        };
        Ok(trajectory)
    }
}

fn settings_tolerances(model: &Model, settings: &SimSettings) -> Tolerances {
    tolerances(model, settings.rtol, settings.atol_scale, settings.max_step)
}

/// The default engine: the method [`choose_method`] picks for the model
/// (explicit Dormand-Prince or the implicit-explicit pair), read at the
/// slipping equilibrium under `slipping`. The trajectory names the method
/// that ran.
#[derive(Debug, Clone, Copy, Default)]
pub struct AutoEngine {
    /// The inputs of the slipping equilibrium the choice is read at.
    pub slipping: Inputs,
}

impl AutoEngine {
    /// For a scenario: its counter-surfaces slide at the platform velocity
    /// less the reference's traverse velocity.
    pub fn for_scenario(scenario: &Scenario) -> Self {
        Self {
            slipping: scenario.slipping_inputs(),
        }
    }

    /// The method this engine takes for `model` started at `x0` and
    /// integrated to `rtol`.
    pub fn choice(&self, model: &Model, x0: &[f64], rtol: f64) -> MethodChoice {
        choose_method(model, &self.slipping, x0, rtol)
    }

    /// The engine of the method it takes for `model` started at `x0` and
    /// integrated to `rtol`: for many runs of one model, the choice made once.
    pub fn resolved(&self, model: &Model, x0: &[f64], rtol: f64) -> Box<dyn Engine> {
        Box::new(AdaptiveEngine::new(self.choice(model, x0, rtol).method))
    }
}

impl Engine for AutoEngine {
    fn kind(&self) -> EngineKind {
        EngineKind::Auto
    }

    fn simulate(
        &self,
        model: &Model,
        x0: &[f64],
        excitation: &dyn Excitation,
        settings: &SimSettings,
        progress: &mut Progress<'_>,
    ) -> Result<Trajectory, SimError> {
        self.resolved(model, x0, settings.rtol)
            .simulate(model, x0, excitation, settings, progress)
    }
}
