//! The servo of a closed-loop record: a scenario's own servo law (PID,
//! feedforward compensation, disturbance observer), its reference and its
//! counter-surface velocity, closing the loop around the one-mass plant of
//! [`super::plant`] on the simulated encoder reading.
//!
//! The law is [`Controller::law`], the one `fistage run` integrates, in
//! continuous time: the force of a closed-loop record is the servo's, and
//! the plant simulation recomputes it from the simulated position instead of
//! replaying the logged one. The servo's own states (error integral,
//! compensator, observer) are laid out after the plant's `(x, v, z)`.
//!
//! Only a stage whose plant *is* paper Eq. 31 qualifies: one joint, one
//! friction contact, no isolator, the encoder and the contact reading that
//! joint one to one. A stage with FI has a second mass behind the isolator;
//! the fit refuses it rather than fit the wrong plant.

use std::path::Path;

use fistage_model::initial_state;
use fistage_model::{
    Controller, InputValues, Inputs, LugreParams, Model, Reference, Scalar, ServoValues, load,
};

use crate::error::{IdentError, Result};

/// Number of plant states before the servo's: position, velocity, bristle.
pub const PLANT_STATES: usize = 3;

/// The most servo states a controller has (integral, three feedforward, observer).
pub const MAX_SERVO_STATES: usize = 5;

/// A scenario's servo, reference and platform, for a closed-loop fit.
#[derive(Debug, Clone, PartialEq)]
pub struct ServoLoop {
    /// The scenario file, for messages.
    pub source: String,
    /// The servo law, its own states at [`PLANT_STATES`] onwards.
    controller: Controller,
    /// The servo reference.
    reference: Reference,
    /// Counter-surface velocity, m/s.
    pub platform_velocity: f64,
    /// Start values of the servo's states.
    initial: Vec<f64>,
    /// Typical size of each servo state (absolute tolerances).
    nominal: Vec<f64>,
    /// The scenario's own friction parameters (for comparison in reports,
    /// never a start of the fit).
    pub scenario_friction: LugreParams,
    /// The scenario's moving mass, kg.
    pub scenario_mass: f64,
}

impl ServoLoop {
    /// Reads the scenario at `path` and checks that its stage is Eq. 31.
    pub fn from_scenario(path: &Path) -> Result<Self> {
        let loaded = load(path)?;
        let source = path.display().to_string();
        let model = &loaded.model;
        let refuse = |message: String| IdentError::Simulation {
            file: source.clone(),
            message,
        };
        let Some(controller) = model.controller() else {
            return Err(refuse(
                "closed-loop identification needs the scenario's servo, and this scenario has no \
                 [controller]"
                    .into(),
            ));
        };
        let layout = model.layout();
        if layout.nq != 1 || layout.nv != 1 || !model.isolators().is_empty() {
            return Err(refuse(format!(
                "closed-loop identification fits paper Eq. 31, one mass on one contact; this \
                 stage has {} position coordinate(s) and {} isolator(s) (a stage with FI is not \
                 a one-mass plant)",
                layout.nq,
                model.isolators().len()
            )));
        }
        let [friction] = model.frictions() else {
            return Err(refuse(format!(
                "closed-loop identification needs exactly one friction contact, this stage has {}",
                model.frictions().len()
            )));
        };
        let x0 = initial_state(model, &loaded.scenario)?;
        check_one_to_one(model, controller, &x0).map_err(refuse)?;
        let (compact, servo_indices) = compact(controller);
        if servo_indices.len() > MAX_SERVO_STATES {
            return Err(refuse(format!(
                "closed-loop identification follows a servo of at most {MAX_SERVO_STATES} states \
                 (integral, one compensator, observer); this one has {}",
                servo_indices.len()
            )));
        }
        Ok(Self {
            source,
            controller: compact,
            reference: loaded.scenario.reference.clone(),
            platform_velocity: loaded.scenario.platform_velocity,
            initial: servo_indices.iter().map(|&i| x0[i]).collect(),
            nominal: servo_indices.iter().map(|&i| layout.nominal[i]).collect(),
            scenario_friction: friction.lugre,
            scenario_mass: model.mass_matrix(&x0)[(0, 0)],
        })
    }

    /// Number of servo states.
    pub fn n_states(&self) -> usize {
        self.initial.len()
    }

    /// Start values of the servo's states.
    pub fn initial(&self) -> &[f64] {
        &self.initial
    }

    /// Typical size of each servo state.
    pub fn nominal(&self) -> &[f64] {
        &self.nominal
    }

    /// Times in `(t0, t1]` where the reference is not smooth.
    pub fn breakpoints(&self, t0: f64, t1: f64) -> Vec<f64> {
        let mut out: Vec<f64> = (self.reference.breakpoints().into_iter())
            .filter(|&t| t > t0 && t <= t1)
            .collect();
        out.sort_by(f64::total_cmp);
        out
    }

    /// The servo force at time `t` on the plant state `y` (position,
    /// velocity, bristle, then the servo's states), and the values whose
    /// rates [`ServoLoop::write_rates`] writes.
    #[inline]
    pub fn force<S: Scalar>(&self, t: f64, y: &[S]) -> (S, ServoValues<S>) {
        let sample = self.reference.sample(t);
        let inputs = InputValues {
            reference_position: S::constant(sample.position),
            reference_velocity: S::constant(sample.velocity),
            servo_force: S::zero(),
            platform_velocity: S::constant(self.platform_velocity),
        };
        self.controller.law(y[0], y[1], y, &inputs)
    }

    /// Writes the rates of the servo's states into `dy` (laid out as `y`).
    #[inline]
    pub fn write_rates<S: Scalar>(&self, values: &ServoValues<S>, dy: &mut [S]) {
        for (index, rate) in self.controller.state_rates(values) {
            dy[index] = rate;
        }
    }
}

/// The controller with its states renumbered from [`PLANT_STATES`], and
/// the model indices they came from (in the new order).
fn compact(controller: &Controller) -> (Controller, Vec<usize>) {
    let mut out = controller.clone();
    let mut from = Vec::new();
    let mut renumber = |index: &mut usize, count: usize| {
        let old = *index;
        *index = PLANT_STATES + from.len();
        from.extend(old..old + count);
    };
    if let Some(i) = out.integral_index.as_mut() {
        renumber(i, 1);
    }
    for f in out.feedforward.iter_mut() {
        let n = f.n_states();
        renumber(&mut f.state_index, n);
    }
    if let Some(o) = out.observer.as_mut() {
        renumber(&mut o.state_index, 1);
    }
    (out, from)
}

/// Checks that the servo's encoder and the friction contact read the one
/// joint one to one (a unit move of the joint moves the reading by one, a
/// unit joint velocity is a unit slip), so that the plant's `x` is the
/// encoder's reading.
fn check_one_to_one(
    model: &Model,
    controller: &Controller,
    x0: &[f64],
) -> std::result::Result<(), String> {
    let inputs = Inputs::default();
    let mut ws = model.workspace();
    let reading = |x: &[f64], ws: &mut fistage_model::Workspace| {
        model.evaluate(x, &inputs, ws);
        let e = &ws.elements;
        (
            e.sensor_position[controller.sensor],
            e.sensor_velocity[controller.sensor],
            e.slip_velocity[0],
        )
    };
    let (p0, _, _) = reading(x0, &mut ws);
    let mut moved = x0.to_vec();
    let (dq, dv) = (1e-6, 1e-3);
    moved[0] += dq;
    moved[model.layout().v_start()] += dv;
    let (p1, v1, slip) = reading(&moved, &mut ws);
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
    if !close(p1 - p0, dq) || !close(v1, dv) {
        return Err(format!(
            "the encoder '{}' does not read the joint one to one (a joint move of {dq:e} m reads \
             {:e} m)",
            model.sensors()[controller.sensor].name,
            p1 - p0
        ));
    }
    if !close(slip, dv) {
        return Err(format!(
            "the friction contact does not slide with the joint one to one (a joint velocity of \
             {dv:e} m/s slides at {slip:e} m/s)"
        ));
    }
    // At rest the friction is sigma0 z whatever the position, so a joint
    // move changes the acceleration by the change of the servo's force over
    // the mass when the drive pushes the joint one to one.
    let mass = model.mass_matrix(x0)[(0, 0)];
    let values = inputs.values::<f64>();
    let acceleration_and_force = |x: &[f64], ws: &mut fistage_model::Workspace| {
        let mut dx = vec![0.0; x.len()];
        model.rhs(x, &inputs, &mut dx, ws);
        let (position, _, _) = reading(x, ws);
        let (force, _) = controller.law(position, 0.0, x, &values);
        (dx[model.layout().v_start()], force)
    };
    let mut moved = x0.to_vec();
    moved[model.layout().v_start()] = 0.0;
    let (a0, f0) = acceleration_and_force(&moved, &mut ws);
    moved[0] += dq;
    let (a1, f1) = acceleration_and_force(&moved, &mut ws);
    let (pushed, commanded) = (mass * (a1 - a0), f1 - f0);
    if (pushed - commanded).abs() > 1e-6 * commanded.abs().max(1e-12) {
        return Err(format!(
            "the drive '{}' does not push the joint one to one (a servo force change of {commanded:e} \
             N moves the joint with {pushed:e} N)",
            model.actuators()[controller.actuator].name
        ));
    }
    Ok(())
}
