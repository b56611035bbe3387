//! Seeded lab-style records from known parameters: the
//! [`lab_program`] through the plant at a tight
//! tolerance, with what a lab adds: encoder quantisation, position noise,
//! and an unmeasured force disturbance (low-pass filtered noise, acting on
//! the stage but absent from the recorded force). The sensor errors and the
//! disturbance are also used by `fistage_analysis::lab` on full stage models.

use fistage_model::LugreParams;

use super::data::{Record, StartState};
use super::plant::{Anchors, Drive, PlantTolerance, Theta, simulate};
use super::program::lab_program;
use super::segments::Segment;
use crate::error::Result;
use crate::synth::Rng;

/// What the sensors and the surroundings add to a record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LabErrors {
    /// Encoder step, m (0: no quantisation).
    pub quantum: f64,
    /// Standard deviation of white position noise, m.
    pub position_noise: f64,
    /// RMS of the unmeasured force disturbance, N.
    pub disturbance_rms: f64,
    /// Correlation time of the disturbance, s.
    pub disturbance_time: f64,
    /// Seed of the noise and the disturbance.
    pub seed: u64,
}

impl LabErrors {
    /// None at all.
    pub fn exact() -> Self {
        Self {
            quantum: 0.0,
            position_noise: 0.0,
            disturbance_rms: 0.0,
            disturbance_time: 0.05,
            seed: 0,
        }
    }

    /// A 1 nm encoder and nothing else.
    pub fn encoder() -> Self {
        Self {
            quantum: 1e-9,
            ..Self::exact()
        }
    }

    /// The disturbance force at each sample (held over the interval), N.
    pub fn disturbance(&self, n: usize, dt: f64) -> Vec<f64> {
        if self.disturbance_rms == 0.0 {
            return vec![0.0; n];
        }
        let mut rng = Rng::new(self.seed ^ 0x5eed_d157);
        let a = (-dt / self.disturbance_time).exp();
        let gain = (1.0 - a * a).sqrt() * self.disturbance_rms;
        let mut d = self.disturbance_rms * rng.normal();
        (0..n)
            .map(|_| {
                let out = d;
                d = a * d + gain * rng.normal();
                out
            })
            .collect()
    }

    /// The encoder's reading of true positions: noise, then quantisation.
    pub fn measure(&self, position: &mut [f64]) {
        let mut rng = Rng::new(self.seed);
        for x in position.iter_mut() {
            if self.position_noise > 0.0 {
                *x += self.position_noise * rng.normal();
            }
            if self.quantum > 0.0 {
                *x = (*x / self.quantum).round() * self.quantum;
            }
        }
    }
}

/// A synthetic record of the lab program on the Eq. 31 plant.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordSynth {
    /// The friction.
    pub lugre: LugreParams,
    /// The moving mass, kg.
    pub mass: f64,
    /// Sample interval, s.
    pub dt: f64,
    /// Sensor and disturbance errors.
    pub errors: LabErrors,
}

impl RecordSynth {
    /// A 10 kHz record with a 1 nm encoder.
    pub fn new(lugre: LugreParams, mass: f64) -> Self {
        Self {
            lugre,
            mass,
            dt: 1e-4,
            errors: LabErrors::encoder(),
        }
    }

    /// The record and its true segments.
    pub fn generate(&self) -> Result<(Record, Vec<Segment>)> {
        let (time, force, segments) = lab_program(self.lugre.f_c, self.lugre.f_s, self.dt);
        let n = time.len();
        let disturbance = self.errors.disturbance(n, self.dt);
        let acting: Vec<f64> = force.iter().zip(&disturbance).map(|(f, d)| f + d).collect();
        let driven = Record {
            source: "synthetic".into(),
            columns: ["t_s".into(), "f_servo_N".into(), "x_m".into()],
            rows: (2..n as u64 + 2).collect(),
            row_word: "line",
            time,
            force: acting,
            position: vec![0.0; n],
            start: StartState::default(),
            sensors: Vec::new(),
        };
        let theta = Theta::new(&self.lugre, self.mass);
        let tolerance = PlantTolerance::for_theta(&theta, 1e-11);
        let mut position = simulate(
            &driven,
            Drive::Recorded,
            &theta,
            &[],
            false,
            &Anchors::default(),
            tolerance,
        )?
        .position;
        self.errors.measure(&mut position);
        Ok((
            Record {
                force,
                position,
                ..driven
            },
            segments,
        ))
    }
}
