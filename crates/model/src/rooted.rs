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

use crate::dynamics::{Workspace, bushing_force, rotation_log, servo_force};
use crate::model::{Frame, Inputs, JointMotion, Model};

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
    inverse_mass: f64,
    /// Centre of mass in body axes.
    com: Vector3<f64>,
    /// Inertia about the centre of mass and its inverse, body axes.
    inertia: Matrix3<f64>,
    inverse_inertia: Matrix3<f64>,
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
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct FloatingState {
    rotation: Matrix3<f64>,
    origin: Vector3<f64>,
    velocity: Vector3<f64>,
    omega: Vector3<f64>,
    /// Sum of element forces.
    force: Vector3<f64>,
    /// Sum of element moments about `origin`.
    moment: Vector3<f64>,
}

/// State of a rail body during one evaluation.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct RailState {
    position: f64,
    rate: f64,
    /// Sum of element forces along the rail.
    force: f64,
}

/// Scratch space of the fast path (part of [`Workspace`]).
#[derive(Debug, Clone, Default)]
pub(crate) struct RootedScratch {
    floating: Vec<FloatingState>,
    rails: Vec<RailState>,
    /// Per isolator: relative rotation vector and rate, in the parent's attach axes.
    relative: Vec<(Vector3<f64>, Vector3<f64>)>,
}

/// `None` for the identity, else the matrix.
fn unless_identity(m: Matrix3<f64>) -> Option<Matrix3<f64>> {
    (m != Matrix3::identity()).then_some(m)
}

/// `m^T v`, with `None` the identity.
#[inline(always)]
fn to_local(m: &Option<Matrix3<f64>>, v: Vector3<f64>) -> Vector3<f64> {
    match m {
        Some(m) => m.tr_mul(&v),
        None => v,
    }
}

/// `m v`, with `None` the identity.
#[inline(always)]
fn to_world(m: &Option<Matrix3<f64>>, v: Vector3<f64>) -> Vector3<f64> {
    match m {
        Some(m) => m * v,
        None => v,
    }
}

/// `a b`, with `None` the identity.
fn compose(a: &Option<Matrix3<f64>>, b: &Option<Matrix3<f64>>) -> Option<Matrix3<f64>> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a * b),
        (Some(m), None) | (None, Some(m)) => Some(*m),
        (None, None) => None,
    }
}

impl RootedPlan {
    /// The plan for `model`, or `None` when some body hangs from another body,
    /// turns about a revolute joint or floats with a singular inertia (the
    /// general path handles those).
    pub(crate) fn build(model: &Model) -> Option<Self> {
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
                        inverse_mass: 1.0 / body.mass,
                        com: body.com,
                        inertia: body.inertia,
                        inverse_inertia: body.inertia.try_inverse()?,
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
                let relative = compose(&parent.attach.map(|m| m.transpose()), &child.attach);
                RelativeRotation::Constant(relative.map_or(Vector3::zeros(), |r| rotation_log(&r)))
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
    pub(crate) fn scratch(&self) -> RootedScratch {
        RootedScratch {
            floating: vec![FloatingState::default(); self.floating.len()],
            rails: vec![RailState::default(); self.rails.len()],
            relative: vec![(Vector3::zeros(), Vector3::zeros()); self.isolators.len()],
        }
    }

    /// The state derivative.
    pub(crate) fn rhs(
        &self,
        model: &Model,
        x: &[f64],
        inputs: &Inputs,
        dx: &mut [f64],
        ws: &mut Workspace,
    ) {
        debug_assert!(
            ws.rooted.floating.len() == self.floating.len()
                && ws.rooted.rails.len() == self.rails.len(),
            "a workspace made for another model"
        );
        self.body_states(x, dx, &mut ws.rooted);
        self.isolator_forces(model, &mut ws.rooted);
        self.servo(model, x, inputs, ws);
        self.friction_forces(model, x, inputs, dx, &mut ws.rooted);
        self.accelerations(dx, &ws.rooted);
        if let Some(index) = model.controller.as_ref().and_then(|c| c.integral_index) {
            dx[index] = ws.elements.tracking_error;
        }
    }

    /// Poses and velocities of every body, and the position rates.
    fn body_states(&self, x: &[f64], dx: &mut [f64], scratch: &mut RootedScratch) {
        for (body, state) in self.floating.iter().zip(&mut scratch.floating) {
            let (q0, v0) = (body.q0, body.v0);
            let offset = Vector3::new(x[q0], x[q0 + 1], x[q0 + 2]);
            let (w, i, j, k) = (x[q0 + 3], x[q0 + 4], x[q0 + 5], x[q0 + 6]);
            let linear = Vector3::new(x[v0], x[v0 + 1], x[v0 + 2]);
            let angular = Vector3::new(x[v0 + 3], x[v0 + 4], x[v0 + 5]);
            // Quaternion rate q' = (0, omega) q / 2, omega in the joint frame.
            dx[q0] = linear.x;
            dx[q0 + 1] = linear.y;
            dx[q0 + 2] = linear.z;
            dx[q0 + 3] = -0.5 * (angular.x * i + angular.y * j + angular.z * k);
            dx[q0 + 4] = 0.5 * (w * angular.x + angular.y * k - angular.z * j);
            dx[q0 + 5] = 0.5 * (w * angular.y + angular.z * i - angular.x * k);
            dx[q0 + 6] = 0.5 * (w * angular.z + angular.x * j - angular.y * i);
            let attitude = quaternion_rotation(w, i, j, k);
            state.rotation = match &body.joint_rotation {
                Some(joint) => joint * attitude,
                None => attitude,
            };
            state.origin = body.joint_origin + to_world(&body.joint_rotation, offset);
            state.velocity = to_world(&body.joint_rotation, linear);
            state.omega = to_world(&body.joint_rotation, angular);
            state.force = Vector3::zeros();
            state.moment = Vector3::zeros();
        }
        for (body, state) in self.rails.iter().zip(&mut scratch.rails) {
            state.position = x[body.q0];
            state.rate = x[body.v0];
            state.force = 0.0;
            dx[body.q0] = state.rate;
        }
    }

    /// Where an isolator end's point is, world frame.
    #[inline(always)]
    fn end_point(end: &IsolatorEnd, scratch: &RootedScratch) -> Vector3<f64> {
        match end.carrier {
            Carrier::World => end.point,
            Carrier::Rail(r) => end.point + end.rail_axis * scratch.rails[r].position,
            Carrier::Floating(f) => {
                let body = &scratch.floating[f];
                body.origin + body.rotation * end.point
            }
        }
    }

    /// Velocity of the material point of an end's carrier at world point `at`.
    #[inline(always)]
    fn carrier_velocity(
        end: &IsolatorEnd,
        at: &Vector3<f64>,
        scratch: &RootedScratch,
    ) -> Vector3<f64> {
        match end.carrier {
            Carrier::World => Vector3::zeros(),
            Carrier::Rail(r) => end.rail_axis * scratch.rails[r].rate,
            Carrier::Floating(f) => {
                let body = &scratch.floating[f];
                body.velocity + body.omega.cross(&(at - body.origin))
            }
        }
    }

    /// World rotation of an end's attach frame (`None`: the identity).
    #[inline(always)]
    fn end_rotation(end: &IsolatorEnd, scratch: &RootedScratch) -> Option<Matrix3<f64>> {
        match end.carrier {
            Carrier::World | Carrier::Rail(_) => end.attach,
            Carrier::Floating(f) => {
                let rotation = scratch.floating[f].rotation;
                Some(match &end.attach {
                    Some(attach) => rotation * attach,
                    None => rotation,
                })
            }
        }
    }

    fn end_omega(end: &IsolatorEnd, scratch: &RootedScratch) -> Vector3<f64> {
        match end.carrier {
            Carrier::Floating(f) => scratch.floating[f].omega,
            _ => Vector3::zeros(),
        }
    }

    /// A force (at world point `at`) and torque on an end's carrier.
    #[inline(always)]
    fn load(
        end: &IsolatorEnd,
        at: &Vector3<f64>,
        force: &Vector3<f64>,
        torque: &Vector3<f64>,
        scratch: &mut RootedScratch,
    ) {
        match end.carrier {
            Carrier::World => {}
            Carrier::Rail(r) => scratch.rails[r].force += end.rail_axis.dot(force),
            Carrier::Floating(f) => {
                let body = &mut scratch.floating[f];
                body.force += force;
                body.moment += (at - body.origin).cross(force) + torque;
            }
        }
    }

    /// Bushing wrenches (see the general path for the conventions: deflection
    /// of the child attach frame in the parent's attach axes).
    fn isolator_forces(&self, model: &Model, scratch: &mut RootedScratch) {
        for (k, (isolator, element)) in self.isolators.iter().zip(&model.isolators).enumerate() {
            let (parent, child) = (&isolator.parent, &isolator.child);
            let parent_rotation = Self::end_rotation(parent, scratch);
            let parent_point = Self::end_point(parent, scratch);
            let child_point = Self::end_point(child, scratch);
            let child_velocity = Self::carrier_velocity(child, &child_point, scratch);
            let parent_velocity = Self::carrier_velocity(parent, &child_point, scratch);
            let translation = to_local(&parent_rotation, child_point - parent_point);
            let translation_rate = to_local(&parent_rotation, child_velocity - parent_velocity);
            let (rotation, rotation_rate) = match isolator.relative_rotation {
                RelativeRotation::Constant(rotation) => (rotation, Vector3::zeros()),
                RelativeRotation::SameAs(earlier) => scratch.relative[earlier],
                RelativeRotation::Computed => {
                    let child_rotation = Self::end_rotation(child, scratch);
                    let relative =
                        compose(&parent_rotation.map(|m| m.transpose()), &child_rotation);
                    let rotation = relative.map_or(Vector3::zeros(), |r| rotation_log(&r));
                    let rate = to_local(
                        &parent_rotation,
                        Self::end_omega(child, scratch) - Self::end_omega(parent, scratch),
                    );
                    scratch.relative[k] = (rotation, rate);
                    (rotation, rate)
                }
            };
            let (stiffness, damping) = (&element.stiffness, &element.damping);
            // The bushing law on three attach axes from `first`, in the world.
            let law = |first: usize, deflection: &Vector3<f64>, rate: &Vector3<f64>| {
                to_world(
                    &parent_rotation,
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
            let force = law(0, &translation, &translation_rate);
            let torque = law(3, &rotation, &rotation_rate);
            Self::load(child, &child_point, &force, &torque, scratch);
            Self::load(parent, &child_point, &-force, &-torque, scratch);
        }
    }

    /// Coordinate and rate of a point-and-axis element; for floating bodies
    /// also the lever arm from the body origin.
    #[inline(always)]
    fn reading(point: &PointOnBody, scratch: &RootedScratch) -> (f64, f64, Vector3<f64>) {
        match point {
            PointOnBody::Rail {
                body,
                along,
                offset,
            } => {
                let rail = &scratch.rails[*body];
                (
                    offset + along * rail.position,
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
                let arm = state.rotation * point;
                (
                    (state.origin + arm).dot(axis) - zero_offset,
                    (state.velocity + state.omega.cross(&arm)).dot(axis),
                    arm,
                )
            }
        }
    }

    /// A force along a point element's axis, applied at its point.
    #[inline(always)]
    fn push(point: &PointOnBody, arm: &Vector3<f64>, force: f64, scratch: &mut RootedScratch) {
        match point {
            PointOnBody::Rail { body, along, .. } => scratch.rails[*body].force += along * force,
            PointOnBody::Floating { body, axis, .. } => {
                let state = &mut scratch.floating[*body];
                let force = axis * force;
                state.force += force;
                state.moment += arm.cross(&force);
            }
        }
    }

    /// Sensor readings, the servo law and the actuator forces.
    fn servo(&self, model: &Model, x: &[f64], inputs: &Inputs, ws: &mut Workspace) {
        for (k, sensor) in self.sensors.iter().enumerate() {
            let (position, velocity, _) = Self::reading(sensor, &ws.rooted);
            ws.elements.sensor_position[k] = position;
            ws.elements.sensor_velocity[k] = velocity;
        }
        servo_force(model, x, &inputs.values(), &mut ws.elements);
        for (actuator, force) in self.actuators.iter().zip(&ws.elements.actuator_force) {
            if *force != 0.0 {
                let (_, _, arm) = Self::reading(actuator, &ws.rooted);
                Self::push(actuator, &arm, *force, &mut ws.rooted);
            }
        }
    }

    /// LuGre forces and bristle rates.
    fn friction_forces(
        &self,
        model: &Model,
        x: &[f64],
        inputs: &Inputs,
        dx: &mut [f64],
        scratch: &mut RootedScratch,
    ) {
        for (contact, friction) in self.frictions.iter().zip(&model.frictions) {
            let (_, velocity, arm) = Self::reading(contact, scratch);
            let slip = velocity - inputs.platform_velocity;
            let (force, z_rate) = friction.lugre.force_and_z_rate(slip, x[friction.z_index]);
            dx[friction.z_index] = z_rate;
            Self::push(contact, &arm, -force, scratch);
        }
    }

    /// Newton-Euler for each floating body, the rail law for each rail body.
    fn accelerations(&self, dx: &mut [f64], scratch: &RootedScratch) {
        for (body, state) in self.floating.iter().zip(&scratch.floating) {
            let rotation = &state.rotation;
            let omega = state.omega;
            let arm = rotation * body.com;
            // Moment about the centre of mass (gravity has none there) and
            // the gyroscopic term, in body axes.
            let moment = rotation.tr_mul(&(state.moment - arm.cross(&state.force)));
            let omega_body = rotation.tr_mul(&omega);
            let spin = omega_body.cross(&(body.inertia * omega_body));
            let alpha = rotation * (body.inverse_inertia * (moment - spin));
            let accel = state.force * body.inverse_mass + self.gravity
                - alpha.cross(&arm)
                - omega.cross(&omega.cross(&arm));
            let accel = to_local(&body.joint_rotation, accel);
            let alpha = to_local(&body.joint_rotation, alpha);
            let v0 = body.v0;
            dx[v0] = accel.x;
            dx[v0 + 1] = accel.y;
            dx[v0 + 2] = accel.z;
            dx[v0 + 3] = alpha.x;
            dx[v0 + 4] = alpha.y;
            dx[v0 + 5] = alpha.z;
        }
        for (body, state) in self.rails.iter().zip(&scratch.rails) {
            dx[body.v0] = state.force * body.inverse_mass + body.gravity_along;
        }
    }
}

/// The rotation matrix of the quaternion (w, i, j, k), normalised on the way
/// (the scale 2 / |q|^2 makes it exact for any length).
#[inline(always)]
fn quaternion_rotation(w: f64, i: f64, j: f64, k: f64) -> Matrix3<f64> {
    let s = 2.0 / (w * w + i * i + j * j + k * k);
    let (wi, wj, wk) = (s * w * i, s * w * j, s * w * k);
    let (ii, ij, ik) = (s * i * i, s * i * j, s * i * k);
    let (jj, jk, kk) = (s * j * j, s * j * k, s * k * k);
    Matrix3::new(
        1.0 - (jj + kk),
        ij - wk,
        ik + wj,
        ij + wk,
        1.0 - (ii + kk),
        jk - wi,
        ik - wj,
        jk + wi,
        1.0 - (ii + jj),
    )
}
