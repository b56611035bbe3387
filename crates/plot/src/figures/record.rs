//! The figure of a record fit: measured and simulated position, the
//! residual and the force against time.

use std::path::Path;

use fistage_ident::record::{Record, RecordFit};

use super::{short_name, svg_and_png};
use crate::{Figure, Panel, PlotError, Series, write_figure};

/// Draws `fit` into `dir`; returns the file names.
pub fn write(record: &Record, fit: &RecordFit, dir: &Path) -> Result<Vec<String>, PlotError> {
    let figure = fit_figure(record, fit);
    svg_and_png(dir, "fit", |path| write_figure(&figure, path))
}

/// Measured and simulated position (mm), the residual (nm) and the force (N)
/// against time.
fn fit_figure(record: &Record, fit: &RecordFit) -> Figure {
    let t = record.time.clone();
    let mm = |x: &[f64]| x.iter().map(|v| v * 1e3).collect::<Vec<f64>>();
    let residual: Vec<f64> = fit
        .simulated
        .iter()
        .zip(&record.position)
        .map(|(s, m)| (s - m) * 1e9)
        .collect();
    Figure::new(
        format!("Record fit: {}", short_name(&record.source)),
        "time (s)",
        vec![
            Panel::new(
                "position (mm)",
                vec![
                    Series::line("measured", t.clone(), mm(&record.position)),
                    Series::line("simulated (fit)", t.clone(), mm(&fit.simulated)),
                ],
            ),
            Panel::new(
                "residual (nm)",
                vec![Series::line("simulated - measured", t.clone(), residual)],
            ),
            Panel::new(
                "force (N)",
                vec![Series::line("force command", t, record.force.clone())],
            ),
        ],
    )
}
