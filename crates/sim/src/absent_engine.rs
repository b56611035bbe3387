//! An engine a build left out (the rapier engine without the `rapier`
//! feature): it refuses every run by name instead of running another engine.

use fistage_model::{EngineKind, Model};

use crate::engine::{Engine, Progress};
use crate::settings::{SimError, SimSettings};
use crate::trajectory::Trajectory;
use fistage_model::excitation::Excitation;

/// An engine kind this build does not contain, and the feature that brings it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct AbsentEngine {
    kind: EngineKind,
    feature: &'static str,
}

impl AbsentEngine {
    /// The rapier engine (the `rapier` feature).
    pub(crate) fn rapier() -> Self {
        Self {
            kind: EngineKind::Rapier,
            feature: "rapier",
        }
    }

    /// Why this engine does not run.
    pub(crate) fn error(&self) -> SimError {
        SimError::EngineNotBuilt {
            engine: self.kind.name(),
            feature: self.feature,
        }
    }
}

impl Engine for AbsentEngine {
    fn kind(&self) -> EngineKind {
        self.kind
    }

    fn simulate(
        &self,
        _model: &Model,
        _x0: &[f64],
        _excitation: &dyn Excitation,
        _settings: &SimSettings,
        _progress: &mut Progress<'_>,
    ) -> Result<Trajectory, SimError> {
        Err(self.error())
    }
}
