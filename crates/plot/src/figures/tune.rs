//! The figure of a gain search: the worst largest real part over the
//! population on the (k, c) grid, the chosen gains marked.

use std::path::Path;

use fistage_analysis::robust::tune::Tuning;

use super::svg_and_png;
use crate::{ColourScale, Heatmap, PlotError, Series, write_heatmap};

/// Draws `region` into `dir`: cells where a stage was undetermined are left
/// empty. Returns the file names.
pub fn write(tuning: &Tuning, dir: &Path) -> Result<Vec<String>, PlotError> {
    let values = tuning
        .grid
        .iter()
        .map(|s| {
            if s.undetermined > 0 {
                f64::NAN
            } else {
                s.worst_max_real_eig
            }
        })
        .collect();
    let mut map = Heatmap::new(
        format!("worst largest real part over {} stages", tuning.members),
        "k [N/m]",
        "c [N s/m]",
        tuning.k.clone(),
        tuning.c.clone(),
        values,
        ColourScale::Diverging,
    );
    map.x_log = true;
    map.y_log = true;
    map.value_label = "max Re(lambda) over the population [1/s]".into();
    if let Some([k, c]) = tuning.gains {
        map.overlay
            .push(Series::markers("chosen gains", vec![k], vec![c]));
    }
    svg_and_png(dir, "region", |path| write_heatmap(&map, path))
}
