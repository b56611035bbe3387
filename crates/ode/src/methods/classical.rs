//! The classical fourth-order Runge-Kutta method with an embedded
//! third-order estimate that costs nothing: the derivative at the new point
//! (the next step's first stage) takes the fourth stage's place in the
//! weights, `y_hat = y + h/6 (k1 + 2 k2 + 2 k3 + k5)`, a third-order
//! solution, so the error estimate is `h/6 (k4 - k5)`. Four evaluations a
//! step, the PI step-size controller of [`crate::step_control`] with
//! fourth-order gains, cubic Hermite dense output from the values and
//! derivatives at both ends of a step.
//!
//! Where it pays: loose tolerances on stages with lightly damped stiff
//! oscillations (the stiff directions of a 6-DOF table's isolator bushings).
//! There the step is set by those modes, not by the smooth motion: along
//! eigenvalues of 2 % damping the classical method is stable up to
//! `h |lambda| = 2.87`, Dormand-Prince 5(4) up to 2.08, and in practice both
//! error estimates hold the step near `h |lambda| = 2`, where the classical
//! method spends four evaluations a step against six.

use crate::hermite::HermiteStep;
use crate::method::{AdaptiveMethod, MethodState};
use crate::sized::{state_count, with_state_count};
use crate::step_control::{
    EmbeddedPair, Gains, PiController, StepControl, accepted_step, step_control,
};
use crate::tolerances::first_step;
use crate::{Checkpoint, OdeSystem, StepCounts, StepFailure, Tolerances};

/// The integrator between steps.
pub struct ClassicalRungeKutta {
    tol: Tolerances,
    n: usize,
    /// Current time.
    pub t: f64,
    /// Current state.
    pub x: Vec<f64>,
    /// Suggested next step.
    pub h: f64,
    /// Stages: slot 0 holds f at the current point, slots 1 to 3 a trial
    /// step's second to fourth stages, slot 4 f at its new point.
    k: [Vec<f64>; 5],
    stage: Vec<f64>,
    x_new: Vec<f64>,
    /// Dense output of the last accepted step.
    dense: HermiteStep,
    controller: PiController,
    /// Counters.
    pub counts: StepCounts,
    non_finite: Option<usize>,
}

impl<S: OdeSystem + ?Sized> AdaptiveMethod<S> for ClassicalRungeKutta {
    fn unstarted(system: &S, start: &Checkpoint, tol: Tolerances) -> Self {
        let n = system.dim();
        let zeros = || vec![0.0; n];
        Self {
            tol,
            n,
            t: start.t,
            x: start.x.clone(),
            h: start.h,
            k: std::array::from_fn(|_| zeros()),
            stage: zeros(),
            x_new: zeros(),
            dense: HermiteStep::new(start.t, &start.x),
            controller: PiController::with_gains(Gains::FOURTH_ORDER),
            counts: start.counts,
            non_finite: None,
        }
    }

    fn start(&mut self, system: &mut S) {
        self.h = first_step(
            system,
            self.t,
            &self.x,
            &self.tol,
            4.0,
            &mut self.k[0],
            &mut self.stage,
            &mut self.x_new,
            &mut self.counts,
        );
    }

    /// The dense output of the last step is kept.
    fn restart(&mut self, system: &mut S) {
        self.dense.keep_end(&mut self.k[0]);
        system.rhs(self.t, &self.x, &mut self.k[0]);
        self.counts.rhs_evaluations += 1;
        self.controller.reset();
    }

    fn step(&mut self, system: &mut S, t_stop: f64) -> Result<(), StepFailure> {
        accepted_step(self, system, t_stop)
    }

    fn interpolate(&mut self, _system: &mut S, t: f64, out: &mut [f64]) {
        ClassicalRungeKutta::interpolate(self, t, out);
    }
}

impl MethodState for ClassicalRungeKutta {
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

impl ClassicalRungeKutta {
    /// The trial step ([`EmbeddedPair::trial`]) over `N` states (`N` = 0, `DYNAMIC`: `self.n`).
    #[inline(always)]
    fn attempt_sized<const N: usize, S: OdeSystem + ?Sized>(
        &mut self,
        system: &mut S,
        h: f64,
    ) -> f64 {
        let (t, n) = (self.t, state_count::<N>(self.n));
        let [k1, k2, k3, k4, k5] = &mut self.k;
        let (k1, k2, k3, k4, k5) = (
            &mut k1[..n],
            &mut k2[..n],
            &mut k3[..n],
            &mut k4[..n],
            &mut k5[..n],
        );
        let x = &self.x[..n];
        let stage = &mut self.stage[..n];
        let half = 0.5 * h;
        for i in 0..n {
            stage[i] = x[i] + half * k1[i];
        }
        system.rhs(t + half, stage, k2);
        for i in 0..n {
            stage[i] = x[i] + half * k2[i];
        }
        system.rhs(t + half, stage, k3);
        for i in 0..n {
            stage[i] = x[i] + h * k3[i];
        }
        system.rhs(t + h, stage, k4);
        let x_new = &mut self.x_new[..n];
        let sixth = h / 6.0;
        for i in 0..n {
            x_new[i] = x[i] + sixth * ((k1[i] + k4[i]) + 2.0 * (k2[i] + k3[i]));
        }
        system.rhs(t + h, x_new, k5);
        self.counts.rhs_evaluations += 4;
        let atol = &self.tol.atol[..n];
        let mut sum = -0.0;
        for i in 0..n {
            let e = sixth * (k4[i] - k5[i]);
            let scale = atol[i] + self.tol.rtol * x[i].abs().max(x_new[i].abs());
            sum += (e / scale) * (e / scale);
        }
        let mean_square = sum / n as f64;
        if mean_square.is_finite() {
            self.non_finite = None;
            mean_square
        } else {
            self.non_finite = (0..n).find(|&i| !x_new[i].is_finite() || !k5[i].is_finite());
            f64::INFINITY
        }
    }

    /// The state at `t` inside the last accepted step: cubic Hermite from
    /// the values and derivatives at both ends.
    pub fn interpolate(&self, t: f64, out: &mut [f64]) {
        self.dense
            .interpolate(&self.x, &self.k[0], t, &mut out[..self.n]);
    }

    /// Start time of the last accepted step.
    pub fn previous_time(&self) -> f64 {
        self.dense.start_time()
    }
}

impl<S: OdeSystem + ?Sized> EmbeddedPair<S> for ClassicalRungeKutta {
    fn control(&mut self) -> StepControl<'_> {
        step_control!(self)
    }

    /// One trial step of size h into `x_new` (with f there in slot 4); the
    /// mean square of the scaled error estimate. Small systems take a copy
    /// whose length is a compile-time constant, as in [`crate::DormandPrince`].
    fn trial(&mut self, system: &mut S, h: f64) -> f64 {
        with_state_count!(self.n, self.attempt_sized(system, h))
    }

    /// Moves to the new point; f there (slot 4) becomes the first stage.
    fn advance(&mut self, _system: &mut S, h: f64, t_new: f64) {
        self.dense.begin(self.t, h, &mut self.x, &mut self.k[0]);
        std::mem::swap(&mut self.x, &mut self.x_new);
        self.k.swap(0, 4);
        self.t = t_new;
        self.counts.steps += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::dormand_prince::tests::{Oscillator, oscillator_tolerances};

    fn run(rtol: f64) -> (f64, f64, StepCounts) {
        let w = 2.0 * std::f64::consts::PI;
        let mut system = Oscillator { w };
        let tol = oscillator_tolerances(rtol);
        let mut rk = ClassicalRungeKutta::new(&mut system, 0.0, &[1.0, 0.0], tol);
        let (mut worst_dense, mut out) = (0.0_f64, [0.0; 2]);
        while rk.t < 3.0 {
            rk.step(&mut system, 3.0).expect("step");
            let mid = 0.5 * (rk.previous_time() + rk.t);
            rk.interpolate(mid, &mut out);
            worst_dense = worst_dense.max((out[0] - (w * mid).cos()).abs());
        }
        let end = (rk.x[0] - (w * 3.0).cos()).abs();
        (end, worst_dense, rk.counts)
    }

    #[test]
    fn converges_at_fourth_order_with_error_control() {
        let (coarse, coarse_dense, coarse_counts) = run(1e-6);
        let (fine, fine_dense, fine_counts) = run(1e-10);
        assert!(coarse < 2e-5 && fine < 2e-9, "{coarse} {fine}");
        assert!(
            coarse_dense < 1e-4 && fine_dense < 1e-8,
            "{coarse_dense} {fine_dense}"
        );
        // 10^4 tighter costs about 10^(4/4) = 10x the steps at fourth order
        // (a fifth-order method 6.3x, a third-order one 22x).
        let ratio = fine_counts.steps as f64 / coarse_counts.steps as f64;
        assert!((7.0..14.0).contains(&ratio), "step ratio {ratio}");
        assert_eq!(
            fine_counts.rhs_evaluations,
            2 + 4 * (fine_counts.steps + fine_counts.rejected)
        );
    }

    #[test]
    fn on_a_lightly_damped_stiff_mode_it_takes_fewer_evaluations_than_dormand_prince() {
        // A mode of 2 % damping at 1e4 rad/s following a slow force: the
        // solution is the force's quasi-static deflection, which a loose
        // tolerance would take in long steps; the stiff mode holds both
        // methods' steps near h w = 2 (the classical method is stable up to
        // 2.87, Dormand-Prince 5(4) up to 2.08).
        struct Mode;
        impl OdeSystem for Mode {
            fn dim(&self) -> usize {
                2
            }
            fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
                let w = 1e4;
                dx[0] = x[1];
                dx[1] = w * w * ((10.0 * t).sin() - x[0]) - 2.0 * 0.02 * w * x[1];
            }
        }
        let tol = || Tolerances {
            rtol: 1e-3,
            atol: vec![1e-3; 2],
            max_step: f64::INFINITY,
            min_step_relative: 1e-14,
        };
        let x0 = [0.0, 0.0];
        let mut rk = ClassicalRungeKutta::new(&mut Mode, 0.0, &x0, tol());
        while rk.t < 0.1 {
            rk.step(&mut Mode, 0.1).expect("step");
        }
        let mut dp = crate::DormandPrince::new(&mut Mode, 0.0, &x0, tol());
        while dp.t < 0.1 {
            dp.step(&mut Mode, 0.1).expect("step");
        }
        let (rk_evaluations, dp_evaluations) =
            (rk.counts.rhs_evaluations, dp.counts.rhs_evaluations);
        println!("classical {:?}, Dormand-Prince {:?}", rk.counts, dp.counts);
        assert!((rk.x[0] - 1.0f64.sin()).abs() < 1e-2, "{}", rk.x[0]);
        // Steps of h w between 1 and 2.87 (0.1 s * w / 2.87 = 348 steps).
        assert!((348..1000).contains(&rk.counts.steps), "{:?}", rk.counts);
        assert!((rk_evaluations as f64) < 0.8 * dp_evaluations as f64);
    }
}
