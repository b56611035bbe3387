//! The systems the methods integrate: `x' = f(t, x)` ([`OdeSystem`]), with
//! some states treated implicitly ([`SplitSystem`], for the implicit-explicit
//! pair) or with its Jacobian ([`JacobianSystem`], for the Rosenbrock method).
//! Nothing here knows a stage model: the simulation crate implements these
//! for a model driven by its inputs, the identification crate for its plant.

use nalgebra::DMatrix;

/// A system `x' = f(t, x)`.
pub trait OdeSystem {
    /// Number of states.
    fn dim(&self) -> usize;
    /// Writes f(t, x) into `dx`.
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]);
}

/// A system with some states treated implicitly.
pub trait SplitSystem: OdeSystem {
    /// Indices of the implicitly treated states.
    fn implicit_states(&self) -> &[usize];
    /// f(t, x) at an implicit stage: on entry the implicit entries of `x`
    /// hold the stage's explicit part `c`, on return the values that solve
    /// `x_i = c_i + step f_i(t, x)`; `dx` is f at the solved point.
    fn rhs_implicit(&mut self, t: f64, x: &mut [f64], step: f64, dx: &mut [f64]);
}

/// A system that also gives its Jacobian `df/dx`.
pub trait JacobianSystem: OdeSystem {
    /// `df/dx` at (t, x).
    fn jacobian(&mut self, t: f64, x: &[f64]) -> DMatrix<f64>;
}
