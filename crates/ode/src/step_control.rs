//! The step-size controller of the embedded Runge-Kutta pairs (Dormand-Prince
//! 5(4), the implicit-explicit pair, DOP853, the classical method): a PI
//! controller on the logarithm of the scaled error norm (Gustafsson), with
//! the gains of Hairer's DOPRI5 for the fifth-order pairs and of his DOP853
//! for the eighth-order one, and the loop that takes one accepted step with
//! it (`accepted_step`), so the way from one step's error to the next
//! step's size is written once.

use crate::{StepFailure, Tolerances};

/// Controller state: the logarithm of the last accepted step's error norm.
#[derive(Debug, Clone, Copy)]
pub struct PiController {
    log_error_previous: f64,
    gains: Gains,
}

/// The gains and bounds of a controller, by the order of the method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gains {
    /// Exponent of the current error norm.
    alpha: f64,
    /// Exponent of the previous accepted step's error norm.
    beta: f64,
    /// Smallest factor of the step size, accepted or rejected.
    smallest: f64,
    /// Largest growth factor after an accepted step.
    largest: f64,
}

impl Gains {
    /// Fifth-order pairs (Hairer's DOPRI5: beta 0.04, factors 0.2 to 10).
    pub const FIFTH_ORDER: Self = Self {
        alpha: ALPHA,
        beta: BETA,
        smallest: 0.2,
        largest: 10.0,
    };
    /// Fourth-order pairs (the fifth-order gains with the exponent 1/4
    /// of a third-order estimate).
    pub const FOURTH_ORDER: Self = Self {
        alpha: 0.25 - BETA * 0.75,
        beta: BETA,
        smallest: 0.2,
        largest: 10.0,
    };
    /// Eighth-order pairs (Hairer's DOP853 defaults: an integral controller
    /// with exponent 1/8, factors 1/3 to 6).
    pub const EIGHTH_ORDER: Self = Self {
        alpha: 1.0 / 8.0,
        beta: 0.0,
        smallest: 1.0 / 3.0,
        largest: 6.0,
    };
}

/// What the controller makes of one trial step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Judgement {
    /// Keep the step; the next one is `factor` times as long.
    Accept {
        /// Growth factor of the step.
        factor: f64,
    },
    /// Retry with a step `factor` (< 1) times as long.
    Reject {
        /// Shrink factor of the step.
        factor: f64,
    },
}

const SAFETY: f64 = 0.9;
const BETA: f64 = 0.04;
/// 1/5 for a method of order 5 (the embedded estimate's order plus one),
/// less the share the integral term takes.
const ALPHA: f64 = 0.2 - BETA * 0.75;
/// Floor of the remembered error norm (and its start): a step with a tiny
/// error does not let the next grow without bound.
const LOG_ERROR_FLOOR: f64 = -9.210_340_371_976_184; // ln 1e-4

impl Default for PiController {
    fn default() -> Self {
        Self::with_gains(Gains::FIFTH_ORDER)
    }
}

impl PiController {
    /// A controller with `gains` and no history.
    pub fn with_gains(gains: Gains) -> Self {
        Self {
            log_error_previous: LOG_ERROR_FLOOR,
            gains,
        }
    }

    /// Forgets the history, as after a discontinuity of the inputs.
    pub fn reset(&mut self) {
        *self = Self::with_gains(self.gains);
    }

    /// Judges a trial step from the mean square of its scaled error estimate
    /// (the square of the error norm: no square root on the way). After a
    /// rejection within the same step the step does not grow at once: a step
    /// at the stability limit would fail again.
    pub fn judge(&mut self, mean_square: f64, after_rejection: bool) -> Judgement {
        let Gains {
            alpha,
            beta,
            smallest,
            largest,
        } = self.gains;
        if mean_square <= 1.0 {
            // ln 0 = -inf is floored below.
            let log_error = 0.5 * mean_square.ln();
            let factor = if mean_square == 0.0 {
                largest
            } else {
                (SAFETY * (beta * self.log_error_previous - alpha * log_error).exp())
                    .clamp(smallest, largest)
            };
            let factor = if after_rejection {
                factor.min(1.0)
            } else {
                factor
            };
            self.log_error_previous = log_error.max(LOG_ERROR_FLOOR);
            Judgement::Accept { factor }
        } else if mean_square.is_finite() {
            Judgement::Reject {
                factor: (SAFETY * (-0.5 * alpha * mean_square.ln()).exp()).clamp(smallest, 1.0),
            }
        } else {
            Judgement::Reject { factor: 0.1 }
        }
    }
}

/// What the step loop reads and writes of a pair between its trials.
pub(crate) struct StepControl<'a> {
    /// Current time.
    pub t: f64,
    /// Suggested next step.
    pub h: &'a mut f64,
    pub tol: &'a Tolerances,
    pub controller: &'a mut PiController,
    /// The pair's count of rejected trials.
    pub rejected: &'a mut u64,
    /// The first state that was not finite in the last trial.
    pub non_finite: Option<usize>,
}

/// The [`StepControl`] of a pair whose step-size state has the usual field
/// names (`t`, `h`, `tol`, `controller`, `counts`, `non_finite`).
macro_rules! step_control {
    ($pair:expr) => {
        $crate::step_control::StepControl {
            t: $pair.t,
            h: &mut $pair.h,
            tol: &$pair.tol,
            controller: &mut $pair.controller,
            rejected: &mut $pair.counts.rejected,
            non_finite: $pair.non_finite,
        }
    };
}
pub(crate) use step_control;

/// An embedded Runge-Kutta pair, as the shared step loop drives it.
pub(crate) trait EmbeddedPair<S: ?Sized> {
    /// The pair's step-size state.
    fn control(&mut self) -> StepControl<'_>;
    /// One trial step of size `h`: the mean square of its scaled error
    /// estimate (infinite where not finite).
    fn trial(&mut self, system: &mut S, h: f64) -> f64;
    /// Moves to the trial's new point at `t_new`.
    fn advance(&mut self, system: &mut S, h: f64, t_new: f64);
}

/// Takes one accepted step of `pair`, not beyond `t_stop` (landing on it
/// exactly, not on t + (t_stop - t)). Rejected trials are retried with a
/// smaller step; a non-finite error estimate counts as a rejection.
pub(crate) fn accepted_step<S: ?Sized, P: EmbeddedPair<S>>(
    pair: &mut P,
    system: &mut S,
    t_stop: f64,
) -> Result<(), StepFailure> {
    let mut rejected = false;
    loop {
        let control = pair.control();
        let t = control.t;
        let Some((h, lands)) = control.tol.next_step(t, *control.h, t_stop) else {
            return Err(StepFailure::StepSizeUnderflow {
                t,
                h: control.h.min(control.tol.max_step),
                non_finite: control.non_finite,
            });
        };
        let mean_square = pair.trial(system, h);
        let control = pair.control();
        match control.controller.judge(mean_square, rejected) {
            Judgement::Accept { factor } => {
                pair.advance(system, h, if lands { t_stop } else { t + h });
                let control = pair.control();
                *control.h = Tolerances::suggestion_after(*control.h, h * factor, lands);
                return Ok(());
            }
            Judgement::Reject { factor } => {
                *control.rejected += 1;
                rejected = true;
                *control.h = h * factor;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_at_the_tolerance_keeps_the_step_near_its_size() {
        let mut controller = PiController::default();
        // Error norm 1 after a history at the floor: 0.9 * (1e-4)^0.04 = 0.62.
        let Judgement::Accept { factor } = controller.judge(1.0, false) else {
            panic!("an error norm of 1 is accepted");
        };
        assert!(
            (factor - 0.9 * 1e-4f64.powf(BETA)).abs() < 1e-12,
            "{factor}"
        );
        // An error 32x the tolerance (norm^2 = 1024) shrinks by 0.9 * 32^-0.17.
        let Judgement::Reject { factor } = controller.judge(1024.0, false) else {
            panic!("an error norm of 32 is rejected");
        };
        assert!(
            (factor - 0.9 * 32f64.powf(-ALPHA)).abs() < 1e-12,
            "{factor}"
        );
        assert_eq!(
            controller.judge(f64::NAN, false),
            Judgement::Reject { factor: 0.1 }
        );
        assert_eq!(
            controller.judge(1e-30, true),
            Judgement::Accept { factor: 1.0 }
        );
    }
}
