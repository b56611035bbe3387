//! What an integration reports and keeps between steps: why a step could
//! not be taken ([`StepFailure`]), its counters ([`StepCounts`]) and the
//! point it can be resumed from exactly ([`Checkpoint`]).

/// Why a step attempt could not proceed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepFailure {
    /// The step size fell below the smallest allowed step at time t.
    StepSizeUnderflow {
        /// Time reached.
        t: f64,
        /// Step size tried.
        h: f64,
        /// First state that became non-finite in the last rejected attempt, if any.
        non_finite: Option<usize>,
    },
}

/// Counters of an integration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct StepCounts {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
}

/// Where an integration stands between steps: enough to resume it exactly.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    /// Time.
    pub t: f64,
    /// State.
    pub x: Vec<f64>,
    /// Suggested next step.
    pub h: f64,
    /// Counters so far.
    pub counts: StepCounts,
}
