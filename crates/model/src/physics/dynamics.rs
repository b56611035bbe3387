//! The model's physics: forward kinematics, force elements (isolator bushings,
//! LuGre contacts, actuator, sensor, PID servo), the joint-space equations of
//! motion `M(q) v' = tau(q, v, inputs)`, the state derivative, output signals and
//! stored energy.
//!
//! Rigid-body dynamics are written in world coordinates: a forward pass gives
//! each body's pose, twist and velocity-product ("bias") accelerations; force
//! elements add external wrenches (moments about the world origin); a backward
//! pass sums the wrench every joint must transmit when joint accelerations are
//! zero, whose projection on the joint axes is `-tau`. The mass matrix comes from
//! body Jacobians. Every joint is a set of unit axes, linear or angular: a
//! prismatic joint is one linear axis, a revolute joint one angular axis, a
//! floating joint three of each.
//!
//! Everything is generic over [`Scalar`], so the same code runs in `f64` and in
//! dual numbers for the exact Jacobian ([`crate::linearize`]).

use nalgebra::{DMatrix, DVector, Matrix3, Quaternion, Rotation3, Unit, UnitQuaternion, Vector3};

use crate::elements::{Body, BodyWrench, Frame, Inputs, JointMotion, RigidBody, Structure};
use crate::laws::{
    bushing_wrench, cast3, cast33, newton_euler, quaternion_rate, quaternion_rotation,
    relative_rotation, servo_forces,
};
use crate::reference::ReferenceSample;
use crate::rooted::RootedScratch;
use crate::scalar::Scalar;
use crate::values::ServoValues;
pub use crate::values::{ElementValues, InputValues};

/// How [`crate::Model::rhs`] evaluates a model; every path gives the same state
/// derivative as [`crate::Model::rhs_general`] up to round-off.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EvaluationPath {
    /// No joint rotates a body: kinematics are linear in the coordinates, so
    /// constant Jacobian rows and a constant inverse mass matrix
    /// (module `translational`).
    ConstantJacobian,
    /// Every body is jointed straight to the world, floating or on a rail:
    /// one Newton-Euler body or rail mass each, coupled only through force
    /// elements, with the geometry resolved at build time (module `rooted`).
    RootedBodies,
    /// Bodies in chains: recursive kinematics and a backward pass.
    General,
}

/// Scratch space for evaluating a model without allocating. One per thread.
#[derive(Debug, Clone)]
pub struct Workspace<S: Scalar = f64> {
    rotation: Vec<Matrix3<S>>,
    origin: Vec<Vector3<S>>,
    omega: Vec<Vector3<S>>,
    velocity: Vec<Vector3<S>>,
    bias_alpha: Vec<Vector3<S>>,
    bias_accel: Vec<Vector3<S>>,
    dof_axis: Vec<Vector3<S>>,
    dof_center: Vec<Vector3<S>>,
    dof_angular: Vec<bool>,
    /// Per body: it never turns and its axes stay those of the world, so
    /// its rotation is the identity and its angular velocity zero.
    parallel: Vec<bool>,
    force: Vec<Vector3<S>>,
    moment: Vec<Vector3<S>>,
    tau: DVector<S>,
    block_mass: Vec<Vec<S>>,
    block_rhs: Vec<Vec<S>>,
    pub(crate) generalized: Vec<S>,
    /// Scratch space of the rooted fast path ([`crate::rooted`]).
    pub(crate) rooted: crate::rooted::RootedScratch<S>,
    /// How the bristle states enter the evaluation (explicit unless an
    /// implicit-explicit integrator asks otherwise).
    pub(crate) bristles: crate::bristle::BristleStage<S>,
    /// Per-element results of the last [`crate::Model::evaluate`] or [`crate::Model::outputs`]
    /// (the fast paths of [`crate::Model::rhs`] fill only the sensor, actuator and
    /// tracking-error entries).
    pub elements: ElementValues<S>,
}

impl Structure {
    /// A workspace sized for this structure, with the fast path's scratch space.
    pub(crate) fn workspace_with<S: Scalar>(&self, rooted: RootedScratch<S>) -> Workspace<S> {
        let nb = self.bodies.len();
        let nv = self.layout.nv;
        let zeros = || vec![Vector3::zeros(); nb];
        let mut dof_angular = vec![false; nv];
        for body in &self.bodies {
            let v0 = body.joint.v_offset;
            match body.joint.motion {
                JointMotion::Prismatic { .. } => {}
                JointMotion::Revolute { .. } => dof_angular[v0] = true,
                JointMotion::Floating => dof_angular[v0 + 3..v0 + 6].fill(true),
            }
        }
        let (nf, ni, na, ns) = (
            self.frictions.len(),
            self.isolators.len(),
            self.actuators.len(),
            self.sensors.len(),
        );
        Workspace {
            parallel: self.parallel_bodies(),
            rotation: vec![Matrix3::identity(); nb],
            origin: zeros(),
            omega: zeros(),
            velocity: zeros(),
            bias_alpha: zeros(),
            bias_accel: zeros(),
            dof_axis: vec![Vector3::zeros(); nv],
            dof_center: vec![Vector3::zeros(); nv],
            dof_angular,
            force: zeros(),
            moment: zeros(),
            tau: DVector::zeros(nv),
            block_mass: self
                .mass_blocks
                .iter()
                .map(|b| vec![S::zero(); b.dofs.len() * b.dofs.len()])
                .collect(),
            block_rhs: self
                .mass_blocks
                .iter()
                .map(|b| vec![S::zero(); b.dofs.len()])
                .collect(),
            generalized: vec![S::zero(); nv],
            rooted,
            bristles: crate::bristle::BristleStage::explicit(
                nf,
                self.controller.as_ref().map_or(0, |c| c.feedforward.len()),
            ),
            elements: ElementValues {
                friction_force: vec![S::zero(); nf],
                slip_velocity: vec![S::zero(); nf],
                z_rate: vec![S::zero(); nf],
                contact_displacement: vec![S::zero(); nf],
                actuator_force: vec![S::zero(); na],
                sensor_position: vec![S::zero(); ns],
                sensor_velocity: vec![S::zero(); ns],
                isolator_deflection: vec![[S::zero(); 6]; ni],
                isolator_rate: vec![[S::zero(); 6]; ni],
                reference: ReferenceSample::default(),
                servo: ServoValues::zero(),
            },
        }
    }

    /// Which bodies never turn and keep the world's axes: no joint between
    /// them and the world rotates and every joint frame on the way is
    /// unrotated.
    fn parallel_bodies(&self) -> Vec<bool> {
        let mut parallel: Vec<bool> = Vec::with_capacity(self.bodies.len());
        for body in &self.bodies {
            let parent_parallel = body.parent.is_none_or(|p| parallel[p]);
            parallel.push(
                parent_parallel && !body.turns && body.joint.origin_rotation == Matrix3::identity(),
            );
        }
        parallel
    }

    /// State derivative by the general recursive dynamics, for any model and scalar.
    pub(crate) fn rhs_general<S: Scalar>(
        &self,
        x: &[S],
        inputs: &InputValues<S>,
        dx: &mut [S],
        ws: &mut Workspace<S>,
    ) {
        self.evaluate_values(x, inputs, ws);
        self.position_rates(x, dx);
        self.accelerations(ws);
        let nq = self.layout.nq;
        let nv = self.layout.nv;
        dx[nq..nq + nv].copy_from_slice(ws.tau.as_slice());
        for (friction, rate) in self.frictions.iter().zip(&ws.elements.z_rate) {
            dx[friction.z_index] = *rate;
        }
        if let Some(controller) = &self.controller {
            controller.write_rates(&ws.elements.servo, dx);
        }
    }

    /// Kinematics and force elements at state x; results stay in `ws`.
    pub(crate) fn evaluate(&self, x: &[f64], inputs: &Inputs, ws: &mut Workspace) {
        ws.elements.reference = inputs.reference;
        self.evaluate_values(x, &inputs.values(), ws);
    }

    pub(crate) fn evaluate_values<S: Scalar>(
        &self,
        x: &[S],
        inputs: &InputValues<S>,
        ws: &mut Workspace<S>,
    ) {
        self.kinematics(x, ws);
        ws.force.fill(Vector3::zeros());
        ws.moment.fill(Vector3::zeros());
        self.isolator_forces(ws);
        self.friction_forces(x, inputs, ws);
        self.sensors_and_servo(x, inputs, ws);
    }

    /// Each sensor's reading at state x, in sensor order, from the
    /// kinematics alone (no force element is evaluated).
    pub(crate) fn sensor_positions(&self, x: &[f64], out: &mut [f64], ws: &mut Workspace) {
        self.kinematics(x, ws);
        for (reading, sensor) in out.iter_mut().zip(&self.sensors) {
            let (point, _) = point_state(Frame::Body(sensor.body), &sensor.point, ws);
            *reading = point.dot(&sensor.axis) - sensor.zero_offset;
        }
    }

    /// Writes every output signal (see [`crate::Model::signals`]) at state x.
    pub(crate) fn outputs(&self, x: &[f64], inputs: &Inputs, out: &mut [f64], ws: &mut Workspace) {
        ws.elements.reference = inputs.reference;
        self.outputs_of(x, &inputs.values(), out, ws);
    }

    /// [`crate::Model::outputs`] in any scalar type: with dual numbers it gives exact
    /// derivatives of the outputs (e.g. their direct dependence on the inputs).
    pub(crate) fn outputs_of<S: Scalar>(
        &self,
        x: &[S],
        inputs: &InputValues<S>,
        out: &mut [S],
        ws: &mut Workspace<S>,
    ) {
        self.evaluate_values(x, inputs, ws);
        let e = &ws.elements;
        let mut k = 0;
        let mut put = |value: S| {
            out[k] = value;
            k += 1;
        };
        for (p, v) in e.sensor_position.iter().zip(&e.sensor_velocity) {
            put(*p);
            put(*v);
        }
        if let Some(controller) = &self.controller {
            put(inputs.reference_position);
            put(e.servo.error);
            if !controller.feedforward.is_empty() {
                put(e.servo.feedforward);
            }
            if controller.feedforward.len() > 1 {
                for force in &e.servo.compensator_forces[..controller.feedforward.len()] {
                    put(*force);
                }
            }
            if controller.observer.is_some() {
                put(e.servo.estimate);
            }
        }
        for f in &e.actuator_force {
            put(*f);
        }
        let nq = self.layout.nq;
        for body in &self.bodies {
            let (q0, v0) = (body.joint.q_offset, nq + body.joint.v_offset);
            match body.joint.motion {
                JointMotion::Prismatic { .. } | JointMotion::Revolute { .. } => {
                    put(x[q0]);
                    put(x[v0]);
                }
                JointMotion::Floating => {
                    (0..3).for_each(|i| put(x[q0 + i]));
                    let (roll, pitch, yaw) = quaternion_at(x, q0 + 3).euler_angles();
                    [roll, pitch, yaw].into_iter().for_each(&mut put);
                    (0..6).for_each(|i| put(x[v0 + i]));
                }
            }
        }
        for i in 0..self.frictions.len() {
            put(e.friction_force[i]);
            put(e.slip_velocity[i]);
            put(x[self.frictions[i].z_index]);
        }
        for deflection in &e.isolator_deflection {
            deflection.iter().for_each(|d| put(*d));
        }
    }

    /// Kinetic energy + isolator springs + bristle springs sigma0 z^2 / 2 +
    /// gravitational potential (relative to the world origin), J. With no servo
    /// and no platform motion this never increases.
    pub(crate) fn stored_energy(&self, x: &[f64], ws: &mut Workspace) -> f64 {
        self.evaluate(x, &Inputs::default(), ws);
        let mut energy = 0.0;
        for (i, body) in self.bodies.iter().enumerate() {
            let r = ws.rotation[i] * body.com;
            let v_com = ws.velocity[i] + ws.omega[i].cross(&r);
            let inertia = ws.rotation[i] * body.inertia * ws.rotation[i].transpose();
            energy += 0.5 * body.mass * v_com.norm_squared()
                + 0.5 * ws.omega[i].dot(&(inertia * ws.omega[i]))
                - body.mass * self.gravity.dot(&(ws.origin[i] + r));
        }
        for (isolator, d) in self.isolators.iter().zip(&ws.elements.isolator_deflection) {
            energy += (0..6)
                .map(|a| 0.5 * isolator.stiffness[a] * d[a] * d[a])
                .sum::<f64>();
        }
        for friction in &self.frictions {
            let z = x[friction.z_index];
            energy += 0.5 * friction.lugre.sigma0 * z * z;
        }
        energy
    }

    /// Forward pass: poses, twists, bias accelerations and joint axes in world coordinates.
    fn kinematics<S: Scalar>(&self, x: &[S], ws: &mut Workspace<S>) {
        let nq = self.layout.nq;
        for (i, body) in self.bodies.iter().enumerate() {
            let zero = Vector3::zeros();
            let (
                parent_rotation,
                parent_origin,
                parent_omega,
                parent_velocity,
                parent_alpha,
                parent_accel,
            ) = match body.parent {
                Some(p) => (
                    ws.rotation[p],
                    ws.origin[p],
                    ws.omega[p],
                    ws.velocity[p],
                    ws.bias_alpha[p],
                    ws.bias_accel[p],
                ),
                None => (Matrix3::identity(), zero, zero, zero, zero, zero),
            };
            let joint = &body.joint;
            let (joint_rotation, joint_origin) = match body.parent {
                // Root bodies: the joint frame is given in the world.
                None => (
                    cast33::<S>(&joint.origin_rotation),
                    cast3::<S>(&joint.origin.translation.vector),
                ),
                Some(_) => (
                    parent_rotation * cast33::<S>(&joint.origin_rotation),
                    parent_origin + parent_rotation * cast3::<S>(&joint.origin.translation.vector),
                ),
            };
            let (q0, v0) = (joint.q_offset, joint.v_offset);
            let mut linear_rate = Vector3::zeros();
            let mut angular_rate = Vector3::zeros();
            let (rotation, origin) = match joint.motion {
                JointMotion::Prismatic { axis } => {
                    let s = joint_rotation * cast3::<S>(&axis);
                    ws.dof_axis[v0] = s;
                    linear_rate = s * x[nq + v0];
                    (joint_rotation, joint_origin + s * x[q0])
                }
                JointMotion::Revolute { axis } => {
                    let s = joint_rotation * cast3::<S>(&axis);
                    ws.dof_axis[v0] = s;
                    ws.dof_center[v0] = joint_origin;
                    angular_rate = s * x[nq + v0];
                    let turn =
                        Rotation3::from_axis_angle(&Unit::new_unchecked(cast3::<S>(&axis)), x[q0]);
                    (joint_rotation * turn.matrix(), joint_origin)
                }
                JointMotion::Floating => {
                    let offset = Vector3::new(x[q0], x[q0 + 1], x[q0 + 2]);
                    let origin = joint_origin + joint_rotation * offset;
                    let attitude = quaternion_rotation(x[q0 + 3], x[q0 + 4], x[q0 + 5], x[q0 + 6]);
                    for k in 0..3 {
                        let s = joint_rotation.column(k).into_owned();
                        ws.dof_axis[v0 + k] = s;
                        ws.dof_axis[v0 + 3 + k] = s;
                        ws.dof_center[v0 + 3 + k] = origin;
                        linear_rate += s * x[nq + v0 + k];
                        angular_rate += s * x[nq + v0 + 3 + k];
                    }
                    (joint_rotation * attitude, origin)
                }
            };
            ws.rotation[i] = rotation;
            ws.origin[i] = origin;
            if body.parent.is_none() {
                // The world neither moves nor turns: no transport terms.
                ws.omega[i] = angular_rate;
                ws.velocity[i] = linear_rate;
                ws.bias_alpha[i] = zero;
                ws.bias_accel[i] = zero;
                continue;
            }
            let r = origin - parent_origin;
            let two = S::constant(2.0);
            ws.omega[i] = parent_omega + angular_rate;
            ws.velocity[i] = parent_velocity + parent_omega.cross(&r) + linear_rate;
            ws.bias_alpha[i] = parent_alpha + parent_omega.cross(&angular_rate);
            ws.bias_accel[i] = parent_accel
                + parent_alpha.cross(&r)
                + parent_omega.cross(&parent_omega.cross(&r))
                + parent_omega.cross(&linear_rate) * two;
        }
    }

    fn isolator_forces<S: Scalar>(&self, ws: &mut Workspace<S>) {
        for (k, isolator) in self.isolators.iter().enumerate() {
            // Attach-frame rotations; None is the identity (skipped products).
            let attach = |frame: Frame, side: usize, ws: &Workspace<S>| {
                let attach = (!isolator.attach_is_identity[side])
                    .then(|| cast33::<S>(&isolator.attach_rotations[side]));
                match (frame_rotation(frame, ws), attach) {
                    (Some(rotation), Some(attach)) => Some(rotation * attach),
                    (rotation, None) => rotation,
                    (None, attach) => attach,
                }
            };
            let parent_rotation = attach(isolator.parent, 0, ws);
            let child_rotation = attach(isolator.child, 1, ws);
            let (parent_point, _) = point_state(
                isolator.parent,
                &isolator.parent_attach.translation.vector,
                ws,
            );
            let (child_point, child_point_velocity) = point_state(
                isolator.child,
                &isolator.child_attach.translation.vector,
                ws,
            );
            // Velocity of the parent's material point that coincides with the child attach point.
            let parent_velocity_there = match isolator.parent {
                Frame::World => Vector3::zeros(),
                Frame::Body(b) if ws.parallel[b] => ws.velocity[b],
                Frame::Body(b) => ws.velocity[b] + ws.omega[b].cross(&(child_point - ws.origin[b])),
            };
            let (rotation, rotation_rate) = relative_rotation(
                &parent_rotation,
                &child_rotation,
                frame_omega(isolator.parent, ws),
                frame_omega(isolator.child, ws),
            );
            let wrench = bushing_wrench(
                &isolator.stiffness,
                &isolator.damping,
                &parent_rotation,
                child_point - parent_point,
                child_point_velocity - parent_velocity_there,
                rotation,
                rotation_rate,
            );
            apply_wrench(
                ws,
                isolator.child,
                &child_point,
                &wrench.force,
                &wrench.torque,
            );
            apply_wrench(
                ws,
                isolator.parent,
                &child_point,
                &-wrench.force,
                &-wrench.torque,
            );
            ws.elements.isolator_deflection[k] = wrench.deflection;
            ws.elements.isolator_rate[k] = wrench.rate;
        }
    }

    fn friction_forces<S: Scalar>(&self, x: &[S], inputs: &InputValues<S>, ws: &mut Workspace<S>) {
        for (k, friction) in self.frictions.iter().enumerate() {
            let frame = Frame::Body(friction.body);
            let axis = cast3::<S>(&friction.axis);
            let (point, point_velocity) = point_state(frame, &friction.point, ws);
            let slip = point_velocity.dot(&axis) - inputs.platform_velocity;
            let (force, z_rate) = ws.bristles.law(k, friction, slip, x[friction.z_index]);
            apply_wrench(ws, frame, &point, &(axis * -force), &Vector3::zeros());
            ws.elements.friction_force[k] = force;
            ws.elements.slip_velocity[k] = slip;
            ws.elements.z_rate[k] = z_rate;
            ws.elements.contact_displacement[k] =
                point.dot(&axis) - S::constant(friction.zero_offset);
        }
    }

    fn sensors_and_servo<S: Scalar>(
        &self,
        x: &[S],
        inputs: &InputValues<S>,
        ws: &mut Workspace<S>,
    ) {
        for (k, sensor) in self.sensors.iter().enumerate() {
            let axis = cast3::<S>(&sensor.axis);
            let (point, velocity) = point_state(Frame::Body(sensor.body), &sensor.point, ws);
            ws.elements.sensor_position[k] = point.dot(&axis) - S::constant(sensor.zero_offset);
            ws.elements.sensor_velocity[k] = velocity.dot(&axis);
        }
        servo_forces(self, x, inputs, &mut ws.elements, &mut ws.bristles);
        for (k, actuator) in self.actuators.iter().enumerate() {
            let frame = Frame::Body(actuator.body);
            let (point, _) = point_state(frame, &actuator.point, ws);
            let force = cast3::<S>(&actuator.axis) * ws.elements.actuator_force[k];
            apply_wrench(ws, frame, &point, &force, &Vector3::zeros());
        }
    }

    /// Backward pass and solve: leaves the joint accelerations in `ws.tau`.
    fn accelerations<S: Scalar>(&self, ws: &mut Workspace<S>) {
        let nb = self.bodies.len();
        let gravity = cast3::<S>(&self.gravity);
        // Wrench each body needs from its joint for zero joint accelerations.
        for i in 0..nb {
            let body = &self.bodies[i];
            let r = ws.rotation[i] * cast3::<S>(&body.com);
            let com = ws.origin[i] + r;
            let (inertial_force, inertial_moment) = if body.turns {
                let omega = ws.omega[i];
                let alpha = ws.bias_alpha[i];
                let accel_com = ws.bias_accel[i] + alpha.cross(&r) + omega.cross(&omega.cross(&r));
                let inertial_force = (accel_com - gravity) * S::constant(body.mass);
                // I_world alpha + omega x I_world omega, evaluated in body
                // axes (three rotations instead of forming R I R^T).
                let rotation = &ws.rotation[i];
                let inertia = cast33::<S>(&body.inertia);
                let (omega_body, alpha_body) = (rotation.tr_mul(&omega), rotation.tr_mul(&alpha));
                let spin = omega_body.cross(&(inertia * omega_body));
                let inertial_moment =
                    com.cross(&inertial_force) + rotation * (inertia * alpha_body + spin);
                (inertial_force, inertial_moment)
            } else {
                // No angular velocity or acceleration: translation only.
                let inertial_force = (ws.bias_accel[i] - gravity) * S::constant(body.mass);
                (inertial_force, com.cross(&inertial_force))
            };
            ws.force[i] = inertial_force - ws.force[i];
            ws.moment[i] = inertial_moment - ws.moment[i];
        }
        for i in (0..nb).rev() {
            let body = &self.bodies[i];
            let (force, moment) = (ws.force[i], ws.moment[i]);
            let v0 = body.joint.v_offset;
            for dof in v0..v0 + body.joint.motion.nv() {
                let s = ws.dof_axis[dof];
                ws.tau[dof] = -if ws.dof_angular[dof] {
                    s.dot(&(moment - ws.dof_center[dof].cross(&force)))
                } else {
                    s.dot(&force)
                };
            }
            if let Some(p) = body.parent {
                ws.force[p] += force;
                ws.moment[p] += moment;
            }
        }
        for (index, block) in self.mass_blocks.iter().enumerate() {
            let k = block.dofs.len();
            let rhs = &mut ws.block_rhs[index];
            for (local, &dof) in block.dofs.iter().enumerate() {
                rhs[local] = ws.tau[dof];
            }
            if let Some((body, mass_properties)) = &block.free_body {
                free_body_accelerations(self, *body, mass_properties, ws);
                continue;
            }
            match &block.constant_inverse {
                Some(inverse) => {
                    for (local, &dof) in block.dofs.iter().enumerate() {
                        ws.tau[dof] = (0..k).fold(S::zero(), |sum, col| {
                            sum + S::constant(inverse[local * k + col]) * rhs[col]
                        });
                    }
                }
                None => {
                    fill_block_mass(
                        self,
                        block,
                        &mut ws.block_mass[index],
                        ws_kinematics(
                            &ws.rotation,
                            &ws.origin,
                            &ws.dof_axis,
                            &ws.dof_center,
                            &ws.dof_angular,
                        ),
                    );
                    let solved =
                        cholesky_solve(&mut ws.block_mass[index], &mut ws.block_rhs[index]);
                    for (local, &dof) in block.dofs.iter().enumerate() {
                        ws.tau[dof] = if solved {
                            ws.block_rhs[index][local]
                        } else {
                            // Singular only for degenerate configurations: make it visible.
                            S::constant(f64::NAN)
                        };
                    }
                }
            }
        }
    }

    /// Position-coordinate rates: joint velocities, and quaternion rates for floating joints.
    fn position_rates<S: Scalar>(&self, x: &[S], dx: &mut [S]) {
        let nq = self.layout.nq;
        for body in &self.bodies {
            let (q0, v0) = (body.joint.q_offset, nq + body.joint.v_offset);
            match body.joint.motion {
                JointMotion::Prismatic { .. } | JointMotion::Revolute { .. } => dx[q0] = x[v0],
                JointMotion::Floating => {
                    dx[q0..q0 + 3].copy_from_slice(&x[v0..v0 + 3]);
                    let q = [x[q0 + 3], x[q0 + 4], x[q0 + 5], x[q0 + 6]];
                    let omega = Vector3::new(x[v0 + 3], x[v0 + 4], x[v0 + 5]);
                    dx[q0 + 3..q0 + 7].copy_from_slice(&quaternion_rate(q, omega));
                }
            }
        }
    }
}

/// The joint accelerations of a lone floating body in closed form, in place of
/// its 6x6 block solve: the generalized forces give the world force and moment
/// about the body origin, and Newton-Euler without velocity terms (those are
/// in the generalized forces already) gives the accelerations.
fn free_body_accelerations<S: Scalar>(
    model: &Structure,
    index: usize,
    mass_properties: &RigidBody,
    ws: &mut Workspace<S>,
) {
    let v0 = model.bodies[index].joint.v_offset;
    let axes = |k: usize| ws.dof_axis[v0 + k];
    // The joint axes are orthonormal: world vector = sum of axis * component.
    let (mut force, mut moment) = (Vector3::zeros(), Vector3::zeros());
    for k in 0..3 {
        force += axes(k) * ws.tau[v0 + k];
        moment += axes(3 + k) * ws.tau[v0 + 3 + k];
    }
    let zero = Vector3::zeros();
    let (accel, alpha) = newton_euler(
        mass_properties,
        &ws.rotation[index],
        zero,
        force,
        moment,
        zero,
    );
    for k in 0..3 {
        ws.tau[v0 + k] = axes(k).dot(&accel);
        ws.tau[v0 + 3 + k] = axes(3 + k).dot(&alpha);
    }
}

/// World position and velocity of a point given in a body frame.
fn point_state<S: Scalar>(
    frame: Frame,
    point: &Vector3<f64>,
    ws: &Workspace<S>,
) -> (Vector3<S>, Vector3<S>) {
    let point = cast3::<S>(point);
    match frame {
        Frame::World => (point, Vector3::zeros()),
        Frame::Body(b) if ws.parallel[b] => (ws.origin[b] + point, ws.velocity[b]),
        Frame::Body(b) => {
            let r = ws.rotation[b] * point;
            (ws.origin[b] + r, ws.velocity[b] + ws.omega[b].cross(&r))
        }
    }
}

/// The rotation of a frame, `None` when it is the identity for every state
/// (the world, bodies parallel to it).
fn frame_rotation<S: Scalar>(frame: Frame, ws: &Workspace<S>) -> Option<Matrix3<S>> {
    match frame {
        Frame::World => None,
        Frame::Body(b) if ws.parallel[b] => None,
        Frame::Body(b) => Some(ws.rotation[b]),
    }
}

fn frame_omega<S: Scalar>(frame: Frame, ws: &Workspace<S>) -> Vector3<S> {
    match frame {
        Frame::World => Vector3::zeros(),
        Frame::Body(b) => ws.omega[b],
    }
}

/// The unit quaternion stored at `x[start..start + 4]` as (w, x, y, z), normalised.
pub fn quaternion_at<S: Scalar>(x: &[S], start: usize) -> UnitQuaternion<S> {
    UnitQuaternion::from_quaternion(Quaternion::new(
        x[start],
        x[start + 1],
        x[start + 2],
        x[start + 3],
    ))
}

fn apply_wrench<S: Scalar>(
    ws: &mut Workspace<S>,
    frame: Frame,
    point: &Vector3<S>,
    force: &Vector3<S>,
    torque: &Vector3<S>,
) {
    if let Frame::Body(b) = frame {
        ws.force[b] += force;
        ws.moment[b] += point.cross(force) + torque;
    }
}

impl Structure {
    /// World pose (rotation, origin) of every body at state x.
    pub(crate) fn body_poses(&self, x: &[f64]) -> Vec<(Matrix3<f64>, Vector3<f64>)> {
        let mut ws = self.workspace_with(RootedScratch::empty());
        self.kinematics(x, &mut ws);
        ws.rotation
            .iter()
            .copied()
            .zip(ws.origin.iter().copied())
            .collect()
    }
}

impl Workspace<f64> {
    /// World rotation of body i after an evaluation.
    pub(crate) fn rotation_of(&self, i: usize) -> Matrix3<f64> {
        self.rotation[i]
    }

    /// World position of body i's frame origin after an evaluation.
    pub(crate) fn origin_of(&self, i: usize) -> Vector3<f64> {
        self.origin[i]
    }

    /// World angular velocity of body i after an evaluation.
    pub(crate) fn omega_of(&self, i: usize) -> Vector3<f64> {
        self.omega[i]
    }

    /// World velocity of body i's frame origin after an evaluation.
    pub(crate) fn velocity_of(&self, i: usize) -> Vector3<f64> {
        self.velocity[i]
    }

    /// The element wrench on body i after an evaluation (before gravity and inertia).
    pub(crate) fn wrench_of(&self, i: usize) -> BodyWrench {
        BodyWrench {
            force: self.force[i],
            moment: self.moment[i],
        }
    }

    /// World velocity of a point (body frame coordinates) after [`crate::Model::evaluate`].
    pub(crate) fn point_velocity(&self, body: usize, point: &Vector3<f64>) -> Vector3<f64> {
        self.velocity[body] + self.omega[body].cross(&(self.rotation[body] * point))
    }
}

/// Kinematic quantities the mass matrix needs, borrowed from a workspace.
struct Kinematics<'a, S: Scalar> {
    rotation: &'a [Matrix3<S>],
    origin: &'a [Vector3<S>],
    dof_axis: &'a [Vector3<S>],
    dof_center: &'a [Vector3<S>],
    dof_angular: &'a [bool],
}

fn ws_kinematics<'a, S: Scalar>(
    rotation: &'a [Matrix3<S>],
    origin: &'a [Vector3<S>],
    dof_axis: &'a [Vector3<S>],
    dof_center: &'a [Vector3<S>],
    dof_angular: &'a [bool],
) -> Kinematics<'a, S> {
    Kinematics {
        rotation,
        origin,
        dof_axis,
        dof_center,
        dof_angular,
    }
}

/// One diagonal block of the mass matrix (row-major, block-local indices).
fn fill_block_mass<S: Scalar>(
    model: &Structure,
    block: &crate::elements::MassBlock,
    out: &mut [S],
    kin: Kinematics<S>,
) {
    fill_mass(
        model,
        &block.bodies,
        block.dofs.len(),
        |b| &b.chain_local,
        out,
        kin,
    );
}

/// The mass matrix over some bodies, `sum m Jv^T Jv + Jw^T I Jw` from body
/// Jacobians, row-major `k x k`; `local` numbers each body's chain of dofs
/// in it.
fn fill_mass<S: Scalar>(
    model: &Structure,
    bodies: &[usize],
    k: usize,
    local: impl Fn(&Body) -> &[usize],
    out: &mut [S],
    kin: Kinematics<S>,
) {
    out.fill(S::zero());
    let mut jacobian: [(Vector3<S>, Vector3<S>); 12] = [(Vector3::zeros(), Vector3::zeros()); 12];
    for &i in bodies {
        let body = &model.bodies[i];
        let com = kin.origin[i] + kin.rotation[i] * cast3::<S>(&body.com);
        let inertia = kin.rotation[i] * cast33::<S>(&body.inertia) * kin.rotation[i].transpose();
        let mass = S::constant(body.mass);
        let chain = &body.chain;
        let columns: Vec<(Vector3<S>, Vector3<S>)>;
        let jac: &[(Vector3<S>, Vector3<S>)] = if chain.len() <= jacobian.len() {
            for (slot, &dof) in jacobian.iter_mut().zip(chain) {
                *slot = body_column(&kin, dof, &com);
            }
            &jacobian[..chain.len()]
        } else {
            columns = chain
                .iter()
                .map(|&dof| body_column(&kin, dof, &com))
                .collect();
            &columns
        };
        let indices = local(body);
        for (a, &row) in indices.iter().enumerate() {
            let (va, wa) = jac[a];
            let inertia_wa = inertia * wa;
            for (b, &col) in indices.iter().enumerate().skip(a) {
                let (vb, wb) = jac[b];
                let entry = mass * va.dot(&vb) + wb.dot(&inertia_wa);
                out[row * k + col] += entry;
                if b != a {
                    out[col * k + row] += entry;
                }
            }
        }
    }
}

/// Linear and angular velocity of a body's centre of mass per unit rate of `dof`.
fn body_column<S: Scalar>(
    kin: &Kinematics<S>,
    dof: usize,
    com: &Vector3<S>,
) -> (Vector3<S>, Vector3<S>) {
    let s = kin.dof_axis[dof];
    if kin.dof_angular[dof] {
        (s.cross(&(com - kin.dof_center[dof])), s)
    } else {
        (s, Vector3::zeros())
    }
}

/// Solves `A x = b` in place for a small symmetric positive definite A
/// (row-major, overwritten by its Cholesky factor); false if A is not positive definite.
fn cholesky_solve<S: Scalar>(a: &mut [S], b: &mut [S]) -> bool {
    let n = b.len();
    for j in 0..n {
        let mut diagonal = a[j * n + j];
        for p in 0..j {
            diagonal -= a[j * n + p] * a[j * n + p];
        }
        // Positive and finite (compared, not read out, so that a compiled
        // evaluation checks the same branch).
        let positive = diagonal.compare_value(0.0) == Some(std::cmp::Ordering::Greater)
            && diagonal.compare_value(f64::INFINITY) == Some(std::cmp::Ordering::Less);
        if !positive {
            return false;
        }
        let diagonal = diagonal.sqrt();
        a[j * n + j] = diagonal;
        for i in j + 1..n {
            let mut value = a[i * n + j];
            for p in 0..j {
                value -= a[i * n + p] * a[j * n + p];
            }
            a[i * n + j] = value / diagonal;
        }
    }
    for i in 0..n {
        let mut value = b[i];
        for p in 0..i {
            value -= a[i * n + p] * b[p];
        }
        b[i] = value / a[i * n + i];
    }
    for i in (0..n).rev() {
        let mut value = b[i];
        for p in i + 1..n {
            value -= a[p * n + i] * b[p];
        }
        b[i] = value / a[i * n + i];
    }
    true
}

/// The joint-space mass matrix at state x (positions are read from x).
pub(crate) fn mass_matrix(model: &Structure, x: &[f64]) -> DMatrix<f64> {
    let mut ws = model.workspace_with(RootedScratch::empty());
    model.kinematics(x, &mut ws);
    let nv = model.layout.nv;
    let bodies: Vec<usize> = (0..model.bodies.len()).collect();
    let mut entries = vec![0.0; nv * nv];
    let kin = ws_kinematics(
        &ws.rotation,
        &ws.origin,
        &ws.dof_axis,
        &ws.dof_center,
        &ws.dof_angular,
    );
    fill_mass(model, &bodies, nv, |b| &b.chain, &mut entries, kin);
    DMatrix::from_row_slice(nv, nv, &entries)
}
