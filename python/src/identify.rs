//! `fistage.identify`: the LuGre fits of `fistage identify` on arrays. Each
//! returns the JSON report `fit.json` holds (parameters with `value`,
//! `ci95`, `std_error`, `unit`; residuals; what the data cannot determine),
//! which the Python side wraps for indexing by parameter name.

use fistage_ident::{
    Complex, FrfData, FrfOptions, FrfReport, Loss, MassOption, Sigma2Input, StribeckData,
    StribeckOptions, StribeckReport, fit_frf, fit_stribeck, fit_stribeck_asymmetric,
};
use pyo3::prelude::*;

use crate::{Error, IdentificationError};

fn json<T: serde::Serialize>(report: &T) -> PyResult<String> {
    serde_json::to_string(report).map_err(|e| Error::new_err(e.to_string()))
}

fn ident_error(e: fistage_ident::IdentError) -> PyErr {
    IdentificationError::new_err(e.to_string())
}

/// The Stribeck fit of f_ss(v) (m/s, N): the report as JSON text.
#[pyfunction]
#[pyo3(signature = (velocity, force, loss = "l2", asymmetric = false))]
pub fn _stribeck(
    py: Python<'_>,
    velocity: Vec<f64>,
    force: Vec<f64>,
    loss: &str,
    asymmetric: bool,
) -> PyResult<String> {
    let loss = match loss {
        "l2" => Loss::L2,
        "huber" => Loss::Huber,
        "l1" => Loss::L1,
        other => {
            return Err(Error::new_err(format!(
                "loss must be \"l2\", \"huber\" or \"l1\", got \"{other}\""
            )));
        }
    };
    if velocity.len() != force.len() {
        return Err(Error::new_err(format!(
            "velocity has {} values and force {}: give one force per velocity",
            velocity.len(),
            force.len()
        )));
    }
    let data = StribeckData::new("arrays", velocity, force);
    let options = StribeckOptions {
        loss,
        ..StribeckOptions::default()
    };
    let report = py.detach(|| {
        if asymmetric {
            let fit = fit_stribeck_asymmetric(&data, &options)?;
            Ok(StribeckReport::new("arrays", &fit.symmetric, Some(&fit)))
        } else {
            let fit = fit_stribeck(&data, &options)?;
            Ok(StribeckReport::new("arrays", &fit, None))
        }
    });
    json(&report.map_err(ident_error)?)
}

/// The pre-motion FRF fit: frequencies in Hz, the response as real and
/// imaginary parts (m/N) or magnitudes alone; the report as JSON text.
#[pyfunction]
#[pyo3(signature = (frequency_hz, real = None, imaginary = None, magnitude = None, mass = None, sigma2 = None))]
pub fn _frf(
    py: Python<'_>,
    frequency_hz: Vec<f64>,
    real: Option<Vec<f64>>,
    imaginary: Option<Vec<f64>>,
    magnitude: Option<Vec<f64>>,
    mass: Option<f64>,
    sigma2: Option<f64>,
) -> PyResult<String> {
    let omega: Vec<f64> = frequency_hz
        .iter()
        .map(|f| 2.0 * std::f64::consts::PI * f)
        .collect();
    let n = omega.len();
    let same = |name: &str, values: &[f64]| {
        if values.len() == n {
            Ok(())
        } else {
            Err(Error::new_err(format!(
                "{name} has {} values and freq {n}: give one per frequency",
                values.len()
            )))
        }
    };
    let data = match (real, imaginary, magnitude) {
        (Some(re), Some(im), None) => {
            same("response", &re)?;
            same("response", &im)?;
            let response = re
                .iter()
                .zip(&im)
                .map(|(a, b)| Complex::new(*a, *b))
                .collect();
            FrfData::new_complex("arrays", omega, response)
        }
        (None, None, Some(magnitude)) => {
            same("magnitude", &magnitude)?;
            FrfData::new_magnitude("arrays", omega, &magnitude)
        }
        _ => {
            return Err(Error::new_err(
                "give response (complex) or magnitude (with phase, or alone)",
            ));
        }
    };
    let options = FrfOptions {
        mass: mass.map_or(MassOption::Fit, MassOption::Known),
        sigma2: sigma2.map(|value| Sigma2Input { value, ci95: None }),
        ..FrfOptions::default()
    };
    let report = py
        .detach(|| fit_frf(&data, &options).map(|fit| FrfReport::new("arrays", &fit)))
        .map_err(ident_error)?;
    json(&report)
}
