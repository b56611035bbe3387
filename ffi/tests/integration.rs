//! The FMI library's integration tests: the C ABI, FMUs in FMPy and a Rust importer, packaging.
//!
//! One test binary per crate: every file of this folder is a module of it, so the
//! crate graph is linked once for all of them.

mod support;

mod c_abi;
mod fmpy;
mod fuzz_seeds;
mod header;
mod model_description;
mod package;
mod parameters;
mod rust_importer;
