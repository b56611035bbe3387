//! What a model is made of, once assembled: rigid bodies in a tree rooted at
//! the world, force elements attached to them, the servo controller, the
//! named state layout and output signals, and the inputs it is driven by.
//! `Structure` holds them for every evaluation path; [`crate::Model`]
//! wraps it with the evaluator chosen for it. The servo's parts are data
//! here (its compensators' friction models, feedforward, virtual bearing and
//! observer); their law is `servo.rs`.

use nalgebra::{Isometry3, Matrix3, Vector3};

use crate::dahl::DahlParams;
use crate::lugre::LugreParams;
use crate::reference::ReferenceSample;
use crate::scalar::Scalar;

/// What a force element or sensor is attached to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Frame {
    /// The ground (or a link welded to it).
    World,
    /// A moving body, by index into [`crate::Model::bodies`].
    Body(usize),
}

/// The joint that connects a body to its parent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointMotion {
    /// Translation along a unit axis of the joint frame.
    Prismatic {
        /// Unit axis in the joint frame.
        axis: Vector3<f64>,
    },
    /// Rotation about a unit axis of the joint frame through its origin.
    Revolute {
        /// Unit axis in the joint frame.
        axis: Vector3<f64>,
    },
    /// Free motion: position (3) and unit quaternion (4) relative to the joint
    /// frame; velocity as linear (3) and angular (3) velocity in the joint frame.
    Floating,
}

impl JointMotion {
    /// Number of position coordinates.
    pub fn nq(&self) -> usize {
        match self {
            Self::Floating => 7,
            _ => 1,
        }
    }

    /// Number of velocity coordinates (degrees of freedom).
    pub fn nv(&self) -> usize {
        match self {
            Self::Floating => 6,
            _ => 1,
        }
    }

    /// Whether the joint can rotate its child.
    pub fn rotates(&self) -> bool {
        !matches!(self, Self::Prismatic { .. })
    }
}

/// A joint with its place in the state vector.
#[derive(Debug, Clone)]
pub struct Joint {
    /// Joint name from the robot file.
    pub name: String,
    /// Kind and axis.
    pub motion: JointMotion,
    /// Joint frame in the parent body frame (world frame for root bodies).
    pub origin: Isometry3<f64>,
    /// Rotation of `origin` as a matrix (kept to avoid conversions in the hot path).
    pub origin_rotation: Matrix3<f64>,
    /// First position coordinate in the state vector.
    pub q_offset: usize,
    /// First velocity coordinate, counted within the velocity block.
    pub v_offset: usize,
}

/// A rigid body: one moving link and every link welded to it by fixed joints.
#[derive(Debug, Clone)]
pub struct Body {
    /// Name of the body's own link.
    pub name: String,
    /// Links merged into this body (its own link first).
    pub links: Vec<String>,
    /// Parent body, `None` for bodies jointed to the world.
    pub parent: Option<usize>,
    /// The joint to the parent.
    pub joint: Joint,
    /// Mass, kg.
    pub mass: f64,
    /// Centre of mass in the body frame, m.
    pub com: Vector3<f64>,
    /// Inertia about the centre of mass, body-frame axes, kg m^2.
    pub inertia: Matrix3<f64>,
    /// Velocity indices of every joint between the world and this body.
    pub chain: Vec<usize>,
    /// The mass block (subtree of one root body) this body belongs to.
    pub block: usize,
    /// Positions of `chain` within that block.
    pub chain_local: Vec<usize>,
    /// Whether any joint between the world and this body rotates (otherwise its
    /// angular velocity and acceleration are zero and its inertia never enters).
    pub turns: bool,
}

/// The joint-space mass matrix is block diagonal: one block per subtree hanging
/// from the world. Each block is factored on its own, and blocks without
/// rotating joints are constant and kept inverted.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MassBlock {
    /// Velocity indices of the block, ascending.
    pub dofs: Vec<usize>,
    /// Bodies of the subtree.
    pub bodies: Vec<usize>,
    /// Row-major inverse when the block does not depend on the configuration.
    pub constant_inverse: Option<Vec<f64>>,
    /// When the block is one floating body: that body and its mass
    /// properties, for the closed-form solve.
    pub free_body: Option<(usize, RigidBody)>,
}

/// A linear six-axis bushing (friction isolator).
#[derive(Debug, Clone)]
pub struct Isolator {
    /// Element name.
    pub name: String,
    /// Parent side.
    pub parent: Frame,
    /// Child side.
    pub child: Frame,
    /// Attach frame in the parent body frame.
    pub parent_attach: Isometry3<f64>,
    /// Attach frame in the child body frame (coincides with the parent's at the
    /// zero configuration).
    pub child_attach: Isometry3<f64>,
    /// Stiffness x, y, z (N/m) and rx, ry, rz (N m/rad) in attach-frame axes.
    pub stiffness: [f64; 6],
    /// Damping x, y, z (N s/m) and rx, ry, rz (N m s/rad).
    pub damping: [f64; 6],
    /// Rotations of the two attach frames as matrices.
    pub attach_rotations: [Matrix3<f64>; 2],
    /// Whether each attach rotation is the identity (its product can be skipped).
    pub attach_is_identity: [bool; 2],
}

/// A solid of the robot file's `<visual>`s, placed on the body its link
/// merged into (or on the world, for links welded to it): what a 3D view draws.
#[derive(Debug, Clone, PartialEq)]
pub struct Visual {
    /// The link that declared it.
    pub link: String,
    /// The body (or the world) it moves with.
    pub frame: Frame,
    /// The solid's frame in the body frame (the world's for [`Frame::World`]).
    pub origin: Isometry3<f64>,
    /// The solid.
    pub shape: crate::robot::VisualShape,
}

/// A LuGre contact between a body and its counter-surface. The counter-surface
/// (rail or platform) is fixed to the world and moves along the contact axis at
/// the platform velocity.
#[derive(Debug, Clone)]
pub struct FrictionContact {
    /// Element name.
    pub name: String,
    /// Sliding body.
    pub body: usize,
    /// Contact point in the body frame.
    pub point: Vector3<f64>,
    /// Sliding axis in world coordinates (the rail direction).
    pub axis: Vector3<f64>,
    /// LuGre parameters.
    pub lugre: LugreParams,
    /// Index of the bristle state z in the state vector.
    pub z_index: usize,
    /// `point . axis` in the zero configuration (for contact displacements).
    pub zero_offset: f64,
}

/// A point on a body and a world-fixed direction: actuators (force along the
/// direction at the point) and sensors (displacement of the point along it).
#[derive(Debug, Clone)]
pub struct PointAxis {
    /// Element name.
    pub name: String,
    /// Body carrying the element.
    pub body: usize,
    /// Point in the body frame.
    pub point: Vector3<f64>,
    /// Direction in world coordinates (fixed: a scale or magnet track on the ground).
    pub axis: Vector3<f64>,
    /// `point . axis` in the zero configuration; sensor readings are relative to it.
    pub zero_offset: f64,
}

/// PID servo acting through an actuator on a sensor reading.
#[derive(Debug, Clone, PartialEq)]
pub struct Controller {
    /// Index into [`crate::Model::sensors`].
    pub sensor: usize,
    /// Index into [`crate::Model::actuators`].
    pub actuator: usize,
    /// Proportional gain, N/m.
    pub k: f64,
    /// Derivative gain, N s/m.
    pub c: f64,
    /// Integral gain, N/(m s).
    pub k_i: f64,
    /// Index of the integral of the tracking error in the state vector (present
    /// only when k_i > 0, so that a PD loop has no spurious zero eigenvalue).
    pub integral_index: Option<usize>,
    /// Feedforward friction compensators (`[compensation]` or
    /// `[[compensation]]`), at most [`crate::compensation::MAX_COMPENSATORS`].
    pub feedforward: Vec<Feedforward>,
    /// Disturbance observer, if any (`[dob]`).
    pub observer: Option<Observer>,
}

/// What a state entry is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StateKind {
    /// Joint translation, m.
    Translation,
    /// Joint angle, rad.
    Angle,
    /// Quaternion component, 1.
    Quaternion,
    /// Linear velocity, m/s.
    LinearVelocity,
    /// Angular velocity, rad/s.
    AngularVelocity,
    /// LuGre bristle deflection z, m.
    Bristle,
    /// Integral of the tracking error, m s.
    ErrorIntegral,
    /// Bristle deflection of a feedforward compensator's LuGre model, m.
    CompensatorBristle,
    /// Friction force of a feedforward compensator's Dahl model, N.
    CompensatorForce,
    /// Isolator deflection of a feedforward compensator's virtual bearing, m.
    CompensatorDeflection,
    /// Velocity of a feedforward compensator's virtual bearing, m/s.
    CompensatorVelocity,
    /// State of a disturbance observer (estimate less its velocity term), N.
    ObserverState,
}

impl StateKind {
    /// SI unit.
    pub fn unit(self) -> &'static str {
        match self {
            Self::Translation => "m",
            Self::Angle => "rad",
            Self::Quaternion => "1",
            Self::LinearVelocity => "m/s",
            Self::AngularVelocity => "rad/s",
            Self::Bristle => "m",
            Self::ErrorIntegral => "m s",
            Self::CompensatorBristle | Self::CompensatorDeflection => "m",
            Self::CompensatorVelocity => "m/s",
            Self::CompensatorForce | Self::ObserverState => "N",
        }
    }
}

/// Names, kinds and blocks of the state vector
/// `[positions (nq) | velocities (nv) | bristles (nz) | servo states]`, the
/// servo's own states being the error integral, the feedforward compensator's
/// state and the observer's, each present only when the servo has it.
#[derive(Debug, Clone, PartialEq)]
pub struct StateLayout {
    /// Entry names, e.g. `table_x.q`, `table.qw`, `bearing_friction.z`.
    pub names: Vec<String>,
    /// Entry kinds.
    pub kinds: Vec<StateKind>,
    /// Typical magnitude per entry, used to scale absolute tolerances.
    pub nominal: Vec<f64>,
    /// Number of position coordinates.
    pub nq: usize,
    /// Number of velocity coordinates.
    pub nv: usize,
    /// Number of bristle states.
    pub nz: usize,
}

impl StateLayout {
    /// Total number of states.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Whether the model has no state at all.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Index of a named entry.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Start of the velocity block.
    pub fn v_start(&self) -> usize {
        self.nq
    }

    /// Start of the bristle block.
    pub fn z_start(&self) -> usize {
        self.nq + self.nv
    }
}

/// Inputs of the model: what a co-simulator or a scenario drives.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Inputs {
    /// Servo reference, m and m/s.
    pub reference: ReferenceSample,
    /// Force added to the actuator force, N (the whole force when there is no controller).
    pub servo_force: f64,
    /// Counter-surface velocity along every contact axis, m/s.
    pub platform_velocity: f64,
}

impl Inputs {
    /// Names and units of the inputs, in a fixed order.
    pub const NAMES: [(&'static str, &'static str); 4] = [
        ("reference_position", "m"),
        ("reference_velocity", "m/s"),
        ("servo_force", "N"),
        ("platform_velocity", "m/s"),
    ];
}

/// A named output signal.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SignalInfo {
    /// Name, e.g. `encoder.position`.
    pub name: String,
    /// SI unit.
    pub unit: &'static str,
}

/// Mass properties of a free rigid body.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RigidBody {
    /// 1 / mass, 1/kg.
    pub inverse_mass: f64,
    /// Centre of mass in body axes, m.
    pub com: Vector3<f64>,
    /// Inertia about the centre of mass, body axes.
    pub inertia: Matrix3<f64>,
    /// Its inverse.
    pub inverse_inertia: Matrix3<f64>,
}

/// World motion of one body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyMotion {
    /// Orientation of the body frame in the world.
    pub rotation: Matrix3<f64>,
    /// Position of the body-frame origin, m.
    pub origin: Vector3<f64>,
    /// Angular velocity, world frame, rad/s.
    pub omega: Vector3<f64>,
    /// Velocity of the body-frame origin, world frame, m/s.
    pub velocity: Vector3<f64>,
}

impl BodyMotion {
    /// At rest at the world origin.
    pub fn identity() -> Self {
        Self {
            rotation: Matrix3::identity(),
            origin: Vector3::zeros(),
            omega: Vector3::zeros(),
            velocity: Vector3::zeros(),
        }
    }
}

/// A force and the moment it carries about the world origin (not gravity).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyWrench {
    /// Force, world frame, N.
    pub force: Vector3<f64>,
    /// Moment about the world origin, world frame, N m.
    pub moment: Vector3<f64>,
}

impl BodyWrench {
    /// The moment about a point `center` (e.g. the body's centre of mass).
    pub fn moment_about(&self, center: &Vector3<f64>) -> Vector3<f64> {
        self.moment - center.cross(&self.force)
    }
}

/// The parts of an assembled model that every evaluation path reads.
#[derive(Debug, Clone)]
pub(crate) struct Structure {
    /// Moving bodies, parents before children.
    pub(crate) bodies: Vec<Body>,
    /// Isolator bushings.
    pub(crate) isolators: Vec<Isolator>,
    /// LuGre contacts.
    pub(crate) frictions: Vec<FrictionContact>,
    /// Actuators.
    pub(crate) actuators: Vec<PointAxis>,
    /// Sensors.
    pub(crate) sensors: Vec<PointAxis>,
    /// Servo controller.
    pub(crate) controller: Option<Controller>,
    /// Gravity, world frame, m/s^2.
    pub(crate) gravity: Vector3<f64>,
    /// State layout.
    pub(crate) layout: StateLayout,
    /// Output signals.
    pub(crate) signals: Vec<SignalInfo>,
    /// Diagonal blocks of the mass matrix.
    pub(crate) mass_blocks: Vec<MassBlock>,
}

impl Structure {
    /// The actuator that receives the external `servo_force` input: the
    /// controller's, or the first actuator when there is no controller.
    #[inline]
    pub(crate) fn servo_actuator(&self) -> Option<usize> {
        match &self.controller {
            Some(controller) => Some(controller.actuator),
            None => (!self.actuators.is_empty()).then_some(0),
        }
    }

    /// Number of states.
    pub(crate) fn n_states(&self) -> usize {
        self.layout.len()
    }

    /// The state at the zero configuration: joints at zero, quaternions at
    /// the identity, everything else zero.
    pub(crate) fn zero_state(&self) -> Vec<f64> {
        let mut x = vec![0.0; self.n_states()];
        for body in &self.bodies {
            if matches!(body.joint.motion, JointMotion::Floating) {
                x[body.joint.q_offset + 3] = 1.0;
            }
        }
        x
    }
}

/// A friction model a compensator simulates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionModel {
    /// LuGre; the state is the compensator's bristle deflection, m.
    Lugre(LugreParams),
    /// Dahl; the state is the friction force, N.
    Dahl(DahlParams),
}

impl FrictionModel {
    /// A parameter by name (NaN for a name the model does not have).
    pub fn get(&self, name: &str) -> f64 {
        match self {
            Self::Lugre(p) => LugreParams::key(name).map_or(f64::NAN, |k| k.get(p)),
            Self::Dahl(p) => DahlParams::key(name).map_or(f64::NAN, |k| k.get(p)),
        }
    }

    /// Sets a parameter by name (a name the model does not have is ignored).
    pub fn set(&mut self, name: &str, value: f64) {
        match self {
            Self::Lugre(p) => {
                if let Some(k) = LugreParams::key(name) {
                    k.set(p, value);
                }
            }
            Self::Dahl(p) => {
                if let Some(k) = DahlParams::key(name) {
                    k.set(p, value);
                }
            }
        }
    }

    /// The first parameter that breaks a rule: (name, what it must be).
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        match self {
            Self::Lugre(p) => p.validate().map_err(fault),
            Self::Dahl(p) => p.validate(),
        }
    }

    /// Checks what makes the model's law defined, each key's own rule (a
    /// LuGre model's `f_s` may lie below its `f_c`: see
    /// [`LugreParams::validate_each`]); else the first key at fault and why.
    pub fn validate_law(&self) -> Result<(), (&'static str, String)> {
        match self {
            Self::Lugre(p) => p.validate_each().map_err(fault),
            Self::Dahl(p) => p.validate(),
        }
    }

    /// What is physically odd about a model whose law is defined, one
    /// sentence each: a LuGre model with f_s below f_c (a friction level
    /// that rises with speed).
    pub fn oddities(&self) -> Vec<String> {
        match self {
            Self::Lugre(p) if p.f_s < p.f_c => {
                // Six significant digits: the errors' products are not round.
                let round = |v: f64| {
                    let scale = 10f64.powi(5 - v.abs().log10().floor() as i32);
                    crate::rule::show((v * scale).round() / scale)
                };
                vec![format!(
                    "the compensator's model has f_s = {} N below f_c = {} N: its Stribeck \
                     curve rises with speed, which no bearing does (the law stays defined: \
                     g >= f_s > 0)",
                    round(p.f_s),
                    round(p.f_c)
                )]
            }
            _ => Vec::new(),
        }
    }

    /// The model as felt through an isolator of stiffness `k_j` and damping
    /// `c_j` along the contact axis, the bearing's mass neglected (paper
    /// Section 2.1). In pre-motion the contact is a spring and damper
    /// (`sigma0`, `sigma1`) in series with the isolator's (`k_j`, `c_j`); at
    /// low frequency the pair acts as the stiffness
    /// `k_c = sigma0 k_j / (sigma0 + k_j)` (Eq. 1) and the damping
    /// `(sigma1 k_j^2 + c_j sigma0^2) / (sigma0 + k_j)^2`. Sliding forces
    /// (`f_c`, `f_s`, `v_s`, `sigma2`) pass through the isolator unchanged.
    /// A Dahl model's stiffness combines the same way.
    pub fn felt_through(&self, k_j: f64, c_j: f64) -> Self {
        let series = |k: f64| k * k_j / (k + k_j);
        match *self {
            Self::Lugre(p) => {
                let total = p.sigma0 + k_j;
                Self::Lugre(LugreParams {
                    sigma0: series(p.sigma0),
                    sigma1: (p.sigma1 * k_j * k_j + c_j * p.sigma0 * p.sigma0) / (total * total),
                    ..p
                })
            }
            Self::Dahl(p) => Self::Dahl(DahlParams {
                sigma: series(p.sigma),
                ..p
            }),
        }
    }

    /// The friction force the model predicts at velocity `v` and internal
    /// state `w`, and the state's rate.
    #[inline(always)]
    pub(crate) fn force_and_rate<S: Scalar>(&self, v: S, w: S) -> (S, S) {
        match self {
            Self::Lugre(p) => p.force_and_z_rate_of(v, w),
            Self::Dahl(p) => (w, p.force_rate_of(v, w)),
        }
    }

    /// What its state is, its name suffix and its typical size.
    pub(crate) fn state(&self) -> (StateKind, &'static str, f64) {
        match self {
            Self::Lugre(p) => (StateKind::CompensatorBristle, "z", p.f_s / p.sigma0),
            Self::Dahl(p) => (StateKind::CompensatorForce, "f_d", p.f_c),
        }
    }
}

/// Feedforward friction compensation: a friction model driven by the
/// reference, simulated with its own state.
#[derive(Debug, Clone, PartialEq)]
pub struct Feedforward {
    /// The name of the friction element it models, when it models one.
    pub element: Option<String>,
    /// The friction model simulated (already felt through the isolator when
    /// the isolator is treated statically).
    pub model: FrictionModel,
    /// The bearing behind the isolator, when it is simulated dynamically.
    pub bearing: Option<VirtualBearing>,
    /// Index of the compensator's first state: the model's state, or with a
    /// virtual bearing the isolator deflection, then the bearing velocity,
    /// then the model's state.
    pub state_index: usize,
}

/// The bearing a compensator simulates behind an isolator: its mass and the
/// isolator's stiffness and damping along the contact axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VirtualBearing {
    /// Bearing mass m_b, kg.
    pub mass: f64,
    /// Isolator stiffness k_j along the contact axis, N/m.
    pub stiffness: f64,
    /// Isolator damping c_j along the contact axis, N s/m.
    pub damping: f64,
}

impl Feedforward {
    /// Number of states it has.
    pub fn n_states(&self) -> usize {
        if self.bearing.is_some() { 3 } else { 1 }
    }

    /// The index of its LuGre model's bristle state, which an
    /// implicit-explicit integrator may treat implicitly (none for Dahl).
    pub fn bristle_state(&self) -> Option<usize> {
        match self.model {
            FrictionModel::Lugre(_) => Some(self.state_index + self.n_states() - 1),
            FrictionModel::Dahl(_) => None,
        }
    }
}

/// A disturbance observer with a first-order Q-filter.
#[derive(Debug, Clone, PartialEq)]
pub struct Observer {
    /// Nominal mass m_n, kg.
    pub nominal_mass: f64,
    /// Q-filter cut-off omega, rad/s (2 pi times the bandwidth in Hz).
    pub cutoff: f64,
    /// Index of the observer state eta in the state vector.
    pub state_index: usize,
}

/// A LuGre parameter's fault as (name, what it must be).
fn fault(e: crate::lugre::InvalidLugreParameter) -> (&'static str, String) {
    let message = e.to_string();
    let tail = message.strip_prefix(e.name).unwrap_or(&message).trim();
    (e.name, tail.to_string())
}
