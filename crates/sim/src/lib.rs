//! fistage-sim: integration engines, trajectories, output signals and their
//! statistics.
//!
//! Data flow: a [`fistage_model::Model`] and an [`Excitation`] go into an
//! [`Engine`], which returns a [`Trajectory`]; [`Trajectory::signals`] turns it
//! into named output signals, [`metrics::summarize`] into statistics.

pub mod cosim;
pub mod dopri;
mod driver;
pub mod engine;
pub mod excitation;
pub mod metrics;
pub mod rapier_engine;
pub mod rosenbrock;
pub mod run;
pub mod select;
pub mod settings;
pub mod trajectory;

pub use cosim::{HeldInputs, Stepper, StepperTolerances};
pub use dopri::{Checkpoint, StepCounts};
pub use engine::{Engine, NativeEngine, RosenbrockEngine};
pub use excitation::{Excitation, ScenarioExcitation};
pub use metrics::{SignalSummary, WindowStats, summarize, window_stats};
pub use rapier_engine::RapierEngine;
pub use run::{RunError, RunOutput, initial_state, initial_state_with, run_scenario};
pub use select::{engine_by_name, engine_for, engine_of_kind};
pub use settings::{SimError, SimSettings, sample_times};
pub use trajectory::{ExtraSignal, SignalTable, SolverStats, Trajectory};
