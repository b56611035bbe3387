//! The force laws of the elements and the rigid-body helpers, each written
//! once and generic over [`Scalar`]: every evaluation path (general,
//! constant-Jacobian, rooted bodies) and the linearisation (dual numbers)
//! call these, so no path can drift from another.
//!
//! - [`bushing_force`]: the isolator law along one attach axis;
//! - [`bushing_wrench`]: the isolator's force and torque from its deflection;
//! - [`Controller::law`] and [`servo_forces`]: the PID servo;
//! - LuGre: [`crate::LugreParams::force_and_z_rate_of`] (in its own module);
//! - [`rotation_log`], [`quaternion_rotation`], [`quaternion_rate`],
//!   [`newton_euler`]: rotations and the free rigid body.

use std::cmp::Ordering::{Greater, Less};

use nalgebra::{Matrix3, Vector3};

use crate::bristle::BristleStage;
use crate::elements::{RigidBody, Structure};
use crate::scalar::Scalar;
use crate::values::{ElementValues, InputValues};

/// A constant vector in scalar type S.
#[inline(always)]
pub(crate) fn cast3<S: Scalar>(v: &Vector3<f64>) -> Vector3<S> {
    Vector3::new(S::constant(v.x), S::constant(v.y), S::constant(v.z))
}

/// A constant matrix in scalar type S.
#[inline(always)]
pub(crate) fn cast33<S: Scalar>(m: &Matrix3<f64>) -> Matrix3<S> {
    Matrix3::from_fn(|r, c| S::constant(m[(r, c)]))
}

/// `m v`, with `None` the identity.
#[inline(always)]
pub(crate) fn rotate<S: Scalar>(m: &Option<Matrix3<S>>, v: Vector3<S>) -> Vector3<S> {
    match m {
        Some(m) => m * v,
        None => v,
    }
}

/// `m^T v`, with `None` the identity.
#[inline(always)]
pub(crate) fn rotate_back<S: Scalar>(m: &Option<Matrix3<S>>, v: Vector3<S>) -> Vector3<S> {
    match m {
        Some(m) => m.tr_mul(&v),
        None => v,
    }
}

/// `a^T b`, with `None` the identity.
#[inline(always)]
pub(crate) fn relative<S: Scalar>(
    a: &Option<Matrix3<S>>,
    b: &Option<Matrix3<S>>,
) -> Option<Matrix3<S>> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.tr_mul(b)),
        (Some(a), None) => Some(a.transpose()),
        (None, Some(b)) => Some(*b),
        (None, None) => None,
    }
}

/// Bushing law along one attach axis: force (or torque) on the child.
#[inline(always)]
pub(crate) fn bushing_force<S: Scalar>(stiffness: f64, damping: f64, deflection: S, rate: S) -> S {
    -(S::constant(stiffness) * deflection + S::constant(damping) * rate)
}

/// An isolator's action on its child, and its deflection.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BushingWrench<S: Scalar> {
    /// Force on the child, world axes (the parent gets its opposite).
    pub force: Vector3<S>,
    /// Torque on the child, world axes.
    pub torque: Vector3<S>,
    /// Translation (m) then rotation vector (rad), parent attach axes.
    pub deflection: [S; 6],
    /// Their rates.
    pub rate: [S; 6],
}

/// The bushing law on all six attach axes. The translation and its rate are
/// given in the world (child attach point minus parent attach point, and the
/// child point's velocity minus that of the parent's material point there);
/// the rotation vector of the child attach frame relative to the parent's
/// and its rate are given in the parent's attach axes, whose world rotation
/// is `parent` (`None`: the identity).
#[inline(always)]
pub(crate) fn bushing_wrench<S: Scalar>(
    stiffness: &[f64; 6],
    damping: &[f64; 6],
    parent: &Option<Matrix3<S>>,
    translation: Vector3<S>,
    translation_rate: Vector3<S>,
    rotation: Vector3<S>,
    rotation_rate: Vector3<S>,
) -> BushingWrench<S> {
    let translation = rotate_back(parent, translation);
    let translation_rate = rotate_back(parent, translation_rate);
    let law = |first: usize, deflection: &Vector3<S>, rate: &Vector3<S>| {
        rotate(
            parent,
            Vector3::from_fn(|i, _| {
                bushing_force(
                    stiffness[first + i],
                    damping[first + i],
                    deflection[i],
                    rate[i],
                )
            }),
        )
    };
    BushingWrench {
        force: law(0, &translation, &translation_rate),
        torque: law(3, &rotation, &rotation_rate),
        deflection: [
            translation.x,
            translation.y,
            translation.z,
            rotation.x,
            rotation.y,
            rotation.z,
        ],
        rate: [
            translation_rate.x,
            translation_rate.y,
            translation_rate.z,
            rotation_rate.x,
            rotation_rate.y,
            rotation_rate.z,
        ],
    }
}

/// The rotation vector of `a^T b` (`None`: the identity) and the rate
/// `a^T (omega_b - omega_a)`: the relative rotation of two frames in the
/// axes of the first.
#[inline(always)]
pub(crate) fn relative_rotation<S: Scalar>(
    a: &Option<Matrix3<S>>,
    b: &Option<Matrix3<S>>,
    omega_a: Vector3<S>,
    omega_b: Vector3<S>,
) -> (Vector3<S>, Vector3<S>) {
    let rotation = relative(a, b).map_or(Vector3::zeros(), |r| rotation_log(&r));
    (rotation, rotate_back(a, omega_b - omega_a))
}

/// The servo: writes the actuator forces and the tracking error from the
/// sensor readings already in `elements`, the compensator's model read
/// through the evaluation's bristle treatment. The external servo force input
/// is added to the controller's actuator (to the first actuator when there is
/// no controller).
#[inline]
pub(crate) fn servo_forces<S: Scalar>(
    model: &Structure,
    x: &[S],
    inputs: &InputValues<S>,
    elements: &mut ElementValues<S>,
    bristles: &mut BristleStage<S>,
) {
    elements.actuator_force.fill(S::zero());
    if let Some(controller) = &model.controller {
        let force = controller.law_into(
            elements.sensor_position[controller.sensor],
            elements.sensor_velocity[controller.sensor],
            x,
            inputs,
            bristles,
            &mut elements.servo,
        );
        elements.actuator_force[controller.actuator] = force;
    }
    if let Some(a) = model.servo_actuator() {
        elements.actuator_force[a] += inputs.servo_force;
    }
}

/// The rotation matrix of the quaternion (w, i, j, k), normalised on the way
/// (the scale 2 / |q|^2 makes it exact for any length).
#[inline(always)]
pub(crate) fn quaternion_rotation<S: Scalar>(w: S, i: S, j: S, k: S) -> Matrix3<S> {
    let s = S::constant(2.0) / (w * w + i * i + j * j + k * k);
    let (wi, wj, wk) = (s * w * i, s * w * j, s * w * k);
    let (ii, ij, ik) = (s * i * i, s * i * j, s * i * k);
    let (jj, jk, kk) = (s * j * j, s * j * k, s * k * k);
    let one = S::one();
    Matrix3::new(
        one - (jj + kk),
        ij - wk,
        ik + wj,
        ij + wk,
        one - (ii + kk),
        jk - wi,
        ik - wj,
        jk + wi,
        one - (ii + jj),
    )
}

/// Quaternion rate `q' = (0, omega) q / 2` of q = (w, i, j, k), with omega in
/// the frame the quaternion rotates into.
#[inline(always)]
pub(crate) fn quaternion_rate<S: Scalar>(q: [S; 4], omega: Vector3<S>) -> [S; 4] {
    let [w, i, j, k] = q;
    let half = S::constant(0.5);
    [
        -half * (omega.x * i + omega.y * j + omega.z * k),
        half * (w * omega.x + omega.y * k - omega.z * j),
        half * (w * omega.y + omega.z * i - omega.x * k),
        half * (w * omega.z + omega.x * j - omega.y * i),
    ]
}

/// Newton-Euler for a free rigid body with world rotation `rotation` and
/// angular velocity `omega`, under a world force and a moment about the body
/// origin, in a uniform field `gravity`: the acceleration of the body origin
/// and the angular acceleration, world axes. With `omega` and `gravity`
/// zero it solves the body's mass matrix for given generalized forces.
#[inline(always)]
pub(crate) fn newton_euler<S: Scalar>(
    body: &RigidBody,
    rotation: &Matrix3<S>,
    omega: Vector3<S>,
    force: Vector3<S>,
    moment: Vector3<S>,
    gravity: Vector3<S>,
) -> (Vector3<S>, Vector3<S>) {
    let arm = rotation * cast3::<S>(&body.com);
    // Moment about the centre of mass (gravity has none there) and the
    // gyroscopic term, in body axes.
    let moment = rotation.tr_mul(&(moment - arm.cross(&force)));
    let omega_body = rotation.tr_mul(&omega);
    let spin = omega_body.cross(&(cast33::<S>(&body.inertia) * omega_body));
    let alpha = rotation * (cast33::<S>(&body.inverse_inertia) * (moment - spin));
    let accel = force * S::constant(body.inverse_mass) + gravity
        - alpha.cross(&arm)
        - omega.cross(&omega.cross(&arm));
    (accel, alpha)
}

/// The rotation vector (axis times angle) of a rotation matrix.
pub(crate) fn rotation_log<S: Scalar>(r: &Matrix3<S>) -> Vector3<S> {
    let half = S::constant(0.5);
    let skew = Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    ) * half;
    let sin_squared = skew.norm_squared();
    let cos = (r.trace() - S::one()) * half;
    if sin_squared.compare_value(1e-4) == Some(Less) && cos.compare_value(0.0) == Some(Greater) {
        // Below about 0.01 rad (every bushing deflection in practice):
        // angle / sin(angle) = asin(s) / s = 1 + s^2/6 + 3 s^4/40 + 5 s^6/112
        // + O(s^8), the first omitted term under 3e-18. No square root (which
        // has no derivative at zero) and no arctangent.
        let series = S::constant(1.0 / 6.0)
            + sin_squared * (S::constant(3.0 / 40.0) + sin_squared * S::constant(5.0 / 112.0));
        return skew * (S::one() + sin_squared * series);
    }
    if cos.compare_value(-0.99) == Some(Greater) {
        let sin = sin_squared.sqrt();
        return skew * (sin.atan2(cos) / sin);
    }
    // Near half a turn the skew part (sin(angle) times the axis) loses the
    // axis; the symmetric part keeps it: (R + R^T)/2 - cos I = (1 - cos) a a^T.
    // The largest diagonal entry gives one component, its row the others; the
    // skew part, however small, gives the sign (at exactly half a turn both
    // signs are the same rotation).
    let scale = S::one() - cos;
    let outer = |i: usize, j: usize| {
        let symmetric = (r[(i, j)] + r[(j, i)]) * half;
        if i == j { symmetric - cos } else { symmetric }
    };
    let pivot = (0..3)
        .max_by(|&a, &b| outer(a, a).value().total_cmp(&outer(b, b).value()))
        .unwrap_or(0);
    let pivot_component = (outer(pivot, pivot) / scale).sqrt();
    let mut axis = Vector3::from_fn(|j, _| {
        if j == pivot {
            pivot_component
        } else {
            outer(pivot, j) / (scale * pivot_component)
        }
    });
    if axis.dot(&skew).compare_value(0.0) == Some(Less) {
        axis = -axis;
    }
    axis * sin_squared.sqrt().atan2(cos)
}

#[cfg(test)]
mod tests {
    use super::rotation_log;
    use nalgebra::{Rotation3, Unit, Vector3};
    use std::f64::consts::PI;

    /// The rotation vector comes back from its matrix on every branch: the
    /// small-angle series (and across its edge near 0.01 rad), the arctangent,
    /// and half a turn.
    #[test]
    fn rotation_log_inverts_the_exponential() {
        let axes = [
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.3, -0.5, 0.8),
            Vector3::new(-0.2, 0.9, 0.1),
        ];
        let angles = [
            0.0,
            1e-9,
            1e-6,
            3e-4,
            0.0099,
            0.01,
            0.0101,
            0.2,
            1.0,
            2.5,
            3.0,
            3.1,
            PI - 1e-5,
            PI - 1e-9,
            PI,
        ];
        for axis in axes {
            let axis = Unit::new_normalize(axis);
            for angle in angles {
                let v = axis.into_inner() * angle;
                let back = rotation_log(Rotation3::from_scaled_axis(v).matrix());
                // At exactly half a turn -v is the same rotation.
                let error = if angle == PI {
                    (back - v).norm().min((back + v).norm())
                } else {
                    (back - v).norm()
                };
                assert!(error <= 2e-15 * angle.max(1.0), "{v:?} -> {back:?}");
            }
        }
    }
}
