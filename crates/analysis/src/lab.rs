//! Identification data measured on the *simulated* stage, the way a lab
//! measures it (paper appendix): the stage of a robot or scenario file is
//! simulated with fistage's own engine, and the measured signals are reduced
//! as a lab reduces them, sensor errors included.
//!
//! **Steady-state friction f_ss(v)** ([`StribeckLab`]). The stage is servoed
//! (a stiff PD loop on its sensor and actuator) to track constant-velocity
//! ramps, one run per velocity and sign. Each ramp starts from rest with a
//! short constant acceleration; the run then waits until the servo transient
//! has died out *and* the stage has slid a set distance (the bristles reach
//! their steady deflection after sliding a few presliding distances
//! `f_s / sigma0`, about 3 um for Table 1, whatever the speed), and measures
//! over a window of at least a set time and a set travel. The measured
//! friction is the servo force (the actuator signal, `drive.force` on the
//! shipped stages) averaged over the window: at constant velocity the table
//! does not accelerate, so the servo force balances the friction force exactly,
//! `f_servo = f_ss(v) = sigma0 z_ss + sigma2 v` (z' = 0). The measured velocity
//! is the encoder's travel over the window divided by its duration. A run
//! whose servo force still drifts or oscillates over the window is refused,
//! not averaged: the stage with friction isolators does that under a stiff
//! servo, which is why the paper locked its isolators for this test.
//!
//! The ramp is fed to the servo as the reference of the model's inputs (an
//! [`Excitation`] of this module), so nothing depends on the scenario's own
//! `[reference]`, `[platform]` or `[controller]`: the scenario contributes the
//! robot and its overrides only. (Moving the counter-surface at `-v` under a
//! stage held still would give the same force; a ramp is what the paper did.)
//!
//! Errors added, per run: white force-sensor noise on every force sample
//! (averaged down over the window), a run-to-run offset (repeatability:
//! lubricant film, temperature; the scatter a measured curve shows) and the
//! encoder's quantisation of the two positions that give the velocity.
//!
//! **Pre-motion FRF** ([`FrfLab`]). The open-loop stage (no controller: the
//! actuator force is the model's `servo_force` input) is driven by
//! `F(t) = A sin(2 pi f t)` from rest, at one frequency after the other. After
//! a settling time (the free response of the pre-motion mode decays at
//! `(sigma1 + sigma2) / (2 M)`, 84 1/s for Table 1), the displacement read by
//! the sensor is sampled synchronously (a whole number of samples per period)
//! over whole periods, with sensor noise and quantisation, and projected on
//! `exp(-j 2 pi f t)`, as is the commanded force: `G = X / F`. Constant
//! offsets and the other harmonics drop out of the projection. (Eq. 33 is the
//! FRF of the rigid stage; with an isolator the stage has a second mode.)
//!
//! At a finite amplitude the LuGre contact is not the linear spring-damper of
//! paper Eq. 32/33: `z' = v - |v| z / g(v)` loses bristle deflection in
//! proportion to `|z| / g(0) = |z| sigma0 / f_s`, which softens the contact and
//! adds hysteretic damping. The first-harmonic FRF therefore deviates from
//! Eq. 33 by an amount that grows with the displacement amplitude relative to
//! the presliding distance. [`FrfLab::paper_like`] drives with 0.01 N, which
//! keeps the bristle deflection below 0.15% of `f_s / sigma0` at low
//! frequencies and near 1% at the resonance of Table 1's stage; even so the
//! hysteresis this adds near the resonance raises the fitted
//! `sigma1 + sigma2` by about 2% on 30 frequencies from 10 Hz to 1 kHz
//! (sigma0 changes by less than 0.05%), a bias proportional to the amplitude
//! (0.44% at 0.002 N); the lab tests check both.
//!
//! Runs are independent and spread over the available cores; each run has its
//! own seeded noise, so the data do not depend on the scheduling.

use std::f64::consts::PI;
use std::path::Path;

use fistage_model::{
    ControllerSettings, Inputs, LugreParams, Model, ReferenceSample, RobotSpec, Scenario, assemble,
};
use fistage_sim::{
    AdaptiveEngine, Engine, Excitation, SignalTable, SimError, SimSettings, Trajectory,
};

use fistage_ident::synth::Rng;
use fistage_ident::{Complex, FrfData, IdentError, Result, StribeckData};
use rayon::prelude::*;

/// A stage to measure: a robot file (or a scenario file, for its robot and
/// overrides) with one friction contact, an actuator and a sensor.
#[derive(Debug, Clone)]
pub struct LabStage {
    source: String,
    robot: RobotSpec,
    scenario: Scenario,
    friction: LugreParams,
    friction_name: String,
    contacts: Vec<(String, LugreParams)>,
    mass: f64,
    sensor: String,
    actuator: String,
}

impl LabStage {
    /// Loads a robot (`.urdf`) or a scenario (`.toml`: its robot with its
    /// overrides; its controller's sensor and actuator are the ones used, its
    /// gains, reference and platform are not). The tests read the sensor and
    /// drive the actuator (the first of each without a scenario servo).
    pub fn load(path: &Path) -> Result<Self> {
        let is_scenario = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
        let scenario = if is_scenario {
            Scenario::from_file(path)?
        } else {
            let name = path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let mut text = toml::Table::new();
            text.insert("robot".into(), name.into());
            text.insert("duration".into(), 1.0.into());
            Scenario::from_str(&text.to_string(), path)?
        };
        let robot = RobotSpec::from_file(&scenario.robot)?;
        let source = path.display().to_string();
        let mut stage = Self {
            source,
            robot,
            scenario,
            friction: LugreParams::paper_table1(),
            friction_name: String::new(),
            contacts: Vec::new(),
            mass: 0.0,
            sensor: String::new(),
            actuator: String::new(),
        };
        let model = stage.model(None)?;
        let problem = |message: String| IdentError::Simulation {
            file: stage.source.clone(),
            message,
        };
        let Some(friction) = model.frictions().first() else {
            return Err(problem(
                "the lab tests need a stage with a friction contact (fistage:friction)".into(),
            ));
        };
        // The scenario's servo names the sensor and actuator; else the first ones.
        let servo = stage.scenario.controller.as_ref();
        let sensor = servo
            .and_then(|c| model.sensors().iter().find(|s| s.name == c.sensor))
            .or(model.sensors().first());
        let actuator = servo
            .and_then(|c| model.actuators().iter().find(|a| a.name == c.actuator))
            .or(model.actuators().first());
        let (Some(sensor), Some(actuator)) = (sensor, actuator) else {
            return Err(problem(
                "the lab tests need a sensor and an actuator (fistage:sensor, fistage:actuator)"
                    .to_string(),
            ));
        };
        stage.friction = friction.lugre;
        stage.friction_name = friction.name.clone();
        stage.contacts = (model.frictions().iter())
            .map(|f| (f.name.clone(), f.lugre))
            .collect();
        stage.sensor = sensor.name.clone();
        stage.actuator = actuator.name.clone();
        stage.mass = model.bodies().iter().map(|b| b.mass).sum();
        Ok(stage)
    }

    /// The file the stage came from.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The LuGre parameters of the contact (after the scenario's overrides):
    /// the truth the identification should find.
    pub fn friction(&self) -> LugreParams {
        self.friction
    }

    /// Every friction contact: name and LuGre parameters.
    pub fn contacts(&self) -> &[(String, LugreParams)] {
        &self.contacts
    }

    /// The sensor the records read first (the servo's, else the first).
    pub fn sensor(&self) -> &str {
        &self.sensor
    }

    /// Refuses a stage with more than one contact, for the tests that
    /// measure one contact's friction (`what` names the test).
    pub(crate) fn single_contact(&self, what: &str) -> Result<()> {
        match self.contacts.len() {
            1 => Ok(()),
            n => Err(IdentError::Simulation {
                file: self.source.clone(),
                message: format!(
                    "{what} measures one friction contact, and this stage has {n}; make a \
                     record (simulate-record) and fit the stage (identify record --stage)"
                ),
            }),
        }
    }

    /// Name of the friction contact.
    pub fn friction_name(&self) -> &str {
        &self.friction_name
    }

    /// Total moving mass, kg (m_t + m_b for the paper's stages).
    pub fn moving_mass(&self) -> f64 {
        self.mass
    }

    /// The stage's model with the given servo (none: open loop).
    pub(crate) fn model(&self, controller: Option<ControllerSettings>) -> Result<Model> {
        let mut scenario = self.scenario.clone();
        scenario.controller = controller;
        scenario.platform_velocity = 0.0;
        let (_, model) = assemble(self.robot.clone(), &scenario)?;
        Ok(model)
    }

    /// The state an open-loop record starts from: the scenario's start
    /// (what a stage fit of the record assumes).
    pub(crate) fn start_state(&self, model: &Model) -> Result<Vec<f64>> {
        let mut scenario = self.scenario.clone();
        scenario.controller = None;
        scenario.compensation.clear();
        scenario.observer = None;
        scenario.platform_velocity = 0.0;
        Ok(fistage_model::initial_state(model, &scenario)?)
    }

    /// Indices of the actuator force and the sensor position among the model's signals.
    pub(crate) fn force_and_position(&self, model: &Model) -> Result<[usize; 2]> {
        let signal = |name: String| {
            model
                .signal_index(&name)
                .ok_or_else(|| IdentError::Simulation {
                    file: self.source.clone(),
                    message: format!("the model has no signal '{name}'"),
                })
        };
        Ok([
            signal(format!("{}.force", self.actuator))?,
            signal(format!("{}.position", self.sensor))?,
        ])
    }

    pub(crate) fn simulation_error(&self, what: &str, error: impl std::fmt::Display) -> IdentError {
        IdentError::Simulation {
            file: self.source.clone(),
            message: format!("{what}: {error}"),
        }
    }
}

/// Integrates `model` from `x0` over `[0, t_end]`, sampled every `dt`.
pub(crate) fn simulate(
    model: &Model,
    x0: &[f64],
    excitation: &dyn Excitation,
    t_end: f64,
    dt: f64,
    tolerance: Tolerance,
) -> std::result::Result<Trajectory, SimError> {
    let settings = SimSettings {
        t_end,
        sample_interval: dt,
        rtol: tolerance.rtol,
        atol_scale: tolerance.atol_scale,
        max_step: None,
        max_steps: 200_000_000,
    };
    AdaptiveEngine::NATIVE.simulate(
        model,
        x0,
        excitation,
        &settings,
        &mut fistage_sim::no_progress,
    )
}

/// One run of a test: `start` drives the model from rest over `settle` (only
/// the end state is kept), then `measuring`, the same excitation with its clock
/// continued, over `window` sampled every `dt`. Returns the signals of the
/// window and the integration steps of the whole run.
fn settle_and_measure(
    model: &Model,
    [start, measuring]: [&dyn Excitation; 2],
    [settle, window, dt]: [f64; 3],
    tolerance: Tolerance,
) -> std::result::Result<(SignalTable, u64), SimError> {
    let x0 = model.zero_state();
    let settled = simulate(model, &x0, start, settle, settle, tolerance)?;
    let measured = simulate(
        model,
        settled.last_state(),
        measuring,
        window,
        dt,
        tolerance,
    )?;
    let steps = settled.stats.counts.steps + measured.stats.counts.steps;
    Ok((measured.signals(model, measuring), steps))
}

/// Integration tolerances of the simulated runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerances are `rtol * atol_scale` times each state's nominal
    /// size (1 mm, 10 mm/s, and the presliding distance for a bristle).
    pub atol_scale: f64,
}

/// The most points a simulated curve or FRF takes (each point is a
/// simulated run): checked before anything is allocated.
pub const MAX_LAB_POINTS: usize = 1000;

/// `n` values from `lo` to `hi`, equally spaced on a logarithmic scale (at least 2).
pub fn log_spaced(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let n = n.max(2);
    (0..n)
        .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
        .collect()
}

/// Rounds to the resolution (none if it is 0).
fn quantise(x: f64, resolution: f64) -> f64 {
    if resolution > 0.0 {
        (x / resolution).round() * resolution
    } else {
        x
    }
}

/// A seed for run `i` of an experiment seeded with `seed`.
fn run_seed(seed: u64, i: usize) -> u64 {
    seed.wrapping_mul(0x9e37_79b9_7f4a_7c15)
        .wrapping_add(i as u64 + 1)
}

/// Runs `run(i, seed of run i)` for `i in 0..n` on rayon's threads; the
/// results in order, or the first error in that order (every run finishes,
/// so which error is reported does not depend on the scheduling).
fn runs<T: Send>(
    n: usize,
    seed: u64,
    run: impl Fn(usize, u64) -> Result<T> + Sync,
) -> Result<Vec<T>> {
    let results: Vec<Result<T>> = (0..n)
        .into_par_iter()
        .map(|i| run(i, run_seed(seed, i)))
        .collect();
    results.into_iter().collect()
}

/// The servo reference of a constant-velocity run: from rest at 0, constant
/// acceleration for `accel_time`, then constant `velocity`; time shifted by
/// `offset` (a run continued from a saved state).
#[derive(Debug, Clone, Copy)]
struct Ramp {
    velocity: f64,
    accel_time: f64,
    offset: f64,
}

impl Excitation for Ramp {
    fn inputs(&self, t: f64) -> Inputs {
        let t = t + self.offset;
        let (v, ta) = (self.velocity, self.accel_time);
        let reference = if t < ta {
            ReferenceSample {
                position: 0.5 * v * t * t / ta,
                velocity: v * t / ta,
            }
        } else {
            ReferenceSample {
                position: v * (t - 0.5 * ta),
                velocity: v,
            }
        };
        Inputs {
            reference,
            ..Inputs::default()
        }
    }

    fn breakpoints(&self) -> Vec<f64> {
        let at = self.accel_time - self.offset;
        if at > 0.0 { vec![at] } else { Vec::new() }
    }
}

/// A sinusoidal actuator force `amplitude sin(omega (t + offset))`.
#[derive(Debug, Clone, Copy)]
struct SineForce {
    amplitude: f64,
    omega: f64,
    offset: f64,
}

impl Excitation for SineForce {
    fn inputs(&self, t: f64) -> Inputs {
        Inputs {
            servo_force: self.amplitude * (self.omega * (t + self.offset)).sin(),
            ..Inputs::default()
        }
    }
}

/// A constant-velocity friction test on the servoed stage.
#[derive(Debug, Clone, PartialEq)]
pub struct StribeckLab {
    /// Test speeds |v|, m/s; each is run in both directions.
    pub speeds: Vec<f64>,
    /// Servo stiffness, N/m.
    pub k: f64,
    /// Servo damping, N s/m.
    pub c: f64,
    /// Duration of the constant acceleration at the start of a run, s.
    pub accel_time: f64,
    /// Time the servo transient needs to die out after the acceleration, s.
    pub servo_settle: f64,
    /// Distance slid before measuring, m (bristle transient).
    pub settle_travel: f64,
    /// Shortest measuring window, s.
    pub window_time: f64,
    /// Shortest travel in the measuring window, m.
    pub window_travel: f64,
    /// Sample rate of the force and the encoder, Hz.
    pub sample_rate: f64,
    /// Force-sensor noise, N rms per sample.
    pub force_noise: f64,
    /// Run-to-run repeatability of the friction force, N rms per run.
    pub run_scatter: f64,
    /// Encoder resolution, m (0: exact).
    pub encoder_resolution: f64,
    /// Largest drift and ripple of the servo force over a window, N (without
    /// sensor errors), for the run to count as steady.
    pub steady_tolerance: f64,
    /// Integration tolerances.
    pub tolerance: Tolerance,
    /// Seed of the sensor errors.
    pub seed: u64,
}

impl StribeckLab {
    /// A test like the paper's appendix: `points` speeds per direction from
    /// 0.5 mm/s to 0.4 m/s (log-spaced), servo k = 1e6 N/m, c = 2500 N s/m
    /// (critically damped on 1.5 kg), 20 ms acceleration, 30 ms servo
    /// settling, 50 um settling travel, windows of at least 20 ms and 100 um,
    /// 10 kHz sampling, force noise 0.05 N per sample, run-to-run scatter
    /// 0.02 N, encoder 0.1 um; a run counts as steady if its servo force
    /// drifts and ripples by less than 1 mN.
    pub fn paper_like(points: usize, seed: u64) -> Self {
        Self {
            speeds: log_spaced(5e-4, 0.4, points),
            k: 1e6,
            c: 2500.0,
            accel_time: 0.02,
            servo_settle: 0.03,
            settle_travel: 50e-6,
            window_time: 0.02,
            window_travel: 100e-6,
            sample_rate: 1e4,
            force_noise: 0.05,
            run_scatter: 0.02,
            encoder_resolution: 1e-7,
            steady_tolerance: 1e-3,
            tolerance: Tolerance {
                rtol: 1e-8,
                atol_scale: 1.0,
            },
            seed,
        }
    }

    /// The same test without sensor errors.
    pub fn exact(self) -> Self {
        Self {
            force_noise: 0.0,
            run_scatter: 0.0,
            encoder_resolution: 0.0,
            ..self
        }
    }

    /// Runs the test: one run per speed and direction (negative speeds first,
    /// in increasing order of velocity). Fails if a run does not reach a
    /// steady state within its window (`steady_tolerance`): the force would
    /// not be f_ss. A stage with friction isolators under a stiff servo does
    /// that (the bearing rings on the isolator, or stick-slips); the paper
    /// locked its isolators for this test, i.e. use the rigid stage.
    pub fn measure(&self, stage: &LabStage) -> Result<StribeckMeasurement> {
        stage.single_contact("the steady-state friction test")?;
        let servo = ControllerSettings {
            sensor: stage.sensor.clone(),
            actuator: stage.actuator.clone(),
            k: self.k,
            c: self.c,
            k_i: 0.0,
        };
        let model = stage.model(Some(servo))?;
        let signals = stage.force_and_position(&model)?;
        let mut velocities: Vec<f64> = self.speeds.iter().rev().map(|s| -s).collect();
        velocities.extend(self.speeds.iter().copied());
        let runs = runs(velocities.len(), self.seed, |i, seed| {
            self.run(stage, &model, velocities[i], signals, seed)
        })?;
        if let Some(run) = runs.iter().find(|r| {
            !(r.drift.abs() <= self.steady_tolerance && r.ripple <= self.steady_tolerance)
        }) {
            return Err(IdentError::Simulation {
                file: stage.source.clone(),
                message: format!(
                    "the f_ss run at {} m/s does not reach a steady state: over its {:.3} s \
                     window the servo force drifts by {:.3e} N and varies by {:.3e} N rms \
                     (allowed {:.1e} N), so its mean is not the steady-state friction; a stage \
                     with friction isolators does this under a stiff servo (the paper locked \
                     the isolators for this test: use the rigid stage)",
                    run.commanded, run.window, run.drift, run.ripple, self.steady_tolerance
                ),
            });
        }
        let data = StribeckData::new(
            format!("{} (simulated f_ss test)", stage.source),
            runs.iter().map(|r| r.velocity).collect(),
            runs.iter().map(|r| r.force).collect(),
        );
        Ok(StribeckMeasurement { data, runs })
    }

    fn run(
        &self,
        stage: &LabStage,
        model: &Model,
        velocity: f64,
        [force, position]: [usize; 2],
        seed: u64,
    ) -> Result<StribeckRun> {
        let speed = velocity.abs();
        let settle = self.accel_time + self.servo_settle.max(self.settle_travel / speed);
        let window = self.window_time.max(self.window_travel / speed);
        let ramp = Ramp {
            velocity,
            accel_time: self.accel_time,
            offset: 0.0,
        };
        let measuring = Ramp {
            offset: settle,
            ..ramp
        };
        let times = [settle, window, 1.0 / self.sample_rate];
        let (signals, steps) =
            settle_and_measure(model, [&ramp, &measuring], times, self.tolerance)
                .map_err(|e| stage.simulation_error(&format!("f_ss run at {velocity} m/s"), e))?;
        let f = &signals.columns[force];
        let x = &signals.columns[position];
        let t = &signals.times;
        let n = f.len();
        let exact_mean = f.iter().sum::<f64>() / n as f64;
        let half = n / 2;
        let drift = f[half..].iter().sum::<f64>() / (n - half) as f64
            - f[..half].iter().sum::<f64>() / half as f64;
        let ripple = (f.iter().map(|v| (v - exact_mean).powi(2)).sum::<f64>() / n as f64).sqrt();
        let mut rng = Rng::new(seed);
        let offset = self.run_scatter * rng.normal();
        let noisy_mean = f
            .iter()
            .map(|v| v + self.force_noise * rng.normal())
            .sum::<f64>()
            / n as f64;
        let travel =
            quantise(x[n - 1], self.encoder_resolution) - quantise(x[0], self.encoder_resolution);
        Ok(StribeckRun {
            commanded: velocity,
            velocity: travel / (t[n - 1] - t[0]),
            force: noisy_mean + offset,
            exact_force: exact_mean,
            drift,
            ripple,
            settle_time: settle,
            window,
            steps,
        })
    }
}

/// One constant-velocity run.
#[derive(Debug, Clone, PartialEq)]
pub struct StribeckRun {
    /// Commanded velocity, m/s.
    pub commanded: f64,
    /// Measured velocity (encoder travel over the window), m/s.
    pub velocity: f64,
    /// Measured friction (mean servo force with the sensor errors), N.
    pub force: f64,
    /// Mean servo force over the window without sensor errors, N.
    pub exact_force: f64,
    /// Mean servo force of the second half of the window minus the first, N
    /// (without sensor errors): what is left of the transient.
    pub drift: f64,
    /// RMS deviation of the servo force from its mean over the window, N
    /// (without sensor errors): oscillation, e.g. a limit cycle.
    pub ripple: f64,
    /// Time from the start of the run to the window, s.
    pub settle_time: f64,
    /// Length of the window, s.
    pub window: f64,
    /// Integration steps of the run.
    pub steps: u64,
}

/// The outcome of a [`StribeckLab`] test.
#[derive(Debug, Clone, PartialEq)]
pub struct StribeckMeasurement {
    /// The measured curve, as a lab file would hold it.
    pub data: StribeckData,
    /// The runs in the order of the data.
    pub runs: Vec<StribeckRun>,
}

/// A stepped-sine FRF test of the open-loop stage.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfLab {
    /// Test frequencies, Hz.
    pub frequencies_hz: Vec<f64>,
    /// Force amplitude, N.
    pub force_amplitude: f64,
    /// Settling time before measuring, s (rounded up to whole periods).
    pub settle_time: f64,
    /// Fewest settling periods.
    pub settle_periods: usize,
    /// Shortest measuring time, s (rounded up to whole periods).
    pub measure_time: f64,
    /// Fewest measured periods.
    pub measure_periods: usize,
    /// Samples per period (synchronous sampling).
    pub samples_per_period: usize,
    /// Displacement-sensor noise, m rms per sample.
    pub displacement_noise: f64,
    /// Displacement-sensor resolution, m (0: exact).
    pub resolution: f64,
    /// Integration tolerances.
    pub tolerance: Tolerance,
    /// Seed of the sensor errors.
    pub seed: u64,
}

impl FrfLab {
    /// A stepped sine like the paper's appendix: `points` frequencies from
    /// 10 Hz to 1 kHz (log-spaced), force amplitude 0.01 N, at least 0.15 s
    /// and 3 periods of settling, at least 0.1 s and 4 periods measured with
    /// 64 samples per period, a 1 nm encoder with 0.5 nm rms noise (the
    /// response at 1 kHz is 0.17 nm: the projection over some 6000 samples
    /// still gives it to about 5%).
    pub fn paper_like(points: usize, seed: u64) -> Self {
        Self {
            frequencies_hz: log_spaced(10.0, 1000.0, points),
            force_amplitude: 0.01,
            settle_time: 0.15,
            settle_periods: 3,
            measure_time: 0.1,
            measure_periods: 4,
            samples_per_period: 64,
            displacement_noise: 5e-10,
            resolution: 1e-9,
            tolerance: Tolerance {
                rtol: 1e-8,
                atol_scale: 1e-4,
            },
            seed,
        }
    }

    /// The same test without sensor errors.
    pub fn exact(self) -> Self {
        Self {
            displacement_noise: 0.0,
            resolution: 0.0,
            ..self
        }
    }

    /// Runs the test: one stepped-sine run per frequency.
    pub fn measure(&self, stage: &LabStage) -> Result<FrfMeasurement> {
        stage.single_contact("the pre-motion FRF test")?;
        let model = stage.model(None)?;
        let signals = stage.force_and_position(&model)?;
        let runs = runs(self.frequencies_hz.len(), self.seed, |i, seed| {
            self.run(stage, &model, self.frequencies_hz[i], signals, seed)
        })?;
        let data = FrfData::new_complex(
            format!("{} (simulated FRF test)", stage.source),
            runs.iter().map(|r| 2.0 * PI * r.frequency_hz).collect(),
            runs.iter().map(|r| r.response).collect(),
        );
        Ok(FrfMeasurement { data, runs })
    }

    fn run(
        &self,
        stage: &LabStage,
        model: &Model,
        frequency_hz: f64,
        [force, position]: [usize; 2],
        seed: u64,
    ) -> Result<FrfRun> {
        let period = 1.0 / frequency_hz;
        let whole = |time: f64, fewest: usize| ((time / period).ceil() as usize).max(fewest);
        let settle = whole(self.settle_time, self.settle_periods) as f64 * period;
        let periods = whole(self.measure_time, self.measure_periods);
        let per_period = self.samples_per_period.max(4);
        let drive = SineForce {
            amplitude: self.force_amplitude,
            omega: 2.0 * PI * frequency_hz,
            offset: 0.0,
        };
        let measuring = SineForce {
            offset: settle,
            ..drive
        };
        let n = periods * per_period;
        let dt = period / per_period as f64;
        let times = [settle, n as f64 * dt, dt];
        let (signals, steps) =
            settle_and_measure(model, [&drive, &measuring], times, self.tolerance)
                .map_err(|e| stage.simulation_error(&format!("FRF run at {frequency_hz} Hz"), e))?;
        let mut rng = Rng::new(seed);
        let x: Vec<f64> = signals.columns[position][..n]
            .iter()
            .map(|x| quantise(x + self.displacement_noise * rng.normal(), self.resolution))
            .collect();
        let exact_x = &signals.columns[position][..n];
        let f = &signals.columns[force][..n];
        let project = |values: &[f64]| {
            let mut sum = Complex::new(0.0, 0.0);
            for (k, value) in values.iter().enumerate() {
                let phase = -2.0 * PI * (k % per_period) as f64 / per_period as f64;
                sum += Complex::from_polar(*value, phase);
            }
            sum.scale(2.0 / n as f64)
        };
        let force_phasor = project(f);
        Ok(FrfRun {
            frequency_hz,
            response: project(&x) / force_phasor,
            exact_response: project(exact_x) / force_phasor,
            peak_bristle: peak_ratio(&signals.columns, stage, model, n),
            settle_time: settle,
            periods,
            steps,
        })
    }
}

/// Largest |z| / (f_s / sigma0) over the measured samples: how far the bristle
/// deflection goes towards gross sliding.
fn peak_ratio(columns: &[Vec<f64>], stage: &LabStage, model: &Model, n: usize) -> f64 {
    let name = format!("{}.z", stage.friction_name);
    let Some(index) = model.signal_index(&name) else {
        return f64::NAN;
    };
    let p = stage.friction;
    let limit = p.f_s / p.sigma0;
    columns[index][..n]
        .iter()
        .fold(0.0f64, |m, z| m.max(z.abs()))
        / limit
}

/// One stepped-sine run.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfRun {
    /// Drive frequency, Hz.
    pub frequency_hz: f64,
    /// Measured X / F (sensor errors included), m/N.
    pub response: Complex,
    /// X / F without sensor errors, m/N.
    pub exact_response: Complex,
    /// Largest bristle deflection over the window relative to `f_s / sigma0`.
    pub peak_bristle: f64,
    /// Settling time, s.
    pub settle_time: f64,
    /// Measured periods.
    pub periods: usize,
    /// Integration steps of the run.
    pub steps: u64,
}

/// The outcome of an [`FrfLab`] test.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfMeasurement {
    /// The measured FRF, as a lab file would hold it.
    pub data: FrfData,
    /// The runs in the order of the data.
    pub runs: Vec<FrfRun>,
}
