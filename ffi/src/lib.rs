//! fistage-fmi: the plant as an FMI 2.0 Co-Simulation unit. This first part
//! defines what the unit exposes, the [`variables`] table with fixed value
//! references, and writes the `modelDescription.xml` that importers read.

pub mod model_description;
pub mod variables;

pub use model_description::{Capabilities, MODEL_IDENTIFIER, model_description};
pub use variables::{Causality, Variable, variables};
