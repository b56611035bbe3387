//! # fistage-ode
//!
//! Adaptive methods for ordinary differential equations `x' = f(t, x)`,
//! behind one interface, [`AdaptiveMethod`]: start at a point, take one
//! accepted step towards a stop time, restart after a discontinuity of the
//! inputs, interpolate inside the last step (dense output), checkpoint and
//! resume bit for bit. Nothing here knows a stage model: the simulation
//! crate drives these methods over a model and its inputs, and the
//! identification crate integrates its plant and sensitivities with them.
//!
//! ## The vocabulary
//!
//! - [`OdeSystem`] (with [`SplitSystem`] for the implicit-explicit pair and
//!   [`JacobianSystem`] for the Rosenbrock method): what is integrated.
//! - [`Tolerances`]: relative and per-state absolute error, the largest and
//!   the smallest step; [`starting_step`] is Hairer's first step.
//! - [`StepCounts`], [`StepFailure`], [`Checkpoint`]: what a run reports
//!   and keeps.
//! - [`step_control`]: the PI step-size controller and the one step loop
//!   the embedded pairs share.
//!
//! ## The methods (`methods/`, one file each; [`MethodKind`] names them)
//!
//! - [`DormandPrince`]: explicit 5(4) with FSAL and Hairer's dense output.
//! - [`ImexRungeKutta`]: Kennedy and Carpenter's ARK5(4)8L\[2\]SA with some
//!   states solved implicitly at each stage.
//! - [`Dop853`]: explicit 8(5,3), for tight tolerances.
//! - [`ClassicalRungeKutta`]: RK4 with a free third-order estimate, for
//!   loose tolerances on lightly damped stiff modes.
//! - [`Rosenbrock`]: ROS34PW2, linearly implicit with a reused Jacobian.
//!
//! ## Example
//!
//! ```
//! use fistage_ode::{AdaptiveMethod, DormandPrince, MethodState, OdeSystem, Tolerances};
//!
//! /// x'' = -x: a harmonic oscillator of period 2 pi.
//! struct Oscillator;
//!
//! impl OdeSystem for Oscillator {
//!     fn dim(&self) -> usize {
//!         2
//!     }
//!     fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
//!         dx[0] = x[1];
//!         dx[1] = -x[0];
//!     }
//! }
//!
//! let tolerances = Tolerances {
//!     rtol: 1e-9,
//!     atol: vec![1e-12; 2],
//!     max_step: f64::INFINITY,
//!     min_step_relative: 1e-14,
//! };
//! let mut system = Oscillator;
//! let mut method = DormandPrince::new(&mut system, 0.0, &[1.0, 0.0], tolerances);
//! while method.time() < 1.0 {
//!     method.step(&mut system, 1.0)?;
//! }
//! assert_eq!(method.time(), 1.0);
//! assert!((method.state()[0] - 1f64.cos()).abs() < 1e-8);
//! // The solution inside the last step, from its continuous extension.
//! let mut x = [0.0; 2];
//! AdaptiveMethod::interpolate(&mut method, &mut system, 0.999, &mut x);
//! assert!((x[0] - 0.999f64.cos()).abs() < 1e-8);
//! # Ok::<(), fistage_ode::StepFailure>(())
//! ```
//!
//! ## Adding a method
//!
//! One file under `methods/` with the method's state, its
//! [`AdaptiveMethod`] implementation (an embedded pair implements the
//! crate's `EmbeddedPair` and calls the shared step loop), and an entry in
//! [`MethodKind`]; the simulation crate's adaptive engine then runs it.

mod hermite;
mod method;
pub mod methods;
mod sized;
pub mod step_control;
mod stepping;
mod system;
mod tolerances;

pub use method::{AdaptiveMethod, MethodKind, MethodState};
pub use methods::classical::ClassicalRungeKutta;
pub use methods::dop853::Dop853;
pub use methods::dormand_prince::DormandPrince;
pub use methods::imex::ImexRungeKutta;
pub use methods::rosenbrock::Rosenbrock;
pub use stepping::{Checkpoint, StepCounts, StepFailure};
pub use system::{JacobianSystem, OdeSystem, SplitSystem};
pub use tolerances::{Tolerances, starting_step};
