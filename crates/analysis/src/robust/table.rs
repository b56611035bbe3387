//! `samples.csv`: one row per sample, `sample` (its index), every drawn
//! value (a column per parameter path), then `stable_linear`, `max_real_eig`,
//! `stable_sim`, `amplitude` (tracking error, m), `yaw_amplitude` (rad),
//! `bistable` and `refused` (why the sample's
//! stage could not be built, if so). Numbers are written in shortest
//! round-trip form, so rows read back exactly, and a row is taken back only
//! when its values are the ones its index draws.

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

/// The sample a line written by [`row`] holds, if it is a sample of `spec`
/// (its index in range and its values the ones that index draws).
pub fn parse_row(line: &str, spec: &RobustSpec) -> Option<SampleResult> {
    let n_values = spec.columns().len();
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
    // A sample whose stage could not be built has no verdict.
    if refused.is_some() && outcome != Outcome::default() {
        return None;
    }
    Some(SampleResult {
        index,
        values,
        outcome,
        refused,
    })
}
