//! The identification crate's integration tests.
//!
//! One test binary per crate: every file of this folder is a module of it, so the
//! crate graph is linked once for all of them.

mod common;

mod asymmetry;
mod bad_input;
mod noisy;
mod record;
mod recovery;
mod report;
mod robust;
mod start_independence;
