//! ROS34PW2 (Rang and Angermann, 2005): a linearly implicit Rosenbrock-W
//! method with 4 stages, order 3 and an embedded order-2 solution, L-stable,
//! and tolerant of an inexact or lagged Jacobian (a W-method), which lets the
//! exact Jacobian be reused over several steps. Each step solves four linear
//! systems with `I - h gamma J` instead of resolving stiff modes with tiny
//! explicit steps. Dense output is the cubic Hermite polynomial through both
//! ends of the step (f at the new point is the next step's first stage).
//!
//! Stage equations (non-autonomous terms omitted, as for a W-method):
//! `(I - h gamma J) k_i = h f(x + sum_j a_ij k_j) + h J sum_j g_ij k_j`,
//! `x_new = x + sum_i b_i k_i`, error `sum_i (b_i - bhat_i) k_i`.

// The coefficients are quoted to the digits the method was published with.
#![allow(clippy::excessive_precision)]

use nalgebra::{DMatrix, DVector};

use crate::method::{AdaptiveMethod, MethodState};
use crate::{Checkpoint, JacobianSystem, StepCounts, StepFailure, Tolerances, starting_step};

const GAMMA: f64 = 4.358_665_215_084_59e-1;
const A21: f64 = 8.717_330_430_169_180_1e-1;
const A31: f64 = 8.445_706_001_536_942_3e-1;
const A32: f64 = -1.129_906_423_648_418_5e-1;
const G21: f64 = -8.717_330_430_169_180_1e-1;
const G31: f64 = -9.033_805_701_304_408_2e-1;
const G32: f64 = 5.418_067_238_809_532_6e-2;
const G41: f64 = 2.421_238_070_609_534_6e-1;
const G42: f64 = -1.223_250_583_904_514_7;
const G43: f64 = 5.452_602_553_351_021_4e-1;
const B: [f64; 4] = [
    2.421_238_070_609_534_6e-1,
    -1.223_250_583_904_514_7,
    1.545_260_255_335_102,
    4.358_665_215_084_59e-1,
];
const B_EMBEDDED: [f64; 4] = [
    3.781_090_314_581_936_9e-1,
    -9.604_229_221_242_317_8e-2,
    0.5,
    2.179_332_607_542_295e-1,
];
const C2: f64 = A21;
const C3: f64 = A31 + A32;

/// Accepted steps over which one Jacobian is reused.
const JACOBIAN_REUSE: u32 = 16;

/// The integrator's state between steps.
pub struct Rosenbrock {
    tol: Tolerances,
    n: usize,
    /// Current time.
    pub t: f64,
    /// Current state.
    pub x: Vec<f64>,
    /// Suggested next step.
    pub h: f64,
    f: Vec<f64>,
    jacobian: DMatrix<f64>,
    jacobian_age: u32,
    previous: (f64, f64, Vec<f64>, Vec<f64>),
    buffers: StageBuffers,
    /// Counters (RHS evaluations include those inside Jacobians, one per column).
    pub counts: StepCounts,
    /// Jacobians computed.
    pub jacobians: u64,
    /// The span whose thousandth is the first step, where the caller knows
    /// one (see [`Rosenbrock::with_initial_span`]).
    initial_span: Option<f64>,
}

impl<S: JacobianSystem + ?Sized> AdaptiveMethod<S> for Rosenbrock {
    fn unstarted(system: &S, start: &Checkpoint, tol: Tolerances) -> Self {
        let n = system.dim();
        Self {
            h: start.h,
            tol,
            n,
            t: start.t,
            x: start.x.clone(),
            f: vec![0.0; n],
            jacobian: DMatrix::zeros(n, n),
            jacobian_age: JACOBIAN_REUSE,
            previous: (start.t, 0.0, start.x.clone(), vec![0.0; n]),
            buffers: StageBuffers::new(n),
            counts: start.counts,
            jacobians: 0,
            initial_span: None,
        }
    }

    /// The first step is a thousandth of the initial span where one was
    /// given, else Hairer's starting step for a third-order method.
    fn start(&mut self, system: &mut S) {
        match self.initial_span {
            Some(span) => {
                self.h = (span * 1e-3).min(self.tol.max_step);
                self.restart(system);
            }
            None => {
                self.restart(system);
                let (h, evaluations) = starting_step(
                    system,
                    self.t,
                    &self.x,
                    &self.f,
                    &self.tol,
                    3.0,
                    self.buffers.y.as_mut_slice(),
                    &mut self.buffers.x_new,
                );
                self.h = h;
                self.counts.rhs_evaluations += evaluations;
            }
        }
    }

    /// Restarts at the current point after a discontinuity: new f and Jacobian.
    fn restart(&mut self, system: &mut S) {
        system.rhs(self.t, &self.x, &mut self.f);
        self.counts.rhs_evaluations += 1;
        self.jacobian_age = JACOBIAN_REUSE;
    }

    fn step(&mut self, system: &mut S, t_stop: f64) -> Result<(), StepFailure> {
        self.accepted_step(system, t_stop)
    }

    fn interpolate(&mut self, _system: &mut S, t: f64, out: &mut [f64]) {
        Rosenbrock::interpolate(self, t, out);
    }
}

impl MethodState for Rosenbrock {
    fn time(&self) -> f64 {
        self.t
    }

    fn state(&self) -> &[f64] {
        &self.x
    }

    fn proposed_step(&self) -> f64 {
        self.h
    }

    fn counts(&self) -> StepCounts {
        self.counts
    }
}

impl Rosenbrock {
    /// Starts at (t0, x0) with a first step of a thousandth of
    /// `initial_span` (e.g. the sampling interval).
    pub fn with_initial_span<S: JacobianSystem + ?Sized>(
        system: &mut S,
        t0: f64,
        x0: &[f64],
        tol: Tolerances,
        initial_span: f64,
    ) -> Self {
        let start = Checkpoint {
            t: t0,
            x: x0.to_vec(),
            h: 0.0,
            counts: StepCounts::default(),
        };
        let mut integrator = Self::unstarted(system, &start, tol);
        integrator.initial_span = Some(initial_span);
        integrator.start(system);
        integrator
    }

    fn refresh_jacobian<S: JacobianSystem + ?Sized>(&mut self, system: &mut S) {
        self.jacobian = system.jacobian(self.t, &self.x);
        self.jacobians += 1;
        self.counts.rhs_evaluations += self.n as u64;
        self.jacobian_age = 0;
    }

    fn error_norm(&self) -> f64 {
        let (x_new, error) = (&self.buffers.x_new, &self.buffers.error);
        let mut sum = 0.0;
        for i in 0..self.n {
            let scale = self.tol.atol[i] + self.tol.rtol * self.x[i].abs().max(x_new[i].abs());
            sum += (error[i] / scale).powi(2);
        }
        (sum / self.n as f64).sqrt()
    }

    /// The four stages of a step of length h, leaving the new state and the
    /// error estimate in the buffers; false when `I - h gamma J` cannot be
    /// solved.
    fn stages<S: JacobianSystem + ?Sized>(&mut self, system: &mut S, h: f64) -> bool {
        let n = self.n;
        let buffers = &mut self.buffers;
        buffers.w.copy_from(&self.jacobian);
        buffers.w *= -h * GAMMA;
        for i in 0..n {
            buffers.w[(i, i)] += 1.0;
        }
        let lu = buffers.w.clone().lu();
        // Stage i: (I - h gamma J) k_i = h f(x + sum_j a_ij k_j) + J (h sum_j g_ij k_j).
        let stage_times = [self.t, self.t + C2 * h, self.t + C3 * h, self.t + h];
        let a: [&[f64]; 4] = [&[], &[A21], &[A31, A32], &[0.0, 0.0, 1.0]];
        let g: [&[f64]; 4] = [&[], &[G21], &[G31, G32], &[G41, G42, G43]];
        for stage in 0..4 {
            let (done, rest) = buffers.k.split_at_mut(stage);
            let k = &mut rest[0];
            if stage == 0 {
                k.as_mut_slice().copy_from_slice(&self.f);
            } else {
                for i in 0..n {
                    buffers.y[i] = self.x[i]
                        + a[stage]
                            .iter()
                            .zip(done.iter())
                            .map(|(a, k)| a * k[i])
                            .sum::<f64>();
                }
                system.rhs(stage_times[stage], buffers.y.as_slice(), k.as_mut_slice());
            }
            *k *= h;
            if stage > 0 {
                for i in 0..n {
                    buffers.y[i] = h * g[stage]
                        .iter()
                        .zip(done.iter())
                        .map(|(g, k)| g * k[i])
                        .sum::<f64>();
                }
                k.gemv(1.0, &self.jacobian, &buffers.y, 1.0);
            }
            if !lu.solve_mut(k) {
                return false;
            }
        }
        self.counts.rhs_evaluations += 3;
        for i in 0..n {
            let (mut step, mut error) = (0.0, 0.0);
            for (s, k) in buffers.k.iter().enumerate() {
                step += B[s] * k[i];
                error += (B[s] - B_EMBEDDED[s]) * k[i];
            }
            buffers.x_new[i] = self.x[i] + step;
            buffers.error[i] = error;
        }
        true
    }

    /// One accepted step, not beyond `t_stop`: the W-method's own step
    /// loop (its step-size rule and its rejections on a singular
    /// iteration matrix are not the embedded pairs').
    fn accepted_step<S: JacobianSystem + ?Sized>(
        &mut self,
        system: &mut S,
        t_stop: f64,
    ) -> Result<(), StepFailure> {
        loop {
            let Some((h, lands)) = self.tol.next_step(self.t, self.h, t_stop) else {
                return Err(StepFailure::StepSizeUnderflow {
                    t: self.t,
                    h: self.h.min(self.tol.max_step),
                    non_finite: self.x.iter().position(|v| !v.is_finite()),
                });
            };
            if self.jacobian_age >= JACOBIAN_REUSE {
                self.refresh_jacobian(system);
            }
            if !self.stages(system, h) {
                // I - h gamma J is singular at this step: try a shorter one.
                self.counts.rejected += 1;
                self.h = h * 0.25;
                continue;
            }
            let norm = self.error_norm();
            if norm.is_finite() && norm <= 1.0 {
                // The old point becomes the start of the dense output, the
                // new one the current state.
                self.previous.0 = self.t;
                self.previous.1 = h;
                std::mem::swap(&mut self.previous.2, &mut self.x);
                std::mem::swap(&mut self.previous.3, &mut self.f);
                self.x.copy_from_slice(&self.buffers.x_new);
                system.rhs(self.t + h, &self.x, &mut self.f);
                self.counts.rhs_evaluations += 1;
                let t_new = if lands { t_stop } else { self.t + h };
                self.t = t_new;
                self.counts.steps += 1;
                self.jacobian_age += 1;
                let factor = if norm == 0.0 {
                    5.0
                } else {
                    (0.9 * norm.powf(-1.0 / 3.0)).clamp(0.2, 5.0)
                };
                self.h = Tolerances::suggestion_after(self.h, h * factor, lands);
                return Ok(());
            }
            self.counts.rejected += 1;
            // A rejection may come from a stale Jacobian: refresh it, unless
            // it was taken at this very point (it would come out the same).
            if self.jacobian_age > 0 {
                self.jacobian_age = JACOBIAN_REUSE;
            }
            let factor = if norm.is_finite() {
                (0.9 * norm.powf(-1.0 / 3.0)).clamp(0.1, 0.9)
            } else {
                0.1
            };
            self.h = h * factor;
        }
    }

    /// State at time `t` inside the last accepted step (cubic Hermite).
    pub fn interpolate(&self, t: f64, out: &mut [f64]) {
        let (t0, h, x0, f0) = &self.previous;
        if *h <= 0.0 {
            out.copy_from_slice(&self.x);
            return;
        }
        let theta = ((t - t0) / h).clamp(0.0, 1.0);
        let (x1, f1) = (&self.x, &self.f);
        let h00 = (1.0 + 2.0 * theta) * (1.0 - theta) * (1.0 - theta);
        let h10 = theta * (1.0 - theta) * (1.0 - theta);
        let h01 = theta * theta * (3.0 - 2.0 * theta);
        let h11 = theta * theta * (theta - 1.0);
        for i in 0..self.n {
            out[i] = h00 * x0[i] + h * h10 * f0[i] + h01 * x1[i] + h * h11 * f1[i];
        }
    }
}

/// Scratch space of one step, allocated once.
struct StageBuffers {
    /// `I - h gamma J`.
    w: DMatrix<f64>,
    k: [DVector<f64>; 4],
    y: DVector<f64>,
    x_new: Vec<f64>,
    error: Vec<f64>,
}

impl StageBuffers {
    fn new(n: usize) -> Self {
        Self {
            w: DMatrix::zeros(n, n),
            k: std::array::from_fn(|_| DVector::zeros(n)),
            y: DVector::zeros(n),
            x_new: vec![0.0; n],
            error: vec![0.0; n],
        }
    }
}
