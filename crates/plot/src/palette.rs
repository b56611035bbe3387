//! Colours: the qualitative series palette, the sequential and diverging colour maps of
//! heatmaps, and the grey used for missing values.

use plotters::style::RGBColor;
use plotters::style::colors::colormaps::{ColorMap, DerivedColorMap};

/// Colour-blind-safe qualitative palette (Okabe and Ito), strongest colours first and the
/// pale yellow last.
const QUALITATIVE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(230, 159, 0),   // orange
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(0, 0, 0),       // black
    RGBColor(240, 228, 66),  // yellow
];

/// Anchors of the sequential map (perceptually uniform, dark purple to yellow).
const SEQUENTIAL: [RGBColor; 9] = [
    RGBColor(68, 1, 84),
    RGBColor(71, 44, 122),
    RGBColor(59, 82, 139),
    RGBColor(44, 114, 142),
    RGBColor(33, 145, 140),
    RGBColor(40, 174, 128),
    RGBColor(94, 201, 98),
    RGBColor(173, 220, 48),
    RGBColor(253, 231, 37),
];

/// Anchors of the diverging map (blue, near-white at the centre, red).
const DIVERGING: [RGBColor; 7] = [
    RGBColor(33, 102, 172),
    RGBColor(103, 169, 207),
    RGBColor(209, 229, 240),
    RGBColor(247, 247, 247),
    RGBColor(253, 219, 199),
    RGBColor(239, 138, 98),
    RGBColor(178, 24, 43),
];

/// Fill of heatmap cells whose value was not computed (NaN).
pub(crate) const MISSING: RGBColor = RGBColor(175, 175, 175);

/// Light grey of major grid lines.
pub(crate) const GRID_MAJOR: RGBColor = RGBColor(222, 222, 222);
/// Lighter grey of minor grid lines.
pub(crate) const GRID_MINOR: RGBColor = RGBColor(240, 240, 240);
/// Axis and frame colour.
pub(crate) const AXIS: RGBColor = RGBColor(40, 40, 40);

/// The colour of the series at `index`, cycling through the palette.
pub(crate) fn series_colour(index: usize) -> RGBColor {
    QUALITATIVE[index % QUALITATIVE.len()]
}

/// The colour of category `index` in a categorical heatmap: the palette, lightened so that
/// overlaid curves stay visible.
pub(crate) fn category_colour(index: usize) -> RGBColor {
    blend(series_colour(index), RGBColor(255, 255, 255), 0.35)
}

/// The sequential map at `t` in `[0, 1]` (clamped).
pub(crate) fn sequential(t: f64) -> RGBColor {
    interpolate(&SEQUENTIAL, t)
}

/// The diverging map at `t` in `[0, 1]` (clamped); `0.5` is the neutral centre.
pub(crate) fn diverging(t: f64) -> RGBColor {
    interpolate(&DIVERGING, t)
}

/// plotters' colour map through equally spaced anchors at `t` (clamped; a
/// non-finite `t` gives the centre, which plotters would not accept).
fn interpolate(anchors: &[RGBColor], t: f64) -> RGBColor {
    let t = if t.is_finite() { t } else { 0.5 };
    DerivedColorMap::new(anchors).get_color_normalized(t, 0.0, 1.0)
}

/// `a` moved towards `b` by `fraction` in `[0, 1]`.
pub(crate) fn blend(a: RGBColor, b: RGBColor, fraction: f64) -> RGBColor {
    let mix = |x: u8, y: u8| {
        let value = f64::from(x) + (f64::from(y) - f64::from(x)) * fraction;
        value.round().clamp(0.0, 255.0) as u8
    };
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_maps_hit_their_end_anchors() {
        assert_eq!(sequential(0.0), SEQUENTIAL[0]);
        assert_eq!(sequential(1.0), SEQUENTIAL[8]);
        assert_eq!(sequential(7.0), SEQUENTIAL[8]);
        assert_eq!(diverging(0.5), DIVERGING[3]);
        assert_eq!(diverging(f64::NAN), DIVERGING[3]);
    }

    #[test]
    fn series_colours_cycle() {
        assert_eq!(series_colour(0), series_colour(QUALITATIVE.len()));
        assert_ne!(series_colour(0), series_colour(1));
    }
}
