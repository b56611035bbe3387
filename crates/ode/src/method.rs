//! The one interface of an adaptive method ([`AdaptiveMethod`], with
//! [`MethodState`] for what it reports whatever it integrates): start at a
//! point, take one accepted step towards a stop time, restart after a
//! discontinuity of the inputs, interpolate inside the last step, and
//! checkpoint and resume bit for bit. What every method does alike
//! (starting, resuming, checkpointing) has its body here once; a method
//! writes only what is its own. [`MethodKind`] names every method.

use crate::{Checkpoint, OdeSystem, StepCounts, StepFailure, Tolerances};

/// Where a method stands between steps, whatever system it integrates.
pub trait MethodState {
    /// The time reached.
    fn time(&self) -> f64;

    /// The state at [`MethodState::time`].
    fn state(&self) -> &[f64];

    /// The size the next step will try.
    fn proposed_step(&self) -> f64;

    /// Steps, rejections and evaluations so far.
    fn counts(&self) -> StepCounts;

    /// What is needed to resume: time, state, step suggestion, counters.
    fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            t: self.time(),
            x: self.state().to_vec(),
            h: self.proposed_step(),
            counts: self.counts(),
        }
    }
}

/// An adaptive method integrating systems of type `S`.
pub trait AdaptiveMethod<S: OdeSystem + ?Sized>: MethodState + Sized {
    /// The method standing at `start` (its time, state, step suggestion and
    /// counters) with its buffers allocated and nothing evaluated yet.
    fn unstarted(system: &S, start: &Checkpoint, tol: Tolerances) -> Self;

    /// Evaluates the system at the first point and picks the first step.
    fn start(&mut self, system: &mut S);

    /// Forgets the history at the current point after a discontinuity of
    /// the inputs: evaluates the system there again and keeps the step
    /// suggestion. The dense output of the last step stays readable.
    fn restart(&mut self, system: &mut S);

    /// Takes one accepted step, not beyond `t_stop` (landing on it exactly
    /// when it is within reach). Rejected attempts are retried with a
    /// smaller step; a non-finite error estimate counts as a rejection.
    fn step(&mut self, system: &mut S, t_stop: f64) -> Result<(), StepFailure>;

    /// The solution at `t` inside the last accepted step (a method may
    /// evaluate the system to form its continuous extension).
    fn interpolate(&mut self, system: &mut S, t: f64, out: &mut [f64]);

    /// Starts at (t0, x0): evaluates the system and picks the first step.
    fn new(system: &mut S, t0: f64, x0: &[f64], tol: Tolerances) -> Self {
        let start = Checkpoint {
            t: t0,
            x: x0.to_vec(),
            h: 0.0,
            counts: StepCounts::default(),
        };
        let mut method = Self::unstarted(system, &start, tol);
        method.start(system);
        method
    }

    /// Resumes from a [`Checkpoint`]: evaluates the system at its point and
    /// keeps its step suggestion and counters. Resuming from the checkpoint
    /// of a method that was then restarted continues exactly as that method
    /// does, bit for bit.
    fn resume(system: &mut S, checkpoint: &Checkpoint, tol: Tolerances) -> Self {
        let mut method = Self::unstarted(system, checkpoint, tol);
        method.restart(system);
        method
    }
}

/// Every adaptive method of this crate, by name. Adding a method is a file
/// under `methods/` and an entry here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MethodKind {
    /// [`crate::DormandPrince`]: explicit 5(4), the default explicit method.
    DormandPrince,
    /// [`crate::ImexRungeKutta`]: ARK5(4)8L\[2\]SA with some states implicit.
    Imex,
    /// [`crate::Dop853`]: explicit 8(5,3), for tight tolerances.
    Dop853,
    /// [`crate::ClassicalRungeKutta`]: RK4 with a third-order estimate, for
    /// loose tolerances.
    Classical,
    /// [`crate::Rosenbrock`]: ROS34PW2, linearly implicit with the Jacobian.
    Rosenbrock,
}

impl MethodKind {
    /// Every method, in the order of this enum.
    pub const ALL: [MethodKind; 5] = [
        MethodKind::DormandPrince,
        MethodKind::Imex,
        MethodKind::Dop853,
        MethodKind::Classical,
        MethodKind::Rosenbrock,
    ];

    /// A name for tables and reports.
    pub fn name(self) -> &'static str {
        match self {
            MethodKind::DormandPrince => "Dormand-Prince 5(4)",
            MethodKind::Imex => "ARK5(4) implicit-explicit",
            MethodKind::Dop853 => "DOP853",
            MethodKind::Classical => "classical RK4",
            MethodKind::Rosenbrock => "ROS34PW2",
        }
    }
}
