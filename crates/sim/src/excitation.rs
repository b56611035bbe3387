//! What drives a model over time: the [`Excitation`] an engine reads the
//! inputs from, and the one a scenario describes.

use fistage_model::{Inputs, Reference, Scenario};

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
