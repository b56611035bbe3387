//! Kennedy and Carpenter's additive Runge-Kutta pair `ARK5(4)8L[2]SA`
//! (Appl. Numer. Math. 44, 2003): an explicit tableau for most states and an
//! L-stable, stiffly accurate singly diagonally implicit tableau (first stage
//! explicit) for the states a [`SplitSystem`] names implicit, the bristle
//! deflections of the LuGre contacts. Their equation is linear in the state
//! for given stage velocities, so each implicit stage is solved exactly
//! inside the one right-hand-side evaluation of that stage: no Newton
//! iteration, no Jacobian. The bristle relaxation (rates to 1e4 1/s and more
//! while slipping) then no longer bounds the step.
//!
//! Fifth order with a fourth-order embedded estimate, the PI step-size
//! controller and step-size rules of [`crate::DormandPrince`], and cubic Hermite dense
//! output from the values and derivatives at both ends of a step. Eight
//! evaluations per step (seven stages and the derivative at the new point,
//! which is the next step's first stage and the dense output's right end).

use crate::hermite::HermiteStep;
use crate::method::{AdaptiveMethod, MethodState};
use crate::sized::{state_count, with_state_count};
use crate::step_control::{EmbeddedPair, PiController, StepControl, accepted_step, step_control};
use crate::tolerances::first_step;
use crate::{Checkpoint, SplitSystem, StepCounts, StepFailure, Tolerances};

const EXPLICIT: [[f64; 8]; 8] = [
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [41.0 / 100.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [
        367902744464.0 / 2072280473677.0,
        677623207551.0 / 8224143866563.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        1268023523408.0 / 10340822734521.0,
        0.0,
        1029933939417.0 / 13636558850479.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        14463281900351.0 / 6315353703477.0,
        0.0,
        66114435211212.0 / 5879490589093.0,
        -54053170152839.0 / 4284798021562.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        14090043504691.0 / 34967701212078.0,
        0.0,
        15191511035443.0 / 11219624916014.0,
        -18461159152457.0 / 12425892160975.0,
        -281667163811.0 / 9011619295870.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        19230459214898.0 / 13134317526959.0,
        0.0,
        21275331358303.0 / 2942455364971.0,
        -38145345988419.0 / 4862620318723.0,
        -1.0 / 8.0,
        -1.0 / 8.0,
        0.0,
        0.0,
    ],
    [
        -19977161125411.0 / 11928030595625.0,
        0.0,
        -40795976796054.0 / 6384907823539.0,
        177454434618887.0 / 12078138498510.0,
        782672205425.0 / 8267701900261.0,
        -69563011059811.0 / 9646580694205.0,
        7356628210526.0 / 4942186776405.0,
        0.0,
    ],
];
const IMPLICIT: [[f64; 8]; 8] = [
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [41.0 / 200.0, 41.0 / 200.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [
        41.0 / 400.0,
        -567603406766.0 / 11931857230679.0,
        41.0 / 200.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        683785636431.0 / 9252920307686.0,
        0.0,
        -110385047103.0 / 1367015193373.0,
        41.0 / 200.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        3016520224154.0 / 10081342136671.0,
        0.0,
        30586259806659.0 / 12414158314087.0,
        -22760509404356.0 / 11113319521817.0,
        41.0 / 200.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        218866479029.0 / 1489978393911.0,
        0.0,
        638256894668.0 / 5436446318841.0,
        -1179710474555.0 / 5321154724896.0,
        -60928119172.0 / 8023461067671.0,
        41.0 / 200.0,
        0.0,
        0.0,
    ],
    [
        1020004230633.0 / 5715676835656.0,
        0.0,
        25762820946817.0 / 25263940353407.0,
        -2161375909145.0 / 9755907335909.0,
        -211217309593.0 / 5846859502534.0,
        -4269925059573.0 / 7827059040749.0,
        41.0 / 200.0,
        0.0,
    ],
    [
        -872700587467.0 / 9133579230613.0,
        0.0,
        0.0,
        22348218063261.0 / 9555858737531.0,
        -1143369518992.0 / 8141816002931.0,
        -39379526789629.0 / 19018526304540.0,
        32727382324388.0 / 42900044865799.0,
        41.0 / 200.0,
    ],
];
const WEIGHTS: [f64; 8] = [
    -872700587467.0 / 9133579230613.0,
    0.0,
    0.0,
    22348218063261.0 / 9555858737531.0,
    -1143369518992.0 / 8141816002931.0,
    -39379526789629.0 / 19018526304540.0,
    32727382324388.0 / 42900044865799.0,
    41.0 / 200.0,
];
const EMBEDDED: [f64; 8] = [
    -975461918565.0 / 9796059967033.0,
    0.0,
    0.0,
    78070527104295.0 / 32432590147079.0,
    -548382580838.0 / 3424219808633.0,
    -33438840321285.0 / 15594753105479.0,
    3629800801594.0 / 4656183773603.0,
    4035322873751.0 / 18575991585200.0,
];
const NODES: [f64; 8] = [
    0.0,
    41.0 / 100.0,
    2935347310677.0 / 11292855782101.0,
    1426016391358.0 / 7196633302097.0,
    92.0 / 100.0,
    24.0 / 100.0,
    3.0 / 5.0,
    1.0,
];

/// The diagonal of the implicit tableau.
const GAMMA: f64 = IMPLICIT[1][1];

/// Stages.
const STAGES: usize = 8;

/// The integrator between steps.
pub struct ImexRungeKutta {
    tol: Tolerances,
    n: usize,
    implicit_states: Vec<usize>,
    /// Current time.
    pub t: f64,
    /// Current state.
    pub x: Vec<f64>,
    /// Suggested next step.
    pub h: f64,
    /// Stage derivatives; slot 0 holds f at the current point.
    k: [Vec<f64>; STAGES],
    stage: Vec<f64>,
    x_new: Vec<f64>,
    /// Dense output of the last accepted step.
    dense: HermiteStep,
    controller: PiController,
    /// Counters.
    pub counts: StepCounts,
    non_finite: Option<usize>,
}

impl<S: SplitSystem + ?Sized> AdaptiveMethod<S> for ImexRungeKutta {
    fn unstarted(system: &S, start: &Checkpoint, tol: Tolerances) -> Self {
        let n = system.dim();
        let implicit_states = system.implicit_states().to_vec();
        let zeros = || vec![0.0; n];
        Self {
            tol,
            n,
            implicit_states,
            t: start.t,
            x: start.x.clone(),
            h: start.h,
            k: std::array::from_fn(|_| zeros()),
            stage: zeros(),
            x_new: zeros(),
            dense: HermiteStep::new(start.t, &start.x),
            controller: PiController::default(),
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
            5.0,
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
        ImexRungeKutta::interpolate(self, t, out);
    }
}

impl MethodState for ImexRungeKutta {
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

impl ImexRungeKutta {
    /// The trial step ([`EmbeddedPair::trial`]) over `N` states (`N` = 0, `DYNAMIC`: `self.n`).
    #[inline(always)]
    fn attempt_sized<const N: usize, S: SplitSystem + ?Sized>(
        &mut self,
        system: &mut S,
        h: f64,
    ) -> f64 {
        let n = state_count::<N>(self.n);
        self.stage_sized::<N, 1, S>(system, h);
        self.stage_sized::<N, 2, S>(system, h);
        self.stage_sized::<N, 3, S>(system, h);
        self.stage_sized::<N, 4, S>(system, h);
        self.stage_sized::<N, 5, S>(system, h);
        self.stage_sized::<N, 6, S>(system, h);
        self.stage_sized::<N, 7, S>(system, h);
        self.counts.rhs_evaluations += (STAGES - 1) as u64;
        let k: [&[f64]; STAGES] = std::array::from_fn(|j| &self.k[j][..n]);
        let x = &self.x[..n];
        let x_new = &mut self.x_new[..n];
        let stage = &self.stage[..n];
        let atol = &self.tol.atol[..n];
        let mut sum = -0.0;
        for m in 0..n {
            let (mut increment, mut error) = (-0.0, -0.0);
            for (j, k) in k.iter().enumerate() {
                let (w, e) = (WEIGHTS[j], WEIGHTS[j] - EMBEDDED[j]);
                if w != 0.0 || e != 0.0 {
                    increment += w * k[m];
                    error += e * k[m];
                }
            }
            x_new[m] = x[m] + h * increment;
            let scale = atol[m] + self.tol.rtol * x[m].abs().max(x_new[m].abs());
            let e = h * error / scale;
            sum += e * e;
        }
        // The implicit tableau is stiffly accurate: its solution is its last
        // stage, which the weights reproduce up to round-off.
        for &m in &self.implicit_states {
            x_new[m] = stage[m];
        }
        let mean_square = sum / n as f64;
        if mean_square.is_finite() {
            self.non_finite = None;
            mean_square
        } else {
            self.non_finite = (0..n).find(|&m| !x_new[m].is_finite());
            f64::INFINITY
        }
    }

    /// Stage `I` of a trial step of size `h`: its point from the earlier
    /// stages (every state by the explicit row, then the implicit states
    /// again by theirs), then its evaluation into slot `I`. With `I` and `N`
    /// constants the rows' zeros fold away and the loops unroll. The newest
    /// stage enters last, so the rest is summed while its evaluation is
    /// still in flight.
    #[inline(always)]
    fn stage_sized<const N: usize, const I: usize, S: SplitSystem + ?Sized>(
        &mut self,
        system: &mut S,
        h: f64,
    ) {
        let n = state_count::<N>(self.n);
        let (done, rest) = self.k.split_at_mut(I);
        let k: [&[f64]; I] = std::array::from_fn(|j| &done[j][..n]);
        let x = &self.x[..n];
        let stage = &mut self.stage[..n];
        for m in 0..n {
            stage[m] = stage_entry(&EXPLICIT[I], &k, x[m], h, m);
        }
        for &m in &self.implicit_states {
            stage[m] = stage_entry(&IMPLICIT[I], &k, x[m], h, m);
        }
        system.rhs_implicit(self.t + NODES[I] * h, stage, h * GAMMA, &mut rest[0][..n]);
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

/// Entry `m` of stage `I`'s point by one tableau row: `x + h sum_j row_j k_j`,
/// the newest stage added last.
#[inline(always)]
fn stage_entry<const I: usize>(
    row: &[f64; STAGES],
    k: &[&[f64]; I],
    x: f64,
    h: f64,
    m: usize,
) -> f64 {
    let mut sum = -0.0;
    for (j, k) in k[..I - 1].iter().enumerate() {
        if row[j] != 0.0 {
            sum += row[j] * k[m];
        }
    }
    (x + h * sum) + (h * row[I - 1]) * k[I - 1][m]
}

impl<S: SplitSystem + ?Sized> EmbeddedPair<S> for ImexRungeKutta {
    fn control(&mut self) -> StepControl<'_> {
        step_control!(self)
    }

    /// One trial step of size h into `x_new`; the mean square of the scaled
    /// error estimate. Small systems take a copy of the arithmetic whose
    /// length is a compile-time constant, as in [`crate::DormandPrince`].
    fn trial(&mut self, system: &mut S, h: f64) -> f64 {
        with_state_count!(self.n, self.attempt_sized(system, h))
    }

    /// Moves to the new point and evaluates f there (the next first stage).
    fn advance(&mut self, system: &mut S, h: f64, t_new: f64) {
        self.dense.begin(self.t, h, &mut self.x, &mut self.k[0]);
        std::mem::swap(&mut self.x, &mut self.x_new);
        self.t = t_new;
        system.rhs(self.t, &self.x, &mut self.k[0]);
        self.counts.rhs_evaluations += 1;
        self.counts.steps += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::OdeSystem;

    /// An oscillator x'' = -w^2 x driving a stiff lag z' = -lambda (z - x),
    /// z implicit. From z(0) = lambda^2 / (lambda^2 + w^2) the lag has no
    /// transient: z = lambda (lambda cos wt + w sin wt) / (lambda^2 + w^2).
    struct StiffLag {
        w: f64,
        lambda: f64,
    }

    const W: f64 = 2.0 * std::f64::consts::PI;

    impl StiffLag {
        fn exact(&self, t: f64) -> [f64; 3] {
            let (w, l) = (self.w, self.lambda);
            [
                (w * t).cos(),
                -w * (w * t).sin(),
                l * (l * (w * t).cos() + w * (w * t).sin()) / (l * l + w * w),
            ]
        }
    }

    impl OdeSystem for StiffLag {
        fn dim(&self) -> usize {
            3
        }
        fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
            dx[0] = x[1];
            dx[1] = -self.w * self.w * x[0];
            dx[2] = -self.lambda * (x[2] - x[0]);
        }
    }

    impl SplitSystem for StiffLag {
        fn implicit_states(&self) -> &[usize] {
            &[2]
        }
        fn rhs_implicit(&mut self, t: f64, x: &mut [f64], step: f64, dx: &mut [f64]) {
            // z = c + step * (-lambda (z - x0)), solved for z.
            x[2] = (x[2] + step * self.lambda * x[0]) / (1.0 + step * self.lambda);
            self.rhs(t, x, dx);
        }
    }

    /// Largest error of the end state and of the dense output at every
    /// step's midpoint over 3 s, with the counts.
    fn run(lambda: f64, rtol: f64) -> (f64, f64, StepCounts) {
        let mut system = StiffLag { w: W, lambda };
        let tol = Tolerances {
            rtol,
            atol: vec![rtol; 3],
            max_step: f64::INFINITY,
            min_step_relative: 1e-14,
        };
        let x0 = system.exact(0.0);
        let mut ark = ImexRungeKutta::new(&mut system, 0.0, &x0, tol);
        let (mut worst_dense, mut out) = (0.0_f64, [0.0; 3]);
        while ark.t < 3.0 {
            ark.step(&mut system, 3.0).expect("step");
            let mid = 0.5 * (ark.previous_time() + ark.t);
            ark.interpolate(mid, &mut out);
            let exact = system.exact(mid);
            worst_dense = (0..3).fold(worst_dense, |w, m| w.max((out[m] - exact[m]).abs()));
        }
        let exact = system.exact(3.0);
        let end = (0..3).fold(0.0_f64, |w, m| w.max((ark.x[m] - exact[m]).abs()));
        (end, worst_dense, ark.counts)
    }

    #[test]
    fn converges_at_fifth_order_on_a_non_stiff_split() {
        let (coarse, _, coarse_counts) = run(10.0, 1e-6);
        let (fine, _, fine_counts) = run(10.0, 1e-10);
        assert!(coarse < 2e-5 && fine < 2e-9, "{coarse} {fine}");
        // 10^4 tighter costs about 10^(4/5) = 6.3x the steps at fifth order
        // (a fourth-order method would need 10x, a third-order 22x).
        let ratio = fine_counts.steps as f64 / coarse_counts.steps as f64;
        assert!((4.0..9.0).contains(&ratio), "step ratio {ratio}");
        assert_eq!(
            fine_counts.rhs_evaluations,
            2 + 7 * (fine_counts.steps + fine_counts.rejected) + fine_counts.steps
        );
    }

    #[test]
    fn a_stiff_implicit_state_does_not_bound_the_step() {
        // An explicit fifth-order method is stable up to |lambda h| of about
        // 3.3: at lambda = 1e7 that is 9e6 steps over 3 s. The implicit
        // tableau has stage order 2, so on this forced stiff lag (a
        // Prothero-Robinson problem) its accuracy in z falls below fifth
        // order and the step count grows with lambda at first; it then levels
        // off, as no stability bound holds it.
        let (mid_end, _, mid) = run(1e6, 1e-8);
        let (stiff_end, stiff_dense, stiff) = run(1e7, 1e-8);
        println!(
            "steps: lambda 1e6 {}, lambda 1e7 {}",
            mid.steps, stiff.steps
        );
        let explicit_bound = 3.0 * 1e7 / 3.3;
        assert!(
            (stiff.steps as f64) * 100.0 < explicit_bound,
            "{}",
            stiff.steps
        );
        assert!(
            (stiff.steps as f64) < 1.25 * mid.steps as f64,
            "{} vs {}",
            stiff.steps,
            mid.steps
        );
        assert!(mid_end < 1e-6 && stiff_end < 1e-6, "{mid_end} {stiff_end}");
        assert!(stiff_dense < 1e-5, "{stiff_dense}");
    }

    #[test]
    fn dense_output_survives_a_restart() {
        let mut system = StiffLag { w: W, lambda: 1e3 };
        let tol = Tolerances {
            rtol: 1e-8,
            atol: vec![1e-8; 3],
            max_step: f64::INFINITY,
            min_step_relative: 1e-14,
        };
        let x0 = system.exact(0.0);
        let mut ark = ImexRungeKutta::new(&mut system, 0.0, &x0, tol);
        for _ in 0..20 {
            ark.step(&mut system, 3.0).expect("step");
        }
        let mid = 0.3 * ark.previous_time() + 0.7 * ark.t;
        let (mut before, mut after) = ([0.0; 3], [0.0; 3]);
        ark.interpolate(mid, &mut before);
        system.w *= 2.0;
        ark.restart(&mut system);
        ark.interpolate(mid, &mut after);
        assert_eq!(before, after);
        assert!((before[0] - (W * mid).cos()).abs() < 1e-6, "{before:?}");
        // The next step starts from the new right-hand side.
        assert_eq!(ark.k[0][1], -system.w * system.w * ark.x[0]);
    }
}
