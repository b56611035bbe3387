//! The error returned by every figure writer, and the internal error of the drawing code.

use std::path::PathBuf;

use plotters::drawing::DrawingAreaErrorKind;

/// Why a figure could not be written. Every variant names the output path.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Creating or writing the output file failed.
    #[error("cannot write figure {}: {source}", .path.display())]
    Io {
        /// The output file.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The drawing backend, the font or the PNG encoder reported an error.
    #[error("drawing figure {} failed: {message}", .path.display())]
    Backend {
        /// The output file.
        path: PathBuf,
        /// What the backend reported.
        message: String,
    },
    /// A series has a different number of x and y values.
    #[error(
        "series \"{label}\" has {x_len} x values but {y_len} y values (figure {})",
        .path.display()
    )]
    LengthMismatch {
        /// The output file.
        path: PathBuf,
        /// The label of the offending series.
        label: String,
        /// Number of x values.
        x_len: usize,
        /// Number of y values.
        y_len: usize,
    },
    /// The file extension is neither `.svg` nor `.png`.
    #[error(
        "cannot write figure {}: unsupported file extension (expected .svg or .png)",
        .path.display()
    )]
    UnsupportedExtension {
        /// The output file.
        path: PathBuf,
    },
    /// A heatmap's value count does not match its row and column centres.
    #[error(
        "heatmap {} has {len} values but {rows} rows x {cols} columns need {expected}",
        .path.display()
    )]
    HeatmapShape {
        /// The output file.
        path: PathBuf,
        /// Number of row centres (`y`).
        rows: usize,
        /// Number of column centres (`x`).
        cols: usize,
        /// `rows * cols`.
        expected: usize,
        /// Number of values given.
        len: usize,
    },
    /// A categorical heatmap holds a value that is not the index of one of its labels.
    #[error(
        "heatmap {}: value {value} is not a category index (expected an integer from 0 to {})",
        .path.display(),
        .count.saturating_sub(1)
    )]
    InvalidCategory {
        /// The output file.
        path: PathBuf,
        /// The offending value.
        value: f64,
        /// Number of category labels.
        count: usize,
    },
}

/// An error raised while drawing, before the output path is attached.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct DrawError(pub(crate) String);

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for DrawError {
    fn from(error: DrawingAreaErrorKind<E>) -> Self {
        DrawError(error.to_string())
    }
}

/// Result of the drawing functions.
pub(crate) type DrawResult<T = ()> = Result<T, DrawError>;
