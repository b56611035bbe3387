//! The status a call returns: `fmi2Status` and `fmi3Status` share their
//! values (OK 0, Warning 1, Discard 2, Error 3, Fatal 4), so both faces
//! return the same numbers.

/// The statuses this unit returns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i32)]
pub(crate) enum Status {
    Ok = 0,
    Discard = 2,
    Error = 3,
    Fatal = 4,
}
