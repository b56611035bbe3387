//! What an adaptive method is asked for: [`Tolerances`] (relative and
//! per-state absolute error, the largest step and the smallest one relative
//! to the time), the step each attempt may take towards a stop time, and
//! Hairer's starting step ([`starting_step`]).

use crate::StepCounts;
use crate::system::OdeSystem;

/// Step-size controller and tolerance settings.
#[derive(Debug, Clone)]
pub struct Tolerances {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance per state.
    pub atol: Vec<f64>,
    /// Largest step, s.
    pub max_step: f64,
    /// Smallest step relative to |t| before the run is declared failed.
    pub min_step_relative: f64,
}

impl Tolerances {
    /// The step to try from `t` toward `t_stop` given a suggestion: the
    /// suggestion capped by `max_step`, or exactly the rest when that is
    /// (nearly) all of it, with whether the step lands on `t_stop`. None when
    /// the step has fallen below round-off level.
    pub fn next_step(&self, t: f64, suggested: f64, t_stop: f64) -> Option<(f64, bool)> {
        let remaining = t_stop - t;
        let h = suggested.min(self.max_step);
        let lands = h >= remaining * (1.0 - 1e-12);
        let h = if lands { remaining } else { h };
        let h_min = self.min_step_relative * t.abs().max(1.0);
        (h >= h_min || h >= remaining).then_some((h, lands))
    }

    /// The next step suggestion after an accepted step of the proposed new
    /// size: a step cut short to land on a stop time does not shrink it
    /// below the suggestion it replaced.
    pub fn suggestion_after(previous: f64, proposed: f64, landed: bool) -> f64 {
        if landed {
            previous.max(proposed)
        } else {
            proposed
        }
    }
}

/// How a method starts at (t, x): evaluates f there into `f0` and picks the
/// first step with [`starting_step`] for a method of order `order`, counting
/// both evaluations in `counts`. `stage` and `f1` are scratch space.
#[allow(clippy::too_many_arguments)]
pub(crate) fn first_step<S: OdeSystem + ?Sized>(
    system: &mut S,
    t: f64,
    x: &[f64],
    tol: &Tolerances,
    order: f64,
    f0: &mut [f64],
    stage: &mut [f64],
    f1: &mut [f64],
    counts: &mut StepCounts,
) -> f64 {
    system.rhs(t, x, f0);
    counts.rhs_evaluations += 1;
    let (h, evaluations) = starting_step(system, t, x, f0, tol, order, stage, f1);
    counts.rhs_evaluations += evaluations;
    h
}

/// Hairer's starting-step heuristic for a method of order `order` from
/// (t, x) with f(t, x) = `f0`: the step and the evaluations it took (one).
/// `stage` and `f1` are scratch space of the state's length.
#[allow(clippy::too_many_arguments)]
pub fn starting_step<S: OdeSystem + ?Sized>(
    system: &mut S,
    t: f64,
    x: &[f64],
    f0: &[f64],
    tol: &Tolerances,
    order: f64,
    stage: &mut [f64],
    f1: &mut [f64],
) -> (f64, u64) {
    let count = x.len();
    let n = count as f64;
    let scale = |i: usize| tol.atol[i] + tol.rtol * x[i].abs();
    let mut d0 = 0.0;
    let mut d1 = 0.0;
    for i in 0..count {
        let sc = scale(i);
        d0 += (x[i] / sc).powi(2);
        d1 += (f0[i] / sc).powi(2);
    }
    let (d0, d1) = ((d0 / n).sqrt(), (d1 / n).sqrt());
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(tol.max_step);
    for i in 0..count {
        stage[i] = x[i] + h0 * f0[i];
    }
    system.rhs(t + h0, stage, f1);
    let mut d2 = 0.0;
    for i in 0..count {
        d2 += ((f1[i] - f0[i]) / scale(i)).powi(2);
    }
    let d2 = (d2 / n).sqrt() / h0;
    let h1 = if d1.max(d2) <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d1.max(d2)).powf(1.0 / order)
    };
    ((100.0 * h0).min(h1).min(tol.max_step), 1)
}
