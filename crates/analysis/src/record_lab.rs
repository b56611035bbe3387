//! Lab-style records from any stage model: the identification program of
//! [`fistage_ident::record::program`] applied open loop to the stage's
//! actuator (the force held over each sample interval), the sensor sampled
//! at every sample time before the next force acts, and the lab's errors
//! (encoder quantisation, position noise, an unmeasured force disturbance)
//! added. The stage is the full assembled model (isolators and all), so a
//! record made here is an independent check of the record fit's one-mass
//! plant.
//!
//! [`RecordLab::measure_closed_loop`] records a scenario run instead: the
//! scenario's own servo drives the stage along its reference (the way
//! `fistage run` integrates it, in continuous time), the unmeasured
//! disturbance entering as an external force the servo does not log.

use fistage_ident::record::program::lab_program;
use fistage_ident::record::{LabErrors, Record, Segment, SensorColumn, StartState};
use fistage_ident::{IdentError, Result};
use std::path::Path;

use fistage_model::ScenarioExcitation;
use fistage_model::initial_state;
use fistage_model::{Inputs, load};
use fistage_sim::Excitation;

use crate::lab::{LabStage, Tolerance, simulate};

/// A recorded run to make.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordLab {
    /// Sample interval, s.
    pub dt: f64,
    /// The lab's errors.
    pub errors: LabErrors,
    /// Integration tolerance of the stage.
    pub tolerance: Tolerance,
    /// Sensors read besides the main one (a bearing encoder), each a
    /// column `<sensor>_m` of the record.
    pub further_sensors: Vec<String>,
}

impl RecordLab {
    /// 10 kHz, a 1 nm encoder, seeded.
    pub fn new(seed: u64) -> Self {
        Self {
            dt: 1e-4,
            errors: LabErrors {
                seed,
                ..LabErrors::encoder()
            },
            tolerance: Tolerance {
                rtol: 1e-10,
                atol_scale: 1.0,
            },
            further_sensors: Vec::new(),
        }
    }

    /// Runs the program on `stage`: the record and its segments.
    pub fn measure(&self, stage: &LabStage) -> Result<(Record, Vec<Segment>)> {
        if !(self.dt > 0.0 && self.dt.is_finite()) {
            return Err(IdentError::InvalidOption(format!(
                "the sample interval must be positive, got {}",
                fistage_model::rule::show(self.dt)
            )));
        }
        check_samples(PROGRAM_DURATION, self.dt)?;
        // The program's levels from the stage's whole friction (the
        // contacts move together under the drive).
        let (f_c, f_s) =
            (stage.contacts().iter()).fold((0.0, 0.0), |(c, s), (_, p)| (c + p.f_c, s + p.f_s));
        let (time, force, segments) = lab_program(f_c, f_s, self.dt);
        let n = time.len();
        if n < fistage_ident::record::data::MIN_SAMPLES {
            return Err(IdentError::InvalidOption(format!(
                "a sample interval of {} s leaves the 7 s program {n} samples; a record needs at \
                 least {}",
                self.dt,
                fistage_ident::record::data::MIN_SAMPLES
            )));
        }
        let disturbance = self.errors.disturbance(n, self.dt);
        let excitation = HeldForce {
            time: time.clone(),
            force: force.iter().zip(&disturbance).map(|(f, d)| f + d).collect(),
        };
        let model = stage.model(None)?;
        let [_, sensor] = stage.force_and_position(&model)?;
        let further: Vec<(String, usize)> = (self.further_sensors.iter())
            .map(|name| {
                model
                    .signal_index(&format!("{name}.position"))
                    .map(|i| (name.clone(), i))
                    .ok_or_else(|| {
                        let names: Vec<&str> =
                            model.sensors().iter().map(|s| s.name.as_str()).collect();
                        IdentError::InvalidOption(format!(
                            "{}: the stage has no sensor '{name}' (its sensors: {})",
                            stage.source(),
                            names.join(", ")
                        ))
                    })
            })
            .collect::<Result<_>>()?;
        let x0 = stage.start_state(&model)?;
        let t_end = time[n - 1];
        let trajectory = simulate(&model, &x0, &excitation, t_end, self.dt, self.tolerance)
            .map_err(|e| stage.simulation_error("the identification run", e))?;
        let signals = trajectory.signals(&model, &excitation);
        let mut position: Vec<f64> = signals.columns[sensor].iter().take(n).copied().collect();
        if position.len() != n {
            return Err(stage.simulation_error(
                "the identification run",
                format!("{} samples for {n} times", position.len()),
            ));
        }
        self.errors.measure(&mut position);
        let mut record = csv_record(stage.source().to_string(), time, force, position);
        for (k, (name, index)) in further.into_iter().enumerate() {
            let mut values: Vec<f64> = signals.columns[index].iter().take(n).copied().collect();
            // Each encoder has its own noise.
            LabErrors {
                seed: self.errors.seed.wrapping_add(1 + k as u64),
                ..self.errors
            }
            .measure(&mut values);
            record.sensors.push(SensorColumn {
                column: format!("{name}_m"),
                sensor: name,
                values,
            });
        }
        Ok((record, segments))
    }
}

impl RecordLab {
    /// Records the run of the scenario at `path` with its own servo over
    /// `duration` seconds (the scenario's when `None`): the servo's force
    /// command and the encoder it reads, with the lab's errors on the
    /// encoder and the disturbance acting unlogged.
    pub fn measure_closed_loop(&self, path: &Path, duration: Option<f64>) -> Result<Record> {
        let loaded = load(path)?;
        let source = path.display().to_string();
        let failed = |message: String| IdentError::Simulation {
            file: source.clone(),
            message,
        };
        let model = &loaded.model;
        let Some(controller) = model.controller() else {
            return Err(failed(
                "a closed-loop record needs the scenario's servo, and it has no [controller]"
                    .into(),
            ));
        };
        let t_end = duration.unwrap_or(loaded.scenario.duration);
        check_samples(t_end, self.dt)?;
        let n = (t_end / self.dt + 1e-9).floor() as usize + 1;
        if !(self.dt > 0.0 && self.dt.is_finite()) || n < fistage_ident::record::data::MIN_SAMPLES {
            return Err(IdentError::InvalidOption(format!(
                "a sample interval of {} s over {t_end} s gives {n} samples; a record needs at \
                 least {}",
                self.dt,
                fistage_ident::record::data::MIN_SAMPLES
            )));
        }
        let time: Vec<f64> = (0..n).map(|k| k as f64 * self.dt).collect();
        let disturbance = self.errors.disturbance(n, self.dt);
        let excitation = DisturbedServo {
            scenario: ScenarioExcitation::from_scenario(&loaded.scenario),
            disturbance: HeldForce {
                time: time.clone(),
                force: disturbance.clone(),
            },
        };
        let signal = |name: String| {
            model
                .signal_index(&name)
                .ok_or_else(|| failed(format!("the model has no signal '{name}'")))
        };
        let sensor = signal(format!(
            "{}.position",
            model.sensors()[controller.sensor].name
        ))?;
        let drive = signal(format!(
            "{}.force",
            model.actuators()[controller.actuator].name
        ))?;
        let x0 = initial_state(model, &loaded.scenario)?;
        let trajectory = simulate(
            model,
            &x0,
            &excitation,
            time[n - 1],
            self.dt,
            self.tolerance,
        )
        .map_err(|e| failed(format!("the closed-loop run: {e}")))?;
        let signals = trajectory.signals(model, &excitation);
        let column =
            |i: usize| -> Vec<f64> { signals.columns[i].iter().take(n).copied().collect() };
        let mut position = column(sensor);
        // The drive's force is the servo's command plus the external force;
        // the log holds the command only.
        let force: Vec<f64> = (column(drive).iter().zip(&disturbance))
            .map(|(f, d)| f - d)
            .collect();
        if position.len() != n || force.len() != n {
            return Err(failed(format!(
                "the closed-loop run gave {} samples for {n} times",
                position.len()
            )));
        }
        self.errors.measure(&mut position);
        Ok(csv_record(source, time, force, position))
    }
}

/// A record as `simulate-record` writes it to CSV (`t_s,f_servo_N,x_m`,
/// data from line 2), starting at rest.
fn csv_record(source: String, time: Vec<f64>, force: Vec<f64>, position: Vec<f64>) -> Record {
    Record {
        source,
        columns: ["t_s".into(), "f_servo_N".into(), "x_m".into()],
        rows: (2..time.len() as u64 + 2).collect(),
        row_word: "line",
        time,
        force,
        position,
        start: StartState::default(),
        sensors: Vec::new(),
    }
}

/// A scenario's inputs with an unlogged external force held over each
/// sample interval.
struct DisturbedServo {
    scenario: ScenarioExcitation,
    disturbance: HeldForce,
}

impl Excitation for DisturbedServo {
    fn inputs(&self, t: f64) -> Inputs {
        Inputs {
            servo_force: self.disturbance.inputs(t).servo_force,
            ..self.scenario.inputs(t)
        }
    }

    fn breakpoints(&self) -> Vec<f64> {
        let mut out = self.scenario.breakpoints();
        if self.disturbance.force.iter().any(|&d| d != 0.0) {
            out.extend(self.disturbance.breakpoints());
        }
        out.sort_by(f64::total_cmp);
        out
    }
}

/// A force held over each sample interval, the stage's only input.
struct HeldForce {
    time: Vec<f64>,
    force: Vec<f64>,
}

impl Excitation for HeldForce {
    fn inputs(&self, t: f64) -> Inputs {
        let k = self.time.partition_point(|&s| s <= t).saturating_sub(1);
        Inputs {
            servo_force: self.force.get(k).copied().unwrap_or(0.0),
            ..Inputs::default()
        }
    }

    fn breakpoints(&self) -> Vec<f64> {
        self.time[1..].to_vec()
    }
}

/// The most samples a simulated record holds (1000 s at 10 kHz; three
/// columns of 8 bytes each): checked before anything is allocated.
pub const MAX_RECORD_SAMPLES: f64 = 1e7;

/// The length of the open-loop lab program, s.
const PROGRAM_DURATION: f64 = 7.0;

/// Refuses a record of `duration` s at interval `dt` s with more than
/// [`MAX_RECORD_SAMPLES`] samples, naming both.
fn check_samples(duration: f64, dt: f64) -> Result<()> {
    let samples = duration / dt;
    if samples.is_finite() && samples <= MAX_RECORD_SAMPLES {
        return Ok(());
    }
    Err(IdentError::InvalidOption(format!(
        "{} s at {} Hz is {} samples; a simulated record holds at most {MAX_RECORD_SAMPLES:e} \
         (shorten the duration or lower the rate)",
        fistage_model::rule::show(duration),
        fistage_model::rule::show(1.0 / dt),
        fistage_model::rule::show(samples),
    )))
}
