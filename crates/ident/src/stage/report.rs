//! A stage fit as `fit.json` carries it: every parameter with its path,
//! value, interval and verdict; what the records could not determine; the
//! joint covariance and replicates (the keys `[robust] from_fit` reads);
//! the residuals of every record; `override.toml`, the fitted values as
//! scenario overrides; and `data_vs_fit.csv`, every reading against the
//! fitted stage's.

use serde::Serialize;

use super::fit::{Continuation, RecordResiduals, StageFit, Tie};
use super::identifiability::{Identifiability, short};
use super::plant::Loop;
use crate::covariance::FitCovariance;
use crate::record::Record;

/// A residual this many times the record's noise is worth a warning.
const FAR_ABOVE_NOISE: f64 = 30.0;

/// One parameter of a stage fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StageParameter {
    /// Its path in the parameter table.
    pub path: String,
    /// Short name, e.g. `f_c(friction_fl)`.
    pub name: String,
    /// SI unit.
    pub unit: String,
    /// The scenario's value.
    pub nominal: f64,
    /// Where the iterations started.
    pub start: f64,
    /// The fitted value (the scenario's when not fitted).
    pub value: f64,
    /// Standard error (jackknife).
    pub std_error: Option<f64>,
    /// 95% interval.
    pub ci95: Option<[f64; 2]>,
    /// Whether it was fitted; false: the records cannot determine it and
    /// it stays at the scenario's value.
    pub fitted: bool,
}

/// The report of a stage fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StageReport {
    /// Always `stage`.
    pub kind: String,
    /// The scenario whose stage was fitted.
    pub scenario: String,
    /// `open` or `closed` loop.
    pub drive: String,
    /// Every parameter.
    pub parameters: Vec<StageParameter>,
    /// Paths the records cannot determine (left at the scenario's values).
    pub undetermined: Vec<String>,
    /// Combinations determined although none of their parameters is alone.
    pub determined_only_together: Vec<String>,
    /// Before the fit (sensitivities at the start).
    pub identifiability_before: Identifiability,
    /// After the fit (jackknife covariance of the parameters fitted).
    pub identifiability_after: Option<Identifiability>,
    /// Parameters that started tied and were spread apart.
    pub ties: Vec<Tie>,
    /// What the ties mean, when there are any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tie_note: Option<String>,
    /// The joint covariance of the fitted parameters.
    pub covariance: Option<FitCovariance>,
    /// The jackknife's replicates of the fitted parameters, SI units.
    pub replicates: Vec<Vec<f64>>,
    /// Per record, its residuals.
    pub records: Vec<RecordResiduals>,
    /// Horizons fitted, s.
    pub horizons: Vec<f64>,
    /// Which continuation gave the values: `anchored`, or
    /// `growing_horizons` (pure output error, then the anchored last phase,
    /// where the anchored one stopped well above the noise).
    pub continuation: Continuation,
    /// Iterations.
    pub iterations: usize,
    /// Whether the last iterations stopped on their own.
    pub converged: bool,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
}

impl StageReport {
    /// The report of `fit` of the stage of `scenario`.
    pub fn new(scenario: &str, fit: &StageFit) -> Self {
        let parameters = (0..fit.paths.len())
            .map(|j| StageParameter {
                path: fit.paths[j].clone(),
                name: short(&fit.paths[j]),
                unit: fit.units[j].to_string(),
                nominal: fit.nominal[j],
                start: fit.start[j],
                value: fit.values[j],
                std_error: fit.estimates[j].std_error,
                ci95: fit.estimates[j].ci95,
                fitted: fit.fitted[j],
            })
            .collect();
        let fitted: Vec<usize> = (0..fit.paths.len()).filter(|&j| fit.fitted[j]).collect();
        let covariance = fit
            .covariance()
            .zip(fit.log_covariance.as_ref())
            .map(|(si, log)| {
                let rows = |m: &nalgebra::DMatrix<f64>| -> Vec<Vec<f64>> {
                    (0..m.nrows())
                        .map(|i| m.row(i).iter().copied().collect())
                        .collect()
                };
                FitCovariance {
                    parameters: fitted.iter().map(|&j| short(&fit.paths[j])).collect(),
                    paths: fitted.iter().map(|&j| Some(fit.paths[j].clone())).collect(),
                    values: fitted.iter().map(|&j| fit.values[j]).collect(),
                    matrix: rows(&si),
                    log_matrix: rows(log),
                    method: "linearised delete-one-block jackknife, 0.25 s blocks of every record"
                        .into(),
                    degrees_of_freedom: fit.degrees_of_freedom,
                }
            });
        let replicates = (fit.log_replicates.iter())
            .map(|d| {
                (fitted.iter().enumerate())
                    .map(|(i, &j)| fit.values[j] * d[i].exp())
                    .collect()
            })
            .collect();
        let together = fit
            .after
            .as_ref()
            .map(Identifiability::determined_only_together)
            .unwrap_or_else(|| fit.before.determined_only_together());
        Self {
            kind: "stage".into(),
            scenario: scenario.to_string(),
            drive: match fit.drive {
                Loop::Open => "open",
                Loop::Closed => "closed",
            }
            .into(),
            parameters,
            undetermined: fit.undetermined(),
            determined_only_together: together,
            identifiability_before: fit.before.clone(),
            identifiability_after: fit.after.clone(),
            tie_note: (!fit.ties.is_empty()).then(|| {
                "elements that share everything but these values are interchangeable: \
                 swapping two leaves the readings unchanged, so the records determine their \
                 values as a set, not which element has which; the start was spread to break \
                 the tie"
                    .to_string()
            }),
            ties: fit.ties.clone(),
            covariance,
            replicates,
            records: fit.records.clone(),
            horizons: fit.horizons.clone(),
            continuation: fit.continuation,
            iterations: fit.iterations,
            converged: fit.converged,
            rhs_evaluations: fit.rhs_evaluations,
        }
    }

    /// A table for the terminal.
    pub fn table(&self) -> String {
        let mut out = format!(
            "stage fit of {} ({} loop), {} iterations{}{}\n",
            self.scenario,
            self.drive,
            self.iterations,
            match self.continuation {
                Continuation::Anchored => "",
                Continuation::GrowingHorizons => ", from growing horizons",
            },
            if self.converged {
                ""
            } else {
                " (stopped at the iteration limit: not a minimum)"
            }
        );
        out += &format!(
            "{:<34} {:>13} {:>13} {:>27} {:>8}\n",
            "parameter", "scenario", "fitted", "95% interval", "unit"
        );
        for p in &self.parameters {
            let interval = match (p.fitted, p.ci95) {
                (false, _) => "undetermined: not fitted".to_string(),
                (true, Some([lo, hi])) => format!("[{lo:.5e}, {hi:.5e}]"),
                (true, None) => "-".to_string(),
            };
            out += &format!(
                "{:<34} {:>13.6e} {:>13.6e} {:>27} {:>8}\n",
                p.path, p.nominal, p.value, interval, p.unit
            );
        }
        for record in &self.records {
            for s in &record.sensors {
                out += &format!(
                    "{} ({}, sensor {}): rms residual {:.3e} m, largest {:.3e} m, noise {:.2e} m\n",
                    record.source, s.column, s.sensor, s.rms, s.max_abs, s.noise
                );
                if s.rms > FAR_ABOVE_NOISE * s.noise {
                    out += &format!(
                        "warning: that residual is {:.0} times the noise the record shows: an \
                         unmeasured force, a model that does not match the stage, or a local \
                         minimum (try another start); the intervals hold only if the model fits\n",
                        s.rms / s.noise
                    );
                }
            }
        }
        if !self.undetermined.is_empty() {
            out += &format!(
                "undetermined (left at the scenario's values): {}\n",
                self.undetermined.join(", ")
            );
        }
        for text in &self.determined_only_together {
            out += &format!("determined only together: {text}\n");
        }
        if let Some(note) = &self.tie_note {
            for tie in &self.ties {
                out += &format!("tied at the start: {}\n", tie.paths.join(", "));
            }
            out += &format!("note: {note}\n");
        }
        out
    }

    /// The fitted values as `[overrides.<element>]` tables (paths of other
    /// kinds as comments).
    pub fn override_toml(&self) -> String {
        let mut out = String::from("# Fitted by fistage identify record --stage\n");
        let mut by_element: Vec<(String, Vec<(String, f64)>)> = Vec::new();
        for p in self.parameters.iter().filter(|p| p.fitted) {
            match p
                .path
                .strip_prefix("overrides.")
                .and_then(|r| r.rsplit_once('.'))
            {
                Some((element, key)) => match by_element.iter_mut().find(|(e, _)| e == element) {
                    Some((_, keys)) => keys.push((key.to_string(), p.value)),
                    None => {
                        by_element.push((element.to_string(), vec![(key.to_string(), p.value)]))
                    }
                },
                None => out += &format!("# {} = {:e}\n", p.path, p.value),
            }
        }
        for (element, keys) in by_element {
            out += &format!("\n[overrides.{element}]\n");
            for (key, value) in keys {
                out += &format!("{key} = {value:e}\n");
            }
        }
        out
    }
}

/// `data_vs_fit.csv` of a stage fit: one row per record, sample and
/// reading (`record` is the record's file), with the measured and the
/// fitted stage's reading and their difference, m.
pub fn stage_fit_csv(records: &[Record], fit: &StageFit) -> String {
    let mut writer = csv::Writer::from_writer(Vec::new());
    // Writing into memory cannot fail.
    let _ = writer.write_record([
        "record",
        "t_s",
        "force_N",
        "sensor",
        "measured_m",
        "simulated_m",
        "residual_m",
    ]);
    for ((record, residuals), simulated) in records.iter().zip(&fit.records).zip(&fit.simulated) {
        for (sensor, readings) in residuals.sensors.iter().zip(simulated) {
            let measured = (record.sensors.iter())
                .find(|s| s.column == sensor.column)
                .map_or(record.position.as_slice(), |s| s.values.as_slice());
            for (k, (x, s)) in measured.iter().zip(readings).enumerate() {
                let _ = writer.write_record([
                    residuals.source.as_str(),
                    &record.time[k].to_string(),
                    &record.force[k].to_string(),
                    &sensor.sensor,
                    &x.to_string(),
                    &s.to_string(),
                    &(s - x).to_string(),
                ]);
            }
        }
    }
    String::from_utf8(writer.into_inner().unwrap_or_default()).unwrap_or_default()
}
