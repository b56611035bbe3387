//! Errors raised while loading robot and scenario files. Every variant names the
//! file and the element or key at fault, so a user can go straight to the line.

use std::path::PathBuf;
use thiserror::Error;

/// An error in a user-supplied file. Loading never writes anything, so a failed
/// load leaves the disk as it was.
#[derive(Debug, Error)]
pub enum LoadError {
    /// The file could not be read.
    #[error("{file}: cannot read: {reason}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The underlying error (in the message, not chained, so it prints once).
        reason: std::io::Error,
    },
    /// The file is not well-formed XML or TOML.
    #[error("{file}: {message}")]
    Syntax {
        /// The file.
        file: PathBuf,
        /// Parser message, with line and column where the parser gives them.
        message: String,
    },
    /// A robot element (link, joint, isolator, friction, actuator, sensor) is invalid.
    #[error("{file}: {element}: {message}")]
    Robot {
        /// The robot file.
        file: PathBuf,
        /// The element, e.g. `friction "bearing_friction"` or `link "table"`.
        element: String,
        /// What is wrong.
        message: String,
    },
    /// A data file (CSV) has a missing column or a bad cell.
    #[error("{file}: {at}: {message}")]
    Data {
        /// The data file.
        file: PathBuf,
        /// Where: `column "x"`, `line 7, column "position_mm"`.
        at: String,
        /// What is wrong.
        message: String,
    },
    /// A scenario key is missing, unknown or out of range.
    #[error("{file}: {key}: {message}")]
    Scenario {
        /// The scenario file.
        file: PathBuf,
        /// The key path, e.g. `controller.k` or `overrides.bearing_friction.sigma0`.
        key: String,
        /// What is wrong.
        message: String,
    },
}

impl LoadError {
    pub(crate) fn robot(
        file: impl Into<PathBuf>,
        element: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self::Robot {
            file: file.into(),
            element: element.into(),
            message: message.into(),
        }
    }

    pub(crate) fn scenario(
        file: impl Into<PathBuf>,
        key: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self::Scenario {
            file: file.into(),
            key: key.into(),
            message: message.into(),
        }
    }
}
