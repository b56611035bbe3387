//! The model crate's integration tests.
//!
//! One test binary per crate: every file of this folder is a module of it, so the
//! crate graph is linked once for all of them.

mod parameter_properties;
