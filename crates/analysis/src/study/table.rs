//! The one reader of every study's tables and journals. A line is taken
//! only when it is whole (ends with a line end: a killed run can leave a
//! cut last line), holds no non-finite number, and is exactly the line
//! [`Study::row`] writes for the row [`Study::parse_row`] reads from it (so
//! a cell cut to "fa" is not read as a missing verdict). A missing file
//! holds no rows; a file whose header is another study's gives none.

use std::path::Path;

use fistage_model::output::OutputError;

use super::{Study, StudyError};

/// The rows of a study's table or journal, as [`read_table`] found them.
pub(super) struct Table<R> {
    /// The finished rows of this study, in file order.
    pub rows: Vec<R>,
    /// The lines not taken, each with why.
    pub refused: Vec<RefusedLine>,
}

/// A line of a table that is not a finished row of its study.
pub(super) struct RefusedLine {
    /// Line number in the file (the header is line 1).
    pub line: usize,
    pub why: &'static str,
}

/// Reads `path` (see the module guide).
pub(super) fn read_table<S: Study>(study: &S, path: &Path) -> Result<Table<S::Row>, StudyError> {
    let mut table = Table {
        rows: Vec::new(),
        refused: Vec::new(),
    };
    let text = match std::fs::read(path) {
        Ok(bytes) => String::from_utf8_lossy(&bytes).into_owned(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(table),
        Err(e) => return Err(OutputError::io("read", path)(e).into()),
    };
    let mut lines = text.split_inclusive('\n');
    match lines.next() {
        None => return Ok(table),
        Some(header) if header.trim_end_matches(['\n', '\r']) == study.header() => {}
        Some(_) => {
            table.refused.push(RefusedLine {
                line: 1,
                why: "not this study's header",
            });
            return Ok(table);
        }
    }
    for (number, line) in lines.enumerate().map(|(k, line)| (k + 2, line)) {
        let Some(line) = line.strip_suffix('\n') else {
            table.refused.push(RefusedLine {
                line: number,
                why: "cut short (no line end)",
            });
            continue;
        };
        let line = line.strip_suffix('\r').unwrap_or(line);
        match take_row(study, line) {
            Ok(row) => table.rows.push(row),
            Err(why) => table.refused.push(RefusedLine { line: number, why }),
        }
    }
    Ok(table)
}

/// One line as a finished row of the study, or why not.
fn take_row<S: Study>(study: &S, line: &str) -> Result<S::Row, &'static str> {
    if line
        .split(',')
        .any(|cell| cell.parse::<f64>().is_ok_and(|v| !v.is_finite()))
    {
        return Err("a non-finite number");
    }
    match study.parse_row(line) {
        Some(row) if study.row(&row) == line => Ok(row),
        _ => Err("damaged, or not a finished row of this study"),
    }
}
