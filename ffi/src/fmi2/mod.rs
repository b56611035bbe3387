//! The plant as an FMI 2.0 unit, Model Exchange and Co-Simulation, over the
//! shared instance (`crate::shared`):
//!
//! - [`types`]: the FMI 2.0 C types as the official headers define them;
//! - [`exports`]: the 44 `fmi2*` functions (header `include/fistage_stage.h`);
//! - [`model_description`]: the FMI 2.0 `modelDescription.xml`.

pub mod exports;
pub mod model_description;
pub mod types;
