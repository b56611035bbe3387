//! The analysis crate's integration tests.
//!
//! One test binary per crate: every file of this folder is a module of it, so the
//! crate graph is linked once for all of them.

mod closed_loop_record;
mod from_fit;
mod lab;
mod robust;
mod stage_fit;
mod sweep_settings;
