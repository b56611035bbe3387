//! The one adaptive driver: every error-controlled integration of a model
//! (a `fistage run`, a sweep point, a Lyapunov estimate, an FMU's
//! communication step) goes through [`drive`]. It owns the ODE adaptor over
//! the model, the absolute-tolerance formula, the segments between the
//! inputs' discontinuities (the integrator restarts at each), the steps
//! that end on the friction law's kinks ([`KinkPredictor`]), the step
//! budget and the mapping of integrator failures to [`SimError`].

use fistage_codegen::{Function, MachineCode, Native, compiled_native, native};
use fistage_model::{InputValues, Model, Workspace};
use std::ops::ControlFlow;

use fistage_ode::{
    AdaptiveMethod, JacobianSystem, OdeSystem, SplitSystem, StepCounts, StepFailure, Tolerances,
};

use crate::kinks::KinkPredictor;
use crate::settings::SimError;
use fistage_model::excitation::Excitation;

/// The model as an ODE `x' = f(t, x)` under an excitation.
pub(crate) struct ModelSystem<'a> {
    model: &'a Model,
    excitation: &'a dyn Excitation,
    /// The inputs, when they do not depend on time.
    constant_inputs: Option<InputValues<f64>>,
    workspace: &'a mut Workspace,
    /// The bristle states (implicit in the implicit-explicit integrator).
    bristles: Vec<usize>,
    /// The right-hand side as machine code, once the run has asked for it.
    native: Tier<'a>,
    /// The implicit bristle stage as machine code, likewise.
    native_implicit: Tier<'a>,
    /// Generic evaluations left before the run compiles what it uses.
    countdown: u32,
}

impl<'a> ModelSystem<'a> {
    pub(crate) fn new(
        model: &'a Model,
        excitation: &'a dyn Excitation,
        workspace: &'a mut Workspace,
    ) -> Self {
        Self {
            model,
            excitation,
            constant_inputs: excitation
                .is_constant()
                .then(|| excitation.inputs(0.0).values()),
            workspace,
            bristles: model.bristle_states(),
            native: Tier::new(model, Function::Rhs),
            native_implicit: Tier::new(model, Function::ImplicitStage),
            countdown: EVALUATIONS_BEFORE_COMPILING,
        }
    }

    /// The same system for a run that has made `evaluations` already (a
    /// co-simulation's earlier communication steps): its countdown to
    /// compiling goes on from there.
    pub(crate) fn after(mut self, evaluations: u64) -> Self {
        let made = u32::try_from(evaluations).unwrap_or(u32::MAX);
        self.countdown = self.countdown.saturating_sub(made);
        self
    }

    #[inline]
    fn inputs(&self, t: f64) -> InputValues<f64> {
        match &self.constant_inputs {
            Some(inputs) => *inputs,
            None => self.excitation.inputs(t).values(),
        }
    }
}

/// Evaluations a run makes with the generic code before it compiles the
/// machine code: about the evaluations that compiling costs (a millisecond
/// or so per hundred operations against one or two nanoseconds per
/// operation evaluated generically), so a short run does not pay for code it
/// would hardly use, and a long one loses at most that much.
const EVALUATIONS_BEFORE_COMPILING: u32 = 10_000;

/// Evaluations on which a compiled function may find a branch going the
/// other way (and leave the evaluation to the generic code) before a run
/// stops trying it: a stage that keeps its bushings beyond the recorded
/// rotation range would otherwise pay for both.
const BAILS_BEFORE_GIVING_UP: u32 = 64;

/// Where a run stands with one compiled function of its model.
struct Tier<'a> {
    function: Function,
    state: TierState<'a>,
    bails: u32,
}

enum TierState<'a> {
    /// Generic evaluation until the run has made enough evaluations.
    Generic,
    /// The machine code.
    Compiled(&'a Native),
    /// The model does not compile (the generic code stays).
    Unavailable,
}

impl<'a> Tier<'a> {
    /// The compiled function if the model has it already.
    fn new(model: &'a Model, function: Function) -> Self {
        let state = match compiled_native(model, function) {
            Some(native) => TierState::Compiled(native),
            None => TierState::Generic,
        };
        Self {
            function,
            state,
            bails: 0,
        }
    }

    /// The compiled function gave up on an evaluation; after
    /// [`BAILS_BEFORE_GIVING_UP`] of them the run evaluates generically.
    fn bailed(&mut self) {
        self.bails += 1;
        if self.bails >= BAILS_BEFORE_GIVING_UP {
            self.state = TierState::Unavailable;
        }
    }

    /// The compiled function for the next evaluation, compiled now if the
    /// run's countdown of generic evaluations has run out; `None`: evaluate
    /// generically (and count).
    #[inline]
    fn next(&mut self, model: &'a Model, countdown: &mut u32) -> Option<&'a Native> {
        match self.state {
            TierState::Compiled(native) => Some(native),
            TierState::Unavailable => None,
            TierState::Generic if *countdown > 0 => {
                *countdown -= 1;
                None
            }
            TierState::Generic => {
                self.state = match native(model, self.function) {
                    Some(native) => TierState::Compiled(native),
                    None => TierState::Unavailable,
                };
                self.next(model, countdown)
            }
        }
    }
}

impl ModelSystem<'_> {
    /// The slip velocity of every friction contact at (t, x).
    #[inline]
    fn slip_velocities(&mut self, t: f64, x: &[f64], out: &mut [f64]) {
        let inputs = self.inputs(t);
        self.model.slip_velocities(x, &inputs, out, self.workspace);
    }
}

impl OdeSystem for ModelSystem<'_> {
    fn dim(&self) -> usize {
        self.model.n_states()
    }

    #[inline]
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        let inputs = self.inputs(t);
        if let Some(native) = self.native.next(self.model, &mut self.countdown) {
            if native.rhs(x, &inputs, dx).is_ok() {
                return;
            }
            self.native.bailed();
        }
        self.model.rhs_of(x, &inputs, dx, self.workspace);
    }
}

impl SplitSystem for ModelSystem<'_> {
    fn implicit_states(&self) -> &[usize] {
        &self.bristles
    }

    #[inline]
    fn rhs_implicit(&mut self, t: f64, x: &mut [f64], step: f64, dx: &mut [f64]) {
        let inputs = self.inputs(t);
        if let Some(native) = self.native_implicit.next(self.model, &mut self.countdown) {
            if native.implicit_stage(x, &inputs, step, dx).is_ok() {
                return;
            }
            self.native_implicit.bailed();
        }
        self.model
            .rhs_implicit_bristles(x, &inputs, step, dx, self.workspace);
    }
}

impl JacobianSystem for ModelSystem<'_> {
    fn jacobian(&mut self, t: f64, x: &[f64]) -> nalgebra::DMatrix<f64> {
        self.model.jacobian(x, &self.excitation.inputs(t))
    }
}

/// Error control: absolute tolerance of state i is `rtol * atol_scale * nominal_i`.
pub(crate) fn tolerances(
    model: &Model,
    rtol: f64,
    atol_scale: f64,
    max_step: Option<f64>,
) -> Tolerances {
    Tolerances {
        rtol,
        atol: model
            .layout()
            .nominal
            .iter()
            .map(|s| s * rtol * atol_scale)
            .collect(),
        max_step: max_step.unwrap_or(f64::INFINITY),
        min_step_relative: 1e-14,
    }
}

/// The slip velocity below which a contact's sign changes are not worth a
/// step of their own: the smallest absolute tolerance of a velocity state.
/// A slip this small moves the bristle rate by less than the bristle
/// state's own tolerance over a step, kink or not.
pub(crate) fn slip_floor(model: &Model, tolerances: &Tolerances) -> f64 {
    let layout = model.layout();
    tolerances.atol[layout.nq..layout.nq + layout.nv]
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min)
}

/// The ends of the segments from `t0` to `t_end`: the breakpoints strictly
/// inside, sorted and without repeats, then `t_end`.
pub(crate) fn segment_ends(breakpoints: Vec<f64>, t0: f64, t_end: f64) -> Vec<f64> {
    let mut ends: Vec<f64> = breakpoints
        .into_iter()
        .filter(|&b| b > t0 && b < t_end)
        .collect();
    ends.sort_by(f64::total_cmp);
    ends.dedup();
    ends.push(t_end);
    ends
}

/// A failed step, in the model's words.
pub(crate) fn step_failure(model: &Model, failure: StepFailure) -> SimError {
    match failure {
        StepFailure::StepSizeUnderflow { t, h, non_finite } => SimError::StepSizeUnderflow {
            t,
            h,
            non_finite: non_finite.map(|i| model.layout().names[i].clone()),
        },
    }
}

/// Integrates through the excitation's segments up to `t_end`: restarts at
/// each breakpoint, stops each step on the next predicted kink of the
/// friction law ([`KinkPredictor`]; slips within `slip_floor` of zero are
/// round-off), stops with [`SimError::TooManySteps`] once more than
/// `max_steps` steps (accepted plus rejected) were taken in this call, and
/// calls `after_step` after every accepted step.
pub(crate) fn drive<'a, I: AdaptiveMethod<ModelSystem<'a>>>(
    integrator: &mut I,
    system: &mut ModelSystem<'a>,
    t_end: f64,
    max_steps: u64,
    slip_floor: f64,
    mut after_step: impl FnMut(&mut I, &mut ModelSystem<'a>) -> ControlFlow<()>,
) -> Result<(), SimError> {
    let model = system.model;
    let ends = segment_ends(system.excitation.breakpoints(), integrator.time(), t_end);
    let start = integrator.counts();
    // Differences first: the totals may come from a restored state.
    let used = |counts: StepCounts| {
        (counts.steps - start.steps).saturating_add(counts.rejected - start.rejected)
    };
    let mut pace = Pace::new(integrator.time());
    let mut kinks = KinkPredictor::new(model.frictions().len(), slip_floor);
    for (segment, &t_stop) in ends.iter().enumerate() {
        if segment > 0 {
            integrator.restart(system);
        }
        kinks.forget();
        while integrator.time() < t_stop {
            let t = integrator.time();
            kinks.record(t, |slips| {
                system.slip_velocities(t, integrator.state(), slips)
            });
            let target = kinks
                .next_crossing(integrator.proposed_step())
                .map_or(t_stop, |crossing| crossing.min(t_stop));
            integrator
                .step(system, target)
                .map_err(|failure| step_failure(model, failure))?;
            let steps = used(integrator.counts());
            if steps > max_steps {
                return Err(SimError::TooManySteps {
                    t: integrator.time(),
                    steps,
                });
            }
            pace.check(integrator.time(), steps, t_end, max_steps)?;
            if after_step(integrator, system).is_break() {
                return Err(SimError::Cancelled {
                    t: integrator.time(),
                });
            }
        }
    }
    Ok(())
}

/// Steps between two looks at the pace of a run.
const PACE_WINDOW: u64 = 1 << 16;

/// How far past the step budget a run's recent pace must point before it is
/// stopped early: a run only fails this way when its last 65 536 steps
/// advanced so little that four times the whole budget would not finish it.
const PACE_MARGIN: f64 = 4.0;

/// The pace of a run over its last window of steps, to stop early a run
/// whose step size has collapsed instead of letting it burn its whole budget.
struct Pace {
    since_time: f64,
    since_steps: u64,
}

impl Pace {
    fn new(t: f64) -> Self {
        Self {
            since_time: t,
            since_steps: 0,
        }
    }

    fn check(&mut self, t: f64, steps: u64, t_end: f64, max_steps: u64) -> Result<(), SimError> {
        if steps - self.since_steps < PACE_WINDOW {
            return Ok(());
        }
        let advanced = t - self.since_time;
        let rate = (steps - self.since_steps) as f64 / advanced.max(f64::MIN_POSITIVE);
        let projected = steps as f64 + rate * (t_end - t);
        if projected > PACE_MARGIN * max_steps as f64 {
            return Err(SimError::StepSizeCollapse {
                t,
                t_end,
                h: advanced / (steps - self.since_steps) as f64,
                projected,
                max_steps,
            });
        }
        self.since_time = t;
        self.since_steps = steps;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fistage_model::excitation::ScenarioExcitation;

    /// A stage turned beyond the recorded rotation range: the compiled
    /// right-hand side gives up on every evaluation, the generic code gives
    /// the numbers, and after a few such evaluations the run stops trying.
    #[test]
    fn a_run_stops_trying_a_compiled_function_that_keeps_giving_up() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let loaded = fistage_model::load(&root.join("scenarios/coupling/friction20_traverse.toml"))
            .expect("loads");
        let model = &loaded.model;
        native(model, Function::Rhs).expect("compiles");
        let excitation = ScenarioExcitation::from_scenario(&loaded.scenario);
        let mut ws = model.workspace();
        let mut system = ModelSystem::new(model, &excitation, &mut ws);
        assert!(matches!(system.native.state, TierState::Compiled(_)));
        let mut x = model.zero_state();
        let qw = model.layout().index("table.qw").expect("quaternion");
        x[qw] = 0.05f64.cos();
        x[qw + 3] = 0.05f64.sin();
        let n = model.n_states();
        let (mut dx, mut expected) = (vec![0.0; n], vec![0.0; n]);
        for _ in 0..BAILS_BEFORE_GIVING_UP {
            system.rhs(0.1, &x, &mut dx);
        }
        assert!(matches!(system.native.state, TierState::Unavailable));
        let inputs = excitation.inputs(0.1).values();
        model.rhs_of(&x, &inputs, &mut expected, &mut model.workspace());
        assert_eq!(dx, expected);
    }
}
