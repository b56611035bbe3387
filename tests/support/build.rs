//! No build step: this script exists for its build-dependency (see the root
//! manifest), which turns on the features the Python package's macros turn
//! on in syn, so that both builds share one syn and everything derived with
//! it.

fn main() {}
