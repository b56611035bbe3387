//! Stacked figures: panels of time responses (or any curves) sharing one x axis, such as
//! table position, bearing position and friction force over time.

use std::borrow::Cow;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, DrawingBackend};

use crate::axis::{Axis, Scale, Ticks};
use crate::chart::{self, Frame, Margins};
use crate::error::{DrawResult, PlotError};
use crate::output::{self, Format, Painter};
use crate::plot::draw_curves;
use crate::series::{Series, check_all};

/// Figure width in pixels.
const WIDTH: u32 = 1000;
/// Height of one panel (without the shared x labels) in pixels.
const PANEL_HEIGHT: u32 = 300;
/// Relative padding of y ranges.
const Y_PAD: f64 = 0.05;

/// One panel of a stacked [`Figure`]: curves over the shared x axis.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Panel {
    /// Vertical axis description, including the unit (e.g. `"table position [m]"`).
    pub y_label: String,
    /// The curves; a legend is shown when there is more than one.
    pub series: Vec<Series>,
    /// Logarithmic vertical axis (values `<= 0` are skipped).
    pub y_log: bool,
}

impl Panel {
    /// A panel with a linear vertical axis.
    pub fn new(y_label: impl Into<String>, series: Vec<Series>) -> Self {
        Panel {
            y_label: y_label.into(),
            series,
            y_log: false,
        }
    }
}

/// Panels stacked vertically, sharing one x axis whose labels appear below the last panel.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Figure {
    /// Title above the panels.
    pub title: String,
    /// Description of the shared horizontal axis (e.g. `"time [s]"`).
    pub x_label: String,
    /// Logarithmic horizontal axis (values `<= 0` are skipped).
    pub x_log: bool,
    /// The panels, top to bottom.
    pub panels: Vec<Panel>,
}

impl Figure {
    /// A figure with a linear x axis.
    pub fn new(title: impl Into<String>, x_label: impl Into<String>, panels: Vec<Panel>) -> Self {
        Figure {
            title: title.into(),
            x_label: x_label.into(),
            x_log: false,
            panels,
        }
    }
}

/// Writes `figure` to `path` as SVG or PNG, chosen by the extension.
///
/// The image is 1000 pixels wide with 300 pixels per panel plus the title and x labels. A
/// figure without panels, or a panel without drawable data, shows "no data".
pub fn write_figure(figure: &Figure, path: &Path) -> Result<(), PlotError> {
    Format::from_path(path)?;
    check_all(figure.panels.iter().flat_map(|p| &p.series), path)?;
    let panels = figure.panels.len().max(1) as u32;
    let height = chart::HEADER_HEIGHT + panels * PANEL_HEIGHT + chart::X_LABEL_HEIGHT;
    output::render(path, (WIDTH, height), &FigurePainter { figure })
}

struct FigurePainter<'f> {
    figure: &'f Figure,
}

impl Painter for FigurePainter<'_> {
    fn paint<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        format: Format,
    ) -> DrawResult {
        let figure = self.figure;
        let body = chart::draw_title(root, &figure.title)?;
        // A figure without panels still shows one empty ("no data") panel.
        let panels: Cow<[Panel]> = if figure.panels.is_empty() {
            Cow::Owned(vec![Panel::default()])
        } else {
            Cow::Borrowed(&figure.panels)
        };
        let layout = Layout::new(&body, &panels, Scale::from_log(figure.x_log))?;
        let areas = split_panels(&body, panels.len());
        let rows = panels.iter().zip(&areas).zip(&layout.y_axes);
        for (index, ((panel, area), y)) in rows.enumerate() {
            let last = index + 1 == panels.len();
            let frame = layout.frame(y, last, panel, &figure.x_label);
            let legend = panel.series.len() > 1;
            draw_curves(area, &frame, &panel.series, legend, format)?;
        }
        Ok(())
    }
}

/// The axes shared by the panels of one figure, and the per-panel y axes.
struct Layout {
    x: Axis,
    x_ticks: Ticks,
    y_axes: Vec<(Axis, Ticks)>,
    left: u32,
}

impl Layout {
    /// Fits all axes and sizes the y label area so the panels line up.
    fn new<DB: DrawingBackend>(
        body: &DrawingArea<DB, Shift>,
        panels: &[Panel],
        x_scale: Scale,
    ) -> DrawResult<Self> {
        let x_values = panels.iter().flat_map(|p| x_values(p, x_scale));
        let x = Axis::fit(x_scale, x_values, 0.0);
        let plot_height = PANEL_HEIGHT - chart::TOP_MARGIN;
        let y_axes: Vec<(Axis, Ticks)> = panels
            .iter()
            .map(|p| y_axis(p, x_scale))
            .map(|axis| (axis, chart::y_ticks(&axis, plot_height)))
            .collect();
        let all_ticks: Vec<&Ticks> = y_axes.iter().map(|(_, ticks)| ticks).collect();
        let left = chart::left_margin(body, &all_ticks)?;
        let plot_width = margins(left, 0).plot_size((WIDTH, PANEL_HEIGHT)).0;
        let x_ticks = chart::x_ticks(&x, plot_width);
        Ok(Layout {
            x,
            x_ticks,
            y_axes,
            left,
        })
    }

    /// The frame of `panel` with its y axis `y`; only the `last` panel shows the x labels.
    fn frame<'t>(
        &self,
        y: &(Axis, Ticks),
        last: bool,
        panel: &'t Panel,
        x_label: &'t str,
    ) -> Frame<'t> {
        Frame {
            x: self.x,
            y: y.0,
            x_ticks: self.x_ticks.clone(),
            y_ticks: y.1.clone(),
            x_desc: if last { x_label } else { "" },
            y_desc: &panel.y_label,
            margins: margins(self.left, if last { chart::X_LABEL_HEIGHT } else { 0 }),
        }
    }
}

/// Margins of a panel with a y label area `left` wide and an x label area `bottom` high.
fn margins(left: u32, bottom: u32) -> Margins {
    Margins {
        top: chart::TOP_MARGIN,
        right: chart::RIGHT_MARGIN,
        left,
        bottom,
    }
}

/// The x values (axis space) of the drawable points of `panel`.
fn x_values(panel: &Panel, x_scale: Scale) -> impl Iterator<Item = f64> + '_ {
    let y_scale = Scale::from_log(panel.y_log);
    panel
        .series
        .iter()
        .flat_map(move |s| s.valid_points(x_scale, y_scale).map(|p| p.0))
}

/// The y axis of `panel`, fitted to its drawable points.
fn y_axis(panel: &Panel, x_scale: Scale) -> Axis {
    let y_scale = Scale::from_log(panel.y_log);
    let values = panel
        .series
        .iter()
        .flat_map(|s| s.valid_points(x_scale, y_scale).map(|p| p.1));
    Axis::fit(y_scale, values, Y_PAD)
}

/// Splits `body` into `count` panels; the last one also holds the x labels.
fn split_panels<DB: DrawingBackend>(
    body: &DrawingArea<DB, Shift>,
    count: usize,
) -> Vec<DrawingArea<DB, Shift>> {
    let breaks: Vec<u32> = (1..count as u32).map(|i| i * PANEL_HEIGHT).collect();
    body.split_by_breakpoints::<u32, u32, _, _>([], breaks)
}
