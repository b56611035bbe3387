//! The second engine: rapier3d-f64 integrates the rigid bodies (fixed step,
//! semi-implicit Euler; the model's prismatic and revolute joints as
//! reduced-coordinate multibody joints where the chain to the world has no
//! floating joint, as impulse joints below a floating body; free bodies for
//! floating joints), while the
//! force elements (isolators, LuGre contacts, servo) are the model's own code
//! ([`Model::element_wrenches`]), applied as external forces every step; the
//! bristle and integrator states advance with the rates the model gives. No
//! physics is written twice: rapier only replaces the native mass matrix and
//! integrator.
//!
//! The step is a fraction of the stability limit of the model's fastest mode
//! at the starting state, shortened so that whole steps fit each output
//! sample. Optional colliders (end-of-travel stops, a payload box resting on a
//! link) come from the scenario's `[rapier]` table.

use std::time::Instant;

use fistage_model::{
    BodyMotion, BodyWrench, Inputs, JointMotion, Model, PayloadSettings, RapierSettings,
};
use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
use rapier3d_f64::math::{Matrix, Pose, Rotation, Vector};
use rapier3d_f64::prelude::*;

use crate::engine::Engine;
use crate::settings::{SimError, SimSettings, sample_times};
use crate::trajectory::{ExtraSignal, SolverStats, Trajectory};
use fistage_model::eigen::spectral_radius;
use fistage_model::excitation::Excitation;
use fistage_ode::StepCounts;

/// Default step as a fraction of the explicit stability limit 2 / |lambda|max.
pub const DEFAULT_STEP_FRACTION: f64 = 0.05;
/// Radius of the balls that meet at an end stop, m.
const STOP_BALL_RADIUS: f64 = 1e-3;
/// Thickness of the support plate under a payload, m.
const SUPPORT_THICKNESS: f64 = 2e-3;

fn vector(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

fn vector3(v: Vector) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

fn rotation(m: &Matrix3<f64>) -> Rotation {
    let q = UnitQuaternion::from_matrix(m);
    Rotation::from_xyzw(q.i, q.j, q.k, q.w).normalize()
}

fn matrix3(q: &Rotation) -> Matrix3<f64> {
    UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q.w, q.x, q.y, q.z))
        .to_rotation_matrix()
        .into_inner()
}

fn pose(isometry: &Isometry3<f64>) -> Pose {
    Pose::from_parts(
        vector(&isometry.translation.vector),
        rotation(isometry.rotation.to_rotation_matrix().matrix()),
    )
}

fn matrix(m: &Matrix3<f64>) -> Matrix {
    Matrix::from_cols(
        vector(&m.column(0).into_owned()),
        vector(&m.column(1).into_owned()),
        vector(&m.column(2).into_owned()),
    )
}

/// The rotation taking the x axis to `axis` (the free direction of a rapier joint frame).
fn align_x_with(axis: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::rotation_between(&Vector3::x(), axis).unwrap_or_else(|| {
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI)
    })
}

/// Everything rapier needs, plus the map from model bodies to rapier bodies.
struct World {
    gravity: Vector,
    parameters: IntegrationParameters,
    pipeline: PhysicsPipeline,
    islands: IslandManager,
    broad_phase: BroadPhaseBvh,
    narrow_phase: NarrowPhase,
    bodies: RigidBodySet,
    colliders: ColliderSet,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    soft_bodies: SoftBodySet,
    ccd: CCDSolver,
    handles: Vec<RigidBodyHandle>,
    /// (model body, its multibody joint).
    joints: Vec<(usize, MultibodyJointHandle)>,
    payload: Option<Payload>,
}

struct Payload {
    body: RigidBodyHandle,
    link: usize,
    /// Payload centre in the link frame at the start.
    start_in_link: Vector3<f64>,
}

impl World {
    fn step(&mut self) {
        self.pipeline.step(
            self.gravity,
            &self.parameters,
            &mut self.islands,
            &mut self.broad_phase,
            &mut self.narrow_phase,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse_joints,
            &mut self.multibody_joints,
            &mut self.soft_bodies,
            &mut self.ccd,
            &(),
            &(),
        );
    }

    /// World motion of every model body.
    fn motions(&self, model: &Model, out: &mut [BodyMotion]) {
        for ((handle, body), motion) in self.handles.iter().zip(model.bodies()).zip(out) {
            let rb = &self.bodies[*handle];
            let position = rb.position();
            let rotation = matrix3(&position.rotation);
            let omega = vector3(rb.angvel());
            let com_offset = rotation * body.com;
            *motion = BodyMotion {
                rotation,
                origin: vector3(position.translation),
                omega,
                velocity: vector3(rb.linvel()) - omega.cross(&com_offset),
            };
        }
    }
}

/// Smallest principal moment of inertia given to rapier, kg m^2: rapier reads a
/// zero moment as an infinite one (no rotation about that axis), while a
/// model's point mass (zero inertia about its centre) must still swing.
const INERTIA_FLOOR: f64 = 1e-12;

/// The body's inertia about its centre of mass with every principal moment at
/// least [`INERTIA_FLOOR`].
fn rapier_inertia(inertia: &Matrix3<f64>) -> Matrix3<f64> {
    let eigen = inertia.symmetric_eigen();
    let floored = eigen.eigenvalues.map(|m| m.max(INERTIA_FLOOR));
    eigen.eigenvectors * Matrix3::from_diagonal(&floored) * eigen.eigenvectors.transpose()
}

fn body_builder(model: &Model, index: usize, motion: &BodyMotion) -> RigidBodyBuilder {
    let body = &model.bodies()[index];
    let com_offset = motion.rotation * body.com;
    RigidBodyBuilder::dynamic()
        .pose(Pose::from_parts(
            vector(&motion.origin),
            rotation(&motion.rotation),
        ))
        .linvel(vector(&(motion.velocity + motion.omega.cross(&com_offset))))
        .angvel(vector(&motion.omega))
        .additional_mass_properties(MassProperties::with_inertia_matrix(
            vector(&body.com),
            body.mass,
            matrix(&rapier_inertia(&body.inertia)),
        ))
        .linear_damping(0.0)
        .angular_damping(0.0)
        .gyroscopic_forces_enabled(true)
        .can_sleep(false)
}

/// The rapier joint of a model joint (None for floating joints: a free body).
fn joint_of(model: &Model, index: usize) -> Option<GenericJoint> {
    let joint = &model.bodies()[index].joint;
    let (axis, locked) = match joint.motion {
        JointMotion::Prismatic { axis } => (axis, JointAxesMask::LOCKED_PRISMATIC_AXES),
        JointMotion::Revolute { axis } => (axis, JointAxesMask::LOCKED_REVOLUTE_AXES),
        JointMotion::Floating => return None,
    };
    let align = align_x_with(&axis);
    let frame1 = Isometry3::from_parts(
        Translation3::from(joint.origin.translation.vector),
        UnitQuaternion::from_matrix(&joint.origin_rotation) * align,
    );
    let frame2 = Isometry3::from_parts(Translation3::identity(), align);
    Some(
        GenericJointBuilder::new(locked)
            .local_frame1(pose(&frame1))
            .local_frame2(pose(&frame2))
            .build(),
    )
}

/// The body and axis of the prismatic joint that `rapier.stop[i]` names.
fn stop_joint(
    model: &Model,
    i: usize,
    joint: &str,
) -> Result<(usize, nalgebra::Vector3<f64>), SimError> {
    let key = format!("rapier.stop[{i}].joint");
    let index = (model.bodies().iter())
        .position(|b| b.joint.name == joint)
        .ok_or_else(|| SimError::InvalidSettings(format!("{key}: no joint named \"{joint}\"")))?;
    match model.bodies()[index].joint.motion {
        JointMotion::Prismatic { axis } => Ok((index, axis)),
        _ => Err(SimError::InvalidSettings(format!(
            "{key}: \"{joint}\" is not a prismatic joint"
        ))),
    }
}

/// The body that carries the payload's link.
fn payload_body(model: &Model, link: &str) -> Result<usize, SimError> {
    (model.bodies().iter())
        .position(|b| b.name == link || b.links.iter().any(|l| l == link))
        .ok_or_else(|| {
            SimError::InvalidSettings(format!(
                "rapier.payload.link: no body or link named \"{link}\""
            ))
        })
}

/// Checks that every collider of the settings names a joint or link of the
/// model, as the engine would find out only when it builds its world.
pub fn check_colliders(model: &Model, settings: &RapierSettings) -> Result<(), SimError> {
    for (i, stop) in settings.stops.iter().enumerate() {
        stop_joint(model, i, &stop.joint)?;
    }
    if let Some(payload) = &settings.payload {
        payload_body(model, &payload.link)?;
    }
    Ok(())
}

fn stop_colliders(
    model: &Model,
    settings: &RapierSettings,
    world: &mut World,
    ground: RigidBodyHandle,
) -> Result<(), SimError> {
    for (i, stop) in settings.stops.iter().enumerate() {
        let (index, axis) = stop_joint(model, i, &stop.joint)?;
        let body = &model.bodies()[index];
        let group = Group::from_bits_truncate(1 << (i % 31));
        let groups = InteractionGroups::new(group, group, InteractionTestMode::And);
        let ball = || {
            ColliderBuilder::ball(STOP_BALL_RADIUS)
                .density(0.0)
                .friction(0.0)
                .restitution(stop.restitution)
                .restitution_combine_rule(CoefficientCombineRule::Max)
                .collision_groups(groups)
        };
        let carriage = world.handles[index];
        world
            .colliders
            .insert_with_parent(ball().build(), carriage, &mut world.bodies);
        let parent = body.parent.map_or(ground, |p| world.handles[p]);
        let direction = body.joint.origin_rotation * axis;
        let limits = [
            stop.lower.map(|q| q - 2.0 * STOP_BALL_RADIUS),
            stop.upper.map(|q| q + 2.0 * STOP_BALL_RADIUS),
        ];
        for centre in limits.into_iter().flatten() {
            let place = body.joint.origin.translation.vector + direction * centre;
            world.colliders.insert_with_parent(
                ball().translation(vector(&place)).build(),
                parent,
                &mut world.bodies,
            );
        }
    }
    Ok(())
}

fn add_payload(
    model: &Model,
    payload: &PayloadSettings,
    motions: &[BodyMotion],
    world: &mut World,
) -> Result<(), SimError> {
    let link = payload_body(model, &payload.link)?;
    let [a, b, c] = payload.size;
    let start_in_link = Vector3::from(payload.position);
    let motion = &motions[link];
    let centre = motion.origin + motion.rotation * start_in_link;
    let velocity = motion.velocity + motion.omega.cross(&(centre - motion.origin));
    let m = payload.mass;
    let inertia = Vector::new(
        m * (b * b + c * c) / 12.0,
        m * (a * a + c * c) / 12.0,
        m * (a * a + b * b) / 12.0,
    );
    let body = world.bodies.insert(
        RigidBodyBuilder::dynamic()
            .pose(Pose::from_parts(
                vector(&centre),
                rotation(&motion.rotation),
            ))
            .linvel(vector(&velocity))
            .angvel(vector(&motion.omega))
            .additional_mass_properties(MassProperties::new(Vector::ZERO, m, inertia))
            .can_sleep(false),
    );
    let group = Group::GROUP_32;
    let groups = InteractionGroups::new(group, group, InteractionTestMode::And);
    world.colliders.insert_with_parent(
        ColliderBuilder::cuboid(a / 2.0, b / 2.0, c / 2.0)
            .density(0.0)
            .friction(payload.friction)
            .collision_groups(groups)
            .build(),
        body,
        &mut world.bodies,
    );
    // A plate under the payload, fixed to the link, twice its footprint.
    let plate_centre = start_in_link - Vector3::new(0.0, 0.0, (c + SUPPORT_THICKNESS) / 2.0);
    world.colliders.insert_with_parent(
        ColliderBuilder::cuboid(a, b, SUPPORT_THICKNESS / 2.0)
            .translation(vector(&plate_centre))
            .density(0.0)
            .friction(payload.friction)
            .collision_groups(groups)
            .build(),
        world.handles[link],
        &mut world.bodies,
    );
    world.payload = Some(Payload {
        body,
        link,
        start_in_link,
    });
    Ok(())
}

fn build_world(
    model: &Model,
    x0: &[f64],
    settings: &RapierSettings,
    dt: f64,
) -> Result<World, SimError> {
    let mut ws = model.workspace();
    let motions = model.body_motions(x0, &mut ws);
    let mut parameters = IntegrationParameters {
        dt,
        // One substep: the model's forces are held over the step, and with
        // more substeps the update stops being symplectic.
        num_solver_iterations: 1,
        ..IntegrationParameters::default()
    };
    // Contacts much stiffer than rapier's game defaults (30/60 Hz), which let a
    // resting payload sink by a fraction of a millimetre.
    parameters.contact_softness = SpringCoefficients::new(300.0, 1.0);
    parameters.static_contact_softness = SpringCoefficients::new(300.0, 1.0);
    let mut world = World {
        gravity: vector(model.gravity()),
        parameters,
        pipeline: PhysicsPipeline::new(),
        islands: IslandManager::new(),
        broad_phase: BroadPhaseBvh::new(),
        narrow_phase: NarrowPhase::new(),
        bodies: RigidBodySet::new(),
        colliders: ColliderSet::new(),
        impulse_joints: ImpulseJointSet::new(),
        multibody_joints: MultibodyJointSet::new(),
        soft_bodies: SoftBodySet::new(),
        ccd: CCDSolver::new(),
        handles: Vec::with_capacity(model.bodies().len()),
        joints: Vec::new(),
        payload: None,
    };
    let ground = world.bodies.insert(RigidBodyBuilder::fixed());
    let grounded = grounded_bodies(model);
    for (index, motion) in motions.iter().enumerate() {
        if model.bodies()[index].mass.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(SimError::InvalidSettings(format!(
                "body \"{}\" has no mass; rapier needs a positive mass for every body",
                model.bodies()[index].name
            )));
        }
        let handle = world.bodies.insert(body_builder(model, index, motion));
        world.handles.push(handle);
        if let Some(joint) = joint_of(model, index) {
            let parent = model.bodies()[index]
                .parent
                .map_or(ground, |p| world.handles[p]);
            if grounded[index] {
                let joint_handle = world
                    .multibody_joints
                    .insert(parent, handle, joint, true)
                    .ok_or_else(|| {
                        SimError::InvalidSettings(format!(
                            "joint \"{}\" would close a loop in rapier's multibody",
                            model.bodies()[index].joint.name
                        ))
                    })?;
                world.joints.push((index, joint_handle));
            } else {
                // Below a floating body: an impulse joint between two bodies
                // that keep the poses and velocities they were built with.
                world.impulse_joints.insert(parent, handle, joint, true);
            }
        }
    }
    stop_colliders(model, settings, &mut world, ground)?;
    if let Some(payload) = &settings.payload {
        add_payload(model, payload, &motions, &mut world)?;
    }
    // A step of zero length settles mass properties and multibody layouts;
    // then remove the damping rapier gives free multibody roots.
    let dt = world.parameters.dt;
    world.parameters.dt = 0.0;
    world.step();
    world.parameters.dt = dt;
    for (_, handle) in &world.joints {
        if let Some((multibody, _)) = world.multibody_joints.get_mut(*handle) {
            multibody.damping_mut().fill(0.0);
        }
    }
    set_joint_coordinates(model, x0, &mut world);
    Ok(world)
}

/// Bodies joined to the world by a chain without floating joints: their
/// joints become reduced-coordinate multibody joints rooted at the fixed
/// ground. Joints below a floating body become impulse joints (a multibody
/// with a free root would restart that root's motion from rest).
fn grounded_bodies(model: &Model) -> Vec<bool> {
    let mut grounded = vec![false; model.bodies().len()];
    for (index, body) in model.bodies().iter().enumerate() {
        let free = matches!(body.joint.motion, JointMotion::Floating);
        grounded[index] = !free && body.parent.is_none_or(|p| grounded[p]);
    }
    grounded
}

/// Puts rapier's multibody joints at the model's joint positions and rates:
/// a multibody places its links from its own coordinates (zero when a joint
/// is inserted), not from the poses the bodies were built with.
fn set_joint_coordinates(model: &Model, x0: &[f64], world: &mut World) {
    let nq = model.layout().nq;
    let mut touched = Vec::new();
    for &(index, handle) in &world.joints {
        let joint = &model.bodies()[index].joint;
        let Some((multibody, link_id)) = world.multibody_joints.get_mut(handle) else {
            continue;
        };
        let Some(link) = multibody.link(link_id) else {
            continue;
        };
        let slot = link.assembly_id();
        let mut displacement = vec![0.0; multibody.ndofs()];
        if slot >= displacement.len() {
            continue;
        }
        displacement[slot] = x0[joint.q_offset];
        multibody.apply_displacements(&displacement);
        multibody.generalized_velocity_mut()[slot] = x0[nq + joint.v_offset];
        touched.push(handle);
    }
    for handle in touched {
        if let Some((multibody, _)) = world.multibody_joints.get_mut(handle) {
            multibody.forward_kinematics(&world.bodies, true);
            multibody.update_rigid_bodies(&mut world.bodies, true);
        }
    }
}

/// Largest |eigenvalue| of the linearised model at (x, u); where the
/// eigenvalues cannot be computed, the largest absolute row sum, which bounds
/// it from above (a smaller step, never a larger one).
pub fn fastest_rate(model: &Model, x: &[f64], inputs: &Inputs) -> f64 {
    let (reduced, _) = model.tangent_jacobian(x, inputs);
    spectral_radius(&reduced).unwrap_or_else(|| {
        reduced
            .row_iter()
            .map(|row| row.iter().map(|v| v.abs()).sum::<f64>())
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
    })
}

/// Slip speed assumed for the bristle stiffness bound when the inputs at the
/// start name no faster one, m/s.
const BRISTLE_SPEED_FLOOR: f64 = 0.01;

/// Largest bristle rate sigma0 |v| / f_C any contact can reach at the slip
/// speed the inputs suggest (the linearisation at rest, where |v| = 0, does
/// not see it).
fn bristle_rate_bound(model: &Model, inputs: &Inputs) -> f64 {
    let speed = inputs
        .platform_velocity
        .abs()
        .max(inputs.reference.velocity.abs())
        .max(BRISTLE_SPEED_FLOOR);
    model
        .frictions()
        .iter()
        .map(|f| f.lugre.sigma0 * speed / f.lugre.f_c)
        .fold(0.0, f64::max)
}

/// The fixed step for a run: `settings.dt`, or a fraction of 2 / |lambda|max
/// (the fastest mode at the start, or the bristle bound if faster),
/// shortened so that a whole number of steps fits each output interval.
pub fn rapier_step(
    model: &Model,
    x0: &[f64],
    inputs: &Inputs,
    rapier: &RapierSettings,
    sample_interval: f64,
) -> (f64, usize) {
    let wanted = rapier.dt.unwrap_or_else(|| {
        let fraction = rapier.step_fraction.unwrap_or(DEFAULT_STEP_FRACTION);
        let rate = fastest_rate(model, x0, inputs).max(bristle_rate_bound(model, inputs));
        if rate > 0.0 {
            fraction * 2.0 / rate
        } else {
            sample_interval
        }
    });
    let per_sample = (sample_interval / wanted).ceil().max(1.0);
    (sample_interval / per_sample, per_sample as usize)
}

/// rapier3d-f64 with the model's force elements.
#[derive(Debug, Clone, Default)]
pub struct RapierEngine {
    /// The scenario's `[rapier]` table.
    pub settings: RapierSettings,
}

impl RapierEngine {
    /// One step of length h from the current state x: the model's element
    /// wrenches as rapier forces, explicit Euler for the bristle and
    /// integrator states, then rapier's step.
    #[allow(clippy::too_many_arguments)]
    fn advance(
        &self,
        model: &Model,
        world: &mut World,
        x: &mut [f64],
        ws: &mut fistage_model::Workspace,
        wrenches: &mut [BodyWrench],
        inputs: &Inputs,
        motions: &mut [BodyMotion],
        h: f64,
    ) {
        world.motions(model, motions);
        model.set_joint_state(motions, x);
        model.element_wrenches(x, inputs, ws, wrenches);
        for (handle, wrench) in world.handles.iter().zip(wrenches.iter()) {
            let rb = &mut world.bodies[*handle];
            let com = vector3(rb.center_of_mass());
            rb.reset_forces(false);
            rb.reset_torques(false);
            rb.add_force(vector(&wrench.force), true);
            rb.add_torque(vector(&wrench.moment_about(&com)), true);
        }
        for (index, rate) in model.internal_rates(ws) {
            x[index] += h * rate;
        }
        world.step();
    }
}

impl Engine for RapierEngine {
    fn kind(&self) -> fistage_model::EngineKind {
        fistage_model::EngineKind::Rapier
    }

    fn simulate(
        &self,
        model: &Model,
        x0: &[f64],
        excitation: &dyn Excitation,
        settings: &SimSettings,
        progress: &mut crate::engine::Progress<'_>,
    ) -> Result<Trajectory, SimError> {
        crate::settings::check_settings(model, x0, settings)?;
        let started = Instant::now();
        let (dt, per_sample) = rapier_step(
            model,
            x0,
            &excitation.inputs(0.0),
            &self.settings,
            settings.sample_interval,
        );
        let times = sample_times(settings.t_end, settings.sample_interval);
        let needed = (settings.t_end / dt).ceil().max(1.0);
        if needed.is_nan() || needed > settings.max_steps as f64 {
            return Err(SimError::FixedStepBudget {
                dt,
                steps: needed,
                max_steps: settings.max_steps,
            });
        }
        let mut world = build_world(model, x0, &self.settings, dt)?;
        let n = model.n_states();
        let mut trajectory = Trajectory::with_capacity(n, times.len());
        let mut payload_signals = world.payload.as_ref().map(|_| {
            [
                "payload.x",
                "payload.y",
                "payload.z",
                "payload.slip",
                "payload.sink",
            ]
            .map(|name| ExtraSignal {
                name: name.into(),
                unit: "m",
                values: Vec::with_capacity(times.len()),
            })
        });
        let mut ws = model.workspace();
        let mut x = x0.to_vec();
        let mut motions = vec![BodyMotion::identity(); model.bodies().len()];
        let mut wrenches = vec![
            BodyWrench {
                force: Vector3::zeros(),
                moment: Vector3::zeros(),
            };
            model.bodies().len()
        ];
        let mut counts = StepCounts::default();
        for (k, &t_sample) in times.iter().enumerate() {
            if k > 0 {
                // Whole steps of dt between grid samples; a final sample off
                // the grid (t_end) gets equal shorter steps.
                let start = times[k - 1];
                let span = t_sample - start;
                let steps = ((span / dt) * (1.0 - 1e-12)).ceil().max(1.0) as usize;
                let h = if steps == per_sample {
                    dt
                } else {
                    span / steps as f64
                };
                world.parameters.dt = h;
                for j in 0..steps {
                    let t = start + j as f64 * h;
                    self.advance(
                        model,
                        &mut world,
                        &mut x,
                        &mut ws,
                        &mut wrenches,
                        &excitation.inputs(t),
                        &mut motions,
                        h,
                    );
                    counts.steps += 1;
                    counts.rhs_evaluations += 1;
                }
                if k % 256 == 0 && progress(t_sample / settings.t_end).is_break() {
                    return Err(SimError::Cancelled { t: t_sample });
                }
            }
            world.motions(model, &mut motions);
            model.set_joint_state(&motions, &mut x);
            if let Some(i) = x.iter().position(|v| !v.is_finite()) {
                return Err(SimError::NonFinite {
                    t: t_sample,
                    dt,
                    state: model.layout().names[i].clone(),
                });
            }
            trajectory.push(t_sample, &x);
            if let (Some(signals), Some(payload)) = (&mut payload_signals, &world.payload) {
                record_payload(&world, payload, &motions, signals);
            }
        }
        let _ = progress(1.0);
        if let Some(signals) = payload_signals {
            trajectory.extra = signals.into();
        }
        trajectory.stats = SolverStats {
            engine: format!("rapier (dt = {dt:.3e} s)"),
            counts,
            wall_time_s: started.elapsed().as_secs_f64(),
        };
        Ok(trajectory)
    }
}

fn record_payload(
    world: &World,
    payload: &Payload,
    motions: &[BodyMotion],
    signals: &mut [ExtraSignal; 5],
) {
    let rb = &world.bodies[payload.body];
    let centre = vector3(rb.center_of_mass());
    let link = &motions[payload.link];
    let in_link = link.rotation.transpose() * (centre - link.origin);
    let moved = in_link - payload.start_in_link;
    let values = [centre.x, centre.y, centre.z, moved.xy().norm(), -moved.z];
    for (signal, value) in signals.iter_mut().zip(values) {
        signal.values.push(value);
    }
}
