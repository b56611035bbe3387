//! Reading and writing files: robot files (URDF with `fistage:` elements)
//! and their checks, scenario files (TOML) with their `[compensation]`,
//! `[dob]`, reference, `[sweep]` and `[robust]` tables, bounded reads of user files, whole-file
//! writes, and MAT-files.

pub mod compensation;
pub mod input;
pub mod mat;
pub mod output;
pub mod reference;
pub mod robot;
pub mod scenario;
pub mod studies;
pub(crate) mod urdf_check;
