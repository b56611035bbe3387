//! What drives a model over time: the [`Excitation`] an engine reads the
//! inputs from, the one a scenario describes, and the state a scenario
//! starts from ([`initial_state`]).

use crate::equilibrium::EquilibriumKind;
use crate::error::LoadError;
use crate::model::Model;
use crate::scenario::{Scenario, Start};
use crate::{Inputs, Reference};

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

/// The scenario's starting state (`start`), with its `[initial]` entries applied.
pub fn initial_state(model: &Model, scenario: &Scenario) -> Result<Vec<f64>, LoadError> {
    let inputs = ScenarioExcitation::from_scenario(scenario).inputs(0.0);
    initial_state_with(model, scenario, &inputs)
}

/// [`initial_state`] with the equilibrium (`start = "static"` or
/// `"slipping"`) taken at the given inputs, e.g. those a co-simulation master
/// set before initialisation.
pub fn initial_state_with(
    model: &Model,
    scenario: &Scenario,
    inputs: &Inputs,
) -> Result<Vec<f64>, LoadError> {
    let mut x = model.zero_state();
    let kind = match scenario.start {
        Start::Zero => None,
        Start::Static => Some(EquilibriumKind::Sticking),
        Start::Slipping => Some(EquilibriumKind::Slipping),
    };
    if let Some(kind) = kind {
        x = model
            .equilibrium(kind, inputs, &x)
            .map_err(|e| scenario.error("start", e.to_string()))?;
    }
    for (name, value) in &scenario.initial {
        let index = model.layout().index(name).ok_or_else(|| {
            scenario.error(
                format!("initial.{name}"),
                format!(
                    "no state of that name (states: {})",
                    model.layout().names.join(", ")
                ),
            )
        })?;
        x[index] = *value;
    }
    Ok(x)
}
