//! Lab-style records from any stage model: the identification program of
//! [`fistage_ident::record::program`] applied open loop to the stage's
//! actuator (the force held over each sample interval), the sensor sampled
//! at every sample time before the next force acts, and the lab's errors
//! (encoder quantisation, position noise, an unmeasured force disturbance)
//! added. The stage is the full assembled model (isolators and all), so a
//! record made here is an independent check of the record fit's one-mass
//! plant.

use fistage_ident::record::program::lab_program;
use fistage_ident::record::{LabErrors, Record, Segment, StartState};
use fistage_ident::{IdentError, Result};
use fistage_model::Inputs;
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
        }
    }

    /// Runs the program on `stage`: the record and its segments.
    pub fn measure(&self, stage: &LabStage) -> Result<(Record, Vec<Segment>)> {
        if !(self.dt > 0.0 && self.dt.is_finite()) {
            return Err(IdentError::InvalidOption(format!(
                "the sample interval must be positive, got {}",
                self.dt
            )));
        }
        let friction = stage.friction();
        let (time, force, segments) = lab_program(friction.f_c, friction.f_s, self.dt);
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
        let x0 = model.zero_state();
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
        let record = Record {
            source: stage.source().to_string(),
            columns: ["t_s".into(), "f_servo_N".into(), "x_m".into()],
            rows: (2..n as u64 + 2).collect(),
            row_word: "line",
            time,
            force,
            position,
            start: StartState::default(),
        };
        Ok((record, segments))
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
