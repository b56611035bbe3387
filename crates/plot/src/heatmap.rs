//! Heatmaps: one value per grid cell (parameter sweeps, stability maps) with a colour bar or a
//! category legend, grey cells for values that were not computed, and overlaid curves such as
//! a stability boundary. This module holds what a heatmap is; `heatmap_writer` draws it.

use crate::series::Series;

/// How heatmap values become colours.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum ColourScale {
    /// Low to high values from dark purple to yellow, with a colour bar.
    #[default]
    Sequential,
    /// Negative values blue, zero near-white, positive values red, symmetric about zero, with
    /// a colour bar.
    Diverging,
    /// Values are indices into `labels` (0, 1, 2, ...), each drawn in its own colour, with a
    /// legend (e.g. stable / oscillating / bistable).
    Categorical {
        /// One name per category index.
        labels: Vec<String>,
    },
}

/// Values on a grid of cell centres. Values are row-major: `values[row * x.len() + col]` is
/// the cell at `y[row]`, `x[col]`; NaN marks a cell that was not computed and is drawn grey.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Heatmap {
    /// Title above the map.
    pub title: String,
    /// Horizontal axis description.
    pub x_label: String,
    /// Vertical axis description.
    pub y_label: String,
    /// Description of the colour bar (unused for categorical maps).
    pub value_label: String,
    /// Logarithmic horizontal axis (cell centres `<= 0` are skipped).
    pub x_log: bool,
    /// Logarithmic vertical axis (cell centres `<= 0` are skipped).
    pub y_log: bool,
    /// Column centres.
    pub x: Vec<f64>,
    /// Row centres.
    pub y: Vec<f64>,
    /// `y.len() * x.len()` values, row by row.
    pub values: Vec<f64>,
    /// How values become colours.
    pub colour_scale: ColourScale,
    /// Curves drawn over the cells (with a white outline); labelled ones get a legend.
    pub overlay: Vec<Series>,
}

impl Heatmap {
    /// A heatmap with linear axes and no overlay.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
        x: Vec<f64>,
        y: Vec<f64>,
        values: Vec<f64>,
        colour_scale: ColourScale,
    ) -> Self {
        Heatmap {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            x,
            y,
            values,
            colour_scale,
            ..Heatmap::default()
        }
    }
}
