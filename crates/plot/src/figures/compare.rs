//! The figures of a comparison: each case's metric along the first axis with
//! a band of one standard deviation, and its reduction against the baseline.

use std::path::Path;

use fistage_analysis::compare::{Comparison, Curve};
use fistage_analysis::sweep::Spacing;

use crate::{PlotError, Series, XyPlot, write_xy};

/// A legend label: the case's title, or its name.
fn label(comparison: &Comparison, case: usize) -> String {
    let case = &comparison.cases[case];
    if case.loaded.scenario.title.is_empty() {
        case.name.clone()
    } else {
        super::title(&case.loaded)
    }
}

/// Draws the metric's curves (`<metric>`) and, with a baseline, their
/// reduction against it (`<metric>_reduction`) into `dir`; returns the SVG
/// names (each has its PNG beside it).
pub fn write(
    comparison: &Comparison,
    curves: &[Curve],
    dir: &Path,
) -> Result<Vec<String>, PlotError> {
    let x_log = comparison
        .axes
        .first()
        .is_some_and(|a| a.spacing == Spacing::Log);
    let band = |mean: &[f64], std: &[f64], sign: f64| -> Vec<f64> {
        mean.iter().zip(std).map(|(m, s)| m + sign * s).collect()
    };
    let spread = if comparison.axes.len() >= 2 {
        format!("mean, +-1 sigma over {}", comparison.axes[1].parameter)
    } else {
        "mean, +-1 sigma over the run's events".into()
    };
    let metric = comparison.metric;
    let mut plots = vec![(
        format!("{}.svg", metric.name()),
        XyPlot {
            x_log,
            ..XyPlot::new(
                metric.name().replace('_', " "),
                comparison.x_label_with_unit(),
                format!("{} [{}] ({spread})", metric.name(), metric.unit()),
                curves
                    .iter()
                    .map(|c| {
                        Series::line_and_markers(
                            label(comparison, c.case),
                            c.x.clone(),
                            c.mean.clone(),
                        )
                        .with_band(band(&c.mean, &c.std, -1.0), band(&c.mean, &c.std, 1.0))
                    })
                    .collect(),
            )
        },
    )];
    if comparison.has_baseline {
        plots.push((
            format!("{}_reduction.svg", metric.name()),
            XyPlot {
                x_log,
                ..XyPlot::new(
                    format!(
                        "{} reduction against {}",
                        metric.name().replace('_', " "),
                        comparison.cases[0].name
                    ),
                    comparison.x_label_with_unit(),
                    format!("reduction [%] ({spread})"),
                    curves
                        .iter()
                        .skip(1)
                        .map(|c| {
                            let (m, s) = (&c.reduction_mean, &c.reduction_std);
                            Series::line_and_markers(
                                label(comparison, c.case),
                                c.x.clone(),
                                m.clone(),
                            )
                            .with_band(band(m, s, -1.0), band(m, s, 1.0))
                        })
                        .collect(),
                )
            },
        ));
    }
    let mut written = Vec::new();
    for (name, plot) in plots {
        for file in [name.clone(), name.replace(".svg", ".png")] {
            write_xy(&plot, &dir.join(&file))?;
        }
        written.push(name);
    }
    Ok(written)
}
