//! The physics, written once over any [`crate::Scalar`]: the element laws
//! (isolator bushings, LuGre and Dahl friction, the bristle states, the
//! servo), the values they read, and the three evaluation paths of the
//! right-hand side (`evaluator` picks one per model when it is built):
//! constant Jacobian (`translational`, `rows`), bodies jointed to the world
//! (`rooted`) and the general path ([`dynamics`]).

pub mod body_motion;
pub(crate) mod bristle;
pub mod dahl;
pub mod dynamics;
pub(crate) mod evaluator;
pub(crate) mod laws;
pub mod lugre;
pub(crate) mod rooted;
pub(crate) mod rows;
pub mod servo;
pub(crate) mod translational;
pub(crate) mod values;
