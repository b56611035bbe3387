//! The grey-box output-error fit of a stage to one or more records.
//!
//! * Every record is simulated from the scenario's start state through its
//!   own samples; a reading is compared as a displacement from its first
//!   sample (an encoder's zero is arbitrary).
//! * Parameters are fitted as logarithms, within a factor 100 of the start.
//! * A growing horizon: the first quarter second of every record is fitted
//!   to convergence, then a horizon twice as long from there, and so on to
//!   the whole records. A far start cannot then follow the first breakaway
//!   into a local minimum, which a fit capped at a few iterations per
//!   window does.
//! * Before the fit, [`Identifiability`] from the sensitivities at the
//!   start names what the records cannot determine; those parameters stay
//!   at the scenario's values. Parameters of elements that share
//!   everything but their values start from the same point, where the
//!   records cannot tell them apart: the start is spread to break the tie,
//!   and the report says which were tied.
//! * After the fit, the linearised delete-one-block jackknife (quarter
//!   second blocks of every record) gives the covariance and intervals, and
//!   its identifiability verdict; a parameter it finds undetermined is fixed
//!   at the scenario's value and the rest refitted.

use nalgebra::{DMatrix, DVector};

use super::identifiability::Identifiability;
use super::plant::{Anchors, Loop, StagePlant};
use crate::csv_input::sensor_header;
use crate::error::{IdentError, Result};
use crate::jackknife::{self, rho, weight};
use crate::record::Record;
use crate::record::start::derivatives;
use crate::stribeck::Loss;
use crate::uncertainty::{Estimate, mad_scale, t95};

/// Options of a stage fit.
#[derive(Debug, Clone, PartialEq)]
pub struct StageOptions {
    /// Relative tolerance of the simulations.
    pub rtol: f64,
    /// Loss (L2 or Huber).
    pub loss: Loss,
    /// Most iterations per horizon.
    pub max_iterations: usize,
    /// How often the simulated stage is translated onto the main sensor's
    /// reading, s (velocities, deflections and bristles run free), as the
    /// one-mass fit does: an unmeasured force then cannot bend the fit by
    /// the drift it causes. `None`: pure output error over growing
    /// horizons (see [`StageOptions::first_horizon`]). A stage with no
    /// free translation along its sensor is always fitted by pure output
    /// error.
    pub anchor_every: Option<f64>,
    /// The first horizon of a pure output-error fit, s.
    pub first_horizon: f64,
}

impl Default for StageOptions {
    fn default() -> Self {
        Self {
            // As the one-mass fit and the command line: at 1e-7 the
            // integration's own noise misled a fit of a disturbed record.
            rtol: 1e-8,
            loss: Loss::L2,
            max_iterations: 60,
            anchor_every: Some(10e-3),
            first_horizon: 0.25,
        }
    }
}

/// Where a stage fit stands, for a progress display.
#[derive(Debug, Clone, PartialEq)]
pub struct StageProgress {
    /// What it is doing.
    pub stage: String,
    /// The fraction of the records' samples the current horizon holds.
    pub horizon_fraction: f64,
    /// Iterations so far.
    pub iterations: usize,
    /// RMS reading residual, m.
    pub rms: f64,
}

/// Elements whose parameters started equal and were spread apart.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Tie {
    /// The tied paths.
    pub paths: Vec<String>,
    /// The factors their starts were multiplied by.
    pub factors: Vec<f64>,
}

/// One record's residuals.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RecordResiduals {
    /// The record's file.
    pub source: String,
    /// Samples.
    pub samples: usize,
    /// Per sensor: (name, column, RMS residual m, largest residual m).
    pub sensors: Vec<SensorResiduals>,
}

/// One sensor's residuals in one record.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SensorResiduals {
    /// The stage's sensor.
    pub sensor: String,
    /// The record's column.
    pub column: String,
    /// RMS residual, m.
    pub rms: f64,
    /// Largest absolute residual, m.
    pub max_abs: f64,
    /// Noise level of the reading the first analysis assumed, m.
    pub noise: f64,
}

/// A fitted stage.
#[derive(Debug, Clone, PartialEq)]
pub struct StageFit {
    /// The parameter paths, in fit order.
    pub paths: Vec<String>,
    /// Units.
    pub units: Vec<&'static str>,
    /// The scenario's values.
    pub nominal: Vec<f64>,
    /// The values the iterations started from (ties spread).
    pub start: Vec<f64>,
    /// The fitted values (the scenario's where fixed).
    pub values: Vec<f64>,
    /// Whether each was fitted (false: undetermined, left at the scenario's value).
    pub fitted: Vec<bool>,
    /// Each parameter's estimate and interval (exact where not fitted).
    pub estimates: Vec<Estimate>,
    /// `Cov(ln theta)` of the fitted parameters (in `paths` order of those
    /// fitted), when the information could be inverted.
    pub log_covariance: Option<DMatrix<f64>>,
    /// The jackknife's replicates, `ln theta_(b) - ln theta` of the fitted.
    pub log_replicates: Vec<DVector<f64>>,
    /// Degrees of freedom of the intervals (blocks - 1).
    pub degrees_of_freedom: usize,
    /// Before the fit, from the sensitivities at the start.
    pub before: Identifiability,
    /// After the fit, from the jackknife (over the parameters fitted then).
    pub after: Option<Identifiability>,
    /// Ties broken at the start.
    pub ties: Vec<Tie>,
    /// Per record, its residuals.
    pub records: Vec<RecordResiduals>,
    /// Per record, per sensor, the simulated reading at every sample, m
    /// (displacement from the first sample plus the first measured reading).
    pub simulated: Vec<Vec<Vec<f64>>>,
    /// Iterations in all.
    pub iterations: usize,
    /// Whether the last horizon's iterations stopped on their own.
    pub converged: bool,
    /// Right-hand-side evaluations in all.
    pub rhs_evaluations: u64,
    /// The horizons fitted, s.
    pub horizons: Vec<f64>,
    /// Which continuation gave the fit.
    pub continuation: Continuation,
    /// How the records were driven.
    pub drive: Loop,
}

/// The way a stage fit reached its values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Continuation {
    /// The stage translated onto the main sensor every 2 ms (with its
    /// velocity), then at the anchor interval.
    Anchored,
    /// Pure output error over growing horizons (then the anchored last
    /// phase, where the fit is anchored).
    GrowingHorizons,
}

impl StageFit {
    /// The parameters the records could not determine (before or after the fit).
    pub fn undetermined(&self) -> Vec<String> {
        (self.paths.iter().zip(&self.fitted))
            .filter(|(_, fitted)| !**fitted)
            .map(|(p, _)| p.clone())
            .collect()
    }

    /// `Cov(theta)` of the fitted parameters, SI units (first order).
    pub fn covariance(&self) -> Option<DMatrix<f64>> {
        let c = self.log_covariance.as_ref()?;
        let values: Vec<f64> = (self.values.iter().zip(&self.fitted))
            .filter(|(_, f)| **f)
            .map(|(v, _)| *v)
            .collect();
        Some(DMatrix::from_fn(values.len(), values.len(), |i, j| {
            values[i] * c[(i, j)] * values[j]
        }))
    }
}

/// A record matched to the stage's sensors.
struct Matched<'a> {
    record: &'a Record,
    /// Per reading: the model's signal, the sensor, the column, the values.
    readings: Vec<(usize, String, String, &'a [f64])>,
    /// Noise level per reading, m.
    noise: Vec<f64>,
    /// The first reading's rate from the data, m/s (NaN where unknown).
    velocity: Vec<f64>,
    /// The signal of the first reading's simulated rate.
    rate_signal: usize,
}

/// Which sensor each position column of `record` reads: the position
/// column the stage's main sensor (or the sensor its name gives), each
/// further `<sensor>_<unit>` column that sensor.
fn match_record<'a>(
    plant: &StagePlant,
    model: &fistage_model::Model,
    record: &'a Record,
) -> Result<Matched<'a>> {
    let sensors = plant.sensors();
    let named = sensor_header(&record.columns[2])
        .map(|(s, _)| s)
        .filter(|s| sensors.contains(s));
    let main = named.unwrap_or_else(|| plant.main_sensor().to_string());
    let mut list = vec![(main, record.columns[2].clone(), record.position.as_slice())];
    for column in &record.sensors {
        if !sensors.contains(&column.sensor) {
            return Err(IdentError::InsufficientData {
                file: record.source.clone(),
                column: column.column.clone(),
                message: format!(
                    "the stage of {} has no sensor '{}' (its sensors: {}); a further position \
                     column is named after a sensor of the robot file, e.g. '{}_nm'",
                    plant.source(),
                    column.sensor,
                    sensors.join(", "),
                    sensors.first().map_or("encoder", String::as_str)
                ),
            });
        }
        if list.iter().any(|(s, _, _)| *s == column.sensor) {
            return Err(IdentError::InsufficientData {
                file: record.source.clone(),
                column: column.column.clone(),
                message: format!(
                    "sensor '{}' is read by the position column '{}' too; rename one",
                    column.sensor, record.columns[2]
                ),
            });
        }
        list.push((
            column.sensor.clone(),
            column.column.clone(),
            column.values.as_slice(),
        ));
    }
    let mut readings = Vec::new();
    for (sensor, column, values) in list {
        let signal = model
            .signal_index(&format!("{sensor}.position"))
            .ok_or_else(|| {
                IdentError::InvalidOption(format!("the model has no {sensor}.position"))
            })?;
        readings.push((signal, sensor, column, values));
    }
    let noise = readings.iter().map(|r| noise_level(r.3)).collect();
    let main = &readings[0].1;
    let rate_signal = model
        .signal_index(&format!("{main}.velocity"))
        .ok_or_else(|| IdentError::InvalidOption(format!("the model has no {main}.velocity")))?;
    let main_record = Record {
        position: readings[0].3.to_vec(),
        ..record.clone()
    };
    Ok(Matched {
        record,
        readings,
        noise,
        velocity: derivatives(&main_record).velocity,
        rate_signal,
    })
}

/// The noise level of a reading: the larger of its quantisation (the
/// smallest step, over sqrt(12)) and the robust scale of its fourth
/// differences (white noise there has 70 times its variance; smooth motion
/// at the sample rate has nearly none).
fn noise_level(values: &[f64]) -> f64 {
    let smallest_step = values
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    let quantum = if smallest_step.is_finite() {
        smallest_step / 12f64.sqrt()
    } else {
        0.0
    };
    let fourth: Vec<f64> = values
        .windows(5)
        .map(|w| w[0] - 4.0 * w[1] + 6.0 * w[2] - 4.0 * w[3] + w[4])
        .collect();
    let white = mad_scale(&fourth) / 70f64.sqrt();
    let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    quantum.max(white).max(1e-15 * scale).max(1e-15)
}

/// The stacked residuals of all records over a horizon.
struct Misfit {
    residual: Vec<f64>,
    /// Rows of `p` (the sensitive parameters), one per residual.
    jacobian: Vec<f64>,
    /// Per record, per reading, the simulated reading at every sample.
    simulated: Vec<Vec<Vec<f64>>>,
    /// Per record, where its rows start.
    offsets: Vec<usize>,
    cost: f64,
    rhs_evaluations: u64,
}

/// What every simulation of one fit shares.
struct Problem<'a> {
    plant: &'a StagePlant,
    records: Vec<Matched<'a>>,
    options: &'a StageOptions,
}

impl Problem<'_> {
    /// Residuals (and, for `sensitive`, their Jacobian) at `values` over
    /// the first `horizon` seconds of each record, each reading divided by
    /// `scale` (its noise level) when given.
    fn misfit(
        &self,
        values: &[f64],
        sensitive: &[usize],
        phase: Phase,
        scaled: bool,
        threshold: f64,
    ) -> Result<Misfit> {
        let Phase {
            horizon,
            anchor_every,
        } = phase;
        let models = self.plant.models(values, sensitive)?;
        let p = sensitive.len();
        let mut out = Misfit {
            residual: Vec::new(),
            jacobian: Vec::new(),
            simulated: Vec::new(),
            offsets: Vec::new(),
            cost: 0.0,
            rhs_evaluations: 0,
        };
        for matched in &self.records {
            let record = matched.record;
            let samples = samples_within(record, horizon);
            let signals: Vec<usize> = matched.readings.iter().map(|r| r.0).collect();
            let direction = anchor_every.and_then(|_| self.plant.translation(&models, signals[0]));
            let anchor_samples = match (anchor_every, &direction) {
                (Some(every), Some(_)) => periodic(record, every),
                _ => Vec::new(),
            };
            // The shortest anchoring sets the velocity too (nearly an
            // equation error, as the one-mass fit's first phase).
            let rate_signal = matched.rate_signal;
            let velocity = (anchor_every.is_some_and(|every| every <= 2e-3))
                .then_some((matched.velocity.as_slice(), rate_signal));
            let anchors = direction.as_ref().map(|d| Anchors {
                samples: &anchor_samples,
                measured: matched.readings[0].3,
                direction: d,
                velocity,
            });
            let sim = self.plant.simulate(
                &models,
                record,
                &signals,
                samples,
                self.options.rtol,
                anchors,
            )?;
            out.rhs_evaluations += sim.rhs_evaluations;
            out.offsets.push(out.residual.len());
            for k in 0..samples {
                for (o, reading) in matched.readings.iter().enumerate() {
                    let scale = if scaled { matched.noise[o] } else { 1.0 };
                    let measured = reading.3[k] - reading.3[0];
                    let simulated = sim.readings[o][k] - sim.readings[o][0];
                    out.residual.push((simulated - measured) / scale);
                    for j in 0..p {
                        let d = sim.jacobian[o][k * p + j] - sim.jacobian[o][j];
                        out.jacobian.push(d / scale);
                    }
                }
            }
            out.simulated.push(
                (matched.readings.iter().enumerate())
                    .map(|(o, reading)| {
                        let first = sim.readings[o][0];
                        (sim.readings[o].iter())
                            .map(|v| v - first + reading.3[0])
                            .collect()
                    })
                    .collect(),
            );
        }
        out.cost = (out.residual.iter())
            .map(|&r| rho(self.options.loss, r, threshold))
            .sum();
        Ok(out)
    }
}

/// What one continuation phase fits: the first `horizon` seconds of every
/// record, re-anchored every `anchor_every` seconds if given.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Phase {
    horizon: f64,
    anchor_every: Option<f64>,
}

/// A sample every `interval` seconds (from the second on).
fn periodic(record: &Record, interval: f64) -> Vec<usize> {
    let every = ((interval / record.sample_interval()).round() as usize).max(1);
    (every..record.len()).step_by(every).collect()
}

/// The samples of `record` within `horizon` seconds of its first.
fn samples_within(record: &Record, horizon: f64) -> usize {
    let end = record.time[0] + horizon;
    record
        .time
        .partition_point(|&t| t <= end * (1.0 + 1e-12))
        .max(2)
}

/// Fits `plant` to `records`; `progress` is told of every iteration and
/// stops the fit (with [`IdentError::Cancelled`]) by returning false.
pub fn fit_stage(
    plant: &StagePlant,
    records: &[Record],
    options: &StageOptions,
    progress: &mut dyn FnMut(&StageProgress) -> bool,
) -> Result<StageFit> {
    check_options(options)?;
    if records.is_empty() {
        return Err(IdentError::InvalidOption("no record to fit".into()));
    }
    let nominal = plant.nominal().to_vec();
    let probe = plant.model_at(&nominal)?;
    let mut matched = Vec::new();
    for record in records {
        record.check()?;
        matched.push(match_record(plant, &probe, record)?);
    }
    let problem = Problem {
        plant,
        records: matched,
        options,
    };
    let paths: Vec<String> = plant
        .parameters()
        .iter()
        .map(|p| p.path().to_string())
        .collect();
    let p = paths.len();
    let all: Vec<usize> = (0..p).collect();
    let whole = records.iter().map(Record::duration).fold(0.0, f64::max);
    let mut report = |stage: &str, fraction: f64, iterations: usize, rms: f64| {
        progress(&StageProgress {
            stage: stage.to_string(),
            horizon_fraction: fraction,
            iterations,
            rms,
        })
    };
    if !report("sensitivities at the start", 0.0, 0, f64::NAN) {
        return Err(IdentError::Cancelled);
    }
    // The phases: near equation error (anchored every 2 ms), then the
    // fit's own output error; or growing horizons of pure output error.
    let phases: Vec<Phase> = match options.anchor_every {
        Some(every) => vec![
            Phase {
                horizon: whole,
                anchor_every: Some(every.min(2e-3)),
            },
            Phase {
                horizon: whole,
                anchor_every: Some(every),
            },
        ],
        None => growing_horizons(options.first_horizon, whole)
            .into_iter()
            .map(|horizon| Phase {
                horizon,
                anchor_every: None,
            })
            .collect(),
    };
    let last_phase = *phases.last().unwrap_or(&Phase {
        horizon: whole,
        anchor_every: None,
    });
    // Ties: the same key of elements that start equal and move the
    // readings equally.
    let at_nominal = problem.misfit(&nominal, &all, last_phase, true, f64::INFINITY)?;
    let mut rhs_evaluations = at_nominal.rhs_evaluations;
    let ties = find_ties(&paths, &nominal, &at_nominal.jacobian);
    let mut start = nominal.clone();
    for tie in &ties {
        for (path, factor) in tie.paths.iter().zip(&tie.factors) {
            if let Some(j) = paths.iter().position(|q| q == path) {
                start[j] *= factor;
            }
        }
    }
    let first = if ties.is_empty() {
        at_nominal
    } else {
        let m = problem.misfit(&start, &all, last_phase, true, f64::INFINITY)?;
        rhs_evaluations += m.rhs_evaluations;
        m
    };
    let before = Identifiability::from_sensitivities(&paths, &first.jacobian);
    let mut fitted: Vec<bool> = before.parameters.iter().map(|v| v.determined).collect();
    let mut values = start.clone();
    for (j, f) in fitted.iter().enumerate() {
        if !f {
            values[j] = nominal[j];
        }
    }
    let mut iterations = 0;
    let mut converged = false;
    let fit_free = |values: &mut Vec<f64>,
                    fitted: &[bool],
                    phases: &[Phase],
                    iterations: &mut usize,
                    converged: &mut bool,
                    rhs: &mut u64,
                    report: &mut dyn FnMut(&str, f64, usize, f64) -> bool|
     -> Result<()> {
        let free: Vec<usize> = (0..p).filter(|&j| fitted[j]).collect();
        if free.is_empty() {
            return Ok(());
        }
        for (w, &phase) in phases.iter().enumerate() {
            let last = w + 1 == phases.len();
            let tolerance = if last { 1e-10 } else { 1e-4 };
            let stage = match phase.anchor_every {
                Some(every) => format!("fitting, anchored every {:.0} ms", every * 1e3),
                None => format!("fitting the first {:.2} s", phase.horizon),
            };
            let outcome = levenberg_marquardt(
                &problem,
                values,
                &free,
                &nominal,
                phase,
                options.max_iterations,
                tolerance,
                &mut |iteration, rms| {
                    let fraction = (w as f64 + 0.5) / phases.len() as f64;
                    report(&stage, fraction, *iterations + iteration, rms)
                },
            )?;
            *iterations += outcome.iterations;
            *rhs += outcome.rhs_evaluations;
            *converged = outcome.converged;
        }
        Ok(())
    };
    let initial = values.clone();
    let mut horizons: Vec<f64> = phases.iter().map(|ph| ph.horizon).collect();
    fit_free(
        &mut values,
        &fitted,
        &phases,
        &mut iterations,
        &mut converged,
        &mut rhs_evaluations,
        &mut report,
    )?;
    let mut continuation = match options.anchor_every {
        Some(_) => Continuation::Anchored,
        None => Continuation::GrowingHorizons,
    };
    // The anchored continuation can stop in a local minimum where several
    // elements' parameters of one key trade places (four bearings on one
    // axis: 350 nm RMS against a 1 nm encoder); where such parameters are
    // fitted and its residual stands well above the noise, the growing
    // horizons of pure output error start again from the same values,
    // polished by the last phase, and the better fit of the last phase's
    // criterion stays. (A record with an unmeasured force also stands above
    // the noise; a stage of one element of each kind never pays this.)
    if continuation == Continuation::Anchored && shares_a_key(&paths) {
        let (rms, evaluations) = scaled_rms(&problem, &values, last_phase)?;
        rhs_evaluations += evaluations;
        if rms > RETRY_ABOVE_NOISE {
            let mut other = initial;
            let mut other_phases: Vec<Phase> = growing_horizons(options.first_horizon, whole)
                .into_iter()
                .map(|horizon| Phase {
                    horizon,
                    anchor_every: None,
                })
                .collect();
            other_phases.push(last_phase);
            let (mut other_iterations, mut other_converged) = (0, false);
            let outcome = fit_free(
                &mut other,
                &fitted,
                &other_phases,
                &mut other_iterations,
                &mut other_converged,
                &mut rhs_evaluations,
                &mut |stage, fraction, iterations, rms| {
                    report(
                        &format!("{stage} (second start)"),
                        fraction,
                        iterations,
                        rms,
                    )
                },
            );
            iterations += other_iterations;
            match outcome {
                Err(IdentError::Cancelled) => return Err(IdentError::Cancelled),
                // A second start that fails to simulate leaves the first.
                Err(_) => {}
                Ok(()) => {
                    let (other_rms, evaluations) = scaled_rms(&problem, &other, last_phase)?;
                    rhs_evaluations += evaluations;
                    if other_rms < rms {
                        values = other;
                        converged = other_converged;
                        continuation = Continuation::GrowingHorizons;
                        horizons = other_phases.iter().map(|ph| ph.horizon).collect();
                    }
                }
            }
        }
    }
    // Intervals; a parameter the jackknife cannot determine is fixed and
    // the rest refitted in the last phase.
    let mut after = None;
    let mut intervals = None;
    for _ in 0..2 {
        let free: Vec<usize> = (0..p).filter(|&j| fitted[j]).collect();
        if free.is_empty() {
            break;
        }
        let (found, misfit) = jackknife_of(&problem, &values, &free, last_phase)?;
        rhs_evaluations += misfit.rhs_evaluations;
        let free_paths: Vec<String> = free.iter().map(|&j| paths[j].clone()).collect();
        let verdict = found
            .as_ref()
            .map(|j| Identifiability::from_covariance(&free_paths, &j.covariance));
        let newly: Vec<usize> = match &verdict {
            Some(v) => (free.iter().zip(&v.parameters))
                .filter(|(_, verdict)| !verdict.determined)
                .map(|(&j, _)| j)
                .collect(),
            None => Vec::new(),
        };
        after = verdict;
        intervals = found.map(|j| (j, free.clone()));
        if newly.is_empty() {
            break;
        }
        for j in newly {
            fitted[j] = false;
            values[j] = nominal[j];
        }
        fit_free(
            &mut values,
            &fitted,
            &[last_phase],
            &mut iterations,
            &mut converged,
            &mut rhs_evaluations,
            &mut report,
        )?;
        intervals = None;
    }
    // The residuals of the fit's own criterion (re-anchored as it was).
    let final_misfit = problem.misfit(&values, &[], last_phase, false, f64::INFINITY)?;
    rhs_evaluations += final_misfit.rhs_evaluations;
    let blocks = time_blocks(&problem, &final_misfit.offsets, whole);
    let dof = blocks.len().saturating_sub(1);
    let t = t95((dof as f64).max(1.0));
    let (log_covariance, log_replicates) = match &intervals {
        Some((j, _)) => (Some(j.covariance.clone()), j.replicates.clone()),
        None => (None, Vec::new()),
    };
    let estimates = (0..p)
        .map(|j| {
            if !fitted[j] {
                return Estimate::exact(values[j]);
            }
            let se = intervals.as_ref().and_then(|(jk, free)| {
                let i = free.iter().position(|&f| f == j)?;
                let v = jk.covariance[(i, i)];
                (v.is_finite() && v >= 0.0).then(|| values[j] * v.sqrt())
            });
            Estimate::new(values[j], se, t, 0.0)
        })
        .collect();
    let residuals = residual_statistics(&problem, &final_misfit);
    Ok(StageFit {
        units: plant.parameters().iter().map(|p| p.unit()).collect(),
        paths,
        nominal,
        start,
        values,
        fitted,
        estimates,
        log_covariance,
        log_replicates,
        degrees_of_freedom: dof,
        before,
        after,
        ties,
        records: residuals,
        simulated: final_misfit.simulated,
        iterations,
        converged,
        rhs_evaluations,
        horizons,
        continuation,
        drive: plant.drive(),
    })
}

/// Whether two fitted paths name the same key of different elements
/// (`overrides.friction_a.f_c` and `overrides.friction_b.f_c`).
fn shares_a_key(paths: &[String]) -> bool {
    let key = |path: &String| path.rsplit('.').next().map(str::to_string);
    let keys: Vec<Option<String>> = paths.iter().map(key).collect();
    (0..keys.len()).any(|i| keys[i + 1..].contains(&keys[i]))
}

/// The RMS of the noise-scaled residuals at `values` by `phase`'s
/// criterion, and the right-hand-side evaluations it took.
fn scaled_rms(problem: &Problem, values: &[f64], phase: Phase) -> Result<(f64, u64)> {
    let misfit = problem.misfit(values, &[], phase, true, f64::INFINITY)?;
    let r = &misfit.residual;
    let rms = (r.iter().map(|v| v * v).sum::<f64>() / r.len().max(1) as f64).sqrt();
    Ok((rms, misfit.rhs_evaluations))
}

fn check_options(options: &StageOptions) -> Result<()> {
    if options.loss == Loss::L1 {
        return Err(IdentError::InvalidOption(
            "a stage fit takes loss l2 or huber".into(),
        ));
    }
    if !(options.rtol >= 1e-12 && options.rtol < 1e-2) {
        return Err(IdentError::InvalidOption(format!(
            "rtol {} is outside [1e-12, 1e-2)",
            options.rtol
        )));
    }
    if !(options.first_horizon.is_finite() && options.first_horizon > 0.0) {
        return Err(IdentError::InvalidOption(format!(
            "the first horizon must be a positive number of s, got {}",
            fistage_model::rule::show(options.first_horizon)
        )));
    }
    if let Some(every) = options.anchor_every
        && !(every.is_finite() && every > 0.0)
    {
        return Err(IdentError::InvalidOption(format!(
            "the anchor interval must be a positive number of s, got {}",
            fistage_model::rule::show(every)
        )));
    }
    Ok(())
}

/// Quarter-second blocks of every record, as row ranges of the stacked residuals.
fn time_blocks(problem: &Problem, offsets: &[usize], horizon: f64) -> Vec<(usize, usize)> {
    let mut blocks = Vec::new();
    for (matched, &offset) in problem.records.iter().zip(offsets) {
        let record = matched.record;
        let readings = matched.readings.len();
        let samples = samples_within(record, horizon);
        let len = ((BLOCK_DURATION / record.sample_interval()) as usize).clamp(1, samples);
        for a in (0..samples).step_by(len) {
            let b = (a + len).min(samples);
            blocks.push((offset + a * readings, offset + b * readings));
        }
    }
    blocks
}

/// Horizons from `first` growing by [`HORIZON_GROWTH`] to `whole`.
fn growing_horizons(first: f64, whole: f64) -> Vec<f64> {
    let mut horizons = Vec::new();
    let mut h = first.min(whole);
    loop {
        horizons.push(h);
        if h >= whole {
            return horizons;
        }
        h = (HORIZON_GROWTH * h).min(whole);
        if h > whole / HORIZON_GROWTH.sqrt() {
            h = whole;
        }
    }
}

/// How much longer each horizon is than the last.
const HORIZON_GROWTH: f64 = 1.5;

/// The RMS of the noise-scaled residuals (noise levels) above which an
/// anchored fit is started again with growing horizons: a clean record's
/// fit stands near 1, a local minimum hundreds of times above; a record
/// with an unmeasured force stands above too and pays a second start.
const RETRY_ABOVE_NOISE: f64 = 3.0;

/// Length of a jackknife block, s.
const BLOCK_DURATION: f64 = 0.25;

/// The jackknife at `values` over the whole records.
fn jackknife_of(
    problem: &Problem,
    values: &[f64],
    free: &[usize],
    phase: Phase,
) -> Result<(Option<jackknife::Jackknife>, Misfit)> {
    let misfit = problem.misfit(values, free, phase, true, f64::INFINITY)?;
    let threshold = threshold_of(problem.options.loss, &misfit.residual);
    let r = &misfit.residual;
    let w = |k: usize| weight(problem.options.loss, r[k], threshold);
    let (h, _) = jackknife::normal_equations(&misfit.jacobian, r, &w, free.len());
    let blocks = time_blocks(problem, &misfit.offsets, phase.horizon);
    let found = jackknife::block_jackknife(&h, &misfit.jacobian, r, &w, &blocks)
        .filter(|j| j.covariance.iter().all(|v| v.is_finite()));
    Ok((found, misfit))
}

fn threshold_of(loss: Loss, residual: &[f64]) -> f64 {
    if loss == Loss::Huber {
        1.345 * mad_scale(residual).max(1e-300)
    } else {
        f64::INFINITY
    }
}

/// Per record and reading, the residual statistics.
fn residual_statistics(problem: &Problem, misfit: &Misfit) -> Vec<RecordResiduals> {
    (problem.records.iter().zip(&misfit.simulated))
        .map(|(matched, simulated)| RecordResiduals {
            source: matched.record.source.clone(),
            samples: matched.record.len(),
            sensors: (matched.readings.iter().enumerate())
                .map(|(o, reading)| {
                    let r: Vec<f64> = (simulated[o].iter().zip(reading.3))
                        .map(|(s, m)| s - m)
                        .collect();
                    SensorResiduals {
                        sensor: reading.1.clone(),
                        column: reading.2.clone(),
                        rms: (r.iter().map(|v| v * v).sum::<f64>() / r.len().max(1) as f64).sqrt(),
                        max_abs: r.iter().fold(0.0f64, |m, v| m.max(v.abs())),
                        noise: matched.noise[o],
                    }
                })
                .collect(),
        })
        .collect()
}

/// Groups of paths with the same key on different elements that start
/// equal and move the readings equally (columns of the scaled Jacobian
/// within 1e-6 of each other), and the factors that spread their starts
/// over +-20%.
fn find_ties(paths: &[String], start: &[f64], jacobian: &[f64]) -> Vec<Tie> {
    let p = paths.len();
    let column = |j: usize| -> Vec<f64> { jacobian.iter().skip(j).step_by(p).copied().collect() };
    let key = |path: &str| path.rsplit_once('.').map(|(_, k)| k.to_string());
    let mut taken = vec![false; p];
    let mut ties = Vec::new();
    for i in 0..p {
        if taken[i] {
            continue;
        }
        let (Some(ki), ci) = (key(&paths[i]), column(i)) else {
            continue;
        };
        let norm = ci.iter().map(|v| v * v).sum::<f64>().sqrt();
        let mut group = vec![i];
        for j in i + 1..p {
            if taken[j] || key(&paths[j]).as_ref() != Some(&ki) || start[j] != start[i] {
                continue;
            }
            let cj = column(j);
            let gap = (ci.iter().zip(&cj))
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt();
            if norm > 0.0 && gap <= 1e-6 * norm {
                group.push(j);
            }
        }
        if group.len() > 1 {
            let m = group.len();
            for &j in &group {
                taken[j] = true;
            }
            ties.push(Tie {
                paths: group.iter().map(|&j| paths[j].clone()).collect(),
                factors: (0..m)
                    .map(|k| 1.0 + 0.2 * (2.0 * k as f64 / (m - 1) as f64 - 1.0))
                    .collect(),
            });
        }
    }
    ties
}

/// The result of one horizon's iterations.
struct Outcome {
    iterations: usize,
    rhs_evaluations: u64,
    converged: bool,
}

/// How far from the start a parameter may go.
const BOX: f64 = 100.0;

/// Levenberg-Marquardt in the logarithms of the `free` parameters over one
/// horizon; `values` holds the start and receives the answer.
#[allow(clippy::too_many_arguments)]
fn levenberg_marquardt(
    problem: &Problem,
    values: &mut Vec<f64>,
    free: &[usize],
    centre: &[f64],
    phase: Phase,
    max_iterations: usize,
    converged_at: f64,
    progress: &mut dyn FnMut(usize, f64) -> bool,
) -> Result<Outcome> {
    let p = free.len();
    let loss = problem.options.loss;
    let mut threshold = f64::INFINITY;
    let mut current = problem.misfit(values, free, phase, true, threshold)?;
    let mut rhs_evaluations = current.rhs_evaluations;
    let mut lambda = 1e-3;
    let mut iterations = 0;
    let mut finished = false;
    let mut stalled = 0;
    while iterations < max_iterations {
        iterations += 1;
        if loss == Loss::Huber {
            threshold = threshold_of(loss, &current.residual);
            current.cost = (current.residual.iter())
                .map(|&r| rho(loss, r, threshold))
                .sum();
        }
        let r = &current.residual;
        let w = |k: usize| weight(loss, r[k], threshold);
        let (h, g) = jackknife::normal_equations(&current.jacobian, r, &w, p);
        let rms = (r.iter().map(|v| v * v).sum::<f64>() / r.len().max(1) as f64).sqrt();
        if !progress(iterations, rms) {
            return Err(IdentError::Cancelled);
        }
        let mut accepted = false;
        let mut small_step = false;
        while lambda < 1e12 {
            let mut damped = h.clone();
            for j in 0..p {
                damped[(j, j)] += lambda * h[(j, j)].max(1e-300);
            }
            let Some(step) = damped.cholesky().map(|c| c.solve(&(-&g))) else {
                lambda *= 10.0;
                continue;
            };
            // Each parameter moves by at most a factor e per step, on its
            // own: a parameter the horizon barely sees (f_c before the first
            // breakaway) asks for a huge step, and shortening the whole step
            // or damping it until that one fits would leave the others none.
            let step = step.map(|v| v.clamp(-1.0, 1.0));
            small_step = step.amax() < 1e-9;
            let mut trial = values.clone();
            for (i, &j) in free.iter().enumerate() {
                trial[j] = (trial[j] * step[i].exp()).clamp(centre[j] / BOX, centre[j] * BOX);
            }
            keep_static_above_coulomb(problem.plant, &mut trial);
            let attempt = problem.misfit(&trial, &[], phase, true, threshold);
            if let Ok(m) = &attempt {
                rhs_evaluations += m.rhs_evaluations;
            }
            match attempt {
                Ok(m) if m.cost.is_finite() && m.cost < current.cost => {
                    let relative = (current.cost - m.cost) / current.cost.max(1e-300);
                    *values = trial;
                    lambda = (lambda / 3.0).max(1e-12);
                    accepted = true;
                    current = problem.misfit(values, free, phase, true, threshold)?;
                    rhs_evaluations += current.rhs_evaluations;
                    // Converged: a step that gained almost nothing and was
                    // short, or three such steps in a row (one long step
                    // gaining little is the way out of a flat start).
                    if relative < converged_at {
                        stalled += 1;
                    } else {
                        stalled = 0;
                    }
                    small_step |= relative < converged_at && (step.amax() < 1e-2 || stalled >= 3);
                    break;
                }
                _ => {
                    lambda *= 4.0;
                    if small_step {
                        break;
                    }
                }
            }
        }
        if !accepted || small_step {
            finished = true;
            break;
        }
    }
    Ok(Outcome {
        iterations,
        rhs_evaluations,
        converged: finished,
    })
}

/// Raises a contact's f_s to its f_c where a step crossed them (both must
/// be paths of the fit for the step to move them apart).
fn keep_static_above_coulomb(plant: &StagePlant, values: &mut [f64]) {
    let paths: Vec<&str> = plant.parameters().iter().map(|p| p.path()).collect();
    for (j, path) in paths.iter().enumerate() {
        let Some(element) = path.strip_suffix(".f_s") else {
            continue;
        };
        let coulomb = format!("{element}.f_c");
        // A margin wider than the sensitivities' parameter steps, so no
        // model they assemble has f_s below f_c.
        if let Some(i) = paths.iter().position(|q| *q == coulomb) {
            values[j] = values[j].max(values[i] * (1.0 + 1e-3));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Only paths of one key on several elements call for a second start.
    #[test]
    fn a_key_shared_by_elements_is_found() {
        let paths = |list: &[&str]| list.iter().map(|p| p.to_string()).collect::<Vec<_>>();
        assert!(shares_a_key(&paths(&[
            "overrides.friction_a.f_c",
            "overrides.isolator.k_x",
            "overrides.friction_b.f_c",
        ])));
        // The FI stage: one element of each kind.
        assert!(!shares_a_key(&paths(&crate::stage::PAPER_FI_PATHS)));
    }
}
