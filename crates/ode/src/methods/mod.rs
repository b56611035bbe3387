//! The adaptive methods, one file each (see [`crate::MethodKind`]).

pub mod classical;
pub mod dop853;
pub mod dormand_prince;
pub mod imex;
pub mod rosenbrock;
