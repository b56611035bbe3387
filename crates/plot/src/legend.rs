//! Legends: a box inside the plotting area, in the corner where it hides the least data, or a
//! row above the plot where the whole area carries data.

use plotters::coord::Shift;
use plotters::prelude::{Circle, DrawingArea, DrawingBackend, PathElement, Rectangle, Text};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{Color, RGBColor, WHITE};

use crate::chart::{Chart, plot_rect, text_width};
use crate::error::DrawResult;
use crate::font;
use crate::geometry::{PixelMap, Point};
use crate::layer::{LINE_WIDTH, Layer, MARKER_RADIUS};

/// Distance between the legend box and the plot frame.
const INSET: i32 = 10;
/// Padding inside the legend box.
const PADDING: i32 = 9;
/// Length of the line sample.
const SAMPLE: i32 = 30;
/// Gap between sample and text.
const GAP: i32 = 8;
/// Border colour.
const BORDER: RGBColor = RGBColor(190, 190, 190);

/// Gap between entries of a legend row above the plot.
const ROW_GAP: i32 = 24;

/// Draws a boxed legend of the labelled `layers` inside the plotting area, in the corner where
/// it covers the fewest drawn points.
pub(crate) fn draw<DB: DrawingBackend>(
    chart: &Chart<DB>,
    layers: &[Layer],
    map: &PixelMap,
) -> DrawResult {
    let entries = labelled(layers);
    if entries.is_empty() {
        return Ok(());
    }
    let area = chart.plotting_area().strip_coord_spec();
    let style = font::regular(font::LEGEND_SIZE);
    let mut widest = 0;
    for entry in &entries {
        widest = widest.max(text_width(&area, entry.label, &style)?);
    }
    let line_height = (font::LEGEND_SIZE * 1.15).round() as i32 + 4;
    let size = (
        2 * PADDING + SAMPLE + GAP + widest as i32,
        2 * PADDING + line_height * entries.len() as i32 - 4,
    );
    let footprint: Vec<Point> = layers.iter().flat_map(|l| l.footprint(map)).collect();
    let (x, y) = best_corner(size, map.size(), &footprint);

    let frame = [(x, y), (x + size.0, y + size.1)];
    area.draw(&Rectangle::new(frame, WHITE.mix(0.9).filled()))?;
    area.draw(&Rectangle::new(frame, BORDER.stroke_width(1)))?;
    for (row, entry) in entries.iter().enumerate() {
        let middle = y + PADDING + line_height * row as i32 + (line_height - 4) / 2;
        draw_entry(&area, entry, (x + PADDING, middle))?;
    }
    Ok(())
}

/// Draws the labelled `layers` as one row above the plotting area, right-aligned with it, for
/// plots whose whole area carries data (heatmaps). `area` is the area the chart was built on.
pub(crate) fn draw_above<DB: DrawingBackend>(
    chart: &Chart<DB>,
    area: &DrawingArea<DB, Shift>,
    layers: &[Layer],
) -> DrawResult {
    let entries = labelled(layers);
    let style = font::regular(font::LEGEND_SIZE);
    let mut widths = Vec::with_capacity(entries.len());
    for entry in &entries {
        widths.push(SAMPLE + GAP + text_width(area, entry.label, &style)? as i32);
    }
    let total: i32 = widths.iter().sum::<i32>() + ROW_GAP * (widths.len() as i32 - 1).max(0);
    let ((x0, y0), (w, _)) = plot_rect(chart, area);
    let mut x = x0 + (w - total).max(0);
    let middle = y0 / 2;
    for (entry, width) in entries.iter().zip(widths) {
        draw_entry(area, entry, (x, middle))?;
        x += width + ROW_GAP;
    }
    Ok(())
}

/// The layers that have a label.
fn labelled<'l, 's>(layers: &'l [Layer<'s>]) -> Vec<&'l Layer<'s>> {
    layers.iter().filter(|l| !l.label.is_empty()).collect()
}

/// One legend entry: a line and/or marker sample starting at `at` (its vertical middle),
/// followed by the label.
fn draw_entry<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entry: &Layer,
    at: (i32, i32),
) -> DrawResult {
    let (x, middle) = at;
    if entry.style.has_line() {
        let line = vec![(x, middle), (x + SAMPLE, middle)];
        area.draw(&PathElement::new(
            line,
            entry.colour.stroke_width(LINE_WIDTH),
        ))?;
    }
    if entry.style.has_markers() {
        let centre = (x + SAMPLE / 2, middle);
        area.draw(&Circle::new(
            centre,
            MARKER_RADIUS + 1,
            entry.colour.filled(),
        ))?;
    }
    let style = font::regular(font::LEGEND_SIZE).pos(Pos::new(HPos::Left, VPos::Center));
    area.draw(&Text::new(entry.label, (x + SAMPLE + GAP, middle), style))?;
    Ok(())
}

/// Top-left corner of the legend box: the corner of the plot whose box covers the fewest
/// footprint pixels (upper right preferred on ties).
fn best_corner(size: (i32, i32), plot: (f64, f64), footprint: &[Point]) -> (i32, i32) {
    let (w, h) = (plot.0 as i32, plot.1 as i32);
    let left = INSET;
    let right = (w - INSET - size.0).max(INSET);
    let top = INSET;
    let bottom = (h - INSET - size.1).max(INSET);
    let corners = [(right, top), (left, top), (right, bottom), (left, bottom)];
    let covered = |&(x, y): &(i32, i32)| {
        let margin = 4.0;
        let (x0, y0) = (f64::from(x) - margin, f64::from(y) - margin);
        let (x1, y1) = (
            f64::from(x + size.0) + margin,
            f64::from(y + size.1) + margin,
        );
        footprint
            .iter()
            .filter(|p| p.0 >= x0 && p.0 <= x1 && p.1 >= y0 && p.1 <= y1)
            .count()
    };
    corners
        .iter()
        .copied()
        .min_by_key(|corner| covered(corner))
        .unwrap_or((right, top))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legend_avoids_the_data() {
        // Data crowd the upper right corner only.
        let footprint: Vec<Point> = (0..100).map(|i| (900.0 + f64::from(i), 20.0)).collect();
        assert_eq!(
            best_corner((200, 60), (1000.0, 300.0), &footprint),
            (10, 10)
        );
        assert_eq!(best_corner((200, 60), (1000.0, 300.0), &[]), (790, 10));
    }
}
