//! The model near a point: the scalar types it is evaluated in (dual
//! numbers for exact derivatives), the exact Jacobian, equilibria and
//! eigenvalues.

pub mod eigen;
pub mod equilibrium;
pub mod linearize;
pub mod scalar;
