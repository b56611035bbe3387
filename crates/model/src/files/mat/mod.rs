//! MAT-files (MATLAB's Level 5 format, versions 6 and 7): reading the
//! variables of a measured record ([`read_variables`]) and writing signal
//! tables and named columns ([`Signals::write_mat`], [`write_columns`]) for
//! MATLAB, Octave and `scipy.io`.

pub mod read;
pub mod write;

pub use read::{MatContent, MatReadError, MatVariable, read_variables};
pub use write::{Signals, matlab_names, write_columns};
