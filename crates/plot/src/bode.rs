//! Bode plots: magnitude (in dB) and phase (in degrees) of frequency responses over a
//! logarithmic frequency axis, as a two-panel [`Figure`].

use std::path::Path;

use crate::error::PlotError;
use crate::figure::{Figure, Panel, write_figure};
use crate::output::Format;
use crate::series::{Series, SeriesStyle};

/// One frequency response of a Bode plot, sampled at the plot's frequencies.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BodeSeries {
    /// Legend text.
    pub label: String,
    /// Linear magnitude |G| at each frequency (drawn as 20·log10|G| dB; values `<= 0` are
    /// skipped).
    pub magnitude: Vec<f64>,
    /// Phase in degrees at each frequency, if known.
    pub phase_deg: Option<Vec<f64>>,
    /// How the response is drawn (markers for measured data, a line for a model).
    pub style: SeriesStyle,
}

impl BodeSeries {
    /// A response drawn in `style`.
    pub fn new(
        label: impl Into<String>,
        magnitude: Vec<f64>,
        phase_deg: Option<Vec<f64>>,
        style: SeriesStyle,
    ) -> Self {
        BodeSeries {
            label: label.into(),
            magnitude,
            phase_deg,
            style,
        }
    }
}

impl<L: Into<String>> From<(L, Vec<f64>, Option<Vec<f64>>, SeriesStyle)> for BodeSeries {
    /// A response from `(label, magnitude, phase_deg, style)`.
    fn from(
        (label, magnitude, phase_deg, style): (L, Vec<f64>, Option<Vec<f64>>, SeriesStyle),
    ) -> Self {
        BodeSeries::new(label, magnitude, phase_deg, style)
    }
}

/// Writes a Bode plot of `series` over `freq_hz` to `path` (SVG or PNG by extension).
///
/// The magnitude panel shows dB; a phase panel is added when any series has a phase. Every
/// magnitude and phase vector must have one value per frequency.
pub fn write_bode(
    title: &str,
    freq_hz: &[f64],
    series: &[BodeSeries],
    path: &Path,
) -> Result<(), PlotError> {
    Format::from_path(path)?;
    check_lengths(freq_hz, series, path)?;
    let magnitude: Vec<Series> = series
        .iter()
        .map(|s| Series::new(s.label.clone(), freq_hz, decibels(&s.magnitude), s.style))
        .collect();
    let phase: Vec<Series> = series
        .iter()
        .filter_map(|s| {
            let phase = s.phase_deg.as_ref()?;
            Some(Series::new(
                s.label.clone(),
                freq_hz,
                phase.clone(),
                s.style,
            ))
        })
        .collect();
    let mut panels = vec![Panel::new("magnitude [dB]", magnitude)];
    if !phase.is_empty() {
        panels.push(Panel::new("phase [\u{b0}]", phase));
    }
    let figure = Figure {
        x_log: true,
        ..Figure::new(title, "frequency [Hz]", panels)
    };
    write_figure(&figure, path)
}

/// Fails with [`PlotError::LengthMismatch`] naming the series (and "phase" for phases).
fn check_lengths(freq_hz: &[f64], series: &[BodeSeries], path: &Path) -> Result<(), PlotError> {
    let mismatch = |label: String, y_len: usize| PlotError::LengthMismatch {
        path: path.to_path_buf(),
        label,
        x_len: freq_hz.len(),
        y_len,
    };
    for s in series {
        if s.magnitude.len() != freq_hz.len() {
            return Err(mismatch(
                format!("{} (magnitude)", s.label),
                s.magnitude.len(),
            ));
        }
        if let Some(phase) = &s.phase_deg
            && phase.len() != freq_hz.len()
        {
            return Err(mismatch(format!("{} (phase)", s.label), phase.len()));
        }
    }
    Ok(())
}

/// 20·log10(|m|) for positive `m`, NaN otherwise.
fn decibels(magnitude: &[f64]) -> Vec<f64> {
    magnitude
        .iter()
        .map(|&m| if m > 0.0 { 20.0 * m.log10() } else { f64::NAN })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magnitudes_convert_to_decibels() {
        let db = decibels(&[1.0, 10.0, 0.1, 0.0, -1.0]);
        assert_eq!(&db[..3], &[0.0, 20.0, -20.0]);
        assert!(db[3].is_nan() && db[4].is_nan());
    }

    #[test]
    fn tuples_convert_to_series() {
        let series: BodeSeries = ("fit", vec![1.0], None, SeriesStyle::Line).into();
        assert_eq!(
            series,
            BodeSeries::new("fit", vec![1.0], None, SeriesStyle::Line)
        );
    }

    #[test]
    fn phase_length_mismatch_names_the_series() {
        let series = [BodeSeries::new(
            "plant",
            vec![1.0; 3],
            Some(vec![0.0; 2]),
            SeriesStyle::Line,
        )];
        let error = check_lengths(&[1.0, 2.0, 3.0], &series, Path::new("bode.svg")).err();
        let message = error.map(|e| e.to_string()).unwrap_or_default();
        assert!(
            message.contains("plant (phase)") && message.contains("bode.svg"),
            "{message}"
        );
    }
}
