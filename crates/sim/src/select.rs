//! Which engine runs: the engine of an [`EngineKind`], by name, or the one a
//! scenario names, with its settings.

use fistage_model::{EngineKind, Scenario};

use crate::engine::{AutoEngine, Engine, ImexEngine, NativeEngine, RosenbrockEngine};
use crate::rapier_engine::RapierEngine;

/// The engine of a kind with default settings (the rapier engine without colliders).
pub fn engine_of_kind(kind: EngineKind) -> Box<dyn Engine> {
    match kind {
        EngineKind::Auto => Box::new(AutoEngine::default()),
        EngineKind::Native => Box::new(NativeEngine),
        EngineKind::Rosenbrock => Box::new(RosenbrockEngine),
        EngineKind::Imex => Box::new(ImexEngine),
        EngineKind::Rapier => Box::new(RapierEngine::default()),
    }
}

/// An engine by name or alias (`auto`, `native`, `dopri5`, `imex`, `ark548`,
/// `rosenbrock`, `implicit`, `rapier`).
pub fn engine_by_name(name: &str) -> Option<Box<dyn Engine>> {
    name.parse().ok().map(engine_of_kind)
}

/// The engine a scenario names (`solver.engine` or `engine`), with its settings.
pub fn engine_for(scenario: &Scenario) -> Box<dyn Engine> {
    match scenario.solver.engine {
        EngineKind::Rapier => Box::new(RapierEngine {
            settings: scenario.rapier.clone(),
        }),
        EngineKind::Auto => Box::new(AutoEngine::for_scenario(scenario)),
        kind => engine_of_kind(kind),
    }
}
