//! The values one evaluation works with in any scalar type: the inputs
//! ([`InputValues`]), what each force element gave ([`ElementValues`]) and
//! what the servo law gave besides its force ([`ServoValues`]).

use crate::compensation::MAX_COMPENSATORS;
use crate::elements::Inputs;
use crate::reference::ReferenceSample;
use crate::scalar::Scalar;

/// Model inputs in any scalar type (see [`Inputs`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InputValues<S> {
    /// Reference position, m.
    pub reference_position: S,
    /// Reference velocity, m/s.
    pub reference_velocity: S,
    /// External servo force, N.
    pub servo_force: S,
    /// Counter-surface velocity, m/s.
    pub platform_velocity: S,
}

impl Inputs {
    /// The inputs as constants of scalar type S.
    pub fn values<S: Scalar>(&self) -> InputValues<S> {
        InputValues {
            reference_position: S::constant(self.reference.position),
            reference_velocity: S::constant(self.reference.velocity),
            servo_force: S::constant(self.servo_force),
            platform_velocity: S::constant(self.platform_velocity),
        }
    }
}

/// Values of the force elements at the last evaluated state.
#[derive(Debug, Clone, Default)]
pub struct ElementValues<S = f64> {
    /// LuGre friction force per contact (positive opposes positive sliding), N.
    pub friction_force: Vec<S>,
    /// Sliding velocity per contact, m/s.
    pub slip_velocity: Vec<S>,
    /// Bristle rate z' per contact, m/s.
    pub z_rate: Vec<S>,
    /// Displacement of each contact point along its axis from the zero configuration, m.
    pub contact_displacement: Vec<S>,
    /// Force per actuator, N.
    pub actuator_force: Vec<S>,
    /// Reading per sensor, m.
    pub sensor_position: Vec<S>,
    /// Rate per sensor, m/s.
    pub sensor_velocity: Vec<S>,
    /// Deflection per isolator: translation (m) then rotation vector (rad), attach axes.
    pub isolator_deflection: Vec<[S; 6]>,
    /// Deflection rate per isolator.
    pub isolator_rate: Vec<[S; 6]>,
    /// Reference used by the controller.
    pub reference: ReferenceSample,
    /// The servo's tracking error, compensator values and state rates.
    pub servo: ServoValues<S>,
}

/// What the servo law gives besides its force: the tracking error, the
/// compensators' contributions, and the rates of the servo's own states
/// (integral, each compensator's, observer). Fixed arrays of
/// [`MAX_COMPENSATORS`] entries: an evaluation allocates nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoValues<S> {
    /// Tracking error x - x_r, m.
    pub error: S,
    /// Feedforward friction compensation force, all compensators, N.
    pub feedforward: S,
    /// Each compensator's force in the servo's order, N (unused entries zero).
    pub compensator_forces: [S; MAX_COMPENSATORS],
    /// Disturbance estimate d_hat, N.
    pub estimate: S,
    /// Rate of the error integral.
    pub(crate) integral_rate: S,
    /// Rates of each compensator's states (its first `n_states` entries).
    pub(crate) compensator_rates: [[S; 3]; MAX_COMPENSATORS],
    /// Rate of the observer state.
    pub(crate) observer_rate: S,
}

impl<S: Scalar> ServoValues<S> {
    /// All zero.
    pub fn zero() -> Self {
        Self {
            error: S::zero(),
            feedforward: S::zero(),
            compensator_forces: [S::zero(); MAX_COMPENSATORS],
            estimate: S::zero(),
            integral_rate: S::zero(),
            compensator_rates: [[S::zero(); 3]; MAX_COMPENSATORS],
            observer_rate: S::zero(),
        }
    }
}

impl<S: Default> Default for ServoValues<S> {
    fn default() -> Self {
        Self {
            error: S::default(),
            feedforward: S::default(),
            compensator_forces: Default::default(),
            estimate: S::default(),
            integral_rate: S::default(),
            compensator_rates: Default::default(),
            observer_rate: S::default(),
        }
    }
}
