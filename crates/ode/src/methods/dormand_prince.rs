//! Dormand-Prince 5(4): an explicit embedded Runge-Kutta pair with the FSAL
//! property, a PI step-size controller and Hairer's fourth-order continuous
//! extension for dense output.

use crate::method::{AdaptiveMethod, MethodState};
use crate::sized::{state_count, with_state_count};
use crate::step_control::{EmbeddedPair, PiController, StepControl, accepted_step, step_control};
use crate::tolerances::first_step;
use crate::{Checkpoint, OdeSystem, StepCounts, StepFailure, Tolerances};

const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// The integrator's state between steps, including the stages of the last
/// accepted step (its dense output).
pub struct DormandPrince {
    tol: Tolerances,
    n: usize,
    /// Current time.
    pub t: f64,
    /// Current state.
    pub x: Vec<f64>,
    /// Suggested next step.
    pub h: f64,
    k: [Vec<f64>; 7],
    x_new: Vec<f64>,
    stage: Vec<f64>,
    /// Where the last stage of the last accepted step is kept (0, or 1 after
    /// a restart put the new first stage in slot 0).
    last_stage_slot: usize,
    t_previous: f64,
    h_previous: f64,
    controller: PiController,
    /// Counters.
    pub counts: StepCounts,
    non_finite: Option<usize>,
}

impl<S: OdeSystem + ?Sized> AdaptiveMethod<S> for DormandPrince {
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
            x_new: zeros(),
            stage: zeros(),
            last_stage_slot: 0,
            t_previous: start.t,
            h_previous: 0.0,
            controller: PiController::default(),
            counts: start.counts,
            non_finite: None,
        }
    }

    /// Evaluates f once and picks the first step with Hairer's heuristic
    /// ([`crate::starting_step`]).
    fn start(&mut self, system: &mut S) {
        let (first, rest) = self.k.split_at_mut(1);
        self.h = first_step(
            system,
            self.t,
            &self.x,
            &self.tol,
            5.0,
            &mut first[0],
            &mut self.stage,
            &mut rest[0],
            &mut self.counts,
        );
    }

    fn restart(&mut self, system: &mut S) {
        // Slot 1 (the second stage) is free between steps: the new first
        // stage goes there and the last step's last stage, which the dense
        // output still needs, moves out of slot 0.
        system.rhs(self.t, &self.x, &mut self.k[1]);
        self.k.swap(0, 1);
        self.last_stage_slot = 1;
        self.counts.rhs_evaluations += 1;
        self.controller.reset();
    }

    fn step(&mut self, system: &mut S, t_stop: f64) -> Result<(), StepFailure> {
        accepted_step(self, system, t_stop)
    }

    fn interpolate(&mut self, _system: &mut S, t: f64, out: &mut [f64]) {
        DormandPrince::interpolate(self, t, out);
    }
}

impl MethodState for DormandPrince {
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

impl DormandPrince {
    /// The trial step ([`EmbeddedPair::trial`]) over `N` states (`N` = 0, `DYNAMIC`: `self.n`).
    #[inline(always)]
    fn attempt_sized<const N: usize, S: OdeSystem + ?Sized>(
        &mut self,
        system: &mut S,
        h: f64,
    ) -> f64 {
        let (t, n) = (self.t, state_count::<N>(self.n));
        let [k1, k2, k3, k4, k5, k6, k7] = &mut self.k;
        // Slices of exactly n entries: the loops below need no bounds checks.
        let (k1, k2, k3, k4, k5, k6, k7) = (
            &mut k1[..n],
            &mut k2[..n],
            &mut k3[..n],
            &mut k4[..n],
            &mut k5[..n],
            &mut k6[..n],
            &mut k7[..n],
        );
        let x = &self.x[..n];
        let atol = &self.tol.atol[..n];
        let stage = &mut self.stage[..n];
        for i in 0..n {
            stage[i] = x[i] + h * A21 * k1[i];
        }
        system.rhs(t + C2 * h, stage, k2);
        for i in 0..n {
            stage[i] = x[i] + h * (A31 * k1[i]) + (h * A32) * k2[i];
        }
        system.rhs(t + C3 * h, stage, k3);
        for i in 0..n {
            stage[i] = x[i] + h * (A41 * k1[i] + A42 * k2[i]) + (h * A43) * k3[i];
        }
        system.rhs(t + C4 * h, stage, k4);
        for i in 0..n {
            stage[i] = x[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i]) + (h * A54) * k4[i];
        }
        system.rhs(t + C5 * h, stage, k5);
        for i in 0..n {
            stage[i] = x[i]
                + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i])
                + (h * A65) * k5[i];
        }
        system.rhs(t + h, stage, k6);
        let x_new = &mut self.x_new[..n];
        for i in 0..n {
            x_new[i] = x[i]
                + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i])
                + (h * A76) * k6[i];
        }
        system.rhs(t + h, x_new, k7);
        self.counts.rhs_evaluations += 6;
        // -0.0: the exact additive identity, so the first addition folds away.
        let mut sum = -0.0;
        for i in 0..n {
            let e = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i])
                + (h * E7) * k7[i];
            let sc = atol[i] + self.tol.rtol * x[i].abs().max(x_new[i].abs());
            sum += (e / sc) * (e / sc);
        }
        let mean_square = sum / n as f64;
        if mean_square.is_finite() {
            self.non_finite = None;
            mean_square
        } else {
            self.non_finite = (0..n).find(|&i| !x_new[i].is_finite() || !k7[i].is_finite());
            f64::INFINITY
        }
    }

    /// State at time `t` inside the last accepted step, written into `out`:
    /// Hairer's fourth-order continuous extension.
    pub fn interpolate(&self, t: f64, out: &mut [f64]) {
        let h = self.h_previous;
        let theta = if h > 0.0 {
            ((t - self.t_previous) / h).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let theta1 = 1.0 - theta;
        let n = self.n;
        let (x_old, x) = (&self.x_new[..n], &self.x[..n]);
        let k1 = &self.k[6][..n];
        let [k3, k4, k5, k6] = [&self.k[2], &self.k[3], &self.k[4], &self.k[5]];
        let k7 = &self.k[self.last_stage_slot][..n];
        for i in 0..n {
            let dy = x[i] - x_old[i];
            let bspl = h * k1[i] - dy;
            let r4 = dy - h * k7[i] - bspl;
            let r5 =
                h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i]);
            out[i] = x_old[i] + theta * (dy + theta1 * (bspl + theta * (r4 + theta1 * r5)));
        }
    }

    /// Start time of the last accepted step.
    pub fn previous_time(&self) -> f64 {
        self.t_previous
    }
}

impl<S: OdeSystem + ?Sized> EmbeddedPair<S> for DormandPrince {
    fn control(&mut self) -> StepControl<'_> {
        step_control!(self)
    }

    /// One trial step of size h; returns the mean square of the scaled
    /// error estimate (the square of the error norm). Small systems
    /// take a copy of the arithmetic whose length is a compile-time constant
    /// (fully unrolled, no loop overhead); the operations are the same.
    fn trial(&mut self, system: &mut S, h: f64) -> f64 {
        with_state_count!(self.n, self.attempt_sized(system, h))
    }

    /// Advances to the new point. The dense output of the step is not
    /// formed here but on demand in [`Self::interpolate`], from the stages
    /// that stay in place until the next attempt: most steps hold no sample.
    fn advance(&mut self, _system: &mut S, h: f64, t_new: f64) {
        self.t_previous = self.t;
        self.h_previous = h;
        self.t = t_new;
        // The old state stays in `x_new` for the dense output.
        std::mem::swap(&mut self.x, &mut self.x_new);
        // FSAL: the last stage is the first of the next step; the old first
        // stage moves to the last slot, where the dense output reads it.
        self.k.swap(0, 6);
        self.last_stage_slot = 0;
        self.counts.steps += 1;
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Harmonic oscillator x'' = -w^2 x (also the classical method's test).
    pub(crate) struct Oscillator {
        pub(crate) w: f64,
    }

    /// The oscillator's tolerances: `rtol`, and `rtol` as the absolute one.
    pub(crate) fn oscillator_tolerances(rtol: f64) -> Tolerances {
        Tolerances {
            rtol,
            atol: vec![rtol; 2],
            max_step: f64::INFINITY,
            min_step_relative: 1e-14,
        }
    }

    impl OdeSystem for Oscillator {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
            dx[0] = x[1];
            dx[1] = -self.w * self.w * x[0];
        }
    }

    fn run(rtol: f64) -> (f64, f64, StepCounts) {
        let w = 2.0 * std::f64::consts::PI;
        let mut system = Oscillator { w };
        let tol = oscillator_tolerances(rtol);
        let mut dp = DormandPrince::new(&mut system, 0.0, &[1.0, 0.0], tol);
        let mut worst_dense = 0.0_f64;
        let mut out = [0.0; 2];
        while dp.t < 3.0 {
            dp.step(&mut system, 3.0).unwrap();
            let mid = 0.5 * (dp.previous_time() + dp.t);
            dp.interpolate(mid, &mut out);
            worst_dense = worst_dense.max((out[0] - (w * mid).cos()).abs());
        }
        ((dp.x[0] - (w * 3.0).cos()).abs(), worst_dense, dp.counts)
    }

    #[test]
    fn dense_output_survives_a_restart() {
        // The dense output is formed on demand from the stages of the last
        // step; a restart must not disturb the stage it reads.
        let mut system = Oscillator {
            w: 2.0 * std::f64::consts::PI,
        };
        let tol = oscillator_tolerances(1e-8);
        let mut dp = DormandPrince::new(&mut system, 0.0, &[1.0, 0.0], tol);
        for _ in 0..5 {
            dp.step(&mut system, 3.0).unwrap();
        }
        let mid = 0.3 * dp.previous_time() + 0.7 * dp.t;
        let (mut before, mut after) = ([0.0; 2], [0.0; 2]);
        dp.interpolate(mid, &mut before);
        system.w *= 2.0;
        dp.restart(&mut system);
        dp.interpolate(mid, &mut after);
        assert_eq!(before, after);
        assert!((before[0] - (2.0 * std::f64::consts::PI * mid).cos()).abs() < 1e-7);
        // The step after the restart uses the new right-hand side.
        let k1 = dp.k[0].clone();
        assert_eq!(k1[1], -system.w * system.w * dp.x[0]);
    }

    #[test]
    fn converges_at_fifth_order_with_accurate_dense_output() {
        let (coarse, coarse_dense, coarse_counts) = run(1e-6);
        let (fine, fine_dense, fine_counts) = run(1e-10);
        assert!(coarse < 1e-5 && fine < 1e-9, "{coarse} {fine}");
        assert!(
            coarse_dense < 1e-5 && fine_dense < 1e-9,
            "{coarse_dense} {fine_dense}"
        );
        // 10^4 tighter tolerance costs about 10^(4/5) = 6.3x the steps for a 5th-order method.
        let ratio = fine_counts.steps as f64 / coarse_counts.steps as f64;
        assert!((4.0..10.0).contains(&ratio), "step ratio {ratio}");
        assert_eq!(
            fine_counts.rhs_evaluations,
            2 + 6 * (fine_counts.steps + fine_counts.rejected)
        );
    }
}
