//! The figures of a population: the histogram of the largest real part, the
//! probability of instability against each parameter, and which tolerance
//! matters most.

use std::path::Path;

use fistage_analysis::robust::{RobustSpec, SampleResult, Summary};

use super::svg_and_png;
use crate::{PlotError, Series, XyPlot, write_xy};

/// A histogram as a step line: (edges, counts) drawn as x, y.
fn histogram(values: &[f64], bins: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let width = if hi > lo {
        (hi - lo) / bins as f64
    } else {
        1.0
    };
    let mut counts = vec![0.0; bins];
    for &v in values {
        counts[(((v - lo) / width) as usize).min(bins - 1)] += 1.0;
    }
    let (mut x, mut y) = (vec![lo], vec![0.0]);
    for (k, &c) in counts.iter().enumerate() {
        let (a, b) = (lo + k as f64 * width, lo + (k + 1) as f64 * width);
        x.extend([a, b]);
        y.extend([c, c]);
    }
    x.push(lo + bins as f64 * width);
    y.push(0.0);
    Some((x, y))
}

/// P(unstable) in ten equal-count bins of one parameter, against the bin's
/// mean deviation from the sample mean in sample standard deviations.
fn probability_curve(results: &[SampleResult], column: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let mut pairs: Vec<(f64, bool)> = results
        .iter()
        .filter_map(|r| {
            Some((
                r.values[column],
                r.outcome.stable_linear.or(r.outcome.stable_sim)?,
            ))
        })
        .collect();
    if pairs.len() < 20 {
        return None;
    }
    let n = pairs.len() as f64;
    let mean = pairs.iter().map(|p| p.0).sum::<f64>() / n;
    let sd = (pairs.iter().map(|p| (p.0 - mean).powi(2)).sum::<f64>() / n).sqrt();
    if sd == 0.0 {
        return None;
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let bins = 10;
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for chunk in pairs.chunks(pairs.len().div_ceil(bins)) {
        let m = chunk.len() as f64;
        x.push((chunk.iter().map(|p| p.0).sum::<f64>() / m - mean) / sd);
        y.push(chunk.iter().filter(|p| !p.1).count() as f64 / m);
    }
    Some((x, y))
}

/// Draws the histogram of the largest real part, P(unstable) against each
/// of the eight most influential parameters, and the sensitivity ranking into
/// `dir` (each where the population has the data); returns the file names.
pub fn write(
    spec: &RobustSpec,
    results: &[SampleResult],
    summary: &Summary,
    dir: &Path,
) -> Result<Vec<String>, PlotError> {
    let mut written = Vec::new();
    let mut write = |plot: &XyPlot, stem: &str| -> Result<(), PlotError> {
        written.extend(svg_and_png(dir, stem, |path| write_xy(plot, path))?);
        Ok(())
    };
    let eig: Vec<f64> = results
        .iter()
        .filter_map(|r| r.outcome.max_real_eig)
        .collect();
    if let Some((x, y)) = histogram(&eig, 40) {
        let top = y.iter().copied().fold(0.0, f64::max);
        let plot = XyPlot::new(
            format!("largest real part over {} samples", eig.len()),
            "max Re(lambda) [1/s]",
            "samples",
            vec![
                Series::line("samples", x, y),
                Series::line("zero: stable to the left", vec![0.0, 0.0], vec![0.0, top]),
            ],
        );
        write(&plot, "max_real_eig_histogram")?;
    }
    let columns = spec.columns();
    let curves: Vec<Series> = summary
        .sensitivity
        .iter()
        .take(8)
        .filter_map(|s| {
            let column = columns.iter().position(|t| t.path == s.parameter)?;
            let (x, y) = probability_curve(results, column)?;
            Some(Series::line_and_markers(s.parameter.clone(), x, y))
        })
        .collect();
    if !curves.is_empty() {
        let plot = XyPlot::new(
            "probability of instability against each parameter",
            "parameter's deviation from its sample mean [sample sd]",
            "P(unstable) in the bin",
            curves,
        );
        write(&plot, "probability_by_parameter")?;
    }
    let bars: Vec<Series> = summary
        .sensitivity
        .iter()
        .enumerate()
        .map(|(rank, s)| {
            let x = (rank + 1) as f64;
            Series::line_and_markers(s.parameter.clone(), vec![x, x], vec![0.0, s.index])
        })
        .collect();
    if !bars.is_empty() {
        let plot = XyPlot::new(
            "which tolerance matters most",
            "rank",
            summary.sensitivity_method,
            bars,
        );
        write(&plot, "sensitivity")?;
    }
    Ok(written)
}
