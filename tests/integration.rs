//! Cross-crate tests: the paper reproduction, the engines against each other and against
//! analytic solutions, the physics laws, and bad input through the library.
//!
//! One test binary per crate: every file of this folder is a module of it, so the
//! crate graph is linked once for all of them.

mod bad_input;
mod compensation;
mod convergence;
mod coupling;
mod dop853;
mod imex;
mod kinks;
mod native_runs;
mod paper_claims;
mod paper_equations;
mod physics;
mod rapier;
mod rk4;
mod rosenbrock;
mod six_dof;
mod stability;
mod trust;
