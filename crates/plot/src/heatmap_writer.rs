//! Drawing a [`Heatmap`]: the cells, the colour key or category legend, the
//! overlaid curves, into SVG or PNG.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, DrawingBackend};
use plotters::style::RGBColor;

use crate::axis::Scale;
use crate::cells::{CellGrid, Colouring};
use crate::chart::{self, Frame, Margins};
use crate::colour_key::ColourKey;
use crate::error::{DrawResult, PlotError};
use crate::heatmap::{ColourScale, Heatmap};
use crate::layer::prepare_all;
use crate::legend;
use crate::output::{self, Format, Painter};
use crate::palette;
use crate::series::check_all;

/// Image size in pixels.
const SIZE: (u32, u32) = (1000, 800);
/// Space above the map, holding the overlay legend.
const TOP_MARGIN: u32 = 36;
/// Space between the map and its colour key (room for the last x tick label).
const RIGHT_MARGIN: u32 = 12;

/// Writes `heatmap` to `path` as SVG or PNG (1000 x 800 pixels), chosen by the extension.
pub fn write_heatmap(heatmap: &Heatmap, path: &Path) -> Result<(), PlotError> {
    Format::from_path(path)?;
    check_shape(heatmap, path)?;
    check_categories(heatmap, path)?;
    check_all(&heatmap.overlay, path)?;
    output::render(path, SIZE, &HeatmapPainter { heatmap })
}

fn check_shape(heatmap: &Heatmap, path: &Path) -> Result<(), PlotError> {
    let (rows, cols) = (heatmap.y.len(), heatmap.x.len());
    let expected = rows.checked_mul(cols);
    if expected == Some(heatmap.values.len()) {
        return Ok(());
    }
    Err(PlotError::HeatmapShape {
        path: path.to_path_buf(),
        rows,
        cols,
        expected: expected.unwrap_or(usize::MAX),
        len: heatmap.values.len(),
    })
}

fn check_categories(heatmap: &Heatmap, path: &Path) -> Result<(), PlotError> {
    let ColourScale::Categorical { labels } = &heatmap.colour_scale else {
        return Ok(());
    };
    let count = labels.len();
    let valid = |v: f64| v.is_nan() || (v >= 0.0 && v.fract() == 0.0 && v < count as f64);
    match heatmap.values.iter().find(|&&v| !valid(v)) {
        None => Ok(()),
        Some(&value) => Err(PlotError::InvalidCategory {
            path: path.to_path_buf(),
            value,
            count,
        }),
    }
}

struct HeatmapPainter<'h> {
    heatmap: &'h Heatmap,
}

impl Painter for HeatmapPainter<'_> {
    fn paint<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        format: Format,
    ) -> DrawResult {
        let heatmap = self.heatmap;
        let body = chart::draw_title(root, &heatmap.title)?;
        let scales = (
            Scale::from_log(heatmap.x_log),
            Scale::from_log(heatmap.y_log),
        );
        let grid = CellGrid::new(heatmap, scales);
        let colouring = Colouring::of(heatmap);
        let plot_height = margins(0).plot_size(body.dim_in_pixel()).1;
        let key = ColourKey::new(&body, heatmap, &colouring, plot_height)?;
        let width = body.dim_in_pixel().0;
        let (main, key_area) =
            body.split_horizontally(width.saturating_sub(key.width.min(width / 3)));
        let frame = frame(&main, heatmap, &grid, plot_height)?;

        let mut chart = chart::build(&main, &frame)?;
        chart::draw_grid(&mut chart, &frame)?;
        let cells = grid.draw(&mut chart, &heatmap.values, &colouring)?;
        let map = chart::pixel_map(&chart, &frame);
        let layers = prepare_all(&heatmap.overlay, scales, &map, overlay_colour);
        for layer in &layers {
            layer.draw(&mut chart, true, format)?;
        }
        if cells == 0 && layers.iter().all(|l| l.is_empty()) {
            chart::draw_no_data(&chart)?;
        }
        chart::draw_box(&chart, &main, &frame)?;
        legend::draw_above(&chart, &main, &layers)?;
        key.draw(&key_area, &chart)
    }
}

/// Margins of the map with a y label area `left` wide.
fn margins(left: u32) -> Margins {
    Margins {
        top: TOP_MARGIN,
        right: RIGHT_MARGIN,
        left,
        bottom: chart::X_LABEL_HEIGHT,
    }
}

/// The frame of the map drawn on `area`.
fn frame<'h, DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    heatmap: &'h Heatmap,
    grid: &CellGrid,
    plot_height: u32,
) -> DrawResult<Frame<'h>> {
    let y_ticks = chart::y_ticks(&grid.y, plot_height);
    let margins = margins(chart::left_margin(area, &[&y_ticks])?);
    let plot_width = margins.plot_size(area.dim_in_pixel()).0;
    Ok(Frame {
        x: grid.x,
        y: grid.y,
        x_ticks: chart::x_ticks(&grid.x, plot_width),
        y_ticks,
        x_desc: &heatmap.x_label,
        y_desc: &heatmap.y_label,
        margins,
    })
}

/// Colour of overlay curve `index`: black first (clear on every colour map), then the palette.
fn overlay_colour(index: usize) -> RGBColor {
    if index == 0 {
        RGBColor(0, 0, 0)
    } else {
        palette::series_colour(index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_and_category_checks_name_the_path() {
        let path = Path::new("sweep.png");
        let mut heatmap = Heatmap::new(
            "t",
            "x",
            "y",
            vec![1.0, 2.0],
            vec![1.0],
            vec![0.0],
            ColourScale::Sequential,
        );
        let message = check_shape(&heatmap, path)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            message.contains("sweep.png") && message.contains("2 columns"),
            "{message}"
        );
        heatmap.values = vec![0.0, 2.0];
        heatmap.colour_scale = ColourScale::Categorical {
            labels: vec!["a".into(), "b".into()],
        };
        assert!(check_shape(&heatmap, path).is_ok());
        let message = check_categories(&heatmap, path)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            message.contains("sweep.png") && message.contains("value 2"),
            "{message}"
        );
        heatmap.values = vec![1.0, f64::NAN];
        assert!(check_categories(&heatmap, path).is_ok());
    }
}
