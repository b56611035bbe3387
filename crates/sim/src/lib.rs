//! fistage-sim: integration engines, trajectories, output signals and their
//! statistics.
//!
//! Data flow: a [`fistage_model::Model`] and an [`Excitation`] go into an
//! [`Engine`], which returns a [`Trajectory`]; [`Trajectory::signals`] turns it
//! into named output signals, [`metrics::summarize`] into statistics.
//!
//! - **Engines** ([`engine_for`] picks the scenario's): [`AutoEngine`], the
//!   default, which takes the implicit-explicit method where the bristles
//!   bound the explicit step and an explicit method elsewhere;
//!   [`AdaptiveEngine`], any method of the ODE layer ([`fistage_ode`],
//!   named by [`MethodKind`]): Dormand-Prince 5(4) (`native`), the additive
//!   Runge-Kutta pair with the bristle states solved exactly at each stage
//!   (`imex`), the classical fourth-order method with a free third-order
//!   estimate (`rk4`, which `auto` takes at loose tolerances where lightly
//!   damped stiff modes hold the explicit step), the explicit eighth-order
//!   pair (`dop853`, opt-in for tight tolerances: on the shipped stages the
//!   bristle and bushing stiffness hold it near its stability limit; it pays
//!   only at rtol 1e-10 on the small ones) and ROS34PW2 (`rosenbrock`,
//!   linearly implicit with the model's exact Jacobian, for very stiff
//!   isolators); `RapierEngine`, rapier3d-f64 under the
//!   model's own force elements, for end stops and loose payloads (the
//!   `rapier` feature, on by default; a build without it refuses
//!   `engine = "rapier"` by name). The
//!   adaptive engines and the co-simulation [`Stepper`] share one driver:
//!   segments between the inputs' discontinuities, steps that end on each
//!   predicted sign change of a contact's slip velocity (where the bristle
//!   law has a kink), the step budget and the failure reporting are
//!   written once.
//! - **A whole run**: [`run_scenario`] starts from the scenario's start state
//!   and returns the trajectory, the selected signals and their statistics.
//!
//! ```
//! use fistage_sim::run_scenario;
//!
//! let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
//! let mut loaded = fistage_model::load(&root.join("scenarios/paper/fig05b_fi.toml"))?;
//! loaded.scenario.duration = 0.2;
//! loaded.scenario.window = [0.1, 0.2];
//! let output = run_scenario(&loaded, &mut fistage_sim::no_progress)?;
//! let table = output
//!     .summary
//!     .iter()
//!     .find(|s| s.name == "table_x.q")
//!     .expect("the table's position is a signal");
//! println!("table p2p over the window: {:e} m", table.stats.peak_to_peak);
//! assert!(output.trajectory.stats.counts.steps > 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

#[cfg(not(feature = "rapier"))]
mod absent_engine;
pub mod choice;
pub mod cosim;
mod driver;
pub mod engine;
mod kinks;
pub mod metrics;
#[cfg(feature = "rapier")]
pub mod rapier_engine;
pub mod run;
pub mod select;
pub mod settings;
pub mod summary;
pub mod tracking;
pub mod trajectory;

pub use cosim::{HeldInputs, Stepper, StepperTolerances};
pub use engine::{AdaptiveEngine, AutoEngine, Engine, Progress, engine_kind_of, no_progress};
pub use fistage_model::excitation::{
    Excitation, ScenarioExcitation, initial_state, initial_state_with,
};
pub use fistage_ode::{Checkpoint, MethodKind, StepCounts};
pub use metrics::{SignalSummary, WindowStats, summarize, window_stats};
#[cfg(feature = "rapier")]
pub use rapier_engine::RapierEngine;
pub use run::{RunError, RunOutput, run_scenario, validate};
pub use select::{engine_for, engine_in, engine_of_kind};
pub use settings::{SimError, SimSettings, sample_times};
pub use tracking::{TrackingMetrics, tracking_metrics};
pub use trajectory::{ExtraSignal, SignalTable, SolverStats, Trajectory};
