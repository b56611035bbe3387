//! fistage-model: robot (URDF) and scenario (TOML) files turned into an
//! immutable, validated [`Model`] of a precision stage, and the model's
//! physics: state layout, right-hand side `dx = f(x, u)` in `f64` or dual
//! numbers (exact Jacobians), equilibria, outputs and stored energy.
//!
//! # A tour
//!
//! - **Files to model.** [`load`] reads a scenario, the robot file it names
//!   and assembles the [`Model`]; [`RobotSpec`] and [`Scenario`] are the two
//!   files checked on their own, [`assemble`] joins them. Every error names
//!   the file, the element or key, and what is wrong ([`LoadError`]).
//! - **Parameters.** Every tunable quantity is one entry of the parameter
//!   table ([`Parameter`]): a path such as `controller.k` or
//!   `overrides.bearing_friction.sigma0`, its unit and validity [`Rule`].
//!   Scenario overrides, sweeps and FMU parameters all write through it.
//! - **Evaluation.** [`Model::rhs`] gives the state derivative with a
//!   per-thread [`Workspace`]; the evaluation is chosen once, when the model
//!   is built, from its structure ([`EvaluationPath`]), and the exact
//!   Jacobian ([`Model::jacobian`]) differentiates that same code.
//!   The crate `fistage-codegen` records the evaluation and compiles it to
//!   machine code ([`machine_code`]): straight-line arithmetic with the
//!   model's numbers in the instructions, checked to give the same numbers,
//!   which the model keeps ([`Model::compile_with`]) and `Model::rhs` and
//!   every engine then run (a run compiles after its first 10 000
//!   evaluations).
//! - **The servo.** A PID on a sensor and an actuator, with optional
//!   feedforward friction compensation (a LuGre or Dahl model driven by the
//!   reference, simulated with its own states, through a simulated bearing
//!   when an isolator carries the modelled element: [`compensation`],
//!   [`servo`]) and a disturbance observer; one law serves every
//!   evaluation path.
//! - **Equilibria.** [`Model::equilibrium`] finds the sticking or slipping
//!   equilibrium by Newton's method with the exact Jacobian.
//!
//! # Example
//!
//! ```
//! use fistage_model::{EquilibriumKind, Inputs, Parameter, RobotSpec, assemble, load};
//!
//! let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
//! let loaded = load(&root.join("scenarios/paper/fig05b_fi.toml"))?;
//! let model = &loaded.model;
//! println!("{} states: {:?}", model.n_states(), model.layout().names);
//!
//! // The state derivative at rest, with the platform moving at 20 mm/s.
//! let inputs = Inputs { platform_velocity: 0.02, ..Inputs::default() };
//! let x = model.zero_state();
//! let mut dx = vec![0.0; model.n_states()];
//! model.rhs(&x, &inputs, &mut dx, &mut model.workspace());
//!
//! // The slipping equilibrium: nothing moves, the bristles are deflected.
//! let slipping = model.equilibrium(EquilibriumKind::Slipping, &inputs, &x).expect("exists");
//! let mut rate = vec![0.0; model.n_states()];
//! model.rhs(&slipping, &inputs, &mut rate, &mut model.workspace());
//! assert!(rate.iter().all(|r| r.abs() < 1e-6));
//!
//! // A stiffer servo, through the parameter table (checked by its rule).
//! let mut scenario = loaded.scenario.clone();
//! let mut robot = RobotSpec::from_file(&scenario.robot)?;
//! Parameter::resolve("controller.k", &scenario, &robot)?.write(&mut scenario, &mut robot, 1e5)?;
//! let (_, stiffer) = assemble(robot, &scenario)?;
//! assert_eq!(stiffer.controller().map(|c| c.k), Some(1e5));
//! # Ok::<(), fistage_model::LoadError>(())
//! ```

#![warn(missing_docs)]

pub mod assembly;
pub mod elements;
pub mod error;
pub mod excitation;
pub mod files;
pub mod linear;
pub mod machine_code;
pub mod model;
pub mod parameter;
pub mod physics;
pub mod rule;

// The rooms' modules at the crate root, where users (and the crate) name them.
pub(crate) use files::urdf_check;
pub use files::{compensation, input, mat, output, reference, robot, scenario, studies};
pub use linear::{eigen, equilibrium, linearize, scalar};
pub use physics::{body_motion, dahl, dynamics, lugre, servo};
pub(crate) use physics::{bristle, evaluator, laws, rooted, rows, translational, values};

pub use assembly::{Loaded, assemble, load};
pub use dynamics::{ElementValues, EvaluationPath, InputValues, Workspace};
pub use elements::{
    Body, BodyMotion, BodyWrench, Controller, Frame, FrictionContact, Inputs, Isolator, Joint,
    JointMotion, PointAxis, SignalInfo, StateKind, StateLayout, Visual,
};
pub use equilibrium::{EquilibriumError, EquilibriumKind};
pub use error::LoadError;
pub use excitation::{Excitation, ScenarioExcitation, initial_state, initial_state_with};
pub use linearize::Tangent;
pub use lugre::{InvalidLugreParameter, LugreKey, LugreOf, LugreParams};
pub use model::Model;
pub use parameter::Parameter;
pub use reference::{Reference, ReferenceSample};
pub use robot::{FISTAGE_NS, IsolatorKey, RobotSpec, VisualShape, VisualSpec};
pub use rule::{Rule, RuleViolation};
pub use scalar::{Dual64, DualSVec64, Scalar};
pub use scenario::{
    ControllerSettings, EngineKind, Gain, OutputFormat, Override, PayloadSettings, RapierSettings,
    Scenario, SolverSettings, Start, StopSettings,
};
pub use values::ServoValues;
