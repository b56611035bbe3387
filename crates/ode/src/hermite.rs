//! Cubic Hermite dense output of the last accepted step, from the states and
//! derivatives at both of its ends: the dense output of the pairs whose
//! first stage is the derivative at a step's start (the implicit-explicit
//! pair and the classical method), kept through restarts.

/// The start of the last accepted step and where its end's derivative is.
pub(crate) struct HermiteStep {
    t_start: f64,
    h: f64,
    x_start: Vec<f64>,
    f_start: Vec<f64>,
    /// The derivative at the step's end, once a restart has put the
    /// derivative under the new inputs in the pair's first-stage slot.
    f_end: Vec<f64>,
    end_in_first_stage: bool,
}

impl HermiteStep {
    /// No step yet: the dense output is the state `x0` at `t0`.
    pub(crate) fn new(t0: f64, x0: &[f64]) -> Self {
        Self {
            t_start: t0,
            h: 0.0,
            x_start: x0.to_vec(),
            f_start: vec![0.0; x0.len()],
            f_end: vec![0.0; x0.len()],
            end_in_first_stage: true,
        }
    }

    /// Before a restart overwrites the pair's first stage: keeps the end
    /// derivative of the last step.
    pub(crate) fn keep_end(&mut self, first_stage: &mut Vec<f64>) {
        if self.end_in_first_stage {
            std::mem::swap(&mut self.f_end, first_stage);
            self.end_in_first_stage = false;
        }
    }

    /// A step of size `h` from the current point (`t`, `x`, with the
    /// derivative in `first_stage`) was accepted: that point becomes the
    /// start, and the buffers handed back hold nothing of use. The pair then
    /// puts the new point in `x` and its derivative in `first_stage`.
    pub(crate) fn begin(&mut self, t: f64, h: f64, x: &mut Vec<f64>, first_stage: &mut Vec<f64>) {
        std::mem::swap(&mut self.x_start, x);
        std::mem::swap(&mut self.f_start, first_stage);
        self.t_start = t;
        self.h = h;
        self.end_in_first_stage = true;
    }

    /// The state at `t` inside the step that ends at `x_end` (the pair's
    /// first stage holds the derivative there unless a restart moved it).
    pub(crate) fn interpolate(&self, x_end: &[f64], first_stage: &[f64], t: f64, out: &mut [f64]) {
        let f_end = if self.end_in_first_stage {
            first_stage
        } else {
            &self.f_end
        };
        let s = if self.h > 0.0 {
            ((t - self.t_start) / self.h).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let (h00, h10, h01, h11) = (
            (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s),
            s * (1.0 - s) * (1.0 - s),
            s * s * (3.0 - 2.0 * s),
            s * s * (s - 1.0),
        );
        let h = self.h;
        for m in 0..out.len() {
            out[m] = h00 * self.x_start[m]
                + h * h10 * self.f_start[m]
                + h01 * x_end[m]
                + h * h11 * f_end[m];
        }
    }

    /// Start time of the last accepted step.
    pub(crate) fn start_time(&self) -> f64 {
        self.t_start
    }
}
