//! The figures of the curve fits: a Stribeck curve's data against its fit
//! (outliers marked, each branch of an asymmetric fit drawn), and the Bode
//! plot of a pre-motion FRF against its fit.

use std::path::Path;

use fistage_ident::{AsymmetricFit, FrfData, FrfFit, StribeckData, StribeckFit};

use super::{short_name, svg_and_png};
use crate::{BodeSeries, PlotError, Series, SeriesStyle, XyPlot, write_bode, write_xy};

/// Draws `fit` (the Stribeck curve, data and fit) into `dir`; returns the file names.
pub fn write_stribeck(
    data: &StribeckData,
    fit: &StribeckFit,
    asymmetric: Option<&AsymmetricFit>,
    dir: &Path,
) -> Result<Vec<String>, PlotError> {
    let plot = stribeck_plot(data, fit, asymmetric);
    svg_and_png(dir, "fit", |path| write_xy(&plot, path))
}

/// Draws `fit` (the FRF's Bode plot, data and fit) into `dir`; returns the file names.
pub fn write_frf(data: &FrfData, fit: &FrfFit, dir: &Path) -> Result<Vec<String>, PlotError> {
    let (title, freq_hz, series) = frf_bode(data, fit);
    svg_and_png(dir, "fit", |path| {
        write_bode(&title, &freq_hz, &series, path)
    })
}

/// Points of the fitted curve per sign present, per branch.
const CURVE_POINTS: usize = 300;

/// f_ss against v, in mm/s and N: the measured points (those the fit flags as
/// outliers in a series of their own), the fitted curve and, for an asymmetric
/// fit, the curve of each branch fitted alone.
pub fn stribeck_plot(
    data: &StribeckData,
    fit: &StribeckFit,
    asymmetric: Option<&AsymmetricFit>,
) -> XyPlot {
    let mm = |v: f64| v * 1e3;
    let flagged = &fit.residuals.suspected_outliers;
    let (mut kept, mut outliers) = ((Vec::new(), Vec::new()), (Vec::new(), Vec::new()));
    for ((&v, &f), line) in data.velocity.iter().zip(&data.force).zip(&data.lines) {
        let target = if flagged.contains(line) {
            &mut outliers
        } else {
            &mut kept
        };
        target.0.push(mm(v));
        target.1.push(f);
    }
    let mut series = vec![Series::markers("measured", kept.0, kept.1)];
    if !outliers.0.is_empty() {
        series.push(Series::markers(
            format!("suspected outliers ({} fit)", fit.loss.name()),
            outliers.0,
            outliers.1,
        ));
    }
    let (v, f) = stribeck_curve(&data.velocity, |v| fit.predict(v), None);
    let v: Vec<f64> = v.into_iter().map(mm).collect();
    series.push(Series::line(format!("fit ({})", fit.loss.name()), v, f));
    if let Some(a) = asymmetric {
        for (branch, sign, label) in [
            (&a.positive, 1.0, "fit of v > 0 alone"),
            (&a.negative, -1.0, "fit of v < 0 alone"),
        ] {
            let (v, f) = stribeck_curve(&data.velocity, |v| branch.predict(v), Some(sign));
            let v: Vec<f64> = v.into_iter().map(mm).collect();
            series.push(Series::line(label, v, f));
        }
    }
    XyPlot::new(
        format!(
            "Steady-state friction of {}: data and fit",
            short_name(&data.source)
        ),
        "sliding velocity v [mm/s]",
        "steady-state friction force f_ss [N]",
        series,
    )
}

/// The curve `predict` over the data's range of |v| on each velocity sign
/// present (or only on `only_sign`), log-spaced, the branches separated by a
/// NaN (the plot bridges a gap narrower than a pixel, so on a wide velocity
/// axis the line shows the jump of f_ss at v = 0).
fn stribeck_curve(
    velocity: &[f64],
    predict: impl Fn(f64) -> f64,
    only_sign: Option<f64>,
) -> (Vec<f64>, Vec<f64>) {
    let abs = velocity.iter().map(|v| v.abs());
    let lo = abs.clone().fold(f64::INFINITY, f64::min);
    let hi = abs.fold(0.0, f64::max);
    let (mut vs, mut fs) = (Vec::new(), Vec::new());
    for sign in [-1.0, 1.0] {
        if only_sign.is_some_and(|s| s != sign) || !velocity.iter().any(|v| v * sign > 0.0) {
            continue;
        }
        if !vs.is_empty() {
            vs.push(f64::NAN);
            fs.push(f64::NAN);
        }
        let mut speeds: Vec<f64> = (0..CURVE_POINTS)
            .map(|i| lo * (hi / lo).powf(i as f64 / (CURVE_POINTS - 1) as f64))
            .collect();
        if sign < 0.0 {
            speeds.reverse();
        }
        for speed in speeds {
            vs.push(sign * speed);
            fs.push(predict(sign * speed));
        }
    }
    (vs, fs)
}

/// The Bode plot of an FRF fit: title, frequencies (the data's and a dense
/// logarithmic grid, merged) and the two responses, each NaN where it has no
/// value. Measured phases are moved by whole turns next to the model's.
pub fn frf_bode(data: &FrfData, fit: &FrfFit) -> (String, Vec<f64>, Vec<BodeSeries>) {
    let to_hz = |w: f64| w / (2.0 * std::f64::consts::PI);
    let lo = data.omega.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = data.omega.iter().copied().fold(0.0, f64::max);
    // (omega, index of the data point or None for a curve point)
    let mut points: Vec<(f64, Option<usize>)> = data
        .omega
        .iter()
        .enumerate()
        .map(|(i, &w)| (w, Some(i)))
        .collect();
    let n = 2 * CURVE_POINTS;
    points.extend((0..n).map(|i| (lo * (hi / lo).powf(i as f64 / (n - 1) as f64), None)));
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut freq_hz = Vec::with_capacity(points.len());
    let (mut data_mag, mut data_phase) = (Vec::new(), Vec::new());
    let (mut fit_mag, mut fit_phase) = (Vec::new(), Vec::new());
    for &(w, index) in &points {
        let model = fit.response(w);
        freq_hz.push(to_hz(w));
        fit_mag.push(model.norm());
        fit_phase.push(model.arg().to_degrees());
        match index {
            Some(i) => {
                let g = data.response[i];
                data_mag.push(g.norm());
                data_phase.push((model.arg() + (g / model).arg()).to_degrees());
            }
            None => {
                data_mag.push(f64::NAN);
                data_phase.push(f64::NAN);
            }
        }
    }
    let phase = data.has_phase;
    let series = vec![
        BodeSeries::new(
            "measured",
            data_mag,
            phase.then_some(data_phase),
            SeriesStyle::Markers,
        ),
        BodeSeries::new(
            format!(
                "fit: sigma0 = {:.4e} N/m, sigma1 + sigma2 = {:.4} N s/m",
                fit.sigma0.value, fit.damping.value
            ),
            fit_mag,
            phase.then_some(fit_phase),
            SeriesStyle::Line,
        ),
    ];
    let title = format!(
        "Pre-motion FRF x/F of {}: data and fit",
        short_name(&data.source)
    );
    (title, freq_hz, series)
}
