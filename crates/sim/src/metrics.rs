//! Signal statistics over a time window: mean, peak-to-peak, RMS, min, max and
//! standard deviation, as reported in `summary.json`.

use serde::Serialize;

use crate::trajectory::SignalTable;

/// Statistics of one signal over a window.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WindowStats {
    /// Mean.
    pub mean: f64,
    /// max - min.
    pub peak_to_peak: f64,
    /// Root mean square (about zero).
    pub rms: f64,
    /// Minimum.
    pub min: f64,
    /// Maximum.
    pub max: f64,
    /// Standard deviation (about the mean).
    pub std: f64,
}

/// Statistics of `values` at `times` restricted to `start <= t <= end`. `None`
/// when no sample falls in the window.
pub fn window_stats(times: &[f64], values: &[f64], start: f64, end: f64) -> Option<WindowStats> {
    let tolerance = 1e-9 * end.abs().max(1.0);
    let selected: Vec<f64> = times
        .iter()
        .zip(values)
        .filter(|(t, _)| **t >= start - tolerance && **t <= end + tolerance)
        .map(|(_, v)| *v)
        .collect();
    if selected.is_empty() {
        return None;
    }
    let n = selected.len() as f64;
    let mean = selected.iter().sum::<f64>() / n;
    let min = selected.iter().copied().fold(f64::INFINITY, f64::min);
    let max = selected.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let rms = (selected.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
    let std = (selected.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    Some(WindowStats {
        mean,
        peak_to_peak: max - min,
        rms,
        min,
        max,
        std,
    })
}

/// A named signal's statistics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SignalSummary {
    /// Signal name.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Statistics over the window.
    #[serde(flatten)]
    pub stats: WindowStats,
}

/// Statistics of every signal in the table over `[start, end]`.
pub fn summarize(table: &SignalTable, start: f64, end: f64) -> Vec<SignalSummary> {
    table
        .names
        .iter()
        .zip(&table.units)
        .zip(&table.columns)
        .filter_map(|((name, unit), column)| {
            window_stats(&table.times, column, start, end).map(|stats| SignalSummary {
                name: name.clone(),
                unit: unit.clone(),
                stats,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sine_statistics() {
        let times: Vec<f64> = (0..=10000).map(|k| k as f64 * 1e-4).collect();
        let values: Vec<f64> = times
            .iter()
            .map(|t| 2.0 + 3.0 * (2.0 * std::f64::consts::PI * 5.0 * t).sin())
            .collect();
        let s = window_stats(&times, &values, 0.2, 1.0).unwrap();
        assert!((s.mean - 2.0).abs() < 1e-3);
        assert!((s.peak_to_peak - 6.0).abs() < 1e-6);
        assert!((s.std - 3.0 / 2f64.sqrt()).abs() < 1e-3);
        assert!((s.rms - (4.0 + 4.5f64).sqrt()).abs() < 1e-3);
        assert!(window_stats(&times, &values, 2.0, 3.0).is_none());
    }
}
