//! Heatmap cells: edges from cell centres, the axes spanning them, the mapping from values to
//! colours, and drawing the cells (merging equal neighbours to keep SVG files small).

use plotters::prelude::{DrawingBackend, Rectangle};
use plotters::style::{Color, RGBColor};

use crate::axis::{Axis, Scale};
use crate::chart::Chart;
use crate::error::DrawResult;
use crate::heatmap::{ColourScale, Heatmap};
use crate::palette::{self, MISSING};

/// Axis-space extent of a cell along one axis.
type Edges = (f64, f64);

/// The mapping from values to colours, resolved against the data.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Colouring {
    /// Linear map of `axis.lo..axis.hi` onto the sequential or diverging colour map.
    Continuous {
        /// The value range.
        axis: Axis,
        /// Diverging (instead of sequential) colour map.
        diverging: bool,
    },
    /// Category indices.
    Categorical,
}

impl Colouring {
    /// The colouring of `heatmap`: sequential over the value range, diverging symmetric about
    /// zero, or by category.
    pub(crate) fn of(heatmap: &Heatmap) -> Self {
        let finite = heatmap.values.iter().copied().filter(|v| v.is_finite());
        match heatmap.colour_scale {
            ColourScale::Sequential => Colouring::Continuous {
                axis: Axis::fit(Scale::Linear, finite, 0.0),
                diverging: false,
            },
            ColourScale::Diverging => {
                let limit = finite.fold(0.0_f64, |m, v| m.max(v.abs()));
                let limit = if limit > 0.0 { limit } else { 1.0 };
                let axis = Axis {
                    scale: Scale::Linear,
                    lo: -limit,
                    hi: limit,
                    has_data: true,
                };
                Colouring::Continuous {
                    axis,
                    diverging: true,
                }
            }
            ColourScale::Categorical { .. } => Colouring::Categorical,
        }
    }

    /// The colour at position `t` in `[0, 1]` of a continuous map.
    pub(crate) fn map_colour(diverging: bool, t: f64) -> RGBColor {
        if diverging {
            palette::diverging(t)
        } else {
            palette::sequential(t)
        }
    }

    /// The colour of a cell holding `value` (grey when not finite).
    pub(crate) fn colour(&self, value: f64) -> RGBColor {
        if !value.is_finite() {
            return MISSING;
        }
        match self {
            Colouring::Continuous { axis, diverging } => {
                Self::map_colour(*diverging, (value - axis.lo) / axis.span())
            }
            Colouring::Categorical => palette::category_colour(value as usize),
        }
    }
}

/// Cell edges along both axes and the axes spanning them.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CellGrid {
    /// Edges of each column (`None` where its centre cannot be drawn).
    x_edges: Vec<Option<Edges>>,
    /// Drawable columns from left to right.
    x_order: Vec<usize>,
    /// Edges of each row (`None` where its centre cannot be drawn).
    y_edges: Vec<Option<Edges>>,
    /// Horizontal axis.
    pub(crate) x: Axis,
    /// Vertical axis.
    pub(crate) y: Axis,
}

impl CellGrid {
    /// The grid of `heatmap`; without drawable cells the axes fit the overlay instead.
    pub(crate) fn new(heatmap: &Heatmap, scales: (Scale, Scale)) -> Self {
        let (x_edges, x_order) = cell_edges(&heatmap.x, scales.0);
        let (y_edges, _) = cell_edges(&heatmap.y, scales.1);
        let overlay = || {
            heatmap
                .overlay
                .iter()
                .flat_map(|s| s.valid_points(scales.0, scales.1))
        };
        let x = grid_axis(&x_edges, scales.0, overlay().map(|p| p.0));
        let y = grid_axis(&y_edges, scales.1, overlay().map(|p| p.1));
        CellGrid {
            x_edges,
            x_order,
            y_edges,
            x,
            y,
        }
    }

    /// Draws the cells of `values` (row-major, one row per y centre), merging horizontal
    /// neighbours of equal colour; returns the number of rectangles drawn.
    pub(crate) fn draw<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<DB>,
        values: &[f64],
        colouring: &Colouring,
    ) -> DrawResult<usize> {
        let cols = self.x_edges.len();
        let mut rectangles = Vec::new();
        for (row, edges) in self.y_edges.iter().enumerate() {
            let Some((y0, y1)) = *edges else { continue };
            let colour_at = |col: usize| {
                colouring.colour(values.get(row * cols + col).copied().unwrap_or(f64::NAN))
            };
            for (x0, x1, colour) in self.row_runs(colour_at) {
                rectangles.push(Rectangle::new([(x0, y1), (x1, y0)], colour.filled()));
            }
        }
        let count = rectangles.len();
        chart.draw_series(rectangles)?;
        Ok(count)
    }

    /// Horizontal runs of equally coloured neighbouring cells in one row.
    fn row_runs(&self, colour_at: impl Fn(usize) -> RGBColor) -> Vec<(f64, f64, RGBColor)> {
        let mut runs: Vec<(f64, f64, RGBColor)> = Vec::new();
        for &col in &self.x_order {
            let Some((x0, x1)) = self.x_edges[col] else {
                continue;
            };
            let colour = colour_at(col);
            match runs.last_mut() {
                Some(run) if run.2 == colour => run.1 = x1,
                _ => runs.push((x0, x1, colour)),
            }
        }
        runs
    }
}

/// Axis-space extent of each cell along one axis (`None` where the centre cannot be drawn),
/// and the drawable indices sorted by position.
fn cell_edges(centres: &[f64], scale: Scale) -> (Vec<Option<Edges>>, Vec<usize>) {
    let positions: Vec<Option<f64>> = centres.iter().map(|&c| scale.to_axis(c)).collect();
    let mut order: Vec<(usize, f64)> = positions
        .iter()
        .enumerate()
        .filter_map(|(i, p)| Some((i, (*p)?)))
        .collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    let sorted: Vec<f64> = order.iter().map(|&(_, p)| p).collect();
    let mut edges = vec![None; centres.len()];
    for (k, &(i, _)) in order.iter().enumerate() {
        edges[i] = Some(edges_at(&sorted, k, scale));
    }
    (edges, order.into_iter().map(|(i, _)| i).collect())
}

/// Edges of the cell at `k` in the sorted centres: half way to each neighbour.
fn edges_at(sorted: &[f64], k: usize, scale: Scale) -> Edges {
    let c = sorted[k];
    if sorted.len() == 1 {
        let half = match scale {
            Scale::Log => 0.5,
            Scale::Linear if c == 0.0 => 0.5,
            Scale::Linear => 0.1 * c.abs(),
        };
        return (c - half, c + half);
    }
    let below = if k > 0 {
        0.5 * (sorted[k - 1] + c)
    } else {
        c - 0.5 * (sorted[1] - c)
    };
    let above = if k + 1 < sorted.len() {
        0.5 * (c + sorted[k + 1])
    } else {
        c + 0.5 * (c - sorted[k - 1])
    };
    (below, above)
}

/// The axis spanning all cell edges, or fitted to `overlay` when there are no cells.
fn grid_axis(edges: &[Option<Edges>], scale: Scale, overlay: impl Iterator<Item = f64>) -> Axis {
    let bounds: Vec<f64> = edges.iter().flatten().flat_map(|&(a, b)| [a, b]).collect();
    if bounds.is_empty() {
        Axis::fit(scale, overlay, 0.05)
    } else {
        Axis::fit(scale, bounds, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_edges_lie_half_way_between_centres() {
        let (edges, order) = cell_edges(&[2.0, 0.0, 1.0, f64::NAN], Scale::Linear);
        assert_eq!(order, vec![1, 2, 0]);
        assert_eq!(
            edges,
            vec![Some((1.5, 2.5)), Some((-0.5, 0.5)), Some((0.5, 1.5)), None]
        );
        let (log_edges, _) = cell_edges(&[1.0, 10.0, 0.0], Scale::Log);
        assert_eq!(log_edges, vec![Some((-0.5, 0.5)), Some((0.5, 1.5)), None]);
    }

    #[test]
    fn single_cells_get_a_width() {
        let (edges, _) = cell_edges(&[4.0], Scale::Linear);
        assert_eq!(edges, vec![Some((3.6, 4.4))]);
    }

    #[test]
    fn equal_neighbours_merge_into_one_run() {
        let heatmap = Heatmap::new(
            "t",
            "x",
            "y",
            vec![0.0, 1.0, 2.0, 3.0],
            vec![0.0],
            vec![0.0; 4],
            ColourScale::Sequential,
        );
        let grid = CellGrid::new(&heatmap, (Scale::Linear, Scale::Linear));
        let black = RGBColor(0, 0, 0);
        let white = RGBColor(255, 255, 255);
        let runs = grid.row_runs(|col| if col == 3 { white } else { black });
        assert_eq!(runs, vec![(-0.5, 2.5, black), (2.5, 3.5, white)]);
    }

    #[test]
    fn diverging_colouring_is_symmetric_about_zero() {
        let heatmap = Heatmap::new(
            "t",
            "x",
            "y",
            vec![1.0, 2.0],
            vec![1.0],
            vec![-1.0, 3.0],
            ColourScale::Diverging,
        );
        let colouring = Colouring::of(&heatmap);
        assert_eq!(colouring.colour(0.0), palette::diverging(0.5));
        assert_eq!(colouring.colour(3.0), palette::diverging(1.0));
        assert_eq!(colouring.colour(f64::NAN), MISSING);
    }
}
