//! The assembled, immutable stage model: its structure (bodies, force
//! elements, servo, state layout, signals), the evaluator chosen for it when
//! it was built, and the robot description it was built from. Everything a
//! user does with a model (simulate, linearise, find equilibria, read
//! outputs) starts here; the evaluation paths below it see only the structure.

use std::sync::{Arc, OnceLock};

use nalgebra::{Matrix3, Vector3};

use crate::dynamics::{EvaluationPath, InputValues, Workspace};
use crate::elements::{
    Body, Controller, FrictionContact, Inputs, Isolator, PointAxis, SignalInfo, StateLayout,
    Structure,
};
use crate::evaluator::Evaluator;
use crate::machine_code::{Compiled, Function, MachineCode, NotCompiled};
use crate::robot::RobotSpec;
use crate::scalar::Scalar;

/// The assembled stage. Built once by [`crate::assemble`] and immutable: its
/// parts are read through methods, and parameter changes build a new model
/// (so nothing resolved at build time can go stale).
#[derive(Debug, Clone)]
pub struct Model {
    pub(crate) name: String,
    pub(crate) structure: Structure,
    /// How the right-hand side is evaluated (chosen once, when built).
    pub(crate) evaluator: Evaluator,
    /// The robot file after the scenario's overrides: what the parameter table reads.
    pub(crate) robot: RobotSpec,
    /// The right-hand side and the implicit bristle stage as machine code,
    /// each compiled when [`Model::compile_with`] is first called for it
    /// (shared by the model's clones).
    pub(crate) machine_code: Arc<[OnceLock<Compiled>; 2]>,
    /// What a reader should know about this legal but odd study (a
    /// compensator's model with f_s below f_c, say).
    pub(crate) notes: Vec<String>,
    /// The scenario's `[compensation]` and `[dob]` as written (the
    /// parameter table reads the compensator's and observer's values here).
    pub(crate) compensation: Vec<crate::compensation::CompensationSettings>,
    pub(crate) observer: Option<crate::compensation::ObserverSettings>,
    /// The robot file's visual solids, placed on their bodies.
    pub(crate) visuals: Vec<crate::elements::Visual>,
}

impl Model {
    /// Robot name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The robot file's `<visual>` boxes, cylinders and spheres, each on the
    /// body its link merged into (or the world), for drawing.
    pub fn visuals(&self) -> &[crate::elements::Visual] {
        &self.visuals
    }

    /// What a reader should know about this legal but odd study, one
    /// sentence each (the program prints them as warnings).
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// Moving bodies, parents before children.
    pub fn bodies(&self) -> &[Body] {
        &self.structure.bodies
    }

    /// Isolator bushings.
    pub fn isolators(&self) -> &[Isolator] {
        &self.structure.isolators
    }

    /// LuGre contacts.
    pub fn frictions(&self) -> &[FrictionContact] {
        &self.structure.frictions
    }

    /// Actuators.
    pub fn actuators(&self) -> &[PointAxis] {
        &self.structure.actuators
    }

    /// Sensors.
    pub fn sensors(&self) -> &[PointAxis] {
        &self.structure.sensors
    }

    /// The servo controller, if any.
    pub fn controller(&self) -> Option<&Controller> {
        self.structure.controller.as_ref()
    }

    /// Gravity, world frame, m/s^2.
    pub fn gravity(&self) -> &Vector3<f64> {
        &self.structure.gravity
    }

    /// State layout.
    pub fn layout(&self) -> &StateLayout {
        &self.structure.layout
    }

    /// Output signals, in the order [`Model::outputs`] writes them.
    pub fn signals(&self) -> &[SignalInfo] {
        &self.structure.signals
    }

    /// The robot description the model was built from, after the scenario's
    /// overrides (the values [`crate::Parameter::read`] reads).
    pub fn robot(&self) -> &RobotSpec {
        &self.robot
    }

    /// Number of states.
    pub fn n_states(&self) -> usize {
        self.structure.n_states()
    }

    /// Index of a named output signal.
    pub fn signal_index(&self, name: &str) -> Option<usize> {
        self.signals().iter().position(|s| s.name == name)
    }

    /// The state at the zero configuration: joints at zero, quaternions at the
    /// identity, everything else zero.
    pub fn zero_state(&self) -> Vec<f64> {
        self.structure.zero_state()
    }

    /// Which evaluation [`Model::rhs`] takes for this model.
    pub fn evaluation_path(&self) -> EvaluationPath {
        self.evaluator.path()
    }

    /// A workspace sized for this model, for `f64` evaluation.
    pub fn workspace(&self) -> Workspace<f64> {
        self.workspace_of()
    }

    /// A workspace sized for this model, for any scalar type.
    pub fn workspace_of<S: Scalar>(&self) -> Workspace<S> {
        self.structure.workspace_with(self.evaluator.scratch())
    }

    /// State derivative `dx = f(x, u)`. `x` and `dx` have [`Model::n_states`] entries.
    /// The evaluation depends on the structure (see [`EvaluationPath`]) and
    /// runs as machine code once that is compiled ([`Model::compile_with`]: the
    /// engines ask for it when a run is long enough to pay for it);
    /// [`Model::rhs_general`] is the general path every model can take.
    #[inline]
    pub fn rhs(&self, x: &[f64], inputs: &Inputs, dx: &mut [f64], ws: &mut Workspace) {
        let inputs = inputs.values();
        if let Some(native) = self.compiled(Function::Rhs)
            && native.rhs(x, &inputs, dx).is_ok()
        {
            return;
        }
        self.evaluator.rhs(&self.structure, x, &inputs, dx, ws);
    }

    /// A function of the model as machine code, compiled by `compile` on
    /// this call if no call compiled it before (the code generator is the
    /// crate `fistage-codegen`, whose `machine_code` calls this); or why it
    /// is not compiled, in which case every evaluation runs the generic code
    /// ([`Model::rhs_of`], [`Model::rhs_implicit_of`]). Both give the same
    /// numbers.
    pub fn compile_with(
        &self,
        function: Function,
        compile: impl FnOnce(&Model, Function) -> Compiled,
    ) -> Result<&dyn MachineCode, &NotCompiled> {
        match self
            .native_slot(function)
            .get_or_init(|| compile(self, function))
        {
            Ok(code) => Ok(code.as_ref()),
            Err(why) => Err(why),
        }
    }

    /// A function of the model as machine code if it has been compiled
    /// already (compiling takes about a millisecond per hundred operations:
    /// worth it for a run, not for one evaluation).
    #[inline]
    pub fn compiled(&self, function: Function) -> Option<&dyn MachineCode> {
        match self.native_slot(function).get()? {
            Ok(code) => Some(code.as_ref()),
            Err(_) => None,
        }
    }

    fn native_slot(&self, function: Function) -> &OnceLock<Compiled> {
        match function {
            Function::Rhs => &self.machine_code[0],
            Function::ImplicitStage => &self.machine_code[1],
        }
    }

    /// The same model with nothing compiled: every evaluation runs the
    /// generic code (for comparisons and measurements).
    pub fn interpreted(&self) -> Model {
        let off = || {
            let slot = OnceLock::new();
            let _ = slot.set(Err(NotCompiled::Disabled));
            slot
        };
        Model {
            machine_code: Arc::new([off(), off()]),
            ..self.clone()
        }
    }

    /// [`Model::rhs`] in any scalar type: the evaluation simulation uses,
    /// differentiated exactly with dual numbers.
    #[inline]
    pub fn rhs_of<S: Scalar>(
        &self,
        x: &[S],
        inputs: &InputValues<S>,
        dx: &mut [S],
        ws: &mut Workspace<S>,
    ) {
        self.evaluator.rhs(&self.structure, x, inputs, dx, ws);
    }

    /// [`Model::rhs`] at an implicit stage of the bristle states, for
    /// implicit-explicit integrators: on entry each bristle entry of `x`
    /// ([`Model::bristle_states`]) holds the explicit part `c` of the stage, on return the `z`
    /// that solves `z = c + step z'(v, z)` exactly (the bristle equation is
    /// linear in `z` at the stage's slip velocity, which does not depend on
    /// any bristle state); `dx` is the derivative at the solved point.
    #[inline]
    pub fn rhs_implicit_bristles(
        &self,
        x: &mut [f64],
        inputs: &InputValues<f64>,
        step: f64,
        dx: &mut [f64],
        ws: &mut Workspace,
    ) {
        self.rhs_implicit_of(x, inputs, step, dx, ws);
    }

    /// [`Model::rhs_implicit_bristles`] in any scalar type.
    #[inline]
    pub fn rhs_implicit_of<S: Scalar>(
        &self,
        x: &mut [S],
        inputs: &InputValues<S>,
        step: S,
        dx: &mut [S],
        ws: &mut Workspace<S>,
    ) {
        ws.bristles.set_step(Some(step));
        self.evaluator.rhs(&self.structure, x, inputs, dx, ws);
        ws.bristles.set_step(None);
        for (contact, z) in self.structure.frictions.iter().zip(ws.bristles.solved()) {
            x[contact.z_index] = *z;
        }
        if let Some(controller) = &self.structure.controller {
            let solved = ws.bristles.solved_compensators();
            for (feedforward, w) in controller.feedforward.iter().zip(solved) {
                if let Some(index) = feedforward.bristle_state() {
                    x[index] = *w;
                }
            }
        }
    }

    /// Indices of the bristle states: the LuGre contacts' in contact order,
    /// then the feedforward compensators' LuGre models', in servo order.
    pub fn bristle_states(&self) -> Vec<usize> {
        let contacts = self.structure.frictions.iter().map(|f| f.z_index);
        let compensators = (self.structure.controller.iter())
            .flat_map(|c| &c.feedforward)
            .filter_map(|f| f.bristle_state());
        contacts.chain(compensators).collect()
    }

    /// State derivative by the general recursive dynamics, for any model and
    /// scalar (the reference every faster evaluation is tested against).
    pub fn rhs_general<S: Scalar>(
        &self,
        x: &[S],
        inputs: &InputValues<S>,
        dx: &mut [S],
        ws: &mut Workspace<S>,
    ) {
        self.structure.rhs_general(x, inputs, dx, ws);
    }

    /// Kinematics and force elements at state x; results stay in `ws`
    /// (`ws.elements`).
    pub fn evaluate(&self, x: &[f64], inputs: &Inputs, ws: &mut Workspace) {
        self.structure.evaluate(x, inputs, ws);
    }

    /// Each sensor's reading at state x, m, in [`Model::sensors`] order
    /// (`out` has one entry per sensor): what [`Model::evaluate`] leaves in
    /// `ws.elements.sensor_position`, from the kinematics alone, without
    /// evaluating a force element.
    pub fn sensor_positions(&self, x: &[f64], out: &mut [f64], ws: &mut Workspace) {
        self.structure.sensor_positions(x, out, ws);
    }

    /// The slip velocity of every friction contact at state x, m/s, in
    /// contact order (`out` has one entry per [`Model::frictions`]; extra
    /// entries are left as they are): where one changes sign, the bristle
    /// law has a kink.
    #[inline]
    pub fn slip_velocities(
        &self,
        x: &[f64],
        inputs: &InputValues<f64>,
        out: &mut [f64],
        ws: &mut Workspace,
    ) {
        self.evaluator
            .slip_velocities(&self.structure, x, inputs, out, ws);
    }

    /// Writes every output signal (see [`Model::signals`]) at state x.
    pub fn outputs(&self, x: &[f64], inputs: &Inputs, out: &mut [f64], ws: &mut Workspace) {
        self.structure.outputs(x, inputs, out, ws);
    }

    /// [`Model::outputs`] in any scalar type: with dual numbers it gives exact
    /// derivatives of the outputs (e.g. their direct dependence on the inputs).
    pub fn outputs_of<S: Scalar>(
        &self,
        x: &[S],
        inputs: &InputValues<S>,
        out: &mut [S],
        ws: &mut Workspace<S>,
    ) {
        self.structure.outputs_of(x, inputs, out, ws);
    }

    /// Kinetic energy + isolator springs + bristle springs sigma0 z^2 / 2 +
    /// gravitational potential (relative to the world origin), J. With no servo
    /// and no platform motion this never increases.
    pub fn stored_energy(&self, x: &[f64], ws: &mut Workspace) -> f64 {
        self.structure.stored_energy(x, ws)
    }

    /// The joint-space mass matrix at state x (positions are read from x).
    pub fn mass_matrix(&self, x: &[f64]) -> nalgebra::DMatrix<f64> {
        crate::dynamics::mass_matrix(&self.structure, x)
    }

    /// World pose (rotation, origin) of every body at state x.
    pub fn body_poses(&self, x: &[f64]) -> Vec<(Matrix3<f64>, Vector3<f64>)> {
        self.structure.body_poses(x)
    }
}
