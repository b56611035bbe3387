//! `samples.csv`: one row per sample, `sample` (its index), every drawn
//! value (a column per parameter path), then `stable_linear`, `max_real_eig`,
//! `stable_sim`, `amplitude` (tracking error, m), `yaw_amplitude` (rad),
//! `bistable` and `refused` (why the sample's
//! stage could not be built, if so). Numbers are written in shortest
//! round-trip form, so rows read back exactly, and a row is taken back only
//! when its values are the ones its index draws.

use std::path::Path;

use super::{RobustSpec, SampleResult};
use crate::assess::Outcome;

const VERDICTS: [&str; 7] = [
    "stable_linear",
    "max_real_eig",
    "stable_sim",
    "amplitude",
    "yaw_amplitude",
    "bistable",
    "refused",
];

fn number(value: f64) -> String {
    format!("{value:e}")
}

fn optional<T>(value: Option<T>, show: impl Fn(T) -> String) -> String {
    value.map_or(String::new(), show)
}

/// The header line.
pub fn header(spec: &RobustSpec) -> String {
    let mut columns = vec!["sample".to_string()];
    columns.extend(spec.columns().iter().map(|t| t.path.clone()));
    columns.extend(VERDICTS.map(String::from));
    columns.join(",")
}

/// One row (no line end).
pub fn row(result: &SampleResult) -> String {
    let o = &result.outcome;
    let mut cells = vec![result.index.to_string()];
    cells.extend(result.values.iter().map(|&v| number(v)));
    cells.push(optional(o.stable_linear, |b| b.to_string()));
    cells.push(optional(o.max_real_eig, number));
    cells.push(optional(o.stable_sim, |b| b.to_string()));
    cells.push(optional(o.amplitude, number));
    cells.push(optional(o.yaw_amplitude, number));
    cells.push(optional(o.bistable, |b| b.to_string()));
    // One cell: no delimiter or line end of the reason survives.
    cells.push(optional(result.refused.as_deref(), |why| {
        why.replace([',', '\n', '\r'], " ")
    }));
    cells.join(",")
}

fn parse_bool(cell: &str) -> Option<Option<bool>> {
    match cell {
        "" => Some(None),
        "true" => Some(Some(true)),
        "false" => Some(Some(false)),
        _ => None,
    }
}

fn parse_number(cell: &str) -> Option<Option<f64>> {
    if cell.is_empty() {
        return Some(None);
    }
    cell.parse::<f64>().ok().filter(|v| v.is_finite()).map(Some)
}

/// The rows of `path` that are samples of `spec` (others, and damaged
/// rows such as a half-written last line, are skipped).
pub fn read_rows(path: &Path, spec: &RobustSpec) -> Vec<SampleResult> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Vec::new();
    };
    let n_values = spec.columns().len();
    text.lines()
        .skip(1)
        .filter_map(|line| parse_row(line, spec, n_values))
        .collect()
}

fn parse_row(line: &str, spec: &RobustSpec, n_values: usize) -> Option<SampleResult> {
    let cells: Vec<&str> = line.split(',').collect();
    if cells.len() != 1 + n_values + VERDICTS.len() {
        return None;
    }
    let index: usize = cells[0].parse().ok().filter(|&i| i < spec.samples)?;
    let values = spec.values(index);
    let written = &cells[1..=n_values];
    if values
        .iter()
        .zip(written)
        .any(|(v, cell)| number(*v) != *cell)
    {
        return None;
    }
    let verdicts = &cells[1 + n_values..];
    let outcome = Outcome {
        stable_linear: parse_bool(verdicts[0])?,
        max_real_eig: parse_number(verdicts[1])?,
        stable_sim: parse_bool(verdicts[2])?,
        amplitude: parse_number(verdicts[3])?,
        yaw_amplitude: parse_number(verdicts[4])?,
        bistable: parse_bool(verdicts[5])?,
    };
    let refused = (!verdicts[6].is_empty()).then(|| verdicts[6].to_string());
    Some(SampleResult {
        index,
        values,
        outcome,
        refused,
    })
}
