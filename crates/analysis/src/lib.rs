//! fistage-analysis: what a model does near its equilibria. Equilibria come
//! from [`fistage_model::Model::equilibrium`]; this crate linearises there
//! (exact Jacobian in tangent coordinates), computes every eigenvalue with its
//! frequency and damping ratio, the mode shapes in named coordinates, and how
//! each mode's kinetic energy is shared between the table's six motions and
//! the bearings; sweeps of stability over one or two parameters; and
//! tolerance analyses of populations of stages with servo-gain design
//! ([`robust`], [`robust::tune`]), both judged point by point by [`assess`];
//! comparisons of several scenarios' tracking over a grid against a
//! baseline ([`compare`], the paper's Fig. 3 studies). [`lab`]
//! measures identification data (f_ss(v), the pre-motion FRF) on the simulated
//! stage, as a lab would, for fistage-ident to fit.
//!
//! ```
//! use fistage_analysis::modal_analysis;
//! use fistage_model::{EquilibriumKind, Inputs};
//!
//! let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
//! let loaded = fistage_model::load(&root.join("scenarios/paper/fig05b_fi.toml"))?;
//! let model = &loaded.model;
//! let inputs = Inputs { platform_velocity: 0.02, ..Inputs::default() };
//! let analysis =
//!     modal_analysis(model, &inputs, EquilibriumKind::Slipping, &model.zero_state())
//!         .expect("the slipping equilibrium exists");
//! // Fig. 5b's stage with FI: its slipping equilibrium is linearly stable
//! // (the limit cycle it runs into from rest is the bistable case of the paper).
//! println!("largest real part {:.3} 1/s", analysis.max_real_part);
//! assert!(analysis.stable && analysis.max_real_part < 0.0);
//! # Ok::<(), fistage_model::LoadError>(())
//! ```

#![warn(missing_docs)]

pub mod assess;
pub mod compare;
pub mod lab;
pub mod lyapunov;
pub mod modes;
pub mod record_lab;
pub mod robust;
pub mod routh;
pub mod study;
pub mod sweep;

pub use eigen::{EigenPair, eigen_decomposition};
pub use fistage_model::eigen;
pub use modes::{AnalysisError, ModalAnalysis, Mode, Participation, Verdict, modal_analysis};
