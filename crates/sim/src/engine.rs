//! Engines integrate a [`Model`] driven by an [`Excitation`] and return a
//! [`Trajectory`] sampled on a uniform grid. The native engine is the
//! error-controlled Dormand-Prince 5(4) of [`crate::dopri`], the imex engine
//! the pair of [`crate::imex`], the dop853 engine the eighth-order pair of
//! [`crate::dop853`], the rk4 engine the classical method of [`crate::rk4`],
//! the Rosenbrock engine the linearly implicit method of
//! [`crate::rosenbrock`]; all step through the one driver (module `driver`). Which engine runs is an
//! [`EngineKind`], checked when the scenario is read.

use std::ops::ControlFlow;
use std::time::Instant;

use fistage_model::{EngineKind, Inputs, Model, Scenario};

use crate::dop853::Dop853;
use crate::dopri::{DormandPrince, Tolerances};
use crate::driver::{Integrating, ModelSystem, drive, slip_floor, tolerances};
use crate::excitation::Excitation;
use crate::imex::ImexRungeKutta;
use crate::method::{Method, MethodChoice, choose_method};
use crate::rk4::ClassicalRungeKutta;
use crate::rosenbrock::Rosenbrock;
use crate::settings::{SimError, SimSettings, check_settings, sample_times};
use crate::trajectory::{SolverStats, Trajectory};

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

/// Error-controlled explicit Dormand-Prince 5(4) with dense output.
#[derive(Debug, Clone, Copy, Default)]
pub struct NativeEngine;

/// The loop of the adaptive engines: the driver's segments and step budget,
/// uniform samples by interpolation, progress.
fn integrate<I: Integrating>(
    engine: EngineKind,
    model: &Model,
    x0: &[f64],
    excitation: &dyn Excitation,
    settings: &SimSettings,
    progress: &mut Progress<'_>,
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
        progress: &mut Progress<'_>,
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
        match self.choice(model, x0, rtol).method {
            Method::DormandPrince => Box::new(NativeEngine),
            Method::ImexBristles => Box::new(ImexEngine),
            Method::Classical => Box::new(Rk4Engine),
        }
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

/// The implicit-explicit engine: Kennedy and Carpenter's `ARK5(4)8L[2]SA`
/// with the bristle states implicit (solved exactly at each stage) and
/// everything else explicit, for stages whose bristle relaxation, not
/// accuracy, bounds the explicit step.
#[derive(Debug, Clone, Copy, Default)]
pub struct ImexEngine;

impl Engine for ImexEngine {
    fn kind(&self) -> EngineKind {
        EngineKind::Imex
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
        integrate(
            self.kind(),
            model,
            x0,
            excitation,
            settings,
            progress,
            |system| ImexRungeKutta::new(system, 0.0, x0, tol),
        )
    }
}

/// The explicit eighth-order engine DOP853 (Prince and Dormand's pair in
/// Hairer's form, [`crate::dop853`]), for tight tolerances where the
/// fifth-order step is held by accuracy, not stability.
#[derive(Debug, Clone, Copy, Default)]
pub struct Dop853Engine;

impl Engine for Dop853Engine {
    fn kind(&self) -> EngineKind {
        EngineKind::Dop853
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
        integrate(
            self.kind(),
            model,
            x0,
            excitation,
            settings,
            progress,
            |system| Dop853::new(system, 0.0, x0, tol),
        )
    }
}

/// The classical fourth-order Runge-Kutta method with a free third-order
/// estimate ([`crate::rk4`]): for loose tolerances where lightly damped
/// stiff modes, not accuracy, hold the explicit step.
#[derive(Debug, Clone, Copy, Default)]
pub struct Rk4Engine;

impl Engine for Rk4Engine {
    fn kind(&self) -> EngineKind {
        EngineKind::Rk4
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
        integrate(
            self.kind(),
            model,
            x0,
            excitation,
            settings,
            progress,
            |system| ClassicalRungeKutta::new(system, 0.0, x0, tol),
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
        progress: &mut Progress<'_>,
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
