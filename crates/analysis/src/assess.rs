//! What a study computes at one point of its parameter space (a sweep's grid
//! point, a tolerance analysis's sample): the scenario with the point's
//! parameter values, assembled from the robot file as written, then the
//! linear verdict (eigenvalues at the slipping equilibrium), the simulated
//! verdict (persistent oscillation of the tracking error from rest, on the
//! scenario's engine: by default the method `auto` takes for the point), the
//! oscillation amplitude and bistability (a stable equilibrium beside a limit
//! cycle).

use fistage_model::{
    EngineKind, EquilibriumKind, LoadError, Loaded, Parameter, RobotSpec, Scenario, assemble,
};
use fistage_sim::{AutoEngine, Engine, Excitation, ScenarioExcitation, SimSettings, initial_state};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::modes::{Verdict, modal_analysis};

pub use fistage_model::studies::Analyses;

/// What is computed at each point, and how.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Assessment {
    /// Analyses to run.
    pub analysis: Analyses,
    /// Simulated time per point, s (default: the scenario's duration).
    pub duration: Option<f64>,
    /// Steady peak-to-peak of the tracking error above which a run oscillates, m.
    pub oscillation_threshold: f64,
}

/// What one point gave; `None` where an analysis was not run or could not
/// give an answer (an undetermined linear verdict, a failed simulation).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Outcome {
    /// Slipping equilibrium linearly stable.
    pub stable_linear: Option<bool>,
    /// Largest real part of the non-neutral eigenvalues, 1/s.
    pub max_real_eig: Option<f64>,
    /// No persistent oscillation in simulation from rest.
    pub stable_sim: Option<bool>,
    /// Steady peak-to-peak of the tracking error, m.
    pub amplitude: Option<f64>,
    /// Steady peak-to-peak of the first floating body's yaw, rad.
    pub yaw_amplitude: Option<f64>,
    /// Stable equilibrium beside a limit cycle (linear stable, simulation oscillates).
    pub bistable: Option<bool>,
}

impl Assessment {
    /// Checks the settings read from the scenario's `[table]`: a
    /// non-negative threshold, and a positive duration whose samples fit in
    /// memory. Errors name `table.oscillation_threshold` or `table.duration`.
    pub fn check(&self, scenario: &Scenario, table: &str) -> Result<(), LoadError> {
        let threshold = self.oscillation_threshold;
        if !(threshold.is_finite() && threshold >= 0.0) {
            return Err(scenario.error(
                format!("{table}.oscillation_threshold"),
                format!("must be >= 0, got {threshold}"),
            ));
        }
        if let Some(d) = self.duration {
            let key = format!("{table}.duration");
            if !(d.is_finite() && d > 0.0) {
                return Err(scenario.error(key, format!("must be > 0, got {d}")));
            }
            check_duration(scenario, d).map_err(|why| scenario.error(key, why))?;
        }
        Ok(())
    }

    /// The analyses at one point.
    pub fn assess(&self, loaded: &Loaded) -> Outcome {
        let mut outcome = Outcome::default();
        if self.analysis.linear()
            && let Some((stable, max_real)) = linear_verdict(loaded)
        {
            outcome.stable_linear = stable;
            outcome.max_real_eig = Some(max_real);
        }
        if self.analysis.simulation()
            && let Some((stable, amplitude, yaw)) = simulated_verdict(loaded, self)
        {
            outcome.stable_sim = stable;
            outcome.amplitude = Some(amplitude);
            outcome.yaw_amplitude = yaw;
        }
        if let (Some(linear), Some(simulated)) = (outcome.stable_linear, outcome.stable_sim) {
            outcome.bistable = Some(linear && !simulated);
        }
        outcome
    }
}

/// The most worker threads a study takes: the program's `--threads` and the
/// Python package's `threads=` share this limit.
pub const MAX_THREADS: usize = 1024;

/// The worker threads of a study: `requested` when it is from 1 to
/// [`MAX_THREADS`], every core when none is requested, else why not.
pub fn worker_threads(requested: Option<usize>) -> Result<usize, String> {
    match requested {
        None => Ok(std::thread::available_parallelism().map_or(1, |n| n.get())),
        Some(n) if (1..=MAX_THREADS).contains(&n) => Ok(n),
        Some(n) => Err(format!("threads must be from 1 to {MAX_THREADS}, got {n}")),
    }
}

/// Evaluates `evaluate(index)` for every index on `threads` threads, in
/// index order; `done` is called with each result as it finishes (from
/// worker threads, in completion order) and the count finished so far.
/// Items are handed out one at a time: their costs differ (a run still
/// decaying is extended), and a thread that finishes early must be able to
/// take any item not yet started, not only a whole block of them.
pub fn in_parallel<T: Send>(
    indices: &[usize],
    threads: usize,
    evaluate: &(dyn Fn(usize) -> T + Sync),
    done: &(dyn Fn(&T, usize) + Sync),
) -> Vec<T> {
    let counter = AtomicUsize::new(0);
    let work = || {
        indices
            .par_iter()
            .with_max_len(1)
            .map(|&index| {
                let result = evaluate(index);
                let finished = counter.fetch_add(1, Ordering::Relaxed) + 1;
                done(&result, finished);
                result
            })
            .collect::<Vec<_>>()
    };
    match rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
    {
        Ok(pool) => pool.install(work),
        Err(_) => work(),
    }
}

/// Output samples a point's simulation may hold, extensions included: the
/// limit of a run (each sample is a full state vector).
pub const MAX_POINT_SAMPLES: f64 = fistage_model::scenario::MAX_SAMPLES;

/// Whether a simulated duration per point fits in memory: a run is sampled
/// at the scenario's rate (at least 4000 samples) and may be extended to
/// four times its duration while it is still decaying (longer looks are
/// taken only where they fit).
pub fn check_duration(scenario: &Scenario, duration: f64) -> Result<(), String> {
    let samples = 4.0 * point_samples(scenario, duration);
    if samples > MAX_POINT_SAMPLES {
        return Err(format!(
            "{duration:e} s at {} Hz is up to {samples:.3e} samples per point (runs still decaying are extended to four times their duration); at most {MAX_POINT_SAMPLES:e}",
            scenario.sample_rate
        ));
    }
    Ok(())
}

/// Output samples of one simulated run of `duration` s (at the scenario's
/// rate, at least 4000; see `steady_peak_to_peak`).
fn point_samples(scenario: &Scenario, duration: f64) -> f64 {
    (duration * scenario.sample_rate).max(4000.0)
}

/// Applies one parameter (a path of the parameter table) to a scenario and
/// its (unmodified) robot, with the same paths and rules as scenario
/// overrides and FMU parameters.
pub fn apply_parameter(
    scenario: &mut Scenario,
    robot: &mut RobotSpec,
    parameter: &str,
    value: f64,
) -> Result<(), LoadError> {
    Parameter::resolve(parameter, scenario, robot)?.write(scenario, robot, value)
}

/// The study with these parameter values: the base scenario and the robot
/// file as written, each value applied in turn, then assembled.
pub fn study_with(
    base: &Loaded,
    robot_file: &RobotSpec,
    assignments: &[(&str, f64)],
) -> Result<Loaded, LoadError> {
    let mut scenario = base.scenario.clone();
    let mut robot = robot_file.clone();
    for &(parameter, value) in assignments {
        apply_parameter(&mut scenario, &mut robot, parameter, value)?;
    }
    let (robot, model) = assemble(robot, &scenario)?;
    Ok(Loaded {
        scenario,
        robot,
        model,
    })
}

/// Linear verdict at the slipping equilibrium: (stable, or `None` when the
/// eigenvalues cannot back a verdict; largest real part).
pub fn linear_verdict(loaded: &Loaded) -> Option<(Option<bool>, f64)> {
    let inputs = crate::modes::equilibrium_inputs(&loaded.scenario);
    let analysis = modal_analysis(
        &loaded.model,
        &inputs,
        EquilibriumKind::Slipping,
        &loaded.model.zero_state(),
    )
    .ok()?;
    let stable = match analysis.verdict {
        Verdict::Stable => Some(true),
        Verdict::Unstable => Some(false),
        Verdict::Undetermined => None,
    };
    Some((stable, analysis.max_real_part))
}

/// The engine of a point's simulated verdict: the scenario's adaptive
/// engine, where it is the default (`auto`, or the fixed-step rapier engine)
/// the method `auto` takes for the point's own model, chosen once for the
/// point's runs.
fn verdict_engine(loaded: &Loaded, x0: &[f64]) -> Box<dyn Engine> {
    let scenario = &loaded.scenario;
    match scenario.solver.engine {
        kind if kind.is_adaptive() && kind != EngineKind::Auto => {
            fistage_sim::engine_in(scenario, kind)
        }
        _ => AutoEngine::for_scenario(scenario).resolved(&loaded.model, x0, scenario.solver.rtol),
    }
}

/// Steady peak-to-peaks of a run from rest.
struct Steady {
    /// Tracking error (sensor minus reference) over the last quarter, m.
    last: f64,
    /// The same over the quarter before it, m.
    before: f64,
    /// Yaw of the first floating body over the last quarter, rad (none
    /// without a floating body).
    yaw: Option<f64>,
}

/// The tracking error's peak-to-peak over the last quarter of a run from
/// rest on `engine` and the quarter before it, and the yaw's over the last
/// quarter.
fn steady_peak_to_peak(loaded: &Loaded, engine: &dyn Engine, duration: f64) -> Option<Steady> {
    let scenario = &loaded.scenario;
    let model = &loaded.model;
    let sensor = model.controller().map_or(0, |c| c.sensor);
    model.sensors().get(sensor)?;
    let yaw_signal = model
        .bodies()
        .iter()
        .find(|b| matches!(b.joint.motion, fistage_model::JointMotion::Floating))
        .and_then(|b| model.signal_index(&format!("{}.yaw", b.joint.name)));
    let excitation = ScenarioExcitation::from_scenario(scenario);
    let settings = SimSettings {
        t_end: duration,
        sample_interval: (duration / 4000.0).min(1.0 / scenario.sample_rate),
        ..SimSettings::from_scenario(scenario)
    };
    let x0 = initial_state(model, scenario).ok()?;
    let trajectory = engine
        .simulate(
            model,
            &x0,
            &excitation,
            &settings,
            &mut fistage_sim::no_progress,
        )
        .ok()?;
    let mut ws = model.workspace();
    let mut outputs = vec![0.0; model.signals().len()];
    let range = |from: f64, to: f64, value: &mut dyn FnMut(usize, f64) -> f64| {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (k, &t) in trajectory.times.iter().enumerate() {
            if t >= from && t <= to {
                let v = value(k, t);
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        hi - lo
    };
    // The readings from the kinematics alone: a population evaluates
    // thousands of samples per stage, and the force elements (the Stribeck
    // exponential above all) do not move a sensor.
    let mut readings = vec![0.0; model.sensors().len()];
    let mut tracking = |k: usize, t: f64| {
        model.sensor_positions(trajectory.state(k), &mut readings, &mut ws);
        readings[sensor] - excitation.inputs(t).reference.position
    };
    let last = range(0.75 * duration, duration, &mut tracking);
    let before = range(0.5 * duration, 0.75 * duration, &mut tracking);
    let yaw = yaw_signal.map(|index| {
        let mut ws = model.workspace();
        range(0.75 * duration, duration, &mut |k, t| {
            model.outputs(
                trajectory.state(k),
                &excitation.inputs(t),
                &mut outputs,
                &mut ws,
            );
            outputs[index]
        })
    });
    Some(Steady { last, before, yaw })
}

/// Simulated verdict: (no persistent oscillation, tracking amplitude, yaw
/// amplitude). A run that is still decaying (last-quarter peak-to-peak below
/// 80% of the quarter before, but above the threshold) is run again twice as
/// long, at most twice. One still decaying after the longest look has no
/// verdict (`None`): its motion is neither below the threshold nor
/// persistent, and calling it oscillating would count a decaying stage as
/// an unstable one (a population's interval then spans both outcomes).
fn simulated_verdict(
    loaded: &Loaded,
    assessment: &Assessment,
) -> Option<(Option<bool>, f64, Option<f64>)> {
    let mut duration = assessment.duration.unwrap_or(loaded.scenario.duration);
    let x0 = initial_state(&loaded.model, &loaded.scenario).ok()?;
    let engine = verdict_engine(loaded, &x0);
    for extension in 0..=LONGER_LOOKS {
        let steady = steady_peak_to_peak(loaded, engine.as_ref(), duration)?;
        // A look longer than memory allows is not taken: the run stays
        // without a verdict. (`check_duration` guarantees the first three.)
        let next_fits = point_samples(&loaded.scenario, 2.0 * duration) <= MAX_POINT_SAMPLES;
        let last_look = extension == LONGER_LOOKS || !next_fits;
        match judge(&steady, assessment.oscillation_threshold, last_look) {
            Look::Verdict(verdict) => return Some((verdict, steady.last, steady.yaw)),
            Look::Longer => duration *= 2.0,
        }
    }
    None
}

/// Runs twice as long a still decaying run may get: up to 16 times its
/// duration, where a stage decaying by 25x every 2 s (as some of a 1-DOF FI
/// population do) has long reached the threshold.
const LONGER_LOOKS: usize = 4;

/// What one look at a run's steady motion decides.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Look {
    /// The verdict (no persistent oscillation), or none the motion backs.
    Verdict(Option<bool>),
    /// Still decaying: look at a run twice as long.
    Longer,
}

/// Below the threshold: no oscillation; keeping [`PERSISTENT_RATIO`] of
/// the previous quarter: persistent; else decaying, which is a verdict of
/// its own only once the longest look is taken: none.
fn judge(steady: &Steady, threshold: f64, last_look: bool) -> Look {
    if steady.last <= threshold {
        Look::Verdict(Some(true))
    } else if steady.last >= PERSISTENT_RATIO * steady.before {
        Look::Verdict(Some(false))
    } else if last_look {
        Look::Verdict(None)
    } else {
        Look::Longer
    }
}

/// The share of the previous quarter's peak-to-peak the last quarter's must
/// keep for the motion to count as persistent; below it the run is decaying.
/// A limit cycle keeps its amplitude to about a percent from one quarter to
/// the next; a 1-DOF FI stage settling from its start shrinks by 10 to 20%
/// a quarter at first (4x every 2 s), then faster (25x): with 0.8 such
/// stages were called oscillating, and run for 32 s they settled below
/// 1e-9 m (52 of 4 000 in a Fig. 5b population).
const PERSISTENT_RATIO: f64 = 0.95;

#[cfg(test)]
mod tests {
    use super::*;

    fn steady(last: f64, before: f64) -> Steady {
        Steady {
            last,
            before,
            yaw: None,
        }
    }

    /// A run decaying by 25x every look (as some stages of a 1-DOF FI
    /// population do, down to round-off when run for 16 s) is looked at
    /// longer, and after the longest look has no verdict: it is neither
    /// below the threshold nor persistent. A steady amplitude is a
    /// persistent oscillation at any look; one under the threshold is none.
    #[test]
    fn a_decaying_run_is_not_called_oscillating() {
        let threshold = 1e-9;
        let decaying = steady(4e-8, 1e-6);
        assert_eq!(judge(&decaying, threshold, false), Look::Longer);
        assert_eq!(judge(&decaying, threshold, true), Look::Verdict(None));
        let persistent = steady(3e-6, 3.1e-6);
        assert_eq!(
            judge(&persistent, threshold, false),
            Look::Verdict(Some(false))
        );
        assert_eq!(
            judge(&persistent, threshold, true),
            Look::Verdict(Some(false))
        );
        let settled = steady(5e-10, 1e-6);
        assert_eq!(judge(&settled, threshold, true), Look::Verdict(Some(true)));
        // Shrinking by a sixth a quarter (4x in 2 s) is settling, not a cycle.
        let settling = steady(5.0e-5, 6.0e-5);
        assert_eq!(judge(&settling, threshold, false), Look::Longer);
    }
}
