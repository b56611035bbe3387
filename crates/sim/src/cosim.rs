//! Stepping a model between communication points, as a co-simulation master
//! asks for: the inputs an importer sets are held over each step (added to the
//! scenario's own reference profile), the native engine integrates with error
//! control in between through the one driver of driver (module `driver`), and the
//! stepper can be checkpointed and resumed bit for bit.

use fistage_model::{Inputs, Model, Reference, ReferenceSample, Workspace};

use crate::driver::{ModelSystem, drive, slip_floor, tolerances};
use crate::settings::SimError;
use fistage_model::excitation::Excitation;
use fistage_ode::{AdaptiveMethod, Checkpoint, DormandPrince, MethodState};

/// The inputs over a communication step: the scenario's reference profile plus
/// the held reference offset, the held servo force and platform velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldInputs {
    /// The scenario's reference profile (`Reference::Constant(0)` for none).
    pub profile: Reference,
    /// Importer-set inputs: the reference entries are added to the profile,
    /// servo force and platform velocity are taken as they are.
    pub held: Inputs,
}

impl Excitation for HeldInputs {
    fn inputs(&self, t: f64) -> Inputs {
        let profile = self.profile.sample(t);
        Inputs {
            reference: ReferenceSample {
                position: profile.position + self.held.reference.position,
                velocity: profile.velocity + self.held.reference.velocity,
            },
            servo_force: self.held.servo_force,
            platform_velocity: self.held.platform_velocity,
        }
    }

    fn breakpoints(&self) -> Vec<f64> {
        self.profile.breakpoints()
    }
}

/// Error control of a [`Stepper`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepperTolerances {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance of state i is `rtol * atol_scale * nominal_i`.
    pub atol_scale: f64,
    /// Largest internal step, s.
    pub max_step: Option<f64>,
    /// Largest number of internal steps (accepted plus rejected) per communication step.
    pub max_steps_per_advance: u64,
}

/// A model integrated from one communication point to the next.
#[derive(Debug, Clone)]
pub struct Stepper {
    checkpoint: Checkpoint,
    tolerances: StepperTolerances,
}

impl Stepper {
    /// Starts at (t0, x0). The first step size is chosen on the first advance.
    pub fn new(t0: f64, x0: Vec<f64>, tolerances: StepperTolerances) -> Self {
        Self {
            checkpoint: Checkpoint {
                t: t0,
                x: x0,
                h: 0.0,
                counts: Default::default(),
            },
            tolerances,
        }
    }

    /// Current time, s.
    pub fn time(&self) -> f64 {
        self.checkpoint.t
    }

    /// Current state.
    pub fn state(&self) -> &[f64] {
        &self.checkpoint.x
    }

    /// Everything that determines the future: time, state, step suggestion, counters.
    pub fn checkpoint(&self) -> &Checkpoint {
        &self.checkpoint
    }

    /// Continues from a checkpoint of this model.
    pub fn restore(&mut self, checkpoint: Checkpoint) {
        self.checkpoint = checkpoint;
    }

    /// Integrates to `t_end` with the inputs held; restarts at the profile's
    /// breakpoints inside the step. On failure the stepper is left where it
    /// was (the caller may retry with a smaller step or stop).
    pub fn advance(
        &mut self,
        model: &Model,
        excitation: &HeldInputs,
        t_end: f64,
        workspace: &mut Workspace,
    ) -> Result<(), SimError> {
        let t0 = self.checkpoint.t;
        if !(t_end.is_finite() && t_end > t0) {
            return Err(SimError::InvalidSettings(format!(
                "cannot advance from t = {t0} s to t = {t_end} s"
            )));
        }
        let t = &self.tolerances;
        let tolerances = tolerances(model, t.rtol, t.atol_scale, t.max_step);
        let floor = slip_floor(model, &tolerances);
        let mut system = ModelSystem::new(model, excitation, workspace)
            .after(self.checkpoint.counts.rhs_evaluations);
        let mut integrator = if self.checkpoint.h > 0.0 {
            DormandPrince::resume(&mut system, &self.checkpoint, tolerances)
        } else {
            let mut started = DormandPrince::new(&mut system, t0, &self.checkpoint.x, tolerances);
            started.counts.rhs_evaluations += self.checkpoint.counts.rhs_evaluations;
            started.counts.steps += self.checkpoint.counts.steps;
            started.counts.rejected += self.checkpoint.counts.rejected;
            started
        };
        drive(
            &mut integrator,
            &mut system,
            t_end,
            t.max_steps_per_advance,
            floor,
            |_, _| std::ops::ControlFlow::Continue(()),
        )?;
        if let Some(i) = integrator.x.iter().position(|v| !v.is_finite()) {
            return Err(SimError::StepSizeUnderflow {
                t: integrator.t,
                h: 0.0,
                non_finite: Some(model.layout().names[i].clone()),
            });
        }
        self.checkpoint = integrator.checkpoint();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{AdaptiveEngine, Engine};
    use crate::settings::SimSettings;
    use fistage_model::excitation::ScenarioExcitation;
    use fistage_model::load;
    use std::path::Path;

    fn fig05b() -> fistage_model::Loaded {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        load(&root.join("scenarios/paper/fig05b_fi.toml")).expect("shipped scenario loads")
    }

    fn tolerances(rtol: f64) -> StepperTolerances {
        StepperTolerances {
            rtol,
            atol_scale: 1.0,
            max_step: None,
            max_steps_per_advance: 1_000_000,
        }
    }

    /// The scenario's reference and platform velocity, no servo force.
    fn scenario_inputs(scenario: &fistage_model::Scenario) -> HeldInputs {
        HeldInputs {
            profile: scenario.reference.clone(),
            held: Inputs {
                platform_velocity: scenario.platform_velocity,
                ..Inputs::default()
            },
        }
    }

    /// Stepping 1 ms at a time agrees with one continuous run sampled at the
    /// same points, within the tolerance (restarts change only round-off-level
    /// error-control decisions).
    #[test]
    fn communication_steps_agree_with_a_continuous_run() {
        let loaded = fig05b();
        let model = &loaded.model;
        let scenario = &loaded.scenario;
        let x0 = fistage_model::initial_state(model, scenario).expect("initial state");
        let mut settings = SimSettings::from_scenario(scenario);
        settings.t_end = 0.5;
        settings.sample_interval = 1e-3;
        settings.rtol = 1e-9;
        let excitation = ScenarioExcitation::from_scenario(scenario);
        let continuous = AdaptiveEngine::NATIVE
            .simulate(model, &x0, &excitation, &settings, &mut crate::no_progress)
            .expect("continuous run");
        let held = scenario_inputs(scenario);
        let mut stepper = Stepper::new(0.0, x0, tolerances(1e-9));
        let mut ws = model.workspace();
        let index = model.layout().index("table_x.q").expect("table state");
        let mut worst: f64 = 0.0;
        for k in 1..=500 {
            let t = k as f64 * 1e-3;
            stepper.advance(model, &held, t, &mut ws).expect("advance");
            assert_eq!(
                stepper.time(),
                t,
                "lands on the communication point exactly"
            );
            let reference = continuous.state(k)[index];
            worst = worst.max((stepper.state()[index] - reference).abs());
        }
        assert!(worst < 1e-8, "table position differs by {worst:e} m");
    }

    /// Communication steps of a few evaluations each add up to a run that
    /// compiles its model's machine code.
    #[test]
    fn short_communication_steps_add_up_to_a_compiled_run() {
        use fistage_codegen::Function;
        let loaded = fig05b();
        let model = &loaded.model;
        let scenario = &loaded.scenario;
        let x0 = fistage_model::initial_state(model, scenario).expect("initial state");
        let held = scenario_inputs(scenario);
        let mut stepper = Stepper::new(0.0, x0, tolerances(1e-9));
        let mut ws = model.workspace();
        for k in 1..=500 {
            stepper
                .advance(model, &held, k as f64 * 1e-3, &mut ws)
                .expect("advance");
        }
        let evaluations = stepper.checkpoint().counts.rhs_evaluations;
        assert!(evaluations > 20_000, "{evaluations}");
        assert!(model.compiled(Function::Rhs).is_some());
    }

    /// Restoring a checkpoint and advancing again repeats the trajectory bit for bit.
    #[test]
    fn restore_repeats_bit_for_bit() {
        let loaded = fig05b();
        let model = &loaded.model;
        let x0 = fistage_model::initial_state(model, &loaded.scenario).expect("initial state");
        let held = scenario_inputs(&loaded.scenario);
        let mut ws = model.workspace();
        let mut stepper = Stepper::new(0.0, x0, tolerances(1e-7));
        stepper
            .advance(model, &held, 0.1, &mut ws)
            .expect("advance");
        let saved = stepper.checkpoint().clone();
        let mut first = Vec::new();
        for k in 1..=50 {
            stepper
                .advance(model, &held, 0.1 + k as f64 * 2e-3, &mut ws)
                .expect("advance");
            first.push(stepper.checkpoint().clone());
        }
        stepper.restore(saved);
        for (k, expected) in (1..=50).zip(&first) {
            stepper
                .advance(model, &held, 0.1 + k as f64 * 2e-3, &mut ws)
                .expect("advance");
            let again = stepper.checkpoint();
            assert_eq!(again.t.to_bits(), expected.t.to_bits());
            assert!(
                again
                    .x
                    .iter()
                    .zip(&expected.x)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
        }
    }

    #[test]
    fn advancing_backwards_is_an_error() {
        let loaded = fig05b();
        let model = &loaded.model;
        let held = HeldInputs {
            profile: Reference::Constant { value: 0.0 },
            held: Inputs::default(),
        };
        let mut ws = model.workspace();
        let mut stepper = Stepper::new(1.0, model.zero_state(), tolerances(1e-6));
        for t_end in [0.5, 1.0, f64::NAN] {
            assert!(matches!(
                stepper.advance(model, &held, t_end, &mut ws),
                Err(SimError::InvalidSettings(_))
            ));
        }
        assert_eq!(stepper.time(), 1.0);
    }
}
