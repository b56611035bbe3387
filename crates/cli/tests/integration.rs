//! The `fistage` program end to end.
//!
//! One test binary per crate: every file of this folder is a module of it, so the
//! crate graph is linked once for all of them.

mod browser;
mod cli;
mod slurm;
