//! The figures of fistage's results: what each command draws, assembled from
//! the libraries' result types with this crate's drawing primitives.
//!
//! One file per kind of result. Each `write` draws into a result folder (the
//! staging folder of a `ResultFolder`) and returns the names of the files it
//! wrote, SVG and PNG of each figure; a failure names the figure's file.
//!
//! | file | result | figures |
//! |---|---|---|
//! | [`run`] | a simulated run | `response`, `phase` |
//! | [`modes`] | a modal analysis | `mode_<equilibrium>_<rank>` |
//! | [`sweep`] | a parameter sweep | `map` (two axes) or `sweep` (one) |
//! | [`compare`] | compared cases | `<metric>`, `<metric>_reduction` |
//! | [`robust`] | a population | `max_real_eig_histogram`, `probability_by_parameter`, `sensitivity` |
//! | [`tune`] | a gain search | `region` |
//! | [`curve`] | a Stribeck-curve or FRF fit | `fit` |
//! | [`record`] | a record fit | `fit` |

use std::path::Path;

use fistage_model::Loaded;

use crate::PlotError;

pub mod compare;
pub mod curve;
pub mod modes;
pub mod record;
pub mod robust;
pub mod run;
pub mod sweep;
pub mod tune;

mod units;

/// Writes `<stem>.svg` and `<stem>.png` into `dir` with `draw`; returns their names.
fn svg_and_png(
    dir: &Path,
    stem: &str,
    draw: impl Fn(&Path) -> Result<(), PlotError>,
) -> Result<Vec<String>, PlotError> {
    let mut written = Vec::new();
    for extension in ["svg", "png"] {
        let name = format!("{stem}.{extension}");
        draw(&dir.join(&name))?;
        written.push(name);
    }
    Ok(written)
}

/// The scenario's title (or its file name), shortened to fit a figure's width.
pub fn title(loaded: &Loaded) -> String {
    const LONGEST: usize = 70;
    let title = if loaded.scenario.title.is_empty() {
        loaded.scenario.file.display().to_string()
    } else {
        loaded.scenario.title.clone()
    };
    if title.chars().count() <= LONGEST {
        return title;
    }
    let cut: String = title.chars().take(LONGEST - 3).collect();
    format!("{}...", cut.trim_end())
}

/// The file name of a data source, for titles.
fn short_name(source: &str) -> &str {
    Path::new(source)
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or(source)
}
