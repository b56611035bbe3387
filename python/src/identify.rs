//! `fistage.identify`: the LuGre fits of `fistage identify` on arrays. Each
//! returns the JSON report `fit.json` holds (parameters with `value`,
//! `ci95`, `std_error`, `unit`; residuals; what the data cannot determine),
//! which the Python side wraps for indexing by parameter name.

use fistage_analysis::lab::LabStage;
use fistage_analysis::record_lab::RecordLab;
use fistage_ident::record::{
    FitProgress, LabErrors, MassChoice, Record, RecordOptions, RecordReport, SensorColumn,
    ServoLoop, fit_record, read_record,
};
use fistage_ident::stage::{Loop, StageOptions, StagePlant, StageProgress, StageReport, fit_stage};
use fistage_ident::{
    Complex, FrfData, FrfOptions, FrfReport, Loss, MassOption, Sigma2Input, StribeckData,
    StribeckOptions, StribeckReport, UnitOverrides, fit_frf, fit_stribeck, fit_stribeck_asymmetric,
};
use pyo3::prelude::*;

use crate::{Error, IdentificationError};

fn json<T: serde::Serialize>(report: &T) -> PyResult<String> {
    serde_json::to_string(report).map_err(|e| Error::new_err(e.to_string()))
}

fn ident_error(e: fistage_ident::IdentError) -> PyErr {
    IdentificationError::new_err(e.to_string())
}

/// The Stribeck fit of f_ss(v) (m/s, N): the report as JSON text and its
/// page's section as JSON.
#[pyfunction]
#[pyo3(signature = (velocity, force, loss = "l2", asymmetric = false))]
pub fn _stribeck(
    py: Python<'_>,
    velocity: Vec<f64>,
    force: Vec<f64>,
    loss: &str,
    asymmetric: bool,
) -> PyResult<(String, String)> {
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
    let (fit, asymmetric) = py
        .detach(|| {
            if asymmetric {
                let fit = fit_stribeck_asymmetric(&data, &options)?;
                Ok((fit.symmetric.clone(), Some(fit)))
            } else {
                Ok((fit_stribeck(&data, &options)?, None))
            }
        })
        .map_err(ident_error)?;
    let report = StribeckReport::new("arrays", &fit, asymmetric.as_ref());
    let plot = fistage_plot::figures::curve::stribeck_plot(&data, &fit, asymmetric.as_ref());
    let section = fistage_report::sections::identify::curve_section(
        "identify stribeck",
        &report,
        vec![fistage_report::plot::from_xy(&plot)],
    );
    Ok((json(&report)?, crate::section_json(&section)?))
}

/// The pre-motion FRF fit: frequencies in Hz, the response as real and
/// imaginary parts (m/N) or magnitudes alone; the report as JSON text and
/// its page's section as JSON.
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
) -> PyResult<(String, String)> {
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
    let fit = py
        .detach(|| fit_frf(&data, &options))
        .map_err(ident_error)?;
    let report = FrfReport::new("arrays", &fit);
    let (title, freq_hz, series) = fistage_plot::figures::curve::frf_bode(&data, &fit);
    let section = fistage_report::sections::identify::curve_section(
        "identify frf",
        &report,
        fistage_report::plot::from_bode(&title, &freq_hz, &series),
    );
    Ok((json(&report)?, crate::section_json(&section)?))
}

/// The record fit (output error on the position): time (s), force (N) held
/// over each interval, position (m); the report as JSON text, its page's
/// section as JSON and the simulated position. `progress(iteration, rms)` is called after every
/// iteration (the interpreter held only then); Ctrl-C, or an exception in
/// the callback, stops the fit.
#[pyfunction]
#[pyo3(signature = (time, force, position, mass = None, loss = "l2", horizon = Some(0.01), progress = None, closed_loop = None))]
#[allow(clippy::too_many_arguments)]
pub fn _record(
    py: Python<'_>,
    time: Vec<f64>,
    force: Vec<f64>,
    position: Vec<f64>,
    mass: Option<f64>,
    loss: &str,
    horizon: Option<f64>,
    progress: Option<Py<PyAny>>,
    closed_loop: Option<std::path::PathBuf>,
) -> PyResult<(String, String, Vec<f64>)> {
    let loss = match loss {
        "l2" => Loss::L2,
        "huber" => Loss::Huber,
        other => {
            return Err(Error::new_err(format!(
                "loss must be \"l2\" or \"huber\", got \"{other}\""
            )));
        }
    };
    let record = Record::from_arrays("arrays", time, force, position).map_err(ident_error)?;
    let closed_loop = match closed_loop {
        Some(path) => Some(
            ServoLoop::from_scenario(&path)
                .map_err(|e| crate::LoadError_::new_err(e.to_string()))?,
        ),
        None => None,
    };
    let options = RecordOptions {
        mass: mass.map_or(MassChoice::Fit, MassChoice::Known),
        loss,
        horizon,
        closed_loop,
        ..RecordOptions::default()
    };
    let mut report = progress_reporter(progress.as_ref());
    let fit = py.detach(|| {
        fit_record(&record, &options, &mut |p: &FitProgress| {
            report.call((p.iteration > 0).then_some((p.iteration, p.rms)))
        })
    });
    let fit = report.result(fit)?;
    let fit_report = RecordReport::new(&record, &fit);
    let section = fistage_report::sections::identify::record_section(&record, &fit, &fit_report);
    Ok((
        json(&fit_report)?,
        crate::section_json(&section)?,
        fit.simulated,
    ))
}

/// Per record, per sensor, the simulated readings of a stage fit.
type StageReadings = Vec<Vec<Vec<f64>>>;

/// One record of a stage fit from Python: time, force, main position and
/// further sensors by name.
type StageRecordArrays = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<(String, Vec<f64>)>);

/// The stage fit (`identify record --stage --fit`): the parameter-table
/// `paths` of the scenario's stage fitted to `records` jointly; the report
/// as JSON text, its page's section as JSON and, per record and sensor, the
/// simulated reading.
#[pyfunction]
#[pyo3(signature = (scenario, paths, records, closed_loop = false, loss = "l2", progress = None))]
pub fn _stage(
    py: Python<'_>,
    scenario: &crate::Scenario,
    paths: Vec<String>,
    records: Vec<StageRecordArrays>,
    closed_loop: bool,
    loss: &str,
    progress: Option<Py<PyAny>>,
) -> PyResult<(String, String, StageReadings)> {
    let loss = match loss {
        "l2" => Loss::L2,
        "huber" => Loss::Huber,
        other => {
            return Err(Error::new_err(format!(
                "loss must be \"l2\" or \"huber\", got \"{other}\""
            )));
        }
    };
    let (study, robot) = scenario
        .study()
        .map_err(|e| crate::LoadError_::new_err(e.to_string()))?;
    let drive = if closed_loop {
        Loop::Closed
    } else {
        Loop::Open
    };
    let plant = StagePlant::new(&study, &robot, &paths, drive).map_err(ident_error)?;
    let mut list = Vec::new();
    for (i, (time, force, position, sensors)) in records.into_iter().enumerate() {
        let mut record = Record::from_arrays(format!("records[{i}]"), time, force, position)
            .map_err(ident_error)?;
        record.sensors = (sensors.into_iter())
            .map(|(sensor, values)| SensorColumn {
                column: sensor.clone(),
                sensor,
                values,
            })
            .collect();
        record.check().map_err(ident_error)?;
        list.push(record);
    }
    let options = StageOptions {
        loss,
        ..StageOptions::default()
    };
    let mut report = progress_reporter(progress.as_ref());
    let fit = py.detach(|| {
        fit_stage(&plant, &list, &options, &mut |p: &StageProgress| {
            report.call(p.rms.is_finite().then_some((p.iterations, p.rms)))
        })
    });
    let fit = report.result(fit)?;
    let fit_report = StageReport::new(&study.file.display().to_string(), &fit);
    let section = fistage_report::sections::identify::stage_section(&list, &fit, &fit_report);
    Ok((
        json(&fit_report)?,
        crate::section_json(&section)?,
        fit.simulated,
    ))
}

/// Reads a record file (CSV or MAT-file, columns by unit suffix): time (s),
/// force (N) and position (m).
#[pyfunction]
pub fn _read_record(path: std::path::PathBuf) -> PyResult<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    let record = read_record(&path, &UnitOverrides::default())
        .map_err(|e| crate::LoadError_::new_err(e.to_string()))?;
    Ok((record.time, record.force, record.position))
}

/// Time, force, position and the true parameters (JSON) of a simulated record.
type SimulatedRecord = (Vec<f64>, Vec<f64>, Vec<f64>, String);

/// A lab-style record (chirps, breakaway ramps, holds, steps, rests) of the
/// open-loop stage of a robot or scenario file, or with `closed_loop` a run
/// of the scenario's own servo (over `duration` s, the scenario's when
/// None): time (s), force (N), position (m), and the stage's true
/// parameters as JSON.
#[pyfunction]
#[pyo3(signature = (stage, seed = 1, quantum = 1e-9, noise = 0.0, disturbance = 0.0, rate = 10_000.0, closed_loop = false, duration = None))]
#[allow(clippy::too_many_arguments)]
pub fn _simulate_record(
    py: Python<'_>,
    stage: std::path::PathBuf,
    seed: u64,
    quantum: f64,
    noise: f64,
    disturbance: f64,
    rate: f64,
    closed_loop: bool,
    duration: Option<f64>,
) -> PyResult<SimulatedRecord> {
    for (name, value) in [
        ("quantum", quantum),
        ("noise", noise),
        ("disturbance", disturbance),
    ] {
        if !(value.is_finite() && value >= 0.0) {
            return Err(Error::new_err(format!("{name} must be >= 0, got {value}")));
        }
    }
    if !(rate.is_finite() && rate > 0.0 && rate <= 1e7) {
        return Err(Error::new_err(format!(
            "rate must be in (0, 1e7] Hz, got {rate}"
        )));
    }
    let lab_stage =
        LabStage::load(&stage).map_err(|e| crate::LoadError_::new_err(e.to_string()))?;
    let mut lab = RecordLab::new(seed);
    lab.dt = 1.0 / rate;
    lab.errors = LabErrors {
        quantum,
        position_noise: noise,
        disturbance_rms: disturbance,
        seed,
        ..LabErrors::exact()
    };
    if let Some(d) = duration
        && !(d.is_finite() && d > 0.0)
    {
        return Err(Error::new_err(format!(
            "duration must be a positive number of s, got {d}"
        )));
    }
    let record = py
        .detach(|| match closed_loop {
            true => lab.measure_closed_loop(&stage, duration),
            false => lab.measure(&lab_stage).map(|(record, _)| record),
        })
        .map_err(|e| crate::SimulationError::new_err(e.to_string()))?;
    let p = lab_stage.friction();
    let truth = serde_json::json!({
        "f_c": p.f_c, "f_s": p.f_s, "v_s": p.v_s, "sigma0": p.sigma0,
        "sigma1": p.sigma1, "sigma2": p.sigma2, "mass": lab_stage.moving_mass(),
    });
    Ok((
        record.time,
        record.force,
        record.position,
        truth.to_string(),
    ))
}

/// A fit's progress as Python sees it: Ctrl-C stops the fit, and the
/// optional `progress(iteration, rms)` callback hears each step; the first
/// Python error raised on the way ends the fit and is what it returns.
struct ProgressReporter<'a> {
    callback: Option<&'a Py<PyAny>>,
    raised: Option<PyErr>,
}

fn progress_reporter(callback: Option<&Py<PyAny>>) -> ProgressReporter<'_> {
    ProgressReporter {
        callback,
        raised: None,
    }
}

impl ProgressReporter<'_> {
    /// Reports `step` (iteration, rms) where there is one; whether the fit
    /// goes on.
    fn call(&mut self, step: Option<(usize, f64)>) -> bool {
        Python::attach(|py| {
            if let Err(e) = py.check_signals() {
                self.raised = Some(e);
                return false;
            }
            if let (Some(callback), Some(step)) = (self.callback, step)
                && let Err(e) = callback.call1(py, step)
            {
                self.raised = Some(e);
                return false;
            }
            true
        })
    }

    /// The fit, or the Python error that stopped it.
    fn result<T>(self, fit: Result<T, fistage_ident::IdentError>) -> PyResult<T> {
        match (fit, self.raised) {
            (_, Some(e)) => Err(e),
            (result, None) => result.map_err(ident_error),
        }
    }
}
