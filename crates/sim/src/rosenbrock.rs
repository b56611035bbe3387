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

use crate::dopri::{OdeSystem, StepCounts, StepFailure, Tolerances};

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

/// A system that also gives its Jacobian `df/dx`.
pub trait JacobianSystem: OdeSystem {
    /// `df/dx` at (t, x).
    fn jacobian(&mut self, t: f64, x: &[f64]) -> DMatrix<f64>;
}

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
    /// Counters (RHS evaluations include those inside Jacobians, one per column).
    pub counts: StepCounts,
    /// Jacobians computed.
    pub jacobians: u64,
}

impl Rosenbrock {
    /// Starts at (t0, x0) with a first step of a thousandth of `initial_span`.
    pub fn new(
        system: &mut dyn JacobianSystem,
        t0: f64,
        x0: &[f64],
        tol: Tolerances,
        initial_span: f64,
    ) -> Self {
        let n = system.dim();
        let mut integrator = Self {
            h: (initial_span * 1e-3).min(tol.max_step),
            tol,
            n,
            t: t0,
            x: x0.to_vec(),
            f: vec![0.0; n],
            jacobian: DMatrix::zeros(n, n),
            jacobian_age: JACOBIAN_REUSE,
            previous: (t0, 0.0, x0.to_vec(), vec![0.0; n]),
            counts: StepCounts::default(),
            jacobians: 0,
        };
        integrator.restart(system);
        integrator
    }

    /// Restarts at the current point after a discontinuity: new f and Jacobian.
    pub fn restart(&mut self, system: &mut dyn JacobianSystem) {
        system.rhs(self.t, &self.x, &mut self.f);
        self.counts.rhs_evaluations += 1;
        self.jacobian_age = JACOBIAN_REUSE;
    }

    fn refresh_jacobian(&mut self, system: &mut dyn JacobianSystem) {
        self.jacobian = system.jacobian(self.t, &self.x);
        self.jacobians += 1;
        self.counts.rhs_evaluations += self.n as u64;
        self.jacobian_age = 0;
    }

    fn error_norm(&self, x_new: &[f64], error: &DVector<f64>) -> f64 {
        let mut sum = 0.0;
        for i in 0..self.n {
            let scale = self.tol.atol[i] + self.tol.rtol * self.x[i].abs().max(x_new[i].abs());
            sum += (error[i] / scale).powi(2);
        }
        (sum / self.n as f64).sqrt()
    }

    /// The four stages of a step of length h: the new state and the error
    /// estimate, or None when `I - h gamma J` cannot be solved.
    fn stages(
        &mut self,
        system: &mut dyn JacobianSystem,
        h: f64,
    ) -> Option<(DVector<f64>, DVector<f64>)> {
        let n = self.n;
        let lu = (DMatrix::identity(n, n) - &self.jacobian * (h * GAMMA)).lu();
        let x = DVector::from_column_slice(&self.x);
        let mut stage = vec![0.0; n];
        let mut f_stage = vec![0.0; n];
        let mut evaluate = |t: f64, y: &DVector<f64>| {
            stage.copy_from_slice(y.as_slice());
            system.rhs(t, &stage, &mut f_stage);
            DVector::from_column_slice(&f_stage)
        };
        let j = &self.jacobian;
        let k1 = lu.solve(&(DVector::from_column_slice(&self.f) * h))?;
        let f2 = evaluate(self.t + C2 * h, &(&x + &k1 * A21));
        let k2 = lu.solve(&(f2 * h + j * (&k1 * (G21 * h))))?;
        let f3 = evaluate(self.t + C3 * h, &(&x + &k1 * A31 + &k2 * A32));
        let k3 = lu.solve(&(f3 * h + j * ((&k1 * G31 + &k2 * G32) * h)))?;
        let f4 = evaluate(self.t + h, &(&x + &k3));
        let k4 = lu.solve(&(f4 * h + j * ((&k1 * G41 + &k2 * G42 + &k3 * G43) * h)))?;
        self.counts.rhs_evaluations += 3;
        let mut x_new = x;
        let mut error = DVector::zeros(n);
        for (i, k) in [k1, k2, k3, k4].iter().enumerate() {
            x_new += k * B[i];
            error += k * (B[i] - B_EMBEDDED[i]);
        }
        Some((x_new, error))
    }

    /// Takes one accepted step, not beyond `t_stop`.
    pub fn step(
        &mut self,
        system: &mut dyn JacobianSystem,
        t_stop: f64,
    ) -> Result<(), StepFailure> {
        let n = self.n;
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
            let Some((x_new, error)) = self.stages(system, h) else {
                // I - h gamma J is singular at this step: try a shorter one.
                self.counts.rejected += 1;
                self.h = h * 0.25;
                continue;
            };
            let norm = self.error_norm(x_new.as_slice(), &error);
            if norm.is_finite() && norm <= 1.0 {
                let mut f_new = vec![0.0; n];
                system.rhs(self.t + h, x_new.as_slice(), &mut f_new);
                self.counts.rhs_evaluations += 1;
                let t_new = if lands { t_stop } else { self.t + h };
                self.previous = (
                    self.t,
                    h,
                    std::mem::replace(&mut self.x, x_new.as_slice().to_vec()),
                    std::mem::replace(&mut self.f, f_new),
                );
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
            // A rejection may come from a stale Jacobian: refresh it.
            self.jacobian_age = JACOBIAN_REUSE;
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
