//! The error type of the crate. Every error about user input names the file, the
//! line and data row, and the column at fault.
//!
//! Row convention: `line` is the physical line of the file, counted from 1 as a
//! text editor or a spreadsheet shows it (the header is line 1 when nothing
//! precedes it); `data row` counts data records only, from 1.

use thiserror::Error;

/// Anything that can go wrong while reading data or fitting.
#[derive(Debug, Error)]
pub enum IdentError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// The file.
        file: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The file is not well-formed CSV (for example a row with a different number of cells).
    #[error("{file}: line {line}: malformed CSV: {message}")]
    Csv {
        /// The file.
        file: String,
        /// Physical line, 1-based.
        line: u64,
        /// What the CSV reader said.
        message: String,
    },
    /// A quantity the fit needs has no column in the header.
    #[error(
        "{file}: header (line {line}): no {quantity} column (expected a name like '{example}'; found columns: {found})"
    )]
    MissingColumn {
        /// The file.
        file: String,
        /// Physical line of the header.
        line: u64,
        /// The missing quantity, e.g. `velocity`.
        quantity: &'static str,
        /// An example of an accepted column name.
        example: &'static str,
        /// The columns that are in the header, comma separated.
        found: String,
    },
    /// A header cell is unusable: unknown or missing unit, ambiguous column.
    #[error("{file}: header (line {line}), column '{column}': {message}")]
    BadHeader {
        /// The file.
        file: String,
        /// Physical line of the header.
        line: u64,
        /// The column name as written in the file.
        column: String,
        /// What is wrong.
        message: String,
    },
    /// A data cell is unusable: empty, not a number, not finite or out of range.
    #[error("{file}: line {line} (data row {row}), column '{column}': {message}")]
    BadCell {
        /// The file.
        file: String,
        /// Physical line, 1-based.
        line: u64,
        /// Data row, 1-based, header excluded.
        row: usize,
        /// The column name as written in the file.
        column: String,
        /// What is wrong.
        message: String,
    },
    /// A MAT-file cannot be read.
    #[error("{file}: {message}")]
    NotMatFile {
        /// The file.
        file: String,
        /// What the reader found.
        message: String,
    },
    /// A quantity the fit needs has no variable in a MAT-file.
    #[error(
        "{file}: no {quantity} variable (expected a name like '{example}'; found variables: {found})"
    )]
    MissingVariable {
        /// The file.
        file: String,
        /// The missing quantity.
        quantity: &'static str,
        /// An example of an accepted name.
        example: &'static str,
        /// The variables in the file, comma separated.
        found: String,
    },
    /// A MAT-file variable is unusable as a whole (missing unit, wrong class,
    /// ambiguous name).
    #[error("{file}: variable '{variable}': {message}")]
    BadVariable {
        /// The file.
        file: String,
        /// The variable's name.
        variable: String,
        /// What is wrong.
        message: String,
    },
    /// A value of an array (a MAT-file variable, or an array given to the
    /// library) is unusable.
    #[error("{file}: variable '{variable}', element {element}: {message}")]
    BadElement {
        /// The file (or `<array>`).
        file: String,
        /// The variable or array name.
        variable: String,
        /// Element, 1-based.
        element: usize,
        /// What is wrong.
        message: String,
    },
    /// The data set cannot determine the parameters: too few points, or only one
    /// velocity sign for a two-sided fit.
    #[error("{file}: column '{column}': {message}")]
    InsufficientData {
        /// The file.
        file: String,
        /// The column that lacks points.
        column: String,
        /// What is missing, with counts and line numbers.
        message: String,
    },
    /// The fit was stopped by its caller (its progress callback said stop).
    #[error("the fit was cancelled")]
    Cancelled,
    /// An option given to a fit is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// The stage to simulate could not be loaded (robot or scenario file; the
    /// simulated lab of `fistage_analysis::lab`).
    #[error(transparent)]
    Load(#[from] fistage_model::LoadError),
    /// A simulated measurement (`fistage_analysis::lab`) could not be made.
    #[error("{file}: {message}")]
    Simulation {
        /// The robot or scenario file of the stage.
        file: String,
        /// What went wrong.
        message: String,
    },
    /// The convex solver did not return a solution.
    #[error("{file}: the solver failed: {message}")]
    Solver {
        /// The file whose data were being fitted.
        file: String,
        /// What the solver reported.
        message: String,
    },
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, IdentError>;
