//! fistage-plot: publication-quality SVG and PNG figures of fistage results (time responses,
//! phase portraits, heatmaps, Bode plots), with no system libraries needed.
//!
//! Two layers: the drawing primitives at the crate root ([`Figure`], [`XyPlot`], [`Heatmap`],
//! [`write_bode`]), which know nothing of stages, and [`figures`], one file per kind of result
//! (a run, modes, a sweep, a comparison, a population, a gain search, the fits), which turns
//! the libraries' result types into those primitives. The program, the Python package and
//! anyone else draw a result the same way: `figures::run::write(&loaded, &output, dir)`.
//!
//! Every writer takes the output path; `.svg` or `.png` (any case) selects the format. Text
//! uses the embedded DejaVu Sans font. Non-finite values are skipped (lines break there),
//! panels without drawable data say "no data", and very long series are reduced per pixel
//! column (keeping each column's minimum and maximum) so files stay small.
//!
//! ```
//! use fistage_plot::{Figure, Panel, Series, write_figure};
//!
//! let t: Vec<f64> = (0..1000).map(|i| i as f64 * 1e-3).collect();
//! let x: Vec<f64> = t.iter().map(|t| (10.0 * t).sin()).collect();
//! let figure = Figure::new(
//!     "Step response",
//!     "time [s]",
//!     vec![Panel::new("table position [m]", vec![Series::line("table", t, x)])],
//! );
//! let file = std::env::temp_dir().join(format!("fistage-doc-step-{}.svg", std::process::id()));
//! write_figure(&figure, &file)?;
//! assert!(std::fs::read_to_string(&file).unwrap().contains("<svg"));
//! # std::fs::remove_file(&file).ok();
//! # Ok::<(), fistage_plot::PlotError>(())
//! ```

#![warn(missing_docs)]

mod axis;
mod bode;
mod cells;
mod chart;
mod colour_key;
mod coord;
mod coverage;
mod decimate;
mod error;
mod figure;
pub mod figures;
mod font;
mod geometry;
mod heatmap;
mod heatmap_writer;
mod layer;
mod legend;
mod output;
mod palette;
mod plot;
mod series;
mod xy;

pub use bode::{BodeSeries, write_bode};
pub use decimate::envelope;
pub use error::PlotError;
pub use figure::{Figure, Panel, write_figure};
pub use heatmap::{ColourScale, Heatmap};
pub use heatmap_writer::write_heatmap;
pub use series::{Series, SeriesStyle};
pub use xy::{XyPlot, write_xy};
