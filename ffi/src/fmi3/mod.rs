//! The plant as an FMI 3.0 unit, Model Exchange and Co-Simulation, over the
//! same [`crate::Instance`] as FMI 2.0:
//!
//! - [`types`]: the FMI 3.0 C types as the official headers define them;
//! - [`exports`]: the `fmi3*` functions (the library carries both
//!   standards' symbols; header `include/fistage_stage_fmi3.h`);
//! - [`model_description`]: the FMI 3.0 `modelDescription.xml`.
//!
//! Left out on purpose, since the plant has no use for them: clocks and
//! Scheduled Execution (`fmi3InstantiateScheduledExecution` returns null,
//! the clock functions refuse), event mode in Co-Simulation
//! (`hasEventMode="false"`), early return and intermediate updates,
//! configuration mode (the plant has no structural parameters), variable
//! types other than Float64, output derivatives, and the variable
//! dependency functions (dependencies are left to the description's
//! default: every known).

pub mod exports;
pub mod model_description;
pub mod types;
