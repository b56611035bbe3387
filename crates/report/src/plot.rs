//! Plotly figures as the page's data: time signals reduced for the browser
//! (per column the first, lowest, highest and last point, as the static plots
//! keep them), bars, scatter points and heatmaps.

use serde_json::{Value, json};

use crate::Block;

/// Columns a time plot is reduced to (a wide screen's pixels).
const COLUMNS: u32 = 1600;
/// Significant digits kept of each plotted value.
const DIGITS: usize = 7;

/// A value rounded to [`DIGITS`] significant digits (shorter JSON, nothing a
/// plot can show lost); non-finite values become `null` (a gap).
pub fn value(v: f64) -> Value {
    if !v.is_finite() {
        return Value::Null;
    }
    let rounded: f64 = format!("{v:.prec$e}", prec = DIGITS - 1)
        .parse()
        .unwrap_or(v);
    json!(rounded)
}

/// The values of `series` as JSON numbers.
pub fn values(series: &[f64]) -> Vec<Value> {
    series.iter().map(|v| value(*v)).collect()
}

/// A line trace of `y` against monotonic `x`, reduced to an envelope that
/// keeps every extremum; gaps stay gaps.
pub fn line(name: &str, x: &[f64], y: &[f64]) -> Value {
    let points: Vec<(f64, f64)> = x.iter().copied().zip(y.iter().copied()).collect();
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    for (i, run) in fistage_plot::envelope(&points, COLUMNS)
        .into_iter()
        .enumerate()
    {
        if i > 0 {
            xs.push(Value::Null);
            ys.push(Value::Null);
        }
        for (px, py) in run {
            xs.push(value(px));
            ys.push(value(py));
        }
    }
    json!({ "type": "scatter", "mode": "lines", "name": name, "x": xs, "y": ys })
}

/// A plot block of several traces with axis titles.
pub fn figure(title: &str, traces: Vec<Value>, x_title: &str, y_title: &str) -> Block {
    Block::Plot {
        title: title.to_string(),
        traces,
        layout: json!({
            "xaxis": { "title": { "text": x_title }, "exponentformat": "SI" },
            "yaxis": { "title": { "text": y_title }, "exponentformat": "SI" },
            "legend": { "orientation": "h", "y": -0.2 },
        }),
        height: 380,
    }
}
