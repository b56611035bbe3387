//! fistage-analysis: what a model does near its equilibria. Equilibria come
//! from [`fistage_model::Model::equilibrium`]; this crate linearises there
//! (exact Jacobian in tangent coordinates), computes every eigenvalue with its
//! frequency and damping ratio, the mode shapes in named coordinates, and how
//! each mode's kinetic energy is shared between the table's six motions and
//! the bearings; and sweeps of stability over one or two parameters. [`lab`]
//! measures identification data (f_ss(v), the pre-motion FRF) on the simulated
//! stage, as a lab would, for fistage-ident to fit.

pub mod eigen;
pub mod lab;
pub mod lyapunov;
pub mod modes;
pub mod routh;
pub mod sweep;

pub use eigen::{EigenPair, eigen_decomposition};
pub use modes::{AnalysisError, ModalAnalysis, Mode, Participation, modal_analysis};
