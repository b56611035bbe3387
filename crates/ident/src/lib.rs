//! fistage-ident: LuGre identification from f_ss(v) curves, FRFs and recorded runs.
//!
//! * [`csv_input`] reads lab CSV files (units from column-name suffixes or flags,
//!   converted to SI);
//! * [`stribeck`] fits f_C, f_S, v_s and sigma2 to the steady-state curve by a
//!   convex program per v_s (Clarabel for least squares; exact active-set
//!   solvers, Clarabel as their fallback, for the robust losses) and a global
//!   one-dimensional search, with L2, Huber or L1 loss and an asymmetry test;
//! * [`frf`] fits sigma0, sigma1 + sigma2 (and the mass) to the pre-motion FRF;
//! * [`record`] fits all six LuGre parameters (and the mass) to a recorded
//!   run (force command and encoder position) by output error;
//! * [`stage`] fits any stage's parameters (paths of its parameter table) to
//!   one or more records, and says what the records cannot determine;
//! * [`uncertainty`] gives 95% intervals and residual statistics;
//! * [`synth`] makes seeded synthetic data from known parameters;
//! * [`report`] turns fits into JSON, a table and a scenario override.
//!
//! ```
//! use fistage_ident::{StribeckOptions, fit_stribeck, synth::StribeckSynth};
//! use fistage_model::LugreParams;
//!
//! let truth = LugreParams::paper_table1();
//! let data = StribeckSynth::clean(truth).generate();
//! let fit = fit_stribeck(&data, &StribeckOptions::default()).unwrap();
//! assert!((fit.v_s.value / truth.v_s - 1.0).abs() < 1e-6);
//! ```

#![warn(missing_docs)]

pub mod covariance;
pub mod csv_input;
mod error;
mod exact;
pub mod frf;
mod jackknife;
mod linalg;
mod lm;
mod qp;
pub mod record;
pub mod report;
pub mod stage;
pub mod stribeck;
pub mod synth;
pub mod uncertainty;
pub mod units;

pub use covariance::FitCovariance;
pub use csv_input::{
    UnitOverrides, parse_frf_csv, parse_stribeck_csv, read_frf_csv, read_stribeck_csv,
};
pub use error::{IdentError, Result};
pub use frf::{FrfData, FrfFit, FrfOptions, FrfStart, MassOption, Sigma2Input, fit_frf};
/// A complex number `re + j im` (frequency responses).
pub use num_complex::Complex64 as Complex;
pub use report::{FrfReport, NotIdentifiable, StribeckReport, frf_override, stribeck_override};
pub use stribeck::{
    AsymmetricFit, AsymmetryTest, Loss, StribeckData, StribeckFit, StribeckOptions, fit_stribeck,
    fit_stribeck_asymmetric,
};
pub use uncertainty::{Estimate, ResidualStats};
pub use units::{Quantity, Unit};
