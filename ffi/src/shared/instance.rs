//! One instance in safe Rust: the FMI 2.0 Co-Simulation and Model Exchange
//! state machines, parameter and input values by value reference, stepping
//! with the native engine between communication points (Co-Simulation) or
//! the model's own right-hand side for the importer's solver (Model
//! Exchange, time events at the reference's breakpoints), FMU state
//! snapshots and their byte form, and directional derivatives of outputs
//! and state derivatives. The C ABI in [`crate::fmi2::exports`] is a thin face
//! over this type.

use std::path::Path;

use fistage_model::{Inputs, LoadError, Model, RobotSpec, Scenario, Workspace, assemble};
use fistage_sim::{Excitation, HeldInputs, Stepper, StepperTolerances, initial_state_with};
use thiserror::Error;

use crate::model_description::{Capabilities, model_description};
use crate::phase::Phase;
use crate::state::Snapshot;
use crate::variables::{Binding, Causality, Variable, variables};

/// What the unit offers importers.
pub const CAPABILITIES: Capabilities = Capabilities {
    fmu_state: true,
    directional_derivatives: true,
};

/// Why a step failed, in the unit's terms: its step budget is per
/// communication step and its tolerance comes from fmi2SetupExperiment, so
/// the program's advice (raise solver.max_steps) does not apply here.
fn step_failure_text(error: &fistage_sim::SimError) -> String {
    use fistage_sim::SimError;
    let budget = MAX_STEPS_PER_COMMUNICATION_STEP;
    match error {
        SimError::TooManySteps { t, steps } => format!(
            "gave up at t = {t:.6} s after {steps} steps, the unit's limit per communication step ({budget}): the model is too stiff there for its parameters and state; check them, shorten the communication step, or loosen the tolerance"
        ),
        SimError::StepSizeCollapse {
            t, h, projected, ..
        } => format!(
            "the step size collapsed to {h:.3e} s at t = {t:.6} s: at this pace the communication step needs about {projected:.3e} steps, more than four times the unit's limit ({budget}); check the parameters, or loosen the tolerance"
        ),
        other => other.to_string(),
    }
}

/// The rules of fmi2SetupExperiment's arguments, which a restored FMU state
/// obeys too: a finite start, a finite stop not before it, and a tolerance
/// the program accepts.
fn check_experiment(
    tolerance: Option<f64>,
    start_time: f64,
    stop_time: Option<f64>,
) -> Result<(), String> {
    if !start_time.is_finite() {
        return Err(format!("startTime must be finite, got {start_time}"));
    }
    if let Some(stop) = stop_time
        && !(stop.is_finite() && stop >= start_time)
    {
        return Err(format!("stopTime {stop} is before startTime {start_time}"));
    }
    if let Some(rtol) = tolerance {
        fistage_model::SolverSettings::check_rtol(rtol)
            .map_err(|why| format!("tolerance {why}"))?;
    }
    Ok(())
}

/// More steps or evaluations than any run takes (2^53, where counting in
/// f64 would stop being exact); a restored state beyond it is corrupt, and
/// the counts never overflow.
const MAX_PLAUSIBLE_COUNT: u64 = 1 << 53;

/// What a state this unit saved always satisfies, so that a state made or
/// damaged elsewhere (with a checksum that fits) is refused before it is
/// restored: the experiment's rules, finite settable values, and a
/// checkpoint at a finite time within the experiment with a finite state,
/// a finite, non-negative step size and plausible step counts.
fn check_snapshot(snapshot: &Snapshot, variables: &[Variable]) -> Result<(), String> {
    let corrupt = |why: String| Err(format!("the FMU state is corrupt: {why}"));
    if let Err(why) = check_experiment(snapshot.tolerance, snapshot.start_time, snapshot.stop_time)
    {
        return corrupt(why);
    }
    for (variable, value) in variables.iter().zip(&snapshot.values) {
        if variable.causality != Causality::Output && !value.is_finite() {
            return corrupt(format!("{} is {value}", variable.name));
        }
    }
    let Some(checkpoint) = &snapshot.checkpoint else {
        return Ok(());
    };
    let t = checkpoint.t;
    let within = t >= snapshot.start_time && snapshot.stop_time.is_none_or(|stop| t <= stop);
    if !(t.is_finite() && within) {
        return corrupt(format!("its time {t:e} s is outside the experiment"));
    }
    if !(checkpoint.h.is_finite() && checkpoint.h >= 0.0) {
        return corrupt(format!("its step size is {:e} s", checkpoint.h));
    }
    if let Some(i) = checkpoint.x.iter().position(|x| !x.is_finite()) {
        return corrupt(format!("state {i} is {}", checkpoint.x[i]));
    }
    let counts = &checkpoint.counts;
    if [counts.steps, counts.rejected, counts.rhs_evaluations]
        .iter()
        .any(|&n| n > MAX_PLAUSIBLE_COUNT)
    {
        return corrupt(format!("its step counts ({counts:?}) are beyond any run"));
    }
    Ok(())
}

#[cfg(test)]
thread_local! {
    /// Test hook: the next fmi2DoStep on this thread panics inside the step.
    pub(crate) static INJECT_PANIC: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Largest number of internal steps in one communication step.
const MAX_STEPS_PER_COMMUNICATION_STEP: u64 = 5_000_000;

/// Why a call was refused. Every variant maps to fmi2Error.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CallError {
    /// The call is not allowed in the current phase.
    #[error("{call} is not allowed in the {} state", .phase.name())]
    WrongPhase {
        /// The FMI function.
        call: &'static str,
        /// Current phase.
        phase: Phase,
    },
    /// A value reference that names no variable of this unit.
    #[error("unknown value reference {0}")]
    UnknownValueReference(u32),
    /// A variable that cannot be set now, or not at all.
    #[error("cannot set \"{name}\": {why}")]
    NotSettable {
        /// Variable name.
        name: String,
        /// Reason.
        why: String,
    },
    /// An argument out of range.
    #[error("{0}")]
    InvalidArgument(String),
    /// Loading or assembling the model failed.
    #[error("{0}")]
    Model(String),
    /// The integration failed.
    #[error("{0}")]
    Simulation(String),
    /// The unit does not implement this optional function.
    #[error("{0}")]
    Unsupported(String),
}

/// Which FMI 2.0 interface an instance serves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interface {
    /// The importer's solver integrates the states (fmi2ModelExchange).
    ModelExchange,
    /// The unit integrates between communication points (fmi2CoSimulation).
    CoSimulation,
}

/// The continuous state of a Model Exchange instance: the time and state
/// the importer last set.
#[derive(Debug, Clone, PartialEq)]
struct Continuous {
    t: f64,
    x: Vec<f64>,
}

/// What fmi2NewDiscreteStates reports: the next time event, if any.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventInfo {
    /// The next time the reference is not smooth, after the current time.
    pub next_event_time: Option<f64>,
}

/// The study an instance was made from, before any parameter change.
#[derive(Debug, Clone)]
struct Source {
    scenario: Scenario,
    robot: RobotSpec,
}

/// An instance of the unit.
pub struct Instance {
    interface: Interface,
    source: Source,
    variables: Vec<Variable>,
    guid: String,
    model: Model,
    /// Parameter and input values, by value reference (output entries unused).
    values: Vec<f64>,
    /// The values `model` was built with.
    model_values: Vec<f64>,
    phase: Phase,
    start_time: f64,
    stop_time: Option<f64>,
    tolerance: Option<f64>,
    stepper: Option<Stepper>,
    /// Initial state while in initialization mode (before the stepper exists).
    initial: Option<Vec<f64>>,
    outputs: Vec<f64>,
    outputs_valid: bool,
    workspace: Workspace,
    /// Model Exchange: the importer's time and state after initialisation.
    continuous: Option<Continuous>,
    /// The number of continuous states the model description declares.
    described_states: usize,
}

impl std::fmt::Debug for Instance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Instance")
            .field("model", &self.model.name())
            .field("phase", &self.phase)
            .finish_non_exhaustive()
    }
}

/// Reads `scenario.toml` and the robot file it names from a resource folder,
/// and refuses a scenario the unit cannot honour: it steps with the native
/// engine, which has no colliders.
fn load_source(resources: &Path) -> Result<Source, LoadError> {
    let scenario = Scenario::from_file(&resources.join(crate::resources::SCENARIO_FILE))?;
    if !matches!(
        scenario.solver.engine,
        fistage_model::EngineKind::Native | fistage_model::EngineKind::Auto
    ) {
        return Err(scenario.error(
            "solver.engine",
            format!(
                "an FMU steps with the native engine, not {}; set engine = \"native\" to export it",
                scenario.solver.engine
            ),
        ));
    }
    if !scenario.rapier.stops.is_empty() || scenario.rapier.payload.is_some() {
        return Err(scenario.error(
            "rapier",
            "an FMU has no colliders (end stops, payloads): they need the rapier engine",
        ));
    }
    let robot = RobotSpec::from_file(&scenario.robot)?;
    Ok(Source { scenario, robot })
}

fn start_values(variables: &[Variable]) -> Vec<f64> {
    variables.iter().map(|v| v.start.unwrap_or(0.0)).collect()
}

impl Instance {
    /// A Co-Simulation instance of the unit whose resources are in
    /// `resources`. When `guid` is given it must equal the GUID of the
    /// description those resources produce.
    pub fn new(resources: &Path, guid: Option<&str>) -> Result<Self, CallError> {
        Self::for_interface(resources, guid, Interface::CoSimulation)
    }

    /// An instance serving `interface` (see [`Instance::new`]).
    pub fn for_interface(
        resources: &Path,
        guid: Option<&str>,
        interface: Interface,
    ) -> Result<Self, CallError> {
        let source = load_source(resources).map_err(|e| CallError::Model(e.to_string()))?;
        let (_, model) = assemble(source.robot.clone(), &source.scenario)
            .map_err(|e| CallError::Model(e.to_string()))?;
        let description = model_description(&model, &source.scenario, CAPABILITIES);
        let own_guid = description_guid(&description);
        if let Some(expected) = guid
            && expected != own_guid
        {
            return Err(CallError::InvalidArgument(format!(
                "GUID {expected} does not match this unit's resources ({own_guid}); the FMU was modified or mixed up"
            )));
        }
        let variables = variables(&model, &source.scenario);
        let values = start_values(&variables);
        let n_outputs = model.signals().len();
        let described_states = model.n_states();
        Ok(Self {
            interface,
            continuous: None,
            described_states,
            workspace: model.workspace(),
            guid: own_guid,
            model_values: values.clone(),
            values,
            variables,
            model,
            source,
            phase: Phase::Instantiated,
            start_time: 0.0,
            stop_time: None,
            tolerance: None,
            stepper: None,
            initial: None,
            outputs: vec![0.0; n_outputs],
            outputs_valid: false,
        })
    }

    /// The GUID of this unit's model description.
    pub fn guid(&self) -> &str {
        &self.guid
    }

    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Marks the instance unusable (after an internal error).
    pub fn poison(&mut self) {
        self.phase = Phase::Fatal;
    }

    /// The model: built from the unit's resources, and rebuilt with the
    /// parameters an importer set at fmi2ExitInitializationMode.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Every variable, in value-reference order.
    pub fn variables(&self) -> &[Variable] {
        &self.variables
    }

    /// The interface this instance serves.
    pub fn interface(&self) -> Interface {
        self.interface
    }

    /// The number of continuous states the model description declares.
    pub fn n_continuous_states(&self) -> usize {
        self.described_states
    }

    /// Current time: the last communication point reached (Co-Simulation)
    /// or the time the importer set (Model Exchange).
    pub fn time(&self) -> f64 {
        if let Some(c) = &self.continuous {
            return c.t;
        }
        self.stepper
            .as_ref()
            .map(Stepper::time)
            .unwrap_or(self.start_time)
    }

    fn require_interface(&self, call: &'static str, wanted: Interface) -> Result<(), CallError> {
        if self.interface == wanted {
            return Ok(());
        }
        let (name, other) = match wanted {
            Interface::ModelExchange => ("Model Exchange", "Co-Simulation"),
            Interface::CoSimulation => ("Co-Simulation", "Model Exchange"),
        };
        Err(CallError::InvalidArgument(format!(
            "{call} is a {name} function; this instance was instantiated for {other}"
        )))
    }

    fn require(&self, call: &'static str, allowed: &[Phase]) -> Result<(), CallError> {
        if allowed.contains(&self.phase) {
            Ok(())
        } else {
            Err(CallError::WrongPhase {
                call,
                phase: self.phase,
            })
        }
    }

    /// fmi2SetupExperiment.
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Result<(), CallError> {
        self.require("fmi2SetupExperiment", &[Phase::Instantiated])?;
        check_experiment(tolerance, start_time, stop_time).map_err(CallError::InvalidArgument)?;
        self.start_time = start_time;
        self.stop_time = stop_time;
        self.tolerance = tolerance;
        Ok(())
    }

    /// fmi2EnterInitializationMode.
    pub fn enter_initialization(&mut self) -> Result<(), CallError> {
        self.require("fmi2EnterInitializationMode", &[Phase::Instantiated])?;
        self.phase = Phase::Initialization;
        self.initial = None;
        self.outputs_valid = false;
        Ok(())
    }

    /// fmi2ExitInitializationMode: builds the model with the parameters set
    /// and computes the scenario's initial state; a Model Exchange instance
    /// goes to event mode, a Co-Simulation one is ready to step.
    pub fn exit_initialization(&mut self) -> Result<(), CallError> {
        self.require("fmi2ExitInitializationMode", &[Phase::Initialization])?;
        let x0 = self.initial_state()?;
        match self.interface {
            Interface::CoSimulation => {
                self.stepper = Some(Stepper::new(self.start_time, x0, self.stepper_tolerances()));
                self.phase = Phase::StepComplete;
            }
            Interface::ModelExchange => {
                if x0.len() != self.described_states {
                    return Err(CallError::Model(format!(
                        "the parameters set give {} continuous states where the model description \
                         declares {} (k_i switches the error integral on or off): a Model \
                         Exchange importer cannot follow that; export the FMU with the gains wanted",
                        x0.len(),
                        self.described_states
                    )));
                }
                self.continuous = Some(Continuous {
                    t: self.start_time,
                    x: x0,
                });
                // The importer's integrator asks for the derivatives many
                // times: the right-hand side as machine code (a model that
                // does not compile is evaluated generically).
                let _ = fistage_codegen::machine_code(&self.model, fistage_codegen::Function::Rhs);
                self.phase = Phase::EventMode;
            }
        }
        self.initial = None;
        self.outputs_valid = false;
        Ok(())
    }

    /// fmi2Terminate.
    pub fn terminate(&mut self) -> Result<(), CallError> {
        self.require(
            "fmi2Terminate",
            &[
                Phase::StepComplete,
                Phase::StepFailed,
                Phase::Initialization,
                Phase::EventMode,
                Phase::ContinuousTime,
            ],
        )?;
        self.phase = Phase::Terminated;
        Ok(())
    }

    /// fmi2Reset: back to the state after instantiation, start values restored.
    pub fn reset(&mut self) -> Result<(), CallError> {
        if self.phase == Phase::Fatal {
            return Err(CallError::WrongPhase {
                call: "fmi2Reset",
                phase: self.phase,
            });
        }
        self.values = start_values(&self.variables);
        self.phase = Phase::Instantiated;
        self.start_time = 0.0;
        self.stop_time = None;
        self.tolerance = None;
        self.stepper = None;
        self.continuous = None;
        self.initial = None;
        self.outputs_valid = false;
        Ok(())
    }

    fn variable(&self, vr: u32) -> Result<&Variable, CallError> {
        self.variables
            .get(vr as usize)
            .ok_or(CallError::UnknownValueReference(vr))
    }

    /// Rebuilds the model when parameters changed since it was built.
    fn rebuild_model(&mut self) -> Result<(), CallError> {
        if self.values == self.model_values {
            return Ok(());
        }
        // The file's values with the scenario's overrides, then the importer's
        // values through the parameter table (each checked by its rule).
        let mut scenario = self.source.scenario.clone();
        let mut robot = self.source.robot.clone();
        let rejected = |e: LoadError| CallError::Model(format!("parameters rejected: {e}"));
        fistage_model::assembly::apply_overrides(&mut robot, &scenario).map_err(rejected)?;
        scenario.overrides.clear();
        for variable in &self.variables {
            if let Binding::Parameter(parameter) = &variable.binding {
                let value = self.values[variable.value_reference as usize];
                parameter
                    .write(&mut scenario, &mut robot, value)
                    .map_err(|e| CallError::Model(format!("parameter {}: {e}", variable.name)))?;
            }
        }
        let (_, model) = assemble(robot, &scenario).map_err(rejected)?;
        self.model = model;
        self.workspace = self.model.workspace();
        self.model_values = self.values.clone();
        Ok(())
    }

    fn held_inputs(&self) -> HeldInputs {
        let mut held = Inputs::default();
        for variable in &self.variables {
            if let Binding::Input(index) = variable.binding {
                let value = self.values[variable.value_reference as usize];
                match index {
                    0 => held.reference.position = value,
                    1 => held.reference.velocity = value,
                    2 => held.servo_force = value,
                    _ => held.platform_velocity = value,
                }
            }
        }
        HeldInputs {
            profile: self.source.scenario.reference.clone(),
            held,
        }
    }

    /// The scenario's start (`zero`, `static` or `slipping`), with equilibria
    /// taken at the inputs the importer set, at the start time.
    fn initial_state(&mut self) -> Result<Vec<f64>, CallError> {
        self.rebuild_model()?;
        let inputs = self.held_inputs().inputs(self.start_time);
        initial_state_with(&self.model, &self.source.scenario, &inputs)
            .map_err(|e| CallError::Model(e.to_string()))
    }

    fn stepper_tolerances(&self) -> StepperTolerances {
        let solver = &self.source.scenario.solver;
        StepperTolerances {
            rtol: self.tolerance.unwrap_or(solver.rtol),
            atol_scale: solver.atol_scale,
            max_step: solver.max_step,
            max_steps_per_advance: MAX_STEPS_PER_COMMUNICATION_STEP,
        }
    }

    /// The state the outputs are computed from.
    fn current_state(&mut self) -> Result<&[f64], CallError> {
        if self.stepper.is_none() && self.initial.is_none() {
            self.initial = Some(self.initial_state()?);
        }
        if let Some(c) = &self.continuous {
            return Ok(&c.x);
        }
        match (&self.stepper, &self.initial) {
            (Some(stepper), _) => Ok(stepper.state()),
            (None, Some(x)) => Ok(x),
            (None, None) => Err(CallError::InvalidArgument("no state yet".into())),
        }
    }

    fn refresh_outputs(&mut self) -> Result<(), CallError> {
        if self.outputs_valid {
            return Ok(());
        }
        let x = self.current_state()?.to_vec();
        let inputs = self.held_inputs().inputs(self.time());
        self.model
            .outputs(&x, &inputs, &mut self.outputs, &mut self.workspace);
        if let Some(i) = self.outputs.iter().position(|v| !v.is_finite()) {
            return Err(CallError::Simulation(format!(
                "output \"{}\" is not finite",
                self.model.signals()[i].name
            )));
        }
        self.outputs_valid = true;
        Ok(())
    }

    /// The phases in which values and derivatives can be read.
    const READABLE: [Phase; 6] = [
        Phase::Initialization,
        Phase::StepComplete,
        Phase::StepFailed,
        Phase::Terminated,
        Phase::EventMode,
        Phase::ContinuousTime,
    ];

    /// fmi2GetReal.
    pub fn get_real(&mut self, vrs: &[u32], values: &mut [f64]) -> Result<(), CallError> {
        self.require("fmi2GetReal", &Self::READABLE)?;
        let mut rates: Option<Vec<f64>> = None;
        for (&vr, value) in vrs.iter().zip(values.iter_mut()) {
            let binding = self.variable(vr)?.binding.clone();
            *value = match binding {
                Binding::Output(index) => {
                    self.refresh_outputs()?;
                    self.outputs[index]
                }
                Binding::State(index) => self.state_entry(vr, index)?,
                Binding::Derivative(index) => {
                    if rates.is_none() {
                        rates = Some(self.rates()?);
                    }
                    rates.as_ref().map_or(f64::NAN, |r| r[index])
                }
                Binding::Parameter(_) | Binding::Input(_) => self.values[vr as usize],
            };
        }
        Ok(())
    }

    /// One entry of the current state, for the state variable `vr`.
    fn state_entry(&mut self, vr: u32, index: usize) -> Result<f64, CallError> {
        let x = self.current_state()?;
        x.get(index).copied().ok_or_else(|| {
            CallError::InvalidArgument(format!(
                "value reference {vr}: the parameters set leave the model {} states",
                x.len()
            ))
        })
    }

    /// The state derivatives at the current time, state and inputs.
    fn rates(&mut self) -> Result<Vec<f64>, CallError> {
        let x = self.current_state()?.to_vec();
        if x.len() != self.described_states {
            return Err(CallError::InvalidArgument(format!(
                "the parameters set give the model {} states where the description declares {}",
                x.len(),
                self.described_states
            )));
        }
        let inputs = self.held_inputs().inputs(self.time());
        let mut dx = vec![0.0; x.len()];
        self.model.rhs(&x, &inputs, &mut dx, &mut self.workspace);
        if let Some(i) = dx.iter().position(|v| !v.is_finite()) {
            return Err(CallError::Simulation(format!(
                "the derivative of state {} is not finite at t = {} s",
                self.model.layout().names[i],
                self.time()
            )));
        }
        Ok(dx)
    }

    /// fmi2SetReal. Parameters may be set until initialization ends, inputs any time before termination.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), CallError> {
        self.require(
            "fmi2SetReal",
            &[
                Phase::Instantiated,
                Phase::Initialization,
                Phase::StepComplete,
                Phase::StepFailed,
                Phase::EventMode,
                Phase::ContinuousTime,
            ],
        )?;
        // Check everything first, so a refused call changes nothing.
        for (&vr, &value) in vrs.iter().zip(values) {
            let variable = self.variable(vr)?;
            let refuse = |why: String| {
                Err(CallError::NotSettable {
                    name: variable.name.clone(),
                    why,
                })
            };
            match variable.causality {
                Causality::Output => return refuse("it is an output".into()),
                Causality::Local => {
                    return refuse(
                        "it is a continuous state or derivative, computed by the unit (set \
                         states with fmi2SetContinuousStates)"
                            .into(),
                    );
                }
                Causality::Parameter
                    if !matches!(self.phase, Phase::Instantiated | Phase::Initialization) =>
                {
                    return refuse("parameters are fixed after fmi2ExitInitializationMode".into());
                }
                _ => {}
            }
            if !value.is_finite() {
                return refuse(format!("{value} is not a finite number"));
            }
        }
        for (&vr, &value) in vrs.iter().zip(values) {
            if self.values[vr as usize] != value {
                self.values[vr as usize] = value;
                self.outputs_valid = false;
                if self.variables[vr as usize].causality == Causality::Parameter
                    || self.stepper.is_none()
                {
                    self.initial = None;
                }
            }
        }
        Ok(())
    }

    /// fmi2DoStep: integrates from the current communication point over `step`.
    pub fn do_step(&mut self, communication_point: f64, step: f64) -> Result<(), CallError> {
        self.require_interface("fmi2DoStep", Interface::CoSimulation)?;
        self.require("fmi2DoStep", &[Phase::StepComplete])?;
        if !(step.is_finite() && step > 0.0) {
            return Err(CallError::InvalidArgument(format!(
                "communicationStepSize must be a positive number, got {step}"
            )));
        }
        let now = self.time();
        if !communication_point.is_finite()
            || (communication_point - now).abs() > 1e-9 * now.abs().max(1.0)
        {
            return Err(CallError::InvalidArgument(format!(
                "currentCommunicationPoint {communication_point:?} is not the unit's time {now:?}"
            )));
        }
        let target = communication_point + step;
        if target <= now {
            return Err(CallError::InvalidArgument(format!(
                "step {step:?} from {communication_point:?} does not pass the unit's time {now:?}"
            )));
        }
        if let Some(stop) = self.stop_time
            && target > stop + 1e-9 * stop.abs().max(1.0)
        {
            return Err(CallError::InvalidArgument(format!(
                "step to t = {target} s goes past stopTime {stop} s"
            )));
        }
        let held = self.held_inputs();
        let Some(stepper) = self.stepper.as_mut() else {
            return Err(CallError::WrongPhase {
                call: "fmi2DoStep",
                phase: self.phase,
            });
        };
        self.outputs_valid = false;
        #[cfg(test)]
        if INJECT_PANIC.with(|flag| flag.replace(false)) {
            panic!("injected fault inside the model step");
        }
        match stepper.advance(&self.model, &held, target, &mut self.workspace) {
            Ok(()) => Ok(()),
            Err(error) => {
                self.phase = Phase::StepFailed;
                Err(CallError::Simulation(format!(
                    "fmi2DoStep failed: {}",
                    step_failure_text(&error)
                )))
            }
        }
    }

    /// Counters of the internal integration: (accepted steps, rejected steps, RHS evaluations).
    pub fn step_counts(&self) -> (u64, u64, u64) {
        self.stepper
            .as_ref()
            .map(|s| {
                let c = s.checkpoint().counts;
                (c.steps, c.rejected, c.rhs_evaluations)
            })
            .unwrap_or_default()
    }

    /// fmi2GetFMUstate.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            phase: self.phase,
            values: self.values.clone(),
            start_time: self.start_time,
            stop_time: self.stop_time,
            tolerance: self.tolerance,
            checkpoint: match &self.continuous {
                Some(c) => Some(fistage_sim::Checkpoint {
                    t: c.t,
                    x: c.x.clone(),
                    h: 0.0,
                    counts: Default::default(),
                }),
                None => self.stepper.as_ref().map(|s| s.checkpoint().clone()),
            },
        }
    }

    /// fmi2SetFMUstate.
    pub fn restore(&mut self, snapshot: &Snapshot) -> Result<(), CallError> {
        if self.phase == Phase::Fatal {
            return Err(CallError::WrongPhase {
                call: "fmi2SetFMUstate",
                phase: self.phase,
            });
        }
        if snapshot.values.len() != self.values.len() {
            return Err(CallError::InvalidArgument(
                "the FMU state belongs to a different unit".into(),
            ));
        }
        check_snapshot(snapshot, &self.variables).map_err(CallError::InvalidArgument)?;
        let saved_by = match snapshot.phase {
            Phase::EventMode | Phase::ContinuousTime => Some(Interface::ModelExchange),
            Phase::StepComplete | Phase::StepFailed => Some(Interface::CoSimulation),
            _ => None,
        };
        if saved_by.is_some_and(|i| i != self.interface) {
            return Err(CallError::InvalidArgument(format!(
                "the FMU state was saved in the {} state, which this {:?} instance does not have",
                snapshot.phase.name(),
                self.interface
            )));
        }
        // Parameters first: they decide the state layout (k_i adds a state).
        let previous = self.values.clone();
        self.values = snapshot.values.clone();
        let fits = self.rebuild_model().map(|()| {
            snapshot
                .checkpoint
                .as_ref()
                .is_none_or(|c| c.x.len() == self.model.n_states())
        });
        match fits {
            Ok(true) => {}
            Ok(false) | Err(_) => {
                self.values = previous;
                self.rebuild_model()?;
                return Err(fits.err().unwrap_or_else(|| {
                    CallError::InvalidArgument(
                        "the FMU state's state vector does not fit this unit".into(),
                    )
                }));
            }
        }
        self.phase = snapshot.phase;
        self.start_time = snapshot.start_time;
        self.stop_time = snapshot.stop_time;
        self.tolerance = snapshot.tolerance;
        self.initial = None;
        self.outputs_valid = false;
        if self.interface == Interface::ModelExchange {
            self.stepper = None;
            self.continuous = snapshot.checkpoint.as_ref().map(|c| Continuous {
                t: c.t,
                x: c.x.clone(),
            });
            return Ok(());
        }
        self.stepper = snapshot.checkpoint.as_ref().map(|checkpoint| {
            let mut stepper = Stepper::new(
                checkpoint.t,
                checkpoint.x.clone(),
                self.stepper_tolerances(),
            );
            stepper.restore(checkpoint.clone());
            stepper
        });
        Ok(())
    }

    /// fmi2SerializeFMUstate: the snapshot as bytes, tagged with this unit's GUID.
    pub fn serialize(&self, snapshot: &Snapshot) -> Vec<u8> {
        crate::state::encode(&self.guid, snapshot)
    }

    /// fmi2DeSerializeFMUstate.
    pub fn deserialize(&self, bytes: &[u8]) -> Result<Snapshot, CallError> {
        crate::state::decode(&self.guid, bytes).map_err(CallError::InvalidArgument)
    }

    /// fmi2GetDirectionalDerivative: outputs and state derivatives
    /// (unknowns) along a direction of the inputs and states (knowns), exact
    /// by dual numbers through the model's own right-hand side.
    pub fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        result: &mut [f64],
    ) -> Result<(), CallError> {
        self.require("fmi2GetDirectionalDerivative", &Self::READABLE)?;
        let n = self.described_states;
        let mut input_direction = [0.0; 4];
        let mut state_direction = vec![0.0; n];
        for (&vr, &dv) in knowns.iter().zip(seed) {
            match self.variable(vr)?.binding {
                Binding::Input(index) => input_direction[index] += dv,
                Binding::State(index) => state_direction[index] += dv,
                _ => {
                    return Err(CallError::InvalidArgument(format!(
                        "known \"{}\" is neither an input nor a continuous state",
                        self.variables[vr as usize].name
                    )));
                }
            }
        }
        let mut rows = Vec::with_capacity(unknowns.len());
        for &vr in unknowns {
            match self.variable(vr)?.binding.clone() {
                binding @ (Binding::Output(_) | Binding::Derivative(_)) => rows.push(binding),
                _ => {
                    return Err(CallError::InvalidArgument(format!(
                        "unknown \"{}\" is neither an output nor a state derivative",
                        self.variables[vr as usize].name
                    )));
                }
            }
        }
        let x = self.current_state()?.to_vec();
        if x.len() != n {
            return Err(CallError::InvalidArgument(format!(
                "the parameters set give the model {} states where the description declares {n}",
                x.len()
            )));
        }
        let inputs = self.held_inputs().inputs(self.time());
        let (rates, outputs) = self.model.directional_derivative(
            &x,
            &inputs,
            Some(&state_direction),
            &input_direction,
        );
        for (slot, binding) in result.iter_mut().zip(rows) {
            *slot = match binding {
                Binding::Output(index) => outputs[index],
                Binding::Derivative(index) => rates[index],
                _ => f64::NAN,
            };
        }
        Ok(())
    }

    /// fmi2SetTime (Model Exchange). Before initialisation ends it sets the
    /// start time, as importers that follow the standard's example code
    /// call it right after instantiation (fmi2SetupExperiment, if it comes
    /// later, has the last word).
    pub fn set_time(&mut self, t: f64) -> Result<(), CallError> {
        self.require_interface("fmi2SetTime", Interface::ModelExchange)?;
        self.require(
            "fmi2SetTime",
            &[
                Phase::Instantiated,
                Phase::Initialization,
                Phase::EventMode,
                Phase::ContinuousTime,
            ],
        )?;
        if !t.is_finite() {
            return Err(CallError::InvalidArgument(format!(
                "time must be finite, got {t}"
            )));
        }
        match self.continuous.as_mut() {
            Some(c) => c.t = t,
            None => {
                check_experiment(self.tolerance, t, self.stop_time)
                    .map_err(CallError::InvalidArgument)?;
                self.start_time = t;
                self.initial = None;
            }
        }
        self.outputs_valid = false;
        Ok(())
    }

    /// fmi2SetContinuousStates (Model Exchange).
    pub fn set_continuous_states(&mut self, x: &[f64]) -> Result<(), CallError> {
        let call = "fmi2SetContinuousStates";
        self.require_interface(call, Interface::ModelExchange)?;
        self.require(call, &[Phase::EventMode, Phase::ContinuousTime])?;
        if x.len() != self.described_states {
            return Err(CallError::InvalidArgument(format!(
                "nx = {} where the unit has {} continuous states",
                x.len(),
                self.described_states
            )));
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(CallError::InvalidArgument(format!(
                "state {} (\"{}\") is {}",
                i,
                self.model.layout().names[i],
                x[i]
            )));
        }
        if let Some(c) = self.continuous.as_mut() {
            c.x.copy_from_slice(x);
        }
        self.outputs_valid = false;
        Ok(())
    }

    /// The phases in which the continuous states can be read.
    const STATES_READABLE: [Phase; 4] = [
        Phase::Initialization,
        Phase::EventMode,
        Phase::ContinuousTime,
        Phase::Terminated,
    ];

    /// Checks a Model Exchange read of `n` entries per state.
    fn check_state_read(&self, call: &'static str, n: usize) -> Result<(), CallError> {
        self.require_interface(call, Interface::ModelExchange)?;
        self.require(call, &Self::STATES_READABLE)?;
        if n != self.described_states {
            return Err(CallError::InvalidArgument(format!(
                "nx = {n} where the unit has {} continuous states",
                self.described_states
            )));
        }
        Ok(())
    }

    /// fmi2GetContinuousStates (Model Exchange).
    pub fn get_continuous_states(&mut self, x: &mut [f64]) -> Result<(), CallError> {
        self.check_state_read("fmi2GetContinuousStates", x.len())?;
        let state = self.current_state()?;
        if state.len() != x.len() {
            return Err(CallError::InvalidArgument(format!(
                "the parameters set give the model {} states where the description declares {}",
                state.len(),
                x.len()
            )));
        }
        x.copy_from_slice(state);
        Ok(())
    }

    /// fmi2GetDerivatives (Model Exchange).
    pub fn get_derivatives(&mut self, dx: &mut [f64]) -> Result<(), CallError> {
        self.check_state_read("fmi2GetDerivatives", dx.len())?;
        let rates = self.rates()?;
        dx.copy_from_slice(&rates);
        Ok(())
    }

    /// fmi2GetNominalsOfContinuousStates (Model Exchange): the typical size
    /// of each state, as the unit's own solver scales its tolerances.
    pub fn get_nominals(&mut self, nominals: &mut [f64]) -> Result<(), CallError> {
        let call = "fmi2GetNominalsOfContinuousStates";
        self.require_interface(call, Interface::ModelExchange)?;
        self.require(
            call,
            &[
                Phase::Instantiated,
                Phase::Initialization,
                Phase::EventMode,
                Phase::ContinuousTime,
                Phase::Terminated,
            ],
        )?;
        let nominal = &self.model.layout().nominal;
        if nominals.len() != nominal.len() {
            return Err(CallError::InvalidArgument(format!(
                "nx = {} where the unit has {} continuous states",
                nominals.len(),
                nominal.len()
            )));
        }
        nominals.copy_from_slice(nominal);
        Ok(())
    }

    /// fmi2GetEventIndicators (Model Exchange): the unit has none (its only
    /// events are time events).
    pub fn get_event_indicators(&mut self, n: usize) -> Result<(), CallError> {
        let call = "fmi2GetEventIndicators";
        self.require_interface(call, Interface::ModelExchange)?;
        self.require(call, &Self::STATES_READABLE)?;
        if n != 0 {
            return Err(CallError::InvalidArgument(format!(
                "ni = {n} where the unit has no event indicators"
            )));
        }
        Ok(())
    }

    /// fmi2EnterEventMode (Model Exchange).
    pub fn enter_event_mode(&mut self) -> Result<(), CallError> {
        self.require_interface("fmi2EnterEventMode", Interface::ModelExchange)?;
        self.require(
            "fmi2EnterEventMode",
            &[Phase::ContinuousTime, Phase::EventMode],
        )?;
        self.phase = Phase::EventMode;
        Ok(())
    }

    /// fmi2NewDiscreteStates (Model Exchange): no discrete states change;
    /// the next time event is the reference's next breakpoint.
    pub fn new_discrete_states(&mut self) -> Result<EventInfo, CallError> {
        self.require_interface("fmi2NewDiscreteStates", Interface::ModelExchange)?;
        self.require("fmi2NewDiscreteStates", &[Phase::EventMode])?;
        let t = self.time();
        let margin = 1e-12 * t.abs().max(1.0);
        let next_event_time = (self.source.scenario.reference.breakpoints().into_iter())
            .filter(|&b| b > t + margin)
            .min_by(f64::total_cmp);
        Ok(EventInfo { next_event_time })
    }

    /// fmi2EnterContinuousTimeMode (Model Exchange).
    pub fn enter_continuous_time_mode(&mut self) -> Result<(), CallError> {
        self.require_interface("fmi2EnterContinuousTimeMode", Interface::ModelExchange)?;
        self.require("fmi2EnterContinuousTimeMode", &[Phase::EventMode])?;
        self.phase = Phase::ContinuousTime;
        Ok(())
    }

    /// fmi2CompletedIntegratorStep (Model Exchange): never asks for an event
    /// or the end of the simulation.
    pub fn completed_integrator_step(&mut self) -> Result<(), CallError> {
        self.require_interface("fmi2CompletedIntegratorStep", Interface::ModelExchange)?;
        self.require("fmi2CompletedIntegratorStep", &[Phase::ContinuousTime])?;
        Ok(())
    }
}

/// The `guid="..."` attribute of a model description.
pub(crate) fn description_guid(description: &str) -> String {
    description
        .split_once("guid=\"")
        .and_then(|(_, rest)| rest.split_once('"'))
        .map(|(guid, _)| guid.to_string())
        .unwrap_or_default()
}
