//! Drawing one chart of curves: frame, grid, series, "no data" note and legend. Shared by the
//! stacked figures and the x-y plots.

use plotters::coord::Shift;
use plotters::prelude::{Color, DrawingArea, DrawingBackend, Polygon};

use crate::chart::{self, Frame};
use crate::error::DrawResult;
use crate::layer::prepare_all;
use crate::legend;
use crate::output::Format;
use crate::palette::series_colour;
use crate::series::Series;

/// Draws `series` in the chart described by `frame` for output in `format`; a legend is added
/// when `legend` is set.
pub(crate) fn draw_curves<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    frame: &Frame,
    series: &[Series],
    legend: bool,
    format: Format,
) -> DrawResult {
    let mut chart = chart::build(area, frame)?;
    chart::draw_grid(&mut chart, frame)?;
    let map = chart::pixel_map(&chart, frame);
    for (i, s) in series.iter().enumerate() {
        let outline = s.band_outline(frame.x.scale, frame.y.scale);
        if outline.len() >= 3 {
            let shade = series_colour(i).mix(0.2).filled();
            chart.draw_series(std::iter::once(Polygon::new(outline, shade)))?;
        }
    }
    let layers = prepare_all(series, (frame.x.scale, frame.y.scale), &map, series_colour);
    for layer in &layers {
        layer.draw(&mut chart, false, format)?;
    }
    if layers.iter().all(|l| l.is_empty()) {
        chart::draw_no_data(&chart)?;
    }
    chart::draw_box(&chart, area, frame)?;
    if legend {
        legend::draw(&chart, &layers, &map)?;
    }
    Ok(())
}
