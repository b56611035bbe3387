//! Plotly figures as the page's data: time signals reduced for the browser
//! (per column the first, lowest, highest and last point, as the static plots
//! keep them), bars, scatter points and heatmaps.

use fistage_plot::{BodeSeries, Series, SeriesStyle, XyPlot};
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

/// One of the static figures' series as a trace: a line, markers or both;
/// its band (where it has one) as a filled area before it.
fn series_traces(series: &Series) -> Vec<Value> {
    let mode = match series.style {
        SeriesStyle::Line => "lines",
        SeriesStyle::Markers => "markers",
        SeriesStyle::LineAndMarkers => "lines+markers",
    };
    let mut traces = Vec::new();
    if let Some((low, high)) = &series.band {
        traces.push(json!({
            "type": "scatter", "mode": "lines", "x": values(&series.x), "y": values(low),
            "line": { "width": 0 }, "showlegend": false, "hoverinfo": "skip",
        }));
        traces.push(json!({
            "type": "scatter", "mode": "lines", "x": values(&series.x), "y": values(high),
            "fill": "tonexty", "line": { "width": 0 }, "showlegend": false, "hoverinfo": "skip",
        }));
    }
    traces.push(json!({
        "type": "scatter", "mode": mode, "name": series.label,
        "x": values(&series.x), "y": values(&series.y),
    }));
    traces
}

/// A static figure (the one written as SVG and PNG) as an interactive plot.
pub fn from_xy(plot: &XyPlot) -> Block {
    let mut block = figure(
        &plot.title,
        plot.series.iter().flat_map(series_traces).collect(),
        &plot.x_label,
        &plot.y_label,
    );
    if let Block::Plot { layout, .. } = &mut block {
        layout["hovermode"] = json!("closest");
        for (axis, log) in [("xaxis", plot.x_log), ("yaxis", plot.y_log)] {
            if log {
                layout[axis]["type"] = json!("log");
            }
        }
    }
    block
}

/// A Bode plot (magnitude, and phase where the series have one) as two
/// interactive plots over logarithmic frequency.
pub fn from_bode(title: &str, freq_hz: &[f64], series: &[BodeSeries]) -> Vec<Block> {
    let trace = |s: &BodeSeries, y: &[f64]| {
        let mode = if s.style == SeriesStyle::Markers {
            "markers"
        } else {
            "lines"
        };
        json!({ "type": "scatter", "mode": mode, "name": s.label, "x": values(freq_hz), "y": values(y) })
    };
    let log_x = |mut block: Block, log_y: bool| {
        if let Block::Plot { layout, .. } = &mut block {
            layout["xaxis"]["type"] = json!("log");
            layout["hovermode"] = json!("closest");
            if log_y {
                layout["yaxis"]["type"] = json!("log");
            }
        }
        block
    };
    let mut blocks = vec![log_x(
        figure(
            &format!("{title}: magnitude"),
            series.iter().map(|s| trace(s, &s.magnitude)).collect(),
            "frequency [Hz]",
            "|G| [m/N]",
        ),
        true,
    )];
    let phases: Vec<Value> = series
        .iter()
        .filter_map(|s| s.phase_deg.as_ref().map(|p| trace(s, p)))
        .collect();
    if !phases.is_empty() {
        blocks.push(log_x(
            figure(
                &format!("{title}: phase"),
                phases,
                "frequency [Hz]",
                "phase [deg]",
            ),
            false,
        ));
    }
    blocks
}
