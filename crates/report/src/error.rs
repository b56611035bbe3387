//! Why a page could not be written or read.

use std::path::PathBuf;
use thiserror::Error;

/// Why a page could not be written or read.
#[derive(Debug, Error)]
pub enum ReportError {
    /// This build has no bundle of the page's libraries (npm was missing when it was built).
    #[error(
        "this fistage was built without its HTML report ({0}); install Node.js 18 or newer and rebuild"
    )]
    Unavailable(String),
    /// A file could not be written or read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// A page given to be combined holds no report data.
    #[error("{path}: not a fistage report (no report data in it{hint})")]
    NotAReport {
        /// The file.
        path: PathBuf,
        /// A hint on how it came to be so.
        hint: String,
    },
    /// The report data of a page could not be read.
    #[error("{path}: its report data cannot be read: {source}")]
    Data {
        /// The file.
        path: PathBuf,
        /// What the parser said.
        source: serde_json::Error,
    },
}
