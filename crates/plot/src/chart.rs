//! Chart frames shared by every figure kind: plotters charts over two axes with custom ticks,
//! grid, axis descriptions, the frame box, label multipliers, titles and the "no data" note.

use plotters::coord::Shift;
use plotters::prelude::{
    Cartesian2d, ChartBuilder, ChartContext, DrawingArea, DrawingBackend, Rectangle, Text,
};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{Color, TextStyle};

use crate::axis::{Axis, Ticks};
use crate::coord::TickedRange;
use crate::error::DrawResult;
use crate::font;
use crate::geometry::PixelMap;
use crate::palette::{AXIS, GRID_MAJOR, GRID_MINOR};

/// The plotters coordinate system of every chart: linear axis space with custom ticks.
pub(crate) type Coord = Cartesian2d<TickedRange, TickedRange>;
/// A chart over [`Coord`].
pub(crate) type Chart<'a, DB> = ChartContext<'a, DB, Coord>;

/// Height of the title band at the top of every figure.
pub(crate) const HEADER_HEIGHT: u32 = 56;
/// Height of the x tick labels and description below a plot.
pub(crate) const X_LABEL_HEIGHT: u32 = 64;
/// Space above a plot (room for the top tick label and a label multiplier).
pub(crate) const TOP_MARGIN: u32 = 26;
/// Space right of a plot.
pub(crate) const RIGHT_MARGIN: u32 = 34;
/// Space left of the y axis description (glyphs of rotated text reach slightly past their box).
const LEFT_MARGIN: u32 = 10;
/// Length of tick marks.
const TICK_MARK: u32 = 5;
/// Preferred distance between x tick labels, in pixels.
const X_TICK_SPACING: f64 = 120.0;
/// Preferred distance between y tick labels, in pixels.
const Y_TICK_SPACING: f64 = 62.0;

/// Space around a plotting area, in pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Margins {
    /// Above the plotting area.
    pub(crate) top: u32,
    /// Right of the plotting area.
    pub(crate) right: u32,
    /// Left of the plotting area: y tick labels and description (after a fixed small margin).
    pub(crate) left: u32,
    /// Below the plotting area: x tick labels and description (0 hides them).
    pub(crate) bottom: u32,
}

impl Margins {
    /// The plotting area size inside an area of `size` pixels.
    pub(crate) fn plot_size(&self, size: (u32, u32)) -> (u32, u32) {
        (
            size.0
                .saturating_sub(LEFT_MARGIN + self.left + self.right)
                .max(1),
            size.1.saturating_sub(self.top + self.bottom).max(1),
        )
    }
}

/// Everything that fixes how one chart's axes look.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Frame<'t> {
    /// Horizontal axis.
    pub(crate) x: Axis,
    /// Vertical axis.
    pub(crate) y: Axis,
    /// Horizontal ticks.
    pub(crate) x_ticks: Ticks,
    /// Vertical ticks.
    pub(crate) y_ticks: Ticks,
    /// Horizontal axis description.
    pub(crate) x_desc: &'t str,
    /// Vertical axis description.
    pub(crate) y_desc: &'t str,
    /// Space around the plotting area.
    pub(crate) margins: Margins,
}

/// Ticks for a vertical axis `pixels` high.
pub(crate) fn y_ticks(axis: &Axis, pixels: u32) -> Ticks {
    axis.ticks(pixels, Y_TICK_SPACING)
}

/// Ticks for a horizontal axis `pixels` wide.
pub(crate) fn x_ticks(axis: &Axis, pixels: u32) -> Ticks {
    axis.ticks(pixels, X_TICK_SPACING)
}

/// Width of text in pixels.
pub(crate) fn text_width<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    style: &TextStyle,
) -> DrawResult<u32> {
    if text.is_empty() {
        return Ok(0);
    }
    Ok(area.estimate_text_size(text, style)?.0)
}

/// Width of the left label area that fits the labels of all `ticks` and a rotated description.
pub(crate) fn left_margin<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    ticks: &[&Ticks],
) -> DrawResult<u32> {
    let style = font::regular(font::TICK_SIZE);
    let mut widest = 0;
    for label in ticks.iter().flat_map(|t| t.labels()) {
        widest = widest.max(text_width(area, &label, &style)?);
    }
    let description = (font::LABEL_SIZE * 1.25) as u32;
    Ok(widest + 2 * TICK_MARK + description + 8)
}

/// Builds the chart of `frame` on `area`.
pub(crate) fn build<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    frame: &Frame,
) -> DrawResult<Chart<'a, DB>> {
    let x = TickedRange::new(&frame.x, &frame.x_ticks);
    let y = TickedRange::new(&frame.y, &frame.y_ticks);
    let m = frame.margins;
    let chart = ChartBuilder::on(area)
        .margin_left(LEFT_MARGIN)
        .margin_top(m.top)
        .margin_right(m.right)
        .x_label_area_size(m.bottom)
        .y_label_area_size(m.left)
        .build_cartesian_2d(x, y)?;
    Ok(chart)
}

/// The pixel map of a built chart.
pub(crate) fn pixel_map<DB: DrawingBackend>(chart: &Chart<DB>, frame: &Frame) -> PixelMap {
    PixelMap::new(&frame.x, &frame.y, chart.plotting_area().dim_in_pixel())
}

/// Draws grid lines, axes, tick labels and axis descriptions.
pub(crate) fn draw_grid<DB: DrawingBackend>(chart: &mut Chart<DB>, frame: &Frame) -> DrawResult {
    let x_label = |v: &f64| frame.x_ticks.label(*v);
    let y_label = |v: &f64| frame.y_ticks.label(*v);
    let mut mesh = chart.configure_mesh();
    mesh.x_label_formatter(&x_label)
        .y_label_formatter(&y_label)
        .label_style(font::regular(font::TICK_SIZE))
        .axis_desc_style(font::regular(font::LABEL_SIZE))
        .bold_line_style(GRID_MAJOR.stroke_width(1))
        .light_line_style(GRID_MINOR.stroke_width(1))
        .axis_style(AXIS.stroke_width(1))
        .set_all_tick_mark_size(TICK_MARK);
    if !frame.x_desc.is_empty() {
        mesh.x_desc(frame.x_desc);
    }
    if !frame.y_desc.is_empty() {
        mesh.y_desc(frame.y_desc);
    }
    mesh.draw()?;
    Ok(())
}

/// The plotting area of `chart` as a rectangle inside `area` (which the chart was built on):
/// top-left corner and size in pixels. Elements drawn on a drawing area are clamped to it, so
/// anything outside the plotting area must be drawn on the enclosing area at these offsets.
pub(crate) fn plot_rect<DB: DrawingBackend>(
    chart: &Chart<DB>,
    area: &DrawingArea<DB, Shift>,
) -> ((i32, i32), (i32, i32)) {
    let (x, y) = chart.plotting_area().get_base_pixel();
    let (base_x, base_y) = area.get_base_pixel();
    let (w, h) = chart.plotting_area().dim_in_pixel();
    ((x - base_x, y - base_y), (w as i32, h as i32))
}

/// Draws the box around the plotting area and, on the enclosing `area`, the label multipliers
/// ("×10⁻⁶") above the y axis and below the right end of the x axis.
pub(crate) fn draw_box<DB: DrawingBackend>(
    chart: &Chart<DB>,
    area: &DrawingArea<DB, Shift>,
    frame: &Frame,
) -> DrawResult {
    let plot = chart.plotting_area().strip_coord_spec();
    let (w, h) = plot.dim_in_pixel();
    plot.draw(&Rectangle::new(
        [(0, 0), (w as i32 - 1, h as i32 - 1)],
        AXIS.stroke_width(1),
    ))?;
    let ((x0, y0), (w, h)) = plot_rect(chart, area);
    let style = font::regular(font::TICK_SIZE);
    if let Some(text) = frame.y_ticks.multiplier() {
        let anchored = style.pos(Pos::new(HPos::Left, VPos::Bottom));
        area.draw(&Text::new(text, (x0, y0 - 5), anchored))?;
    }
    if frame.margins.bottom > 0
        && let Some(text) = frame.x_ticks.multiplier()
    {
        let anchored = style.pos(Pos::new(HPos::Right, VPos::Top));
        area.draw(&Text::new(text, (x0 + w, y0 + h + 28), anchored))?;
    }
    Ok(())
}

/// Writes "no data" in the middle of the plotting area.
pub(crate) fn draw_no_data<DB: DrawingBackend>(chart: &Chart<DB>) -> DrawResult {
    let area = chart.plotting_area().strip_coord_spec();
    let (w, h) = area.dim_in_pixel();
    let style = font::regular(font::NOTE_SIZE)
        .color(&font::NOTE_COLOUR)
        .pos(Pos::new(HPos::Center, VPos::Center));
    area.draw(&Text::new("no data", (w as i32 / 2, h as i32 / 2), style))?;
    Ok(())
}

/// Splits off the title band of `root`, writes `title` centred in it and returns the rest.
pub(crate) fn draw_title<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> DrawResult<DrawingArea<DB, Shift>> {
    let (header, body) = root.split_vertically(HEADER_HEIGHT);
    let (w, h) = header.dim_in_pixel();
    let style = font::bold(font::TITLE_SIZE).pos(Pos::new(HPos::Center, VPos::Center));
    header.draw(&Text::new(title, (w as i32 / 2, h as i32 / 2 + 4), style))?;
    Ok(body)
}
