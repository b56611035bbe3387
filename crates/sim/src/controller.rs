//! The step-size controller of the embedded fifth-order pairs (Dormand-Prince
//! and the implicit-explicit pair): a PI controller on the logarithm of the
//! scaled error norm (Gustafsson; the constants of Hairer's DOPRI5), so the
//! way from one step's error to the next step's size is written once.

/// Controller state: the logarithm of the last accepted step's error norm.
#[derive(Debug, Clone, Copy)]
pub struct PiController {
    log_error_previous: f64,
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
        Self {
            log_error_previous: LOG_ERROR_FLOOR,
        }
    }
}

impl PiController {
    /// Forgets the history, as after a discontinuity of the inputs.
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Judges a trial step from the mean square of its scaled error estimate
    /// (the square of the error norm: no square root on the way). After a
    /// rejection within the same step the step does not grow at once: a step
    /// at the stability limit would fail again.
    pub fn judge(&mut self, mean_square: f64, after_rejection: bool) -> Judgement {
        if mean_square <= 1.0 {
            // ln 0 = -inf is floored below.
            let log_error = 0.5 * mean_square.ln();
            let factor = if mean_square == 0.0 {
                10.0
            } else {
                (SAFETY * (BETA * self.log_error_previous - ALPHA * log_error).exp())
                    .clamp(0.2, 10.0)
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
                factor: (SAFETY * (-0.5 * ALPHA * mean_square.ln()).exp()).clamp(0.2, 1.0),
            }
        } else {
            Judgement::Reject { factor: 0.1 }
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
