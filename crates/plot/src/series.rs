//! Data series: the points of one curve, how they are drawn, and the length check every
//! writer applies before drawing.

use std::path::Path;

use crate::axis::Scale;
use crate::error::PlotError;
use crate::geometry::Point;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SeriesStyle {
    /// A solid line through the points; non-finite values break it.
    #[default]
    Line,
    /// A filled circle at every point.
    Markers,
    /// A line with a circle at every point.
    LineAndMarkers,
}

impl SeriesStyle {
    /// Whether a line is drawn.
    pub(crate) fn has_line(self) -> bool {
        matches!(self, SeriesStyle::Line | SeriesStyle::LineAndMarkers)
    }

    /// Whether markers are drawn.
    pub(crate) fn has_markers(self) -> bool {
        matches!(self, SeriesStyle::Markers | SeriesStyle::LineAndMarkers)
    }
}

/// One curve: paired x and y values with a legend label. Its colour comes from the
/// qualitative palette by its position in the panel or plot.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// Legend text (legends appear when a panel or plot has more than one series).
    pub label: String,
    /// Horizontal coordinates.
    pub x: Vec<f64>,
    /// Vertical coordinates; must have as many values as `x`.
    pub y: Vec<f64>,
    /// How the series is drawn.
    pub style: SeriesStyle,
    /// A shaded band around the curve, (lower, upper) at each x (a +-1 sigma
    /// spread, say); both must have as many values as `x`.
    pub band: Option<(Vec<f64>, Vec<f64>)>,
}

impl Series {
    /// A series drawn in `style`.
    pub fn new(
        label: impl Into<String>,
        x: impl Into<Vec<f64>>,
        y: impl Into<Vec<f64>>,
        style: SeriesStyle,
    ) -> Self {
        Series {
            label: label.into(),
            x: x.into(),
            y: y.into(),
            style,
            band: None,
        }
    }

    /// The same series with a shaded band from `lower` to `upper`.
    pub fn with_band(self, lower: impl Into<Vec<f64>>, upper: impl Into<Vec<f64>>) -> Self {
        Self {
            band: Some((lower.into(), upper.into())),
            ..self
        }
    }

    /// A series drawn as a line.
    pub fn line(label: impl Into<String>, x: impl Into<Vec<f64>>, y: impl Into<Vec<f64>>) -> Self {
        Self::new(label, x, y, SeriesStyle::Line)
    }

    /// A series drawn as markers (measured data, for example).
    pub fn markers(
        label: impl Into<String>,
        x: impl Into<Vec<f64>>,
        y: impl Into<Vec<f64>>,
    ) -> Self {
        Self::new(label, x, y, SeriesStyle::Markers)
    }

    /// A series drawn as a line with markers.
    pub fn line_and_markers(
        label: impl Into<String>,
        x: impl Into<Vec<f64>>,
        y: impl Into<Vec<f64>>,
    ) -> Self {
        Self::new(label, x, y, SeriesStyle::LineAndMarkers)
    }

    /// Fails with [`PlotError::LengthMismatch`] when `x` and `y` differ in length.
    pub(crate) fn check_lengths(&self, path: &Path) -> Result<(), PlotError> {
        let band = self
            .band
            .iter()
            .flat_map(|(low, high)| [low.len(), high.len()]);
        match std::iter::once(self.y.len())
            .chain(band)
            .find(|&n| n != self.x.len())
        {
            None => Ok(()),
            Some(y_len) => Err(PlotError::LengthMismatch {
                path: path.to_path_buf(),
                label: self.label.clone(),
                x_len: self.x.len(),
                y_len,
            }),
        }
    }

    /// The band's outline in axis space (upper edge left to right, lower edge
    /// back), skipping x values where either edge cannot be drawn.
    pub(crate) fn band_outline(&self, x: Scale, y: Scale) -> Vec<Point> {
        let Some((low, high)) = &self.band else {
            return Vec::new();
        };
        let edge = |values: &[f64]| -> Vec<(usize, Point)> {
            (self.x.iter().zip(values).enumerate())
                .filter_map(|(i, (&px, &py))| Some((i, (x.to_axis(px)?, y.to_axis(py)?))))
                .collect()
        };
        let (upper, lower) = (edge(high), edge(low));
        let both =
            |i: &usize| upper.iter().any(|(j, _)| j == i) && lower.iter().any(|(j, _)| j == i);
        let mut outline: Vec<Point> = (upper.iter().filter(|(i, _)| both(i)))
            .map(|(_, p)| *p)
            .collect();
        outline.extend((lower.iter().rev().filter(|(i, _)| both(i))).map(|(_, p)| *p));
        outline
    }

    /// The points in axis space for the given scales; undrawable coordinates become NaN.
    pub(crate) fn axis_points(&self, x: Scale, y: Scale) -> Vec<Point> {
        self.x
            .iter()
            .zip(&self.y)
            .map(|(&px, &py)| {
                (
                    x.to_axis(px).unwrap_or(f64::NAN),
                    y.to_axis(py).unwrap_or(f64::NAN),
                )
            })
            .collect()
    }

    /// The drawable points in axis space (both coordinates valid).
    /// The band's edges count too, so that ranges fitted to these points hold it.
    pub(crate) fn valid_points(&self, x: Scale, y: Scale) -> impl Iterator<Item = Point> + '_ {
        let band = self
            .band
            .iter()
            .flat_map(|(low, high)| low.iter().chain(high));
        let band_x = self.band.iter().flat_map(|_| self.x.iter().chain(&self.x));
        self.x
            .iter()
            .zip(&self.y)
            .chain(band_x.zip(band))
            .filter_map(move |(&px, &py)| Some((x.to_axis(px)?, y.to_axis(py)?)))
    }
}

/// Checks the lengths of all `series`.
pub(crate) fn check_all<'s>(
    series: impl IntoIterator<Item = &'s Series>,
    path: &Path,
) -> Result<(), PlotError> {
    series.into_iter().try_for_each(|s| s.check_lengths(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn length_mismatch_names_the_series_and_path() {
        let series = Series::line("bearing position", vec![0.0, 1.0], vec![0.0]);
        let message = series
            .check_lengths(Path::new("out/fig.svg"))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(message.contains("bearing position"), "{message}");
        assert!(message.contains("out/fig.svg"), "{message}");
    }

    #[test]
    fn valid_points_skip_what_the_scales_cannot_draw() {
        let series = Series::line(
            "s",
            vec![1.0, 10.0, -1.0, f64::NAN],
            vec![1.0, 2.0, 3.0, 4.0],
        );
        let points: Vec<Point> = series.valid_points(Scale::Log, Scale::Linear).collect();
        assert_eq!(points, vec![(0.0, 1.0), (1.0, 2.0)]);
    }
}
