//! fistage-model: robot (URDF) and scenario (TOML) files turned into an immutable,
//! validated [`Model`] of a precision stage, and the model's physics: state layout,
//! right-hand side `dx = f(x, u)`, outputs and stored energy.
//!
//! Data flow: [`RobotSpec`] + [`Scenario`] → [`assemble`] → [`Model`], evaluated
//! with a per-thread [`Workspace`].

pub mod assembly;
pub mod body_motion;
pub mod dynamics;
pub mod equilibrium;
pub mod error;
mod evaluator;
mod laws;
pub mod linearize;
pub mod lugre;
pub mod model;
pub mod parameter;
pub mod reference;
pub mod robot;
mod rooted;
pub mod rule;
pub mod scalar;
pub mod scenario;
mod translational;

pub use assembly::{Loaded, assemble, load};
pub use body_motion::{BodyMotion, BodyWrench};
pub use dynamics::{ElementValues, EvaluationPath, InputValues, Workspace};
pub use equilibrium::{EquilibriumError, EquilibriumKind};
pub use error::LoadError;
pub use linearize::Tangent;
pub use lugre::{InvalidLugreParameter, LugreKey, LugreParams};
pub use model::{
    Body, Controller, Frame, FrictionContact, Inputs, Isolator, Joint, JointMotion, Model,
    PointAxis, SignalInfo, StateKind, StateLayout,
};
pub use parameter::{Gain, Parameter};
pub use reference::{Reference, ReferenceSample};
pub use robot::{FISTAGE_NS, IsolatorKey, RobotSpec};
pub use rule::{Rule, RuleViolation};
pub use scalar::{Dual64, Scalar};
pub use scenario::{
    ControllerSettings, EngineKind, Override, PayloadSettings, RapierSettings, Scenario,
    SolverSettings, Start, StopSettings,
};
