//! DOP853: Prince and Dormand's explicit eighth-order Runge-Kutta pair in
//! Hairer's form, for tight tolerances on smooth stretches. Twelve stages a
//! step plus the derivative at the new point (the next step's first stage);
//! the error estimate blends the embedded fifth- and third-order solutions
//! as Hairer's DOP853 does, and the step-size controller is the shared one
//! with his eighth-order gains ([`crate::step_control`]). The seventh-order
//! continuous extension takes three more evaluations, made only for the
//! steps that hold an output sample (or, before a restart replaces the
//! last derivative, at once). Independent of fistage models: it integrates
//! any [`OdeSystem`].

mod tableau;

use crate::method::{AdaptiveMethod, MethodState};
use crate::sized::{state_count, with_state_count};
use crate::step_control::{
    EmbeddedPair, Gains, PiController, StepControl, accepted_step, step_control,
};
use crate::tolerances::first_step;
use crate::{Checkpoint, OdeSystem, StepCounts, StepFailure, Tolerances};
use tableau::{ALL, COUPLING, DENSE, ERROR_FIFTH, ERROR_THIRD, NODES, STEPPING, WEIGHTS};

/// Where stage `j` of the last accepted step is kept between steps: the
/// step's first stage moves to slot 12 when the new point's derivative
/// (stage 12) takes slot 0 as the next first stage.
fn slot(j: usize) -> usize {
    match j {
        0 => STEPPING,
        STEPPING => 0,
        j => j,
    }
}

/// Degree of the continuous extension plus one: its coefficient vectors.
const DENSE_TERMS: usize = 7;

/// The integrator between steps.
pub struct Dop853 {
    tol: Tolerances,
    n: usize,
    /// Current time.
    pub t: f64,
    /// Current state.
    pub x: Vec<f64>,
    /// Suggested next step.
    pub h: f64,
    /// Stage derivatives; slot 0 holds f at the current point.
    k: [Vec<f64>; ALL],
    stage: Vec<f64>,
    /// The trial point; after an accepted step, the step's start.
    x_new: Vec<f64>,
    /// The fifth- and third-order error estimates of the trial step.
    error_fifth: Vec<f64>,
    error_third: Vec<f64>,
    /// Coefficients of the continuous extension of the last accepted step.
    dense: [Vec<f64>; DENSE_TERMS],
    dense_formed: bool,
    t_previous: f64,
    h_previous: f64,
    controller: PiController,
    /// Counters.
    pub counts: StepCounts,
    non_finite: Option<usize>,
}

impl<S: OdeSystem + ?Sized> AdaptiveMethod<S> for Dop853 {
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
            error_fifth: zeros(),
            error_third: zeros(),
            dense: std::array::from_fn(|_| zeros()),
            dense_formed: true,
            t_previous: start.t,
            h_previous: 0.0,
            controller: PiController::with_gains(Gains::EIGHTH_ORDER),
            counts: start.counts,
            non_finite: None,
        }
    }

    fn start(&mut self, system: &mut S) {
        let (first, rest) = self.k.split_at_mut(1);
        self.h = first_step(
            system,
            self.t,
            &self.x,
            &self.tol,
            8.0,
            &mut first[0],
            &mut self.stage,
            &mut rest[0],
            &mut self.counts,
        );
    }

    /// The last step's continuous extension is formed first (its stages lie
    /// inside the step, before the discontinuity), so it is kept.
    fn restart(&mut self, system: &mut S) {
        self.form_dense(system);
        system.rhs(self.t, &self.x, &mut self.k[0]);
        self.counts.rhs_evaluations += 1;
        self.controller.reset();
    }

    fn step(&mut self, system: &mut S, t_stop: f64) -> Result<(), StepFailure> {
        accepted_step(self, system, t_stop)
    }

    /// The state at `t` inside the last accepted step: the seventh-order
    /// continuous extension, formed on the first call in a step.
    fn interpolate(&mut self, system: &mut S, t: f64, out: &mut [f64]) {
        let h = self.h_previous;
        if h <= 0.0 {
            out[..self.n].copy_from_slice(&self.x);
            return;
        }
        self.form_dense(system);
        let s = ((t - self.t_previous) / h).clamp(0.0, 1.0);
        let s1 = 1.0 - s;
        let d = &self.dense;
        for m in 0..self.n {
            let upper = d[3][m] + s * (d[4][m] + s1 * (d[5][m] + s * d[6][m]));
            out[m] = self.x_new[m] + s * (d[0][m] + s1 * (d[1][m] + s * (d[2][m] + s1 * upper)));
        }
    }
}

impl MethodState for Dop853 {
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

impl Dop853 {
    /// The trial step ([`EmbeddedPair::trial`]) over `N` states (`N` = 0, `DYNAMIC`: `self.n`).
    #[inline(always)]
    fn attempt_sized<const N: usize, S: OdeSystem + ?Sized>(
        &mut self,
        system: &mut S,
        h: f64,
    ) -> f64 {
        let (n, t) = (state_count::<N>(self.n), self.t);
        let x = &self.x[..n];
        let stage = &mut self.stage[..n];
        for i in 1..STEPPING {
            combine(stage, x, h, &COUPLING[i][..i], &self.k[..i]);
            system.rhs(t + NODES[i] * h, stage, &mut self.k[i][..n]);
        }
        self.counts.rhs_evaluations += (STEPPING - 1) as u64;
        let x_new = &mut self.x_new[..n];
        combine(x_new, x, h, &WEIGHTS, &self.k[..STEPPING]);
        let atol = &self.tol.atol[..n];
        let (mut fifth, mut third) = (-0.0, -0.0);
        let (e5, e3) = (&mut self.error_fifth[..n], &mut self.error_third[..n]);
        e5.fill(0.0);
        e3.fill(0.0);
        for (j, k) in self.k[..STEPPING].iter().enumerate() {
            let (w5, w3) = (ERROR_FIFTH[j], ERROR_THIRD[j]);
            for ((e5, e3), k) in e5.iter_mut().zip(e3.iter_mut()).zip(&k[..n]) {
                *e5 += w5 * k;
                *e3 += w3 * k;
            }
        }
        for m in 0..n {
            let scale = atol[m] + self.tol.rtol * x[m].abs().max(x_new[m].abs());
            fifth += (e5[m] / scale) * (e5[m] / scale);
            third += (e3[m] / scale) * (e3[m] / scale);
        }
        let blended = fifth + 0.01 * third;
        let mean_square = if blended > 0.0 {
            h * h * fifth * fifth / (n as f64 * blended)
        } else if blended == 0.0 {
            0.0
        } else {
            f64::NAN
        };
        if mean_square.is_finite() {
            self.non_finite = None;
            mean_square
        } else {
            self.non_finite = (0..n).find(|&m| !x_new[m].is_finite());
            f64::INFINITY
        }
    }

    /// Forms the continuous extension of the last accepted step: its three
    /// extra stages, then Hairer's coefficients.
    fn form_dense<S: OdeSystem + ?Sized>(&mut self, system: &mut S) {
        if self.dense_formed {
            return;
        }
        let (n, t0, h) = (self.n, self.t_previous, self.h_previous);
        let x_old = &self.x_new[..n];
        let stage = &mut self.stage[..n];
        for i in STEPPING + 1..ALL {
            stage.copy_from_slice(x_old);
            for (j, &a) in COUPLING[i][..i].iter().enumerate() {
                if a != 0.0 {
                    for (s, k) in stage.iter_mut().zip(&self.k[slot(j)][..n]) {
                        *s += (h * a) * k;
                    }
                }
            }
            system.rhs(t0 + NODES[i] * h, stage, &mut self.k[i][..n]);
        }
        self.counts.rhs_evaluations += (ALL - STEPPING - 1) as u64;
        let (x, first, last) = (&self.x[..n], &self.k[slot(0)], &self.k[slot(STEPPING)]);
        let [rise, start, end, higher @ ..] = &mut self.dense;
        for m in 0..n {
            rise[m] = x[m] - x_old[m];
            start[m] = h * first[m] - rise[m];
            end[m] = rise[m] - h * last[m] - start[m];
        }
        for (row, coefficients) in higher.iter_mut().zip(&DENSE) {
            row[..n].fill(0.0);
            for (j, &d) in coefficients.iter().enumerate() {
                if d != 0.0 {
                    for (r, k) in row[..n].iter_mut().zip(&self.k[slot(j)][..n]) {
                        *r += (h * d) * k;
                    }
                }
            }
        }
        self.dense_formed = true;
    }

    /// Start time of the last accepted step.
    pub fn previous_time(&self) -> f64 {
        self.t_previous
    }
}

/// `out = x + h sum_j a_j k_j` over the non-zero `a_j`.
#[inline(always)]
fn combine(out: &mut [f64], x: &[f64], h: f64, a: &[f64], k: &[Vec<f64>]) {
    let n = out.len();
    out.fill(0.0);
    for (&a, k) in a.iter().zip(k) {
        if a != 0.0 {
            for (o, k) in out.iter_mut().zip(&k[..n]) {
                *o += a * k;
            }
        }
    }
    for (o, x) in out.iter_mut().zip(x) {
        *o = x + h * *o;
    }
}

impl<S: OdeSystem + ?Sized> EmbeddedPair<S> for Dop853 {
    fn control(&mut self) -> StepControl<'_> {
        step_control!(self)
    }

    /// One trial step of size h into `x_new`; the square of Hairer's blended
    /// error norm, `h |e5|^2 / sqrt(n (|e5|^2 + 0.01 |e3|^2))`. Small systems
    /// take a copy of the arithmetic whose length is a compile-time
    /// constant, as in [`crate::DormandPrince`].
    fn trial(&mut self, system: &mut S, h: f64) -> f64 {
        with_state_count!(self.n, self.attempt_sized(system, h))
    }

    /// Moves to the new point and evaluates f there (the next first stage).
    fn advance(&mut self, system: &mut S, h: f64, t_new: f64) {
        self.t_previous = self.t;
        self.h_previous = h;
        self.t = t_new;
        // The step's start stays in `x_new` for the continuous extension.
        std::mem::swap(&mut self.x, &mut self.x_new);
        system.rhs(self.t, &self.x, &mut self.k[STEPPING]);
        self.k.swap(0, STEPPING);
        self.counts.rhs_evaluations += 1;
        self.counts.steps += 1;
        self.dense_formed = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Kepler problem at eccentricity 0.2 over one period: smooth,
    /// with a known solution at the period (the start).
    struct Kepler;

    impl OdeSystem for Kepler {
        fn dim(&self) -> usize {
            4
        }
        fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
            let r3 = (x[0] * x[0] + x[1] * x[1]).powf(1.5);
            dx[0] = x[2];
            dx[1] = x[3];
            dx[2] = -x[0] / r3;
            dx[3] = -x[1] / r3;
        }
    }

    const ECCENTRICITY: f64 = 0.2;

    fn kepler_start() -> [f64; 4] {
        let e = ECCENTRICITY;
        [1.0 - e, 0.0, 0.0, ((1.0 + e) / (1.0 - e)).sqrt()]
    }

    fn tolerances(rtol: f64) -> Tolerances {
        Tolerances {
            rtol,
            atol: vec![rtol; 4],
            max_step: f64::INFINITY,
            min_step_relative: 1e-14,
        }
    }

    /// Error at the period and the counts; with `max_step`, fixed steps.
    fn kepler(rtol: f64, max_step: Option<f64>) -> (f64, StepCounts) {
        let period = 2.0 * std::f64::consts::PI;
        let x0 = kepler_start();
        let mut tol = tolerances(rtol);
        if let Some(h) = max_step {
            tol.max_step = h;
        }
        let mut integrator = Dop853::new(&mut Kepler, 0.0, &x0, tol);
        if let Some(h) = max_step {
            integrator.h = h;
        }
        while integrator.t < period {
            integrator.step(&mut Kepler, period).expect("step");
        }
        let error = (0..4).fold(0.0_f64, |e, m| e.max((integrator.x[m] - x0[m]).abs()));
        (error, integrator.counts)
    }

    #[test]
    fn the_step_converges_at_eighth_order() {
        // Steps a loose tolerance never rejects: the error of the method
        // itself. Halving the step divides it by 2^8 = 256 at eighth order.
        let period = 2.0 * std::f64::consts::PI;
        let (coarse, coarse_counts) = kepler(1.0, Some(period / 50.0));
        let (fine, _) = kepler(1.0, Some(period / 100.0));
        assert_eq!(coarse_counts.rejected, 0);
        let order = (coarse / fine).log2();
        println!("step order {order}: {coarse:e} {fine:e}");
        assert!(
            (7.5..8.8).contains(&order),
            "order {order}: {coarse:e} {fine:e}"
        );
    }

    #[test]
    fn the_error_follows_the_tolerance_at_a_quarter_of_the_cost_of_fifth_order() {
        let (loose, loose_counts) = kepler(1e-7, None);
        let (tight, tight_counts) = kepler(1e-11, None);
        assert!(loose < 1e-4 && tight < 1e-8, "{loose:e} {tight:e}");
        // 10^4 tighter costs 10^(4/8) = 3.2x the steps at eighth order
        // (a fifth-order method needs 6.3x).
        let ratio = tight_counts.steps as f64 / loose_counts.steps as f64;
        println!("errors {loose:e} {tight:e}, step ratio {ratio}");
        assert!((2.3..4.5).contains(&ratio), "step ratio {ratio}");
        assert_eq!(
            tight_counts.rhs_evaluations,
            2 + 11 * (tight_counts.steps + tight_counts.rejected) + tight_counts.steps
        );
    }

    /// x'' = -w^2 x from (1, 0), the dense output against cos and sin; from
    /// time `from` on, w is `w_after` (a discontinuity of the inputs).
    struct Oscillator {
        w: f64,
        w_after: f64,
        from: f64,
    }

    impl Oscillator {
        fn unit() -> Self {
            Self {
                w: 1.0,
                w_after: 1.0,
                from: f64::INFINITY,
            }
        }
    }

    impl OdeSystem for Oscillator {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
            let w = if t >= self.from { self.w_after } else { self.w };
            dx[0] = x[1];
            dx[1] = -w * w * x[0];
        }
    }

    #[test]
    fn the_dense_output_converges_at_seventh_order() {
        // Largest error over ten points inside every step of fixed size.
        let dense_error = |h: f64| {
            let mut system = Oscillator::unit();
            let mut tol = tolerances(1.0);
            tol.max_step = h;
            let mut integrator = Dop853::new(&mut system, 0.0, &[1.0, 0.0], tol);
            integrator.h = h;
            let mut worst = 0.0_f64;
            let mut out = [0.0; 2];
            while integrator.t < 6.0 {
                integrator.step(&mut system, 6.0).expect("step");
                let (t0, t1) = (integrator.previous_time(), integrator.t);
                for i in 1..10 {
                    let t = t0 + (t1 - t0) * i as f64 / 10.0;
                    integrator.interpolate(&mut system, t, &mut out);
                    worst = worst
                        .max((out[0] - t.cos()).abs())
                        .max((out[1] + t.sin()).abs());
                }
            }
            worst
        };
        let (coarse, fine) = (dense_error(0.4), dense_error(0.2));
        let order = (coarse / fine).log2();
        println!("dense order {order}: {coarse:e} {fine:e}");
        // Error O(h^8) of a seventh-degree extension.
        assert!(
            (7.0..9.0).contains(&order),
            "order {order}: {coarse:e} {fine:e}"
        );
    }

    #[test]
    fn the_dense_output_survives_a_restart() {
        let mut system = Oscillator::unit();
        let mut integrator = Dop853::new(&mut system, 0.0, &[1.0, 0.0], tolerances(1e-10));
        for _ in 0..5 {
            integrator.step(&mut system, 10.0).expect("step");
        }
        let mid = 0.3 * integrator.previous_time() + 0.7 * integrator.t;
        // The system changes at the step's end: the extension is of the old one.
        system.from = integrator.t;
        system.w_after = 3.0;
        integrator.restart(&mut system);
        let mut out = [0.0; 2];
        integrator.interpolate(&mut system, mid, &mut out);
        assert!((out[0] - mid.cos()).abs() < 1e-8, "{out:?} at {mid}");
        assert_eq!(integrator.k[0][1], -9.0 * integrator.x[0]);
    }
}
