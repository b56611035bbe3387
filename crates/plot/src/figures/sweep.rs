//! The figures of a parameter sweep: the verdict map of a two-axis sweep with
//! the linear stability boundary over it, or the amplitude and largest real
//! part along a one-axis sweep.

use std::path::Path;

use fistage_analysis::sweep::{Analyses, PointResult, Spacing, SweepSpec};

use super::svg_and_png;
use crate::{ColourScale, Heatmap, PlotError, Series, XyPlot, write_heatmap, write_xy};

/// 0 stable, 1 oscillating (or linearly unstable), 2 bistable; NaN not computed.
fn category(result: &PointResult) -> f64 {
    if result.bistable == Some(true) {
        2.0
    } else if let Some(stable) = result.stable_sim.or(result.stable_linear) {
        if stable { 0.0 } else { 1.0 }
    } else {
        f64::NAN
    }
}

/// Draws the stability map of a two-axis sweep (`map`) or the curves of a
/// one-axis sweep (`sweep`) into `dir`; returns the file names.
pub fn write(
    title: &str,
    spec: &SweepSpec,
    results: &[PointResult],
    dir: &Path,
) -> Result<Vec<String>, PlotError> {
    let mut written = Vec::new();
    match spec.axes.as_slice() {
        [x_axis, y_axis] => {
            let (xs, ys) = (x_axis.values(), y_axis.values());
            let mut values = vec![f64::NAN; xs.len() * ys.len()];
            let mut linear = vec![None; xs.len() * ys.len()];
            for result in results {
                values[result.index] = category(result);
                linear[result.index] = result.stable_linear;
            }
            let (mut bx, mut by) = (Vec::new(), Vec::new());
            let mid = |a: f64, b: f64, log: bool| if log { (a * b).sqrt() } else { 0.5 * (a + b) };
            for row in 0..ys.len() {
                for col in 0..xs.len() {
                    let here = linear[row * xs.len() + col];
                    if col + 1 < xs.len()
                        && here.is_some()
                        && linear[row * xs.len() + col + 1].is_some_and(|v| Some(v) != here)
                    {
                        bx.push(mid(xs[col], xs[col + 1], x_axis.spacing == Spacing::Log));
                        by.push(ys[row]);
                    }
                    if row + 1 < ys.len()
                        && here.is_some()
                        && linear[(row + 1) * xs.len() + col].is_some_and(|v| Some(v) != here)
                    {
                        bx.push(xs[col]);
                        by.push(mid(ys[row], ys[row + 1], y_axis.spacing == Spacing::Log));
                    }
                }
            }
            let mut map = Heatmap::new(
                if title.is_empty() {
                    "stability map".to_string()
                } else {
                    title.to_string()
                },
                x_axis.parameter.clone(),
                y_axis.parameter.clone(),
                xs,
                ys,
                values,
                ColourScale::Categorical {
                    labels: if matches!(spec.analysis, Analyses::Linear) {
                        vec!["stable".into(), "unstable".into(), "bistable".into()]
                    } else {
                        vec!["stable".into(), "oscillating".into(), "bistable".into()]
                    },
                },
            );
            map.x_log = x_axis.spacing == Spacing::Log;
            map.y_log = y_axis.spacing == Spacing::Log;
            map.value_label = "verdict".into();
            if !bx.is_empty() {
                map.overlay
                    .push(Series::markers("linear stability boundary", bx, by));
            }
            written.extend(svg_and_png(dir, "map", |path| write_heatmap(&map, path))?);
        }
        [axis] => {
            let xs: Vec<f64> = results.iter().map(|r| r.parameters[0]).collect();
            let mut series = Vec::new();
            let amplitude: Vec<f64> = results
                .iter()
                .map(|r| r.amplitude.unwrap_or(f64::NAN))
                .collect();
            if amplitude.iter().any(|v| v.is_finite()) {
                series.push(Series::line_and_markers(
                    "steady peak-to-peak [m]",
                    xs.clone(),
                    amplitude,
                ));
            }
            let eig: Vec<f64> = results
                .iter()
                .map(|r| r.max_real_eig.unwrap_or(f64::NAN))
                .collect();
            if eig.iter().any(|v| v.is_finite()) {
                series.push(Series::line_and_markers("max Re(lambda) [1/s]", xs, eig));
            }
            let mut plot = XyPlot::new(title.to_string(), axis.parameter.clone(), "value", series);
            plot.x_log = axis.spacing == Spacing::Log;
            written.extend(svg_and_png(dir, "sweep", |path| write_xy(&plot, path))?);
        }
        _ => {}
    }
    Ok(written)
}
