//! Series prepared for one chart ("layers"): converted to axis space, decimated to the pixel
//! grid, clipped to the visible range, and drawn in their palette colour.

use plotters::prelude::{Circle, DrawingBackend, PathElement, Rectangle};
use plotters::style::{Color, RGBColor, ShapeStyle, WHITE};

use crate::axis::Scale;
use crate::chart::Chart;
use crate::coverage::Trace;
use crate::decimate::{line_trace, marker_points};
use crate::error::DrawResult;
use crate::geometry::{PixelMap, Point};
use crate::output::Format;
use crate::series::{Series, SeriesStyle};

/// Line width in pixels.
pub(crate) const LINE_WIDTH: u32 = 2;
/// Marker radius in pixels.
pub(crate) const MARKER_RADIUS: i32 = 3;
/// Width of the white outline drawn under curves that lie on top of a heatmap.
const HALO_WIDTH: u32 = 6;

/// One series ready to draw.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Layer<'s> {
    /// Legend text.
    pub(crate) label: &'s str,
    /// Drawing style.
    pub(crate) style: SeriesStyle,
    /// Colour.
    pub(crate) colour: RGBColor,
    /// Visible polylines in axis space.
    pub(crate) runs: Vec<Vec<Point>>,
    /// Rectangles (opposite corners in axis space) standing in for a line too dense to draw.
    pub(crate) cells: Vec<[Point; 2]>,
    /// Visible marker positions in axis space.
    pub(crate) markers: Vec<Point>,
}

impl<'s> Layer<'s> {
    /// Prepares `series` for a chart with the given scales and pixel map.
    pub(crate) fn prepare(
        series: &'s Series,
        scales: (Scale, Scale),
        map: &PixelMap,
        colour: RGBColor,
    ) -> Self {
        let points = series.axis_points(scales.0, scales.1);
        let (runs, cells) = match series.style.has_line().then(|| line_trace(&points, map)) {
            Some(Trace::Lines(runs)) => (
                runs.iter().flat_map(|run| map.clip(run)).collect(),
                Vec::new(),
            ),
            Some(Trace::Cells(cells)) => (Vec::new(), cells),
            None => (Vec::new(), Vec::new()),
        };
        // A line with no two connected points still shows its lone points.
        let lone_points = series.style == SeriesStyle::Line && runs.is_empty() && cells.is_empty();
        let markers = if series.style.has_markers() || lone_points {
            marker_points(&points, map)
        } else {
            Vec::new()
        };
        Layer {
            label: &series.label,
            style: series.style,
            colour,
            runs,
            cells,
            markers,
        }
    }

    /// Whether nothing of this layer is visible.
    pub(crate) fn is_empty(&self) -> bool {
        self.runs.is_empty() && self.cells.is_empty() && self.markers.is_empty()
    }

    /// Draws the layer for output in `format`; with `halo`, a white outline drawn first keeps
    /// it visible on any background.
    pub(crate) fn draw<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<DB>,
        halo: bool,
        format: Format,
    ) -> DrawResult {
        let segments = format.needs_segments();
        if halo {
            self.draw_runs(chart, WHITE.stroke_width(HALO_WIDTH), segments)?;
        }
        self.draw_runs(chart, self.colour.stroke_width(LINE_WIDTH), segments)?;
        if !self.cells.is_empty() {
            let fill = self.colour.filled();
            chart.draw_series(
                self.cells
                    .iter()
                    .map(|&corners| Rectangle::new(corners, fill)),
            )?;
        }
        if !self.markers.is_empty() {
            let fill = self.colour.filled();
            let circles = self
                .markers
                .iter()
                .map(|&p| Circle::new(p, MARKER_RADIUS, fill));
            chart.draw_series(circles)?;
        }
        Ok(())
    }

    /// Draws the runs as polylines, or as separate segments when `segments` is set.
    fn draw_runs<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<DB>,
        style: ShapeStyle,
        segments: bool,
    ) -> DrawResult {
        if self.runs.is_empty() {
            return Ok(());
        }
        if segments {
            let pairs = self.runs.iter().flat_map(|run| run.windows(2));
            chart.draw_series(pairs.map(|pair| PathElement::new(pair.to_vec(), style)))?;
        } else {
            chart.draw_series(
                self.runs
                    .iter()
                    .map(|run| PathElement::new(run.clone(), style)),
            )?;
        }
        Ok(())
    }

    /// Pixel positions covered by the layer, sampled every few pixels along its lines.
    pub(crate) fn footprint(&self, map: &PixelMap) -> Vec<Point> {
        let mut pixels: Vec<Point> = self.markers.iter().map(|&p| map.pixel_of(p)).collect();
        for run in &self.runs {
            for pair in run.windows(2) {
                sample_segment(map.pixel_of(pair[0]), map.pixel_of(pair[1]), &mut pixels);
            }
        }
        for [a, b] in &self.cells {
            let (a, b) = (map.pixel_of(*a), map.pixel_of(*b));
            let middle = 0.5 * (a.1 + b.1);
            sample_segment((a.0, middle), (b.0, middle), &mut pixels);
        }
        pixels
    }
}

/// Appends points every few pixels along the segment from pixel `a` to pixel `b`.
fn sample_segment(a: Point, b: Point, pixels: &mut Vec<Point>) {
    const STEP: f64 = 4.0;
    let length = (b.0 - a.0).hypot(b.1 - a.1);
    let steps = (length / STEP).ceil().clamp(1.0, 10_000.0) as usize;
    pixels.extend((0..=steps).map(|k| {
        let t = k as f64 / steps as f64;
        (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
    }));
}

/// Prepares `series` with palette colours by position (`colour` maps the index to a colour).
pub(crate) fn prepare_all<'s>(
    series: &'s [Series],
    scales: (Scale, Scale),
    map: &PixelMap,
    colour: impl Fn(usize) -> RGBColor,
) -> Vec<Layer<'s>> {
    series
        .iter()
        .enumerate()
        .map(|(i, s)| Layer::prepare(s, scales, map, colour(i)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axis::Axis;

    fn map() -> PixelMap {
        let axis = Axis {
            scale: Scale::Linear,
            lo: 0.0,
            hi: 10.0,
            has_data: true,
        };
        PixelMap::new(&axis, &axis, (100, 100))
    }

    #[test]
    fn lone_points_of_a_line_become_markers() {
        let series = Series::line("single", vec![5.0], vec![5.0]);
        let layer = Layer::prepare(&series, (Scale::Linear, Scale::Linear), &map(), WHITE);
        assert!(layer.runs.is_empty());
        assert_eq!(layer.markers, vec![(5.0, 5.0)]);
    }

    #[test]
    fn all_nan_series_is_empty() {
        let series = Series::line_and_markers("nan", vec![1.0, 2.0], vec![f64::NAN; 2]);
        let layer = Layer::prepare(&series, (Scale::Linear, Scale::Linear), &map(), WHITE);
        assert!(layer.is_empty());
    }

    #[test]
    fn footprint_samples_along_lines() {
        let series = Series::line("diag", vec![0.0, 10.0], vec![0.0, 10.0]);
        let layer = Layer::prepare(&series, (Scale::Linear, Scale::Linear), &map(), WHITE);
        let footprint = layer.footprint(&map());
        assert!(footprint.len() > 30);
        assert!(
            footprint
                .iter()
                .any(|p| (p.0 - 50.0).abs() < 3.0 && (p.1 - 50.0).abs() < 3.0)
        );
    }
}
