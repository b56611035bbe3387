//! Single x-y plots: phase portraits (velocity against position), measured data against a
//! fitted model, and other curves that do not share a time axis.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, DrawingBackend};

use crate::axis::{Axis, Scale};
use crate::chart::{self, Frame, Margins};
use crate::error::{DrawResult, PlotError};
use crate::output::{self, Format, Painter};
use crate::plot::draw_curves;
use crate::series::{Series, check_all};

/// Image size in pixels.
const SIZE: (u32, u32) = (1000, 780);
/// Relative padding of both ranges.
const PAD: f64 = 0.05;

/// One chart of curves with its own axes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct XyPlot {
    /// Title above the chart.
    pub title: String,
    /// Horizontal axis description.
    pub x_label: String,
    /// Vertical axis description.
    pub y_label: String,
    /// The curves; a legend is shown when there is more than one.
    pub series: Vec<Series>,
    /// Logarithmic horizontal axis (values `<= 0` are skipped).
    pub x_log: bool,
    /// Logarithmic vertical axis (values `<= 0` are skipped).
    pub y_log: bool,
    /// Same data units per pixel on both axes (ignored when either axis is logarithmic).
    pub equal_aspect: bool,
}

impl XyPlot {
    /// A plot with linear axes and free aspect ratio.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
        series: Vec<Series>,
    ) -> Self {
        XyPlot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series,
            ..XyPlot::default()
        }
    }
}

/// Writes `plot` to `path` as SVG or PNG (1000 x 780 pixels), chosen by the extension.
pub fn write_xy(plot: &XyPlot, path: &Path) -> Result<(), PlotError> {
    Format::from_path(path)?;
    check_all(&plot.series, path)?;
    output::render(path, SIZE, &XyPainter { plot })
}

struct XyPainter<'p> {
    plot: &'p XyPlot,
}

impl Painter for XyPainter<'_> {
    fn paint<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        format: Format,
    ) -> DrawResult {
        let plot = self.plot;
        let body = chart::draw_title(root, &plot.title)?;
        let scales = (Scale::from_log(plot.x_log), Scale::from_log(plot.y_log));
        let points = || {
            plot.series
                .iter()
                .flat_map(|s| s.valid_points(scales.0, scales.1))
        };
        let x = Axis::fit(scales.0, points().map(|p| p.0), PAD);
        let y = Axis::fit(scales.1, points().map(|p| p.1), PAD);

        let mut margins = Margins {
            top: chart::TOP_MARGIN,
            right: chart::RIGHT_MARGIN,
            left: 0,
            bottom: chart::X_LABEL_HEIGHT,
        };
        let plot_height = margins.plot_size(body.dim_in_pixel()).1;
        margins.left = chart::left_margin(&body, &[&chart::y_ticks(&y, plot_height)])?;
        let plot_size = margins.plot_size(body.dim_in_pixel());
        let (x, y) = if plot.equal_aspect && !plot.x_log && !plot.y_log {
            equalise(x, y, plot_size)
        } else {
            (x, y)
        };
        let frame = Frame {
            x,
            y,
            x_ticks: chart::x_ticks(&x, plot_size.0),
            y_ticks: chart::y_ticks(&y, plot_size.1),
            x_desc: &plot.x_label,
            y_desc: &plot.y_label,
            margins,
        };
        draw_curves(&body, &frame, &plot.series, plot.series.len() > 1, format)
    }
}

/// Widens one of the ranges so that both axes have the same units per pixel.
fn equalise(x: Axis, y: Axis, plot_size: (u32, u32)) -> (Axis, Axis) {
    let (w, h) = (f64::from(plot_size.0), f64::from(plot_size.1));
    let per_pixel = (x.span() / w).max(y.span() / h);
    (x.widened_to(per_pixel * w), y.widened_to(per_pixel * h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_aspect_matches_units_per_pixel() {
        let x = Axis {
            scale: Scale::Linear,
            lo: 0.0,
            hi: 10.0,
            has_data: true,
        };
        let y = Axis {
            scale: Scale::Linear,
            lo: -1.0,
            hi: 1.0,
            has_data: true,
        };
        let (x2, y2) = equalise(x, y, (800, 400));
        assert_eq!((x2.lo, x2.hi), (0.0, 10.0));
        assert!((y2.span() / 400.0 - x2.span() / 800.0).abs() < 1e-12);
        assert!((y2.lo + y2.hi).abs() < 1e-12);
    }
}
