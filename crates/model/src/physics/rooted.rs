//! Fast path for models in which every body is jointed directly to the world
//! (no articulated chains), each either floating or sliding on a straight
//! rail: a table on its own bearings, or any number of such parts coupled only
//! through force elements. The mass matrix is then block diagonal with one
//! block per body and no velocity-product transport terms, so each floating
//! body is a free Newton-Euler body and each rail body a point mass on its
//! axis.
//!
//! [`RootedPlan`] resolves everything that does not depend on the state when
//! the model is built: which kind of body carries each element end, attach
//! points and rotations in the frame they are applied in, rail directions
//! projected on element axes, isolators whose relative rotation is constant or
//! repeats an earlier one, masses, inertias and gravity. The element
//! parameters (bushing stiffness and damping, LuGre, servo gains) are read
//! from the model at each call, and their laws are the same functions the
//! general recursive dynamics in [`crate::dynamics`] call; a test checks that
//! both paths give the same state derivative.

use nalgebra::{Matrix3, Vector3};

use crate::bristle::BristleStage;
use crate::elements::{Frame, JointMotion, RigidBody, Structure};
use crate::laws::{
    bushing_wrench, cast3, cast33, newton_euler, quaternion_rate, quaternion_rotation, relative,
    relative_rotation, rotate, rotate_back, rotation_log, servo_forces,
};
use crate::scalar::Scalar;
use crate::values::{ElementValues, InputValues};

/// A floating body jointed to the world.
#[derive(Debug, Clone, PartialEq)]
struct FloatingBody {
    /// First position coordinate (3 offsets then the quaternion w, x, y, z).
    q0: usize,
    /// First velocity coordinate, absolute index in the state.
    v0: usize,
    /// Joint frame in the world; `None` when it is the identity.
    joint_rotation: Option<Matrix3<f64>>,
    joint_origin: Vector3<f64>,
    mass_properties: RigidBody,
}

/// A body on a straight rail jointed to the world: it never turns, so its
/// rotation is constant and its motion is `origin = start + axis q`.
#[derive(Debug, Clone, PartialEq)]
struct RailBody {
    q0: usize,
    /// Velocity coordinate, absolute index in the state.
    v0: usize,
    inverse_mass: f64,
    /// Gravity along the rail, m/s^2.
    gravity_along: f64,
}

/// Where a rail body's rail lies: direction, and the joint frame (the body's
/// pose at q = 0).
#[derive(Debug, Clone, PartialEq)]
struct RailGeometry {
    axis: Vector3<f64>,
    rotation: Matrix3<f64>,
    origin: Vector3<f64>,
}

/// What carries one end of an element.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Carrier {
    World,
    /// Index into [`RootedPlan::rails`].
    Rail(usize),
    /// Index into [`RootedPlan::floating`].
    Floating(usize),
}

/// One end of an isolator, with what can be resolved before the run.
#[derive(Debug, Clone, PartialEq)]
struct IsolatorEnd {
    carrier: Carrier,
    /// World and rail ends: the point in the world at q = 0. Floating ends:
    /// the point in body axes.
    point: Vector3<f64>,
    /// Rail ends: the rail direction in the world.
    rail_axis: Vector3<f64>,
    /// World and rail ends: the attach frame's (constant) world rotation.
    /// Floating ends: the attach rotation in body axes. `None` is the identity.
    attach: Option<Matrix3<f64>>,
}

/// Where an isolator's relative rotation and rotation rate come from.
#[derive(Debug, Clone, Copy, PartialEq)]
enum RelativeRotation {
    /// Neither end turns: a constant rotation vector, zero rate.
    Constant(Vector3<f64>),
    /// The same ends' rotations as an earlier isolator (by index).
    SameAs(usize),
    /// Computed from the ends' rotations.
    Computed,
}

#[derive(Debug, Clone, PartialEq)]
struct IsolatorPlan {
    parent: IsolatorEnd,
    child: IsolatorEnd,
    relative_rotation: RelativeRotation,
}

/// A point-and-axis element (friction contact, sensor, actuator) on a body.
#[derive(Debug, Clone, PartialEq)]
enum PointOnBody {
    /// On a rail body: `along` is rail axis . element axis, `offset` the
    /// element coordinate at q = 0 (minus the element's zero offset).
    Rail {
        body: usize,
        along: f64,
        offset: f64,
    },
    /// On a floating body: the point in body axes, the axis in the world and
    /// the zero offset.
    Floating {
        body: usize,
        point: Vector3<f64>,
        axis: Vector3<f64>,
        zero_offset: f64,
    },
}

/// Everything the fast path needs, resolved from a [`Model`] once.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RootedPlan {
    floating: Vec<FloatingBody>,
    rails: Vec<RailBody>,
    isolators: Vec<IsolatorPlan>,
    frictions: Vec<PointOnBody>,
    sensors: Vec<PointOnBody>,
    actuators: Vec<PointOnBody>,
    /// Gravity in the world, m/s^2.
    gravity: Vector3<f64>,
}

/// State of a floating body during one evaluation, world frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FloatingState<S: Scalar> {
    rotation: Matrix3<S>,
    origin: Vector3<S>,
    velocity: Vector3<S>,
    omega: Vector3<S>,
    /// Sum of element forces.
    force: Vector3<S>,
    /// Sum of element moments about `origin`.
    moment: Vector3<S>,
}

impl<S: Scalar> FloatingState<S> {
    fn at_rest() -> Self {
        Self {
            rotation: Matrix3::identity(),
            origin: Vector3::zeros(),
            velocity: Vector3::zeros(),
            omega: Vector3::zeros(),
            force: Vector3::zeros(),
            moment: Vector3::zeros(),
        }
    }
}

/// State of a rail body during one evaluation.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RailState<S: Scalar> {
    position: S,
    rate: S,
    /// Sum of element forces along the rail.
    force: S,
}

/// Scratch space of the fast path (part of [`Workspace`]).
#[derive(Debug, Clone)]
pub(crate) struct RootedScratch<S: Scalar = f64> {
    floating: Vec<FloatingState<S>>,
    rails: Vec<RailState<S>>,
    /// Per isolator: relative rotation vector and rate, in the parent's attach axes.
    relative: Vec<(Vector3<S>, Vector3<S>)>,
}

impl<S: Scalar> RootedScratch<S> {
    /// No scratch space (models that take another path).
    pub(crate) fn empty() -> Self {
        Self {
            floating: Vec::new(),
            rails: Vec::new(),
            relative: Vec::new(),
        }
    }
}

/// `None` for the identity, else the matrix.
fn unless_identity(m: Matrix3<f64>) -> Option<Matrix3<f64>> {
    (m != Matrix3::identity()).then_some(m)
}

/// A constant optional rotation in scalar type S.
#[inline(always)]
fn cast_rotation<S: Scalar>(m: &Option<Matrix3<f64>>) -> Option<Matrix3<S>> {
    m.as_ref().map(cast33::<S>)
}

impl RootedPlan {
    /// The plan for `model`, or `None` when some body hangs from another body,
    /// turns about a revolute joint or floats with a singular inertia (the
    /// general path handles those).
    pub(crate) fn build(model: &Structure) -> Option<Self> {
        let mut carriers = Vec::with_capacity(model.bodies.len());
        let mut floating = Vec::new();
        let mut rails = Vec::new();
        let nq = model.layout.nq;
        for body in &model.bodies {
            if body.parent.is_some() {
                return None;
            }
            let joint = &body.joint;
            match joint.motion {
                JointMotion::Floating => {
                    carriers.push(Carrier::Floating(floating.len()));
                    floating.push(FloatingBody {
                        q0: joint.q_offset,
                        v0: nq + joint.v_offset,
                        joint_rotation: unless_identity(joint.origin_rotation),
                        joint_origin: joint.origin.translation.vector,
                        mass_properties: RigidBody {
                            inverse_mass: 1.0 / body.mass,
                            com: body.com,
                            inertia: body.inertia,
                            inverse_inertia: body.inertia.try_inverse()?,
                        },
                    });
                }
                JointMotion::Prismatic { axis } => {
                    carriers.push(Carrier::Rail(rails.len()));
                    let rail_axis = joint.origin_rotation * axis;
                    rails.push((
                        RailBody {
                            q0: joint.q_offset,
                            v0: nq + joint.v_offset,
                            inverse_mass: 1.0 / body.mass,
                            gravity_along: rail_axis.dot(&model.gravity),
                        },
                        RailGeometry {
                            axis: rail_axis,
                            rotation: joint.origin_rotation,
                            origin: joint.origin.translation.vector,
                        },
                    ));
                }
                JointMotion::Revolute { .. } => return None,
            }
        }
        let carrier = |frame: Frame| match frame {
            Frame::World => Carrier::World,
            Frame::Body(b) => carriers[b],
        };
        let isolator_end =
            |frame: Frame, attach: &nalgebra::Isometry3<f64>, rotation: Matrix3<f64>| {
                let carrier = carrier(frame);
                let local = attach.translation.vector;
                match carrier {
                    Carrier::World => IsolatorEnd {
                        carrier,
                        point: local,
                        rail_axis: Vector3::zeros(),
                        attach: unless_identity(rotation),
                    },
                    Carrier::Rail(r) => {
                        let rail = &rails[r].1;
                        IsolatorEnd {
                            carrier,
                            point: rail.origin + rail.rotation * local,
                            rail_axis: rail.axis,
                            attach: unless_identity(rail.rotation * rotation),
                        }
                    }
                    Carrier::Floating(_) => IsolatorEnd {
                        carrier,
                        point: local,
                        rail_axis: Vector3::zeros(),
                        attach: unless_identity(rotation),
                    },
                }
            };
        let mut isolators: Vec<IsolatorPlan> = Vec::with_capacity(model.isolators.len());
        for isolator in &model.isolators {
            let parent = isolator_end(
                isolator.parent,
                &isolator.parent_attach,
                isolator.attach_rotations[0],
            );
            let child = isolator_end(
                isolator.child,
                &isolator.child_attach,
                isolator.attach_rotations[1],
            );
            let turns = |end: &IsolatorEnd| matches!(end.carrier, Carrier::Floating(_));
            // Same carrier and attach rotation, or two ends that do not turn
            // with the same (constant) world rotation.
            let same_rotation = |a: &IsolatorEnd, b: &IsolatorEnd| {
                a.attach == b.attach && (a.carrier == b.carrier || (!turns(a) && !turns(b)))
            };
            let relative_rotation = if !turns(&parent) && !turns(&child) {
                let constant = relative(&parent.attach, &child.attach);
                RelativeRotation::Constant(constant.map_or(Vector3::zeros(), |r| rotation_log(&r)))
            } else {
                isolators
                    .iter()
                    .position(|earlier| {
                        earlier.relative_rotation == RelativeRotation::Computed
                            && same_rotation(&earlier.parent, &parent)
                            && same_rotation(&earlier.child, &child)
                    })
                    .map_or(RelativeRotation::Computed, RelativeRotation::SameAs)
            };
            isolators.push(IsolatorPlan {
                parent,
                child,
                relative_rotation,
            });
        }
        let point_on_body = |body: usize, point: &Vector3<f64>, axis: &Vector3<f64>, zero: f64| {
            match carriers[body] {
                Carrier::Rail(r) => {
                    let rail = &rails[r].1;
                    Some(PointOnBody::Rail {
                        body: r,
                        along: rail.axis.dot(axis),
                        offset: (rail.origin + rail.rotation * point).dot(axis) - zero,
                    })
                }
                Carrier::Floating(f) => Some(PointOnBody::Floating {
                    body: f,
                    point: *point,
                    axis: *axis,
                    zero_offset: zero,
                }),
                // Every body is carried by a rail or floats.
                Carrier::World => None,
            }
        };
        Some(Self {
            frictions: model
                .frictions
                .iter()
                .map(|f| point_on_body(f.body, &f.point, &f.axis, f.zero_offset))
                .collect::<Option<_>>()?,
            sensors: model
                .sensors
                .iter()
                .map(|s| point_on_body(s.body, &s.point, &s.axis, s.zero_offset))
                .collect::<Option<_>>()?,
            actuators: model
                .actuators
                .iter()
                .map(|a| point_on_body(a.body, &a.point, &a.axis, 0.0))
                .collect::<Option<_>>()?,
            floating,
            rails: rails.into_iter().map(|(rail, _)| rail).collect(),
            isolators,
            gravity: model.gravity,
        })
    }

    /// Scratch space sized for this plan.
    pub(crate) fn scratch<S: Scalar>(&self) -> RootedScratch<S> {
        let rail = RailState {
            position: S::zero(),
            rate: S::zero(),
            force: S::zero(),
        };
        RootedScratch {
            floating: vec![FloatingState::at_rest(); self.floating.len()],
            rails: vec![rail; self.rails.len()],
            relative: vec![(Vector3::zeros(), Vector3::zeros()); self.isolators.len()],
        }
    }

    /// The state derivative.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn rhs<S: Scalar>(
        &self,
        model: &Structure,
        x: &[S],
        inputs: &InputValues<S>,
        dx: &mut [S],
        scratch: &mut RootedScratch<S>,
        elements: &mut ElementValues<S>,
        bristles: &mut BristleStage<S>,
    ) {
        debug_assert!(
            scratch.floating.len() == self.floating.len()
                && scratch.rails.len() == self.rails.len(),
            "a workspace made for another model"
        );
        self.body_states(x, dx, scratch);
        self.isolator_forces(model, scratch);
        self.servo(model, x, inputs, scratch, elements, bristles);
        self.friction_forces(model, x, inputs, dx, scratch, bristles);
        self.accelerations(dx, scratch);
        if let Some(controller) = &model.controller {
            controller.write_rates(&elements.servo, dx);
        }
    }

    /// Poses and velocities of every body, and the position rates.
    fn body_states<S: Scalar>(&self, x: &[S], dx: &mut [S], scratch: &mut RootedScratch<S>) {
        self.body_motion(x, scratch);
        for body in &self.floating {
            let (q0, v0) = (body.q0, body.v0);
            let (w, i, j, k) = (x[q0 + 3], x[q0 + 4], x[q0 + 5], x[q0 + 6]);
            let angular = Vector3::new(x[v0 + 3], x[v0 + 4], x[v0 + 5]);
            dx[q0..q0 + 3].copy_from_slice(&x[v0..v0 + 3]);
            // Omega in the joint frame, the one the quaternion rotates into.
            dx[q0 + 3..q0 + 7].copy_from_slice(&quaternion_rate([w, i, j, k], angular));
        }
        for body in &self.rails {
            dx[body.q0] = x[body.v0];
        }
    }

    /// Poses and velocities of every body (world frame), forces cleared.
    #[inline(always)]
    fn body_motion<S: Scalar>(&self, x: &[S], scratch: &mut RootedScratch<S>) {
        for (body, state) in self.floating.iter().zip(&mut scratch.floating) {
            let (q0, v0) = (body.q0, body.v0);
            let offset = Vector3::new(x[q0], x[q0 + 1], x[q0 + 2]);
            let (w, i, j, k) = (x[q0 + 3], x[q0 + 4], x[q0 + 5], x[q0 + 6]);
            let linear = Vector3::new(x[v0], x[v0 + 1], x[v0 + 2]);
            let angular = Vector3::new(x[v0 + 3], x[v0 + 4], x[v0 + 5]);
            let attitude = quaternion_rotation(w, i, j, k);
            let joint = cast_rotation::<S>(&body.joint_rotation);
            state.rotation = match &joint {
                Some(joint) => joint * attitude,
                None => attitude,
            };
            state.origin = cast3::<S>(&body.joint_origin) + rotate(&joint, offset);
            state.velocity = rotate(&joint, linear);
            state.omega = rotate(&joint, angular);
            state.force = Vector3::zeros();
            state.moment = Vector3::zeros();
        }
        for (body, state) in self.rails.iter().zip(&mut scratch.rails) {
            state.position = x[body.q0];
            state.rate = x[body.v0];
            state.force = S::zero();
        }
    }

    /// The slip velocity of every friction contact at state `x`, contact
    /// order: the bodies' motion and one reading per contact.
    pub(crate) fn slip_velocities(
        &self,
        x: &[f64],
        platform_velocity: f64,
        out: &mut [f64],
        scratch: &mut RootedScratch<f64>,
    ) {
        self.body_motion(x, scratch);
        for (slip, contact) in out.iter_mut().zip(&self.frictions) {
            let (_, velocity, _) = Self::reading(contact, scratch);
            *slip = velocity - platform_velocity;
        }
    }

    /// Where an isolator end's point is, world frame.
    #[inline(always)]
    fn end_point<S: Scalar>(end: &IsolatorEnd, scratch: &RootedScratch<S>) -> Vector3<S> {
        match end.carrier {
            Carrier::World => cast3::<S>(&end.point),
            Carrier::Rail(r) => {
                cast3::<S>(&end.point) + cast3::<S>(&end.rail_axis) * scratch.rails[r].position
            }
            Carrier::Floating(f) => {
                let body = &scratch.floating[f];
                body.origin + body.rotation * cast3::<S>(&end.point)
            }
        }
    }

    /// Velocity of the material point of an end's carrier at world point `at`.
    #[inline(always)]
    fn carrier_velocity<S: Scalar>(
        end: &IsolatorEnd,
        at: &Vector3<S>,
        scratch: &RootedScratch<S>,
    ) -> Vector3<S> {
        match end.carrier {
            Carrier::World => Vector3::zeros(),
            Carrier::Rail(r) => cast3::<S>(&end.rail_axis) * scratch.rails[r].rate,
            Carrier::Floating(f) => {
                let body = &scratch.floating[f];
                body.velocity + body.omega.cross(&(at - body.origin))
            }
        }
    }

    /// World rotation of an end's attach frame (`None`: the identity).
    #[inline(always)]
    fn end_rotation<S: Scalar>(
        end: &IsolatorEnd,
        scratch: &RootedScratch<S>,
    ) -> Option<Matrix3<S>> {
        match end.carrier {
            Carrier::World | Carrier::Rail(_) => cast_rotation(&end.attach),
            Carrier::Floating(f) => {
                let rotation = scratch.floating[f].rotation;
                Some(match &end.attach {
                    Some(attach) => rotation * cast33::<S>(attach),
                    None => rotation,
                })
            }
        }
    }

    fn end_omega<S: Scalar>(end: &IsolatorEnd, scratch: &RootedScratch<S>) -> Vector3<S> {
        match end.carrier {
            Carrier::Floating(f) => scratch.floating[f].omega,
            _ => Vector3::zeros(),
        }
    }

    /// A force (at world point `at`) and torque on an end's carrier.
    #[inline(always)]
    fn load<S: Scalar>(
        end: &IsolatorEnd,
        at: &Vector3<S>,
        force: &Vector3<S>,
        torque: &Vector3<S>,
        scratch: &mut RootedScratch<S>,
    ) {
        match end.carrier {
            Carrier::World => {}
            Carrier::Rail(r) => {
                scratch.rails[r].force += cast3::<S>(&end.rail_axis).dot(force);
            }
            Carrier::Floating(f) => {
                let body = &mut scratch.floating[f];
                body.force += force;
                body.moment += (at - body.origin).cross(force) + torque;
            }
        }
    }

    /// Bushing wrenches (the law and its conventions: [`bushing_wrench`]).
    fn isolator_forces<S: Scalar>(&self, model: &Structure, scratch: &mut RootedScratch<S>) {
        for (k, (isolator, element)) in self.isolators.iter().zip(&model.isolators).enumerate() {
            let (parent, child) = (&isolator.parent, &isolator.child);
            let parent_rotation = Self::end_rotation(parent, scratch);
            let parent_point = Self::end_point(parent, scratch);
            let child_point = Self::end_point(child, scratch);
            let child_velocity = Self::carrier_velocity(child, &child_point, scratch);
            let parent_velocity = Self::carrier_velocity(parent, &child_point, scratch);
            let (rotation, rotation_rate) = match isolator.relative_rotation {
                RelativeRotation::Constant(rotation) => (cast3::<S>(&rotation), Vector3::zeros()),
                RelativeRotation::SameAs(earlier) => scratch.relative[earlier],
                RelativeRotation::Computed => {
                    let relative = relative_rotation(
                        &parent_rotation,
                        &Self::end_rotation(child, scratch),
                        Self::end_omega(parent, scratch),
                        Self::end_omega(child, scratch),
                    );
                    scratch.relative[k] = relative;
                    relative
                }
            };
            let wrench = bushing_wrench(
                &element.stiffness,
                &element.damping,
                &parent_rotation,
                child_point - parent_point,
                child_velocity - parent_velocity,
                rotation,
                rotation_rate,
            );
            Self::load(child, &child_point, &wrench.force, &wrench.torque, scratch);
            Self::load(
                parent,
                &child_point,
                &-wrench.force,
                &-wrench.torque,
                scratch,
            );
        }
    }

    /// Coordinate and rate of a point-and-axis element; for floating bodies
    /// also the lever arm from the body origin.
    #[inline(always)]
    fn reading<S: Scalar>(point: &PointOnBody, scratch: &RootedScratch<S>) -> (S, S, Vector3<S>) {
        match point {
            PointOnBody::Rail {
                body,
                along,
                offset,
            } => {
                let rail = &scratch.rails[*body];
                let along = S::constant(*along);
                (
                    S::constant(*offset) + along * rail.position,
                    along * rail.rate,
                    Vector3::zeros(),
                )
            }
            PointOnBody::Floating {
                body,
                point,
                axis,
                zero_offset,
            } => {
                let state = &scratch.floating[*body];
                let arm = state.rotation * cast3::<S>(point);
                let axis = cast3::<S>(axis);
                (
                    (state.origin + arm).dot(&axis) - S::constant(*zero_offset),
                    (state.velocity + state.omega.cross(&arm)).dot(&axis),
                    arm,
                )
            }
        }
    }

    /// A force along a point element's axis, applied at its point.
    #[inline(always)]
    fn push<S: Scalar>(
        point: &PointOnBody,
        arm: &Vector3<S>,
        force: S,
        scratch: &mut RootedScratch<S>,
    ) {
        match point {
            PointOnBody::Rail { body, along, .. } => {
                scratch.rails[*body].force += S::constant(*along) * force;
            }
            PointOnBody::Floating { body, axis, .. } => {
                let state = &mut scratch.floating[*body];
                let force = cast3::<S>(axis) * force;
                state.force += force;
                state.moment += arm.cross(&force);
            }
        }
    }

    /// Sensor readings, the servo law and the actuator forces.
    fn servo<S: Scalar>(
        &self,
        model: &Structure,
        x: &[S],
        inputs: &InputValues<S>,
        scratch: &mut RootedScratch<S>,
        elements: &mut ElementValues<S>,
        bristles: &mut BristleStage<S>,
    ) {
        for (k, sensor) in self.sensors.iter().enumerate() {
            let (position, velocity, _) = Self::reading(sensor, scratch);
            elements.sensor_position[k] = position;
            elements.sensor_velocity[k] = velocity;
        }
        servo_forces(model, x, inputs, elements, bristles);
        for (actuator, force) in self.actuators.iter().zip(&elements.actuator_force) {
            if !force.is_exactly_zero() {
                let (_, _, arm) = Self::reading(actuator, scratch);
                Self::push(actuator, &arm, *force, scratch);
            }
        }
    }

    /// LuGre forces and bristle rates.
    fn friction_forces<S: Scalar>(
        &self,
        model: &Structure,
        x: &[S],
        inputs: &InputValues<S>,
        dx: &mut [S],
        scratch: &mut RootedScratch<S>,
        bristles: &mut BristleStage<S>,
    ) {
        for (k, (contact, friction)) in self.frictions.iter().zip(&model.frictions).enumerate() {
            let (_, velocity, arm) = Self::reading(contact, scratch);
            let slip = velocity - inputs.platform_velocity;
            let (force, z_rate) = bristles.law(k, friction, slip, x[friction.z_index]);
            dx[friction.z_index] = z_rate;
            Self::push(contact, &arm, -force, scratch);
        }
    }

    /// Newton-Euler for each floating body, the rail law for each rail body.
    fn accelerations<S: Scalar>(&self, dx: &mut [S], scratch: &RootedScratch<S>) {
        let gravity = cast3::<S>(&self.gravity);
        for (body, state) in self.floating.iter().zip(&scratch.floating) {
            let (accel, alpha) = newton_euler(
                &body.mass_properties,
                &state.rotation,
                state.omega,
                state.force,
                state.moment,
                gravity,
            );
            let joint = cast_rotation::<S>(&body.joint_rotation);
            let accel = rotate_back(&joint, accel);
            let alpha = rotate_back(&joint, alpha);
            let v0 = body.v0;
            dx[v0] = accel.x;
            dx[v0 + 1] = accel.y;
            dx[v0 + 2] = accel.z;
            dx[v0 + 3] = alpha.x;
            dx[v0 + 4] = alpha.y;
            dx[v0 + 5] = alpha.z;
        }
        for (body, state) in self.rails.iter().zip(&scratch.rails) {
            dx[body.v0] =
                state.force * S::constant(body.inverse_mass) + S::constant(body.gravity_along);
        }
    }
}
