//! Which engine runs: the engine of an [`EngineKind`] with default settings,
//! with a scenario's settings, or the one a scenario names.

use fistage_model::{EngineKind, Scenario};

use fistage_ode::MethodKind;

#[cfg(not(feature = "rapier"))]
use crate::absent_engine::AbsentEngine;
use crate::engine::{AdaptiveEngine, AutoEngine, Engine};
#[cfg(feature = "rapier")]
use crate::rapier_engine::RapierEngine;

/// The engine of a kind with default settings (the rapier engine without colliders).
pub fn engine_of_kind(kind: EngineKind) -> Box<dyn Engine> {
    match kind {
        EngineKind::Auto => Box::new(AutoEngine::default()),
        EngineKind::Native => Box::new(AdaptiveEngine::new(MethodKind::DormandPrince)),
        EngineKind::Rosenbrock => Box::new(AdaptiveEngine::new(MethodKind::Rosenbrock)),
        EngineKind::Imex => Box::new(AdaptiveEngine::new(MethodKind::Imex)),
        EngineKind::Dop853 => Box::new(AdaptiveEngine::new(MethodKind::Dop853)),
        EngineKind::Rk4 => Box::new(AdaptiveEngine::new(MethodKind::Classical)),
        EngineKind::Rapier => rapier_engine(fistage_model::RapierSettings::default()),
    }
}

/// The engine a scenario names (`solver.engine` or `engine`), with its settings.
pub fn engine_for(scenario: &Scenario) -> Box<dyn Engine> {
    engine_in(scenario, scenario.solver.engine)
}

/// The engine of `kind` with a scenario's settings: the rapier engine with
/// its `[rapier]` table, the default engine reading its choice at the
/// scenario's slipping velocity (without it there is no slip to read).
pub fn engine_in(scenario: &Scenario, kind: EngineKind) -> Box<dyn Engine> {
    match kind {
        EngineKind::Rapier => rapier_engine(scenario.rapier.clone()),
        EngineKind::Auto => Box::new(AutoEngine::for_scenario(scenario)),
        kind => engine_of_kind(kind),
    }
}

/// The rapier engine with `settings`.
#[cfg(feature = "rapier")]
fn rapier_engine(settings: fistage_model::RapierSettings) -> Box<dyn Engine> {
    Box::new(RapierEngine { settings })
}

/// A build without rapier: an engine that says so.
#[cfg(not(feature = "rapier"))]
fn rapier_engine(_settings: fistage_model::RapierSettings) -> Box<dyn Engine> {
    Box::new(AbsentEngine::rapier())
}
