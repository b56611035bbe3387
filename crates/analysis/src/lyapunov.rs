//! The largest Lyapunov exponent of a scenario's motion, by the classic
//! two-trajectory method: after a transient, a copy of the state is displaced
//! by a small distance d0 (scaled by each state's nominal size), both are
//! integrated over short intervals, and after each interval the growth
//! ln(d / d0) is accumulated and the copy is pulled back to distance d0 along
//! the current separation. The exponent is the accumulated growth over the
//! time. It is about zero on a limit cycle (a displacement along the orbit
//! neither grows nor decays), negative at a stable equilibrium, and clearly
//! positive for chaotic motion.
//!
//! On a stick-slip orbit the speed along the orbit changes by orders of
//! magnitude between sticking and slipping, and a displacement along the orbit
//! follows it, so a finite measuring time T leaves a bias of order
//! ln(speed ratio) / T even on a limit cycle: the default T is 20 s.
//!
//! The separation must stay well above the integrator's error per interval
//! (rtol times the scaled state), or the renormalisation amplifies solver
//! noise into a spurious positive exponent: the default 1e-4 (scaled units)
//! leaves a factor of about 1e3 at rtol 1e-8. Measured on Fig. 12's k_i = 1e6
//! limit cycle: 2.8 1/s at 1e-6, 0.30 at 1e-4, and 0.30 at 1e-6 with
//! rtol 1e-11.
//!
//! The excitation must not depend on time (a constant reference), because
//! every interval restarts the clock.

use fistage_model::{Loaded, Reference, StateKind};
use fistage_sim::{
    AdaptiveEngine, Engine, ScenarioExcitation, SimError, SimSettings, initial_state,
};
use thiserror::Error;

/// Settings of the estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LyapunovSettings {
    /// Time discarded before measuring, s.
    pub transient: f64,
    /// Time over which growth is accumulated, s.
    pub duration: f64,
    /// Renormalisation interval, s.
    pub interval: f64,
    /// Initial separation in scaled units (state / nominal size).
    pub separation: f64,
}

impl Default for LyapunovSettings {
    fn default() -> Self {
        Self {
            transient: 2.0,
            duration: 20.0,
            interval: 0.02,
            separation: 1e-4,
        }
    }
}

/// Why no exponent could be estimated.
#[derive(Debug, Error)]
pub enum LyapunovError {
    /// The reference moves.
    #[error(
        "the Lyapunov exponent needs a constant reference (the scenario's reference varies in time)"
    )]
    TimeVarying,
    /// The scenario's start state is invalid.
    #[error(transparent)]
    Start(#[from] fistage_model::LoadError),
    /// An integration failed.
    #[error(transparent)]
    Simulation(#[from] SimError),
}

fn advance(loaded: &Loaded, x: &[f64], time: f64) -> Result<Vec<f64>, SimError> {
    let excitation = ScenarioExcitation::from_scenario(&loaded.scenario);
    let settings = SimSettings {
        t_end: time,
        sample_interval: time,
        ..SimSettings::from_scenario(&loaded.scenario)
    };
    let trajectory = AdaptiveEngine::NATIVE.simulate(
        &loaded.model,
        x,
        &excitation,
        &settings,
        &mut fistage_sim::no_progress,
    )?;
    Ok(trajectory.last_state().to_vec())
}

/// The largest Lyapunov exponent, 1/s.
pub fn largest_lyapunov(
    loaded: &Loaded,
    settings: &LyapunovSettings,
) -> Result<f64, LyapunovError> {
    if !matches!(loaded.scenario.reference, Reference::Constant { .. }) {
        return Err(LyapunovError::TimeVarying);
    }
    let model = &loaded.model;
    let nominal = &model.layout().nominal;
    let movable: Vec<usize> = (0..model.n_states())
        .filter(|&i| model.layout().kinds[i] != StateKind::Quaternion)
        .collect();
    let mut reference = advance(
        loaded,
        &initial_state(model, &loaded.scenario)?,
        settings.transient,
    )?;
    // Displace along a fixed direction with equal scaled components.
    let mut copy = reference.clone();
    let per_state = settings.separation / (movable.len() as f64).sqrt();
    for &i in &movable {
        copy[i] += per_state * nominal[i];
    }
    let distance = |a: &[f64], b: &[f64]| -> f64 {
        movable
            .iter()
            .map(|&i| ((a[i] - b[i]) / nominal[i]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let steps = (settings.duration / settings.interval).round().max(1.0) as usize;
    let mut growth = 0.0;
    for _ in 0..steps {
        reference = advance(loaded, &reference, settings.interval)?;
        copy = advance(loaded, &copy, settings.interval)?;
        let d = distance(&reference, &copy).max(f64::MIN_POSITIVE);
        growth += (d / settings.separation).ln();
        let pull = settings.separation / d;
        for &i in &movable {
            copy[i] = reference[i] + (copy[i] - reference[i]) * pull;
        }
    }
    Ok(growth / (steps as f64 * settings.interval))
}
