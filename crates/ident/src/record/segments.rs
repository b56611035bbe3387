//! Segments of a record: rests, and the motions between them (chirps,
//! ramps, holds, steps). A segments table (`start_s,end_s[,kind]`) names
//! them; without one they are found from the force: a rest is at least
//! 50 ms of zero force command.
//!
//! The fit uses segments twice: the simulated position is re-anchored to
//! the encoder at the start of each motion (velocity and bristle state carry
//! on), so drift does not pile up from one segment into the next; and the
//! interval estimate treats the residuals of one segment as one correlated
//! block.

use std::path::Path;

use super::data::Record;
use crate::csv_input::read_file;
use crate::error::{IdentError, Result};

/// One segment: samples `start..end` of the record.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Segment {
    /// First sample.
    pub start: usize,
    /// One past the last sample.
    pub end: usize,
    /// What it is (`rest`, `chirp`, `ramp`, `step`, `hold`, or as the table says).
    pub kind: String,
}

impl Segment {
    /// True for a rest.
    pub fn is_rest(&self) -> bool {
        self.kind == "rest"
    }
}

/// Shortest rest that splits a record, s.
const MIN_REST: f64 = 50e-3;

/// Segments found from the force: rests of zero force at least 50 ms long,
/// and the motions between them, labelled by the shape of their force.
pub fn detect_segments(record: &Record) -> Vec<Segment> {
    let n = record.len();
    let peak = record.force.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    let quiet = |k: usize| record.force[k].abs() <= 1e-6 * peak;
    let mut segments = Vec::new();
    let mut k = 0;
    let mut motion_start = 0;
    while k < n {
        if !quiet(k) {
            k += 1;
            continue;
        }
        let rest_start = k;
        while k < n && quiet(k) {
            k += 1;
        }
        let long = record.time[k.min(n - 1)] - record.time[rest_start] >= MIN_REST;
        if long || k == n && rest_start > motion_start {
            if rest_start > motion_start {
                segments.push(motion(record, motion_start, rest_start));
            }
            segments.push(Segment {
                start: rest_start,
                end: k,
                kind: "rest".into(),
            });
            motion_start = k;
        }
    }
    if motion_start < n {
        segments.push(motion(record, motion_start, n));
    }
    segments
}

/// A motion segment labelled by its force: `chirp` (many sign changes),
/// `ramp` (monotonic), `hold` (constant), or `step`.
fn motion(record: &Record, start: usize, end: usize) -> Segment {
    let f = &record.force[start..end];
    let sign_changes = f
        .windows(2)
        .filter(|w| w[0] != 0.0 && w[1] != 0.0 && w[0].signum() != w[1].signum())
        .count();
    let rising = f.windows(2).all(|w| w[1] >= w[0]);
    let falling = f.windows(2).all(|w| w[1] <= w[0]);
    let distinct = f.windows(2).filter(|w| w[1] != w[0]).count();
    let kind = if sign_changes >= 4 {
        "chirp"
    } else if distinct == 0 {
        "hold"
    } else if (rising || falling) && distinct > 10 {
        "ramp"
    } else {
        "step"
    };
    Segment {
        start,
        end,
        kind: kind.into(),
    }
}

/// Reads a segments table: CSV with `start_s`, `end_s` and optionally `kind`
/// (times in the record's clock). Segments must be sorted, not overlap and
/// lie inside the record; the samples between them form rests.
pub fn read_segments(path: &Path, record: &Record) -> Result<Vec<Segment>> {
    let (source, text) = read_file(path)?;
    parse_segments(&source, &text, record)
}

/// [`read_segments`] from text; `source` names it in messages.
pub fn parse_segments(source: &str, text: &str, record: &Record) -> Result<Vec<Segment>> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let csv_error = |e: csv::Error| IdentError::Csv {
        file: source.to_string(),
        line: e.position().map_or(0, |p| p.line()),
        message: e.to_string(),
    };
    let headers = reader.headers().map_err(csv_error)?.clone();
    let column = |name: &str| headers.iter().position(|h| h.eq_ignore_ascii_case(name));
    let (Some(start_col), Some(end_col)) = (column("start_s"), column("end_s")) else {
        return Err(IdentError::MissingColumn {
            file: source.to_string(),
            line: 1,
            quantity: "segment time",
            example: "start_s,end_s,kind",
            found: headers.iter().collect::<Vec<_>>().join(", "),
        });
    };
    let kind_col = column("kind");
    let (t0, t1) = (record.time[0], record.time[record.len() - 1]);
    let mut segments: Vec<Segment> = Vec::new();
    for (row, result) in reader.records().enumerate() {
        let entry = result.map_err(csv_error)?;
        let line = entry.position().map_or(0, |p| p.line());
        let bad = |column: &str, message: String| IdentError::BadCell {
            file: source.to_string(),
            line,
            row: row + 1,
            column: column.to_string(),
            message,
        };
        let number = |col: usize, name: &str| -> Result<f64> {
            let text = entry.get(col).unwrap_or("");
            text.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(name, format!("'{text}' is not a finite number")))
        };
        let (start, end) = (number(start_col, "start_s")?, number(end_col, "end_s")?);
        if start >= end {
            return Err(bad(
                "end_s",
                format!("{end} s is not after start_s {start} s"),
            ));
        }
        if start < t0 - 1e-9 || end > t1 + 1e-9 {
            return Err(bad(
                "start_s",
                format!("[{start}, {end}] s is not inside the record's [{t0}, {t1}] s"),
            ));
        }
        let first = record.time.partition_point(|&t| t < start - 1e-12);
        let last = record.time.partition_point(|&t| t < end - 1e-12);
        if let Some(previous) = segments.last()
            && first < previous.end
        {
            return Err(bad(
                "start_s",
                format!("{start} s overlaps the previous segment (or comes before it)"),
            ));
        }
        let kind = kind_col
            .and_then(|c| entry.get(c))
            .filter(|k| !k.is_empty())
            .unwrap_or("segment")
            .to_lowercase();
        segments.push(Segment {
            start: first,
            end: last.max(first + 1),
            kind,
        });
    }
    if segments.is_empty() {
        return Err(IdentError::InsufficientData {
            file: source.to_string(),
            column: "start_s".into(),
            message: "no segments".into(),
        });
    }
    Ok(fill_gaps(segments, record.len()))
}

/// The samples between given segments become rests, so every sample is in one segment.
fn fill_gaps(given: Vec<Segment>, n: usize) -> Vec<Segment> {
    let mut out = Vec::new();
    let mut at = 0;
    for segment in given {
        if segment.start > at {
            out.push(Segment {
                start: at,
                end: segment.start,
                kind: "rest".into(),
            });
        }
        at = segment.end;
        out.push(segment);
    }
    if at < n {
        out.push(Segment {
            start: at,
            end: n,
            kind: "rest".into(),
        });
    }
    out
}

/// The samples where a motion follows a rest: the fit re-anchors the
/// simulated position there.
pub fn anchors(segments: &[Segment]) -> Vec<usize> {
    segments
        .windows(2)
        .filter(|w| w[0].is_rest() && !w[1].is_rest())
        .map(|w| w[1].start)
        .collect()
}

/// Blocks of correlated residuals for the interval estimate: each motion
/// with the rest before it.
pub fn blocks(segments: &[Segment]) -> Vec<(usize, usize)> {
    let mut out: Vec<(usize, usize)> = Vec::new();
    let mut open: Option<usize> = None;
    for segment in segments {
        let start = *open.get_or_insert(segment.start);
        if !segment.is_rest() {
            out.push((start, segment.end));
            open = None;
        }
    }
    if let Some(start) = open {
        match out.last_mut() {
            Some(last) => last.1 = segments.last().map_or(last.1, |s| s.end),
            None => out.push((start, segments.last().map_or(start, |s| s.end))),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record() -> Record {
        let n = 5000;
        let time: Vec<f64> = (0..n).map(|k| k as f64 * 1e-4).collect();
        let force = time
            .iter()
            .map(|&t| {
                if (0.1..0.2).contains(&t) {
                    (2.0 * std::f64::consts::PI * 50.0 * t).sin()
                } else if (0.3..0.4).contains(&t) {
                    t
                } else {
                    0.0
                }
            })
            .collect();
        Record::from_arrays("<test>", time, force, vec![0.0; n]).expect("valid")
    }

    #[test]
    fn rests_split_the_record_and_motions_are_labelled() {
        let segments = detect_segments(&record());
        let kinds: Vec<&str> = segments.iter().map(|s| s.kind.as_str()).collect();
        assert_eq!(kinds, ["rest", "chirp", "rest", "ramp", "rest"]);
        assert_eq!(
            anchors(&segments),
            vec![segments[1].start, segments[3].start]
        );
        let blocks = blocks(&segments);
        assert_eq!(blocks.len(), 2);
        assert_eq!(blocks[1].1, 5000);
    }

    #[test]
    fn a_table_is_checked_row_by_row() {
        let rec = record();
        let ok = parse_segments("seg.csv", "start_s,end_s,kind\n0.1,0.2,chirp\n", &rec).unwrap();
        assert_eq!(ok.len(), 3);
        assert_eq!(ok[1].kind, "chirp");
        let e = parse_segments("seg.csv", "start_s,end_s\n0.1,0.2\n0.15,0.3\n", &rec)
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 3") && e.contains("overlaps"), "{e}");
        let e = parse_segments("seg.csv", "start_s,end_s\n0.1,x\n", &rec)
            .unwrap_err()
            .to_string();
        assert!(e.contains("'end_s'") && e.contains("'x'"), "{e}");
        let e = parse_segments("seg.csv", "begin,end\n", &rec)
            .unwrap_err()
            .to_string();
        assert!(e.contains("start_s"), "{e}");
    }
}
