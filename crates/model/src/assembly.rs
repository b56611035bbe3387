//! Turns a robot file and a scenario into a [`Model`]: applies the scenario's
//! overrides, walks the link tree from `world`, merges links welded by fixed
//! joints into one body (combining inertia about the merged frame), numbers the
//! state, resolves every element to a body, and checks the mass matrix.

use std::collections::HashMap;
use std::path::Path;

use nalgebra::{Isometry3, Matrix3, Vector3};

use crate::compensation::{CompensationSettings, IsolatorTreatment};
use crate::dynamics;
use crate::elements::{
    Body, Controller, Frame, FrictionContact, Isolator, Joint, JointMotion, MassBlock, PointAxis,
    SignalInfo, StateKind, StateLayout, Structure,
};
use crate::elements::{Feedforward, Observer, VirtualBearing, Visual};
use crate::error::LoadError;
use crate::evaluator::Evaluator;
use crate::model::Model;
use crate::parameter;
use crate::robot::{JointKind, PointAxisSpec, RobotSpec};
use crate::scenario::Scenario;

/// Name of the root link.
pub const WORLD: &str = "world";

/// A loaded study: the scenario and the model it describes.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The checked scenario.
    pub scenario: Scenario,
    /// The robot file after the scenario's overrides.
    pub robot: RobotSpec,
    /// The assembled model.
    pub model: Model,
}

/// Reads a scenario, its robot file, and assembles the model.
pub fn load(scenario_path: &Path) -> Result<Loaded, LoadError> {
    let scenario = Scenario::from_file(scenario_path)?;
    let robot = RobotSpec::from_file(&scenario.robot)?;
    let (robot, model) = assemble(robot, &scenario)?;
    Ok(Loaded {
        scenario,
        robot,
        model,
    })
}

/// Applies the scenario's overrides to the robot and assembles the model.
pub fn assemble(
    mut robot: RobotSpec,
    scenario: &Scenario,
) -> Result<(RobotSpec, Model), LoadError> {
    apply_overrides(&mut robot, scenario)?;
    let model = Assembler::new(&robot, scenario)?.build()?;
    Ok((robot, model))
}

/// Applies `[overrides.<name>]` tables to friction, isolator, actuator, sensor
/// elements and links through the parameter table. Link `mass` scales the
/// link's inertia with it (uniform density).
pub fn apply_overrides(robot: &mut RobotSpec, scenario: &Scenario) -> Result<(), LoadError> {
    for o in &scenario.overrides {
        parameter::apply_override(scenario, robot, &o.target, &o.key, o.value)?;
    }
    // Check each friction element once all its overrides are in (f_c may rise
    // above the file's f_s as long as f_s rises too).
    for friction in &robot.frictions {
        if let Err(e) = friction.lugre.validate() {
            let key = scenario
                .overrides
                .iter()
                .rev()
                .find(|o| o.target == friction.name && o.key == e.name)
                .or_else(|| {
                    scenario
                        .overrides
                        .iter()
                        .find(|o| o.target == friction.name)
                })
                .map(|o| format!("overrides.{}.{}", o.target, o.key))
                .unwrap_or_else(|| format!("overrides.{}", friction.name));
            return Err(scenario.error(key, e.to_string()));
        }
    }
    Ok(())
}

/// Where a link ended up: which body, and the link frame in the body frame.
#[derive(Debug, Clone, Copy)]
struct Placement {
    frame: Frame,
    link_in_body: Isometry3<f64>,
}

struct Assembler<'a> {
    robot: &'a RobotSpec,
    scenario: &'a Scenario,
    placements: HashMap<&'a str, Placement>,
    bodies: Vec<Body>,
    names: Vec<String>,
    kinds: Vec<StateKind>,
    nominal: Vec<f64>,
    /// What a reader should know about a legal but odd study.
    notes: Vec<String>,
}

impl<'a> Assembler<'a> {
    fn new(robot: &'a RobotSpec, scenario: &'a Scenario) -> Result<Self, LoadError> {
        let mut assembler = Self {
            robot,
            scenario,
            placements: HashMap::new(),
            bodies: Vec::new(),
            names: Vec::new(),
            kinds: Vec::new(),
            nominal: Vec::new(),
            notes: Vec::new(),
        };
        assembler.walk_tree()?;
        Ok(assembler)
    }

    fn robot_error(&self, element: impl Into<String>, message: impl Into<String>) -> LoadError {
        LoadError::robot(&self.robot.file, element, message)
    }

    /// Depth-first walk from `world`, merging fixed joints and creating bodies.
    fn walk_tree(&mut self) -> Result<(), LoadError> {
        let robot = self.robot;
        if !robot.links.iter().any(|l| l.name == WORLD) {
            return Err(self.robot_error(
                format!("robot \"{}\"", robot.name),
                "has no link named \"world\"; the tree must be rooted at a link \"world\"",
            ));
        }
        let mut parent_joint: HashMap<&str, usize> = HashMap::new();
        for (index, joint) in robot.joints.iter().enumerate() {
            for (role, link) in [("parent", &joint.parent), ("child", &joint.child)] {
                if !robot.links.iter().any(|l| &l.name == link) {
                    return Err(self.robot_error(
                        format!("joint \"{}\"", joint.name),
                        format!("{role} link \"{link}\" does not exist"),
                    ));
                }
            }
            if joint.child == WORLD {
                return Err(self.robot_error(
                    format!("joint \"{}\"", joint.name),
                    "\"world\" cannot be a child link",
                ));
            }
            if let Some(other) = parent_joint.insert(joint.child.as_str(), index) {
                return Err(self.robot_error(
                    format!("link \"{}\"", joint.child),
                    format!(
                        "is the child of two joints, \"{}\" and \"{}\" (the links must form a tree)",
                        robot.joints[other].name, joint.name
                    ),
                ));
            }
        }
        self.placements.insert(
            WORLD,
            Placement {
                frame: Frame::World,
                link_in_body: Isometry3::identity(),
            },
        );
        let mut stack = vec![WORLD];
        let (mut q_offset, mut v_offset) = (0, 0);
        while let Some(link) = stack.pop() {
            let placement = self.placements[link];
            // Children get their bodies in file order; the stack then visits them in
            // that order too.
            let children: Vec<_> = robot.joints.iter().filter(|j| j.parent == link).collect();
            for joint in &children {
                let origin_in_body = placement.link_in_body * joint.origin;
                let child_placement = match joint.kind {
                    JointKind::Fixed => Placement {
                        frame: placement.frame,
                        link_in_body: origin_in_body,
                    },
                    kind => {
                        let motion = match kind {
                            JointKind::Prismatic => JointMotion::Prismatic { axis: joint.axis },
                            JointKind::Revolute => JointMotion::Revolute { axis: joint.axis },
                            _ => JointMotion::Floating,
                        };
                        let parent = match placement.frame {
                            Frame::World => None,
                            Frame::Body(b) => Some(b),
                        };
                        let mut chain = parent
                            .map(|p| self.bodies[p].chain.clone())
                            .unwrap_or_default();
                        chain.extend(v_offset..v_offset + motion.nv());
                        self.bodies.push(Body {
                            name: joint.child.clone(),
                            links: Vec::new(),
                            parent,
                            joint: Joint {
                                name: joint.name.clone(),
                                motion,
                                origin: origin_in_body,
                                origin_rotation: *origin_in_body
                                    .rotation
                                    .to_rotation_matrix()
                                    .matrix(),
                                q_offset,
                                v_offset,
                            },
                            mass: 0.0,
                            com: Vector3::zeros(),
                            inertia: Matrix3::zeros(),
                            chain,
                            block: 0,
                            chain_local: Vec::new(),
                            turns: motion.rotates() || parent.is_some_and(|p| self.bodies[p].turns),
                        });
                        q_offset += motion.nq();
                        v_offset += motion.nv();
                        Placement {
                            frame: Frame::Body(self.bodies.len() - 1),
                            link_in_body: Isometry3::identity(),
                        }
                    }
                };
                self.placements
                    .insert(joint.child.as_str(), child_placement);
                stack.push(joint.child.as_str());
            }
        }
        if let Some(orphan) = robot
            .links
            .iter()
            .find(|l| !self.placements.contains_key(l.name.as_str()))
        {
            return Err(self.robot_error(
                format!("link \"{}\"", orphan.name),
                "is not connected to \"world\" through joints (or sits on a joint cycle)",
            ));
        }
        Ok(())
    }

    /// Sums the inertia of every link placed on each body.
    fn merge_inertia(&mut self) -> Result<(), LoadError> {
        struct Part {
            mass: f64,
            com: Vector3<f64>,
            inertia: Matrix3<f64>,
        }
        let mut parts: Vec<Vec<Part>> = (0..self.bodies.len()).map(|_| Vec::new()).collect();
        for link in &self.robot.links {
            let placement = self.placements[link.name.as_str()];
            let Frame::Body(body) = placement.frame else {
                continue;
            };
            self.bodies[body].links.push(link.name.clone());
            if link.mass == 0.0 {
                continue;
            }
            let frame = placement.link_in_body * link.inertial_origin;
            let rotation = frame.rotation.to_rotation_matrix();
            parts[body].push(Part {
                mass: link.mass,
                com: frame.translation.vector,
                inertia: rotation.matrix() * link.inertia * rotation.matrix().transpose(),
            });
        }
        for (body, parts) in self.bodies.iter_mut().zip(parts) {
            // Keep the body's own link first in the list.
            if let Some(own) = body.links.iter().position(|l| *l == body.name) {
                body.links.swap(0, own);
            }
            let mass: f64 = parts.iter().map(|p| p.mass).sum();
            if mass <= 0.0 {
                return Err(LoadError::robot(
                    &self.robot.file,
                    format!("link \"{}\"", body.name),
                    format!(
                        "moves on joint \"{}\" but has no mass (give it an <inertial> with mass > 0)",
                        body.joint.name
                    ),
                ));
            }
            let com = parts.iter().map(|p| p.com * p.mass).sum::<Vector3<f64>>() / mass;
            let inertia = parts
                .iter()
                .map(|p| {
                    let d = p.com - com;
                    p.inertia
                        + p.mass * (Matrix3::identity() * d.norm_squared() - d * d.transpose())
                })
                .sum();
            body.mass = mass;
            body.com = com;
            body.inertia = inertia;
        }
        Ok(())
    }

    fn push_state(&mut self, name: String, kind: StateKind, nominal: f64) {
        self.names.push(name);
        self.kinds.push(kind);
        self.nominal.push(nominal);
    }

    /// Positions then velocities, body by body.
    fn number_joint_states(&mut self) {
        const LENGTH: f64 = 1e-3;
        const SPEED: f64 = 1e-2;
        const ANGLE: f64 = 1e-3;
        const RATE: f64 = 1e-2;
        let joints: Vec<(String, JointMotion)> = self
            .bodies
            .iter()
            .map(|b| (b.joint.name.clone(), b.joint.motion))
            .collect();
        for (name, motion) in &joints {
            match motion {
                JointMotion::Prismatic { .. } => {
                    self.push_state(format!("{name}.q"), StateKind::Translation, LENGTH)
                }
                JointMotion::Revolute { .. } => {
                    self.push_state(format!("{name}.q"), StateKind::Angle, ANGLE)
                }
                JointMotion::Floating => {
                    for axis in ["x", "y", "z"] {
                        self.push_state(format!("{name}.{axis}"), StateKind::Translation, LENGTH);
                    }
                    for part in ["qw", "qx", "qy", "qz"] {
                        self.push_state(format!("{name}.{part}"), StateKind::Quaternion, ANGLE);
                    }
                }
            }
        }
        for (name, motion) in &joints {
            match motion {
                JointMotion::Prismatic { .. } => {
                    self.push_state(format!("{name}.v"), StateKind::LinearVelocity, SPEED)
                }
                JointMotion::Revolute { .. } => {
                    self.push_state(format!("{name}.v"), StateKind::AngularVelocity, RATE)
                }
                JointMotion::Floating => {
                    for axis in ["vx", "vy", "vz"] {
                        self.push_state(format!("{name}.{axis}"), StateKind::LinearVelocity, SPEED);
                    }
                    for axis in ["wx", "wy", "wz"] {
                        self.push_state(format!("{name}.{axis}"), StateKind::AngularVelocity, RATE);
                    }
                }
            }
        }
    }

    fn resolve_link(&self, link: &str, element: &str) -> Result<Placement, LoadError> {
        self.placements
            .get(link)
            .copied()
            .ok_or_else(|| self.robot_error(element, format!("link \"{link}\" does not exist")))
    }

    /// The fixed joints between `link` and the world, child to parent.
    fn welds(&self, link: &str) -> Vec<String> {
        let mut names = Vec::new();
        let mut at = link;
        while let Some(joint) = self.robot.joints.iter().find(|j| j.child == at) {
            names.push(format!("\"{}\"", joint.name));
            at = &joint.parent;
            if names.len() > self.robot.joints.len() {
                break;
            }
        }
        names
    }

    /// A point/axis element on a moving body.
    fn moving_point_axis(&self, spec: &PointAxisSpec, kind: &str) -> Result<PointAxis, LoadError> {
        let element = format!("{kind} \"{}\"", spec.name);
        let placement = self.resolve_link(&spec.link, &element)?;
        let Frame::Body(body) = placement.frame else {
            return Err(self.robot_error(
                element,
                format!(
                    "link \"{}\" is welded to the world (by fixed joints {}) and cannot move",
                    spec.link,
                    self.welds(&spec.link).join(", ")
                ),
            ));
        };
        let point = placement.link_in_body * nalgebra::Point3::from(spec.point);
        let axis_in_body = placement.link_in_body.rotation * spec.axis;
        let world = body_pose_at_zero(&self.bodies, body);
        let axis = world.rotation * axis_in_body;
        let zero_offset = (world * point).coords.dot(&axis);
        Ok(PointAxis {
            name: spec.name.clone(),
            body,
            point: point.coords,
            axis,
            zero_offset,
        })
    }

    /// A feedforward compensator of `[compensation]`: its model, the
    /// treatment of the isolator that carries the modelled element (dynamic
    /// unless `isolator` says otherwise), and its states (named
    /// `compensation.<element>.*` when the servo has `several`).
    fn feedforward(
        &mut self,
        settings: &CompensationSettings,
        several: bool,
        robot: &RobotSpec,
        scenario: &Scenario,
        frictions: &[FrictionContact],
        isolators: &[Isolator],
    ) -> Result<Feedforward, LoadError> {
        let (mut model, notes) = settings.bearing_model(robot, &scenario.file)?;
        self.notes.extend(notes);
        let contact =
            (settings.element.as_ref()).and_then(|name| frictions.iter().find(|f| &f.name == name));
        let carried = contact.and_then(|contact| {
            let (k, c) = self.isolator_along(contact, isolators)?;
            Some((contact, k, c))
        });
        let treatment = settings.isolator.unwrap_or(IsolatorTreatment::Dynamic);
        let mut bearing = None;
        match (treatment, carried) {
            (IsolatorTreatment::Ignore, _) => {}
            (_, None) if settings.isolator.is_some() => {
                return Err(scenario.error(
                    "compensation.isolator",
                    match &settings.element {
                        Some(name) => format!(
                            "no isolator with stiffness along its sliding axis carries \"{name}\" in {}",
                            robot.file.display()
                        ),
                        None => "needs compensation.element: the friction element whose isolator it is".into(),
                    },
                ));
            }
            (_, None) => {}
            (IsolatorTreatment::Static, Some((_, k_j, c_j))) => {
                model = model.felt_through(k_j, c_j)
            }
            (IsolatorTreatment::Dynamic, Some((contact, k_j, c_j))) => {
                bearing = Some(VirtualBearing {
                    mass: self.bodies[contact.body].mass,
                    stiffness: k_j,
                    damping: c_j,
                });
            }
        }
        let state_index = self.names.len();
        let prefix = match (&settings.element, several) {
            (Some(element), true) => format!("compensation.{element}"),
            _ => "compensation".to_string(),
        };
        if bearing.is_some() {
            self.push_state(
                format!("{prefix}.deflection"),
                StateKind::CompensatorDeflection,
                1e-4,
            );
            self.push_state(
                format!("{prefix}.bearing_velocity"),
                StateKind::CompensatorVelocity,
                1e-2,
            );
        }
        let (kind, suffix, nominal) = model.state();
        self.push_state(format!("{prefix}.{suffix}"), kind, nominal);
        Ok(Feedforward {
            element: settings.element.clone(),
            model,
            bearing,
            state_index,
        })
    }

    /// The stiffness and damping along a contact's sliding axis of the
    /// isolators that join its body to another (summed: isolators on one
    /// body act in parallel); `None` when none has stiffness along it.
    fn isolator_along(
        &self,
        contact: &FrictionContact,
        isolators: &[Isolator],
    ) -> Option<(f64, f64)> {
        let body = Frame::Body(contact.body);
        let (mut k, mut c) = (0.0, 0.0);
        for isolator in isolators
            .iter()
            .filter(|i| i.parent == body || i.child == body)
        {
            let attach = frame_pose_at_zero(&self.bodies, isolator.parent) * isolator.parent_attach;
            let axis = attach.rotation.inverse() * contact.axis;
            for j in 0..3 {
                k += isolator.stiffness[j] * axis[j] * axis[j];
                c += isolator.damping[j] * axis[j] * axis[j];
            }
        }
        (k > 0.0).then_some((k, c))
    }

    fn build(mut self) -> Result<Model, LoadError> {
        self.merge_inertia()?;
        self.number_joint_states();
        let robot = self.robot;
        let scenario = self.scenario;
        let (nq, nv) = self.bodies.iter().fold((0, 0), |(q, v), b| {
            (q + b.joint.motion.nq(), v + b.joint.motion.nv())
        });

        let visuals = self.visuals();
        let mut frictions = Vec::new();
        for spec in &robot.frictions {
            let as_point = PointAxisSpec {
                name: spec.name.clone(),
                link: spec.link.clone(),
                point: spec.point,
                axis: spec.axis,
            };
            let resolved = self.moving_point_axis(&as_point, "friction")?;
            let z_index = self.names.len();
            self.push_state(
                format!("{}.z", spec.name),
                StateKind::Bristle,
                spec.lugre.f_s / spec.lugre.sigma0,
            );
            frictions.push(FrictionContact {
                name: spec.name.clone(),
                body: resolved.body,
                point: resolved.point,
                axis: resolved.axis,
                lugre: spec.lugre,
                z_index,
                zero_offset: resolved.zero_offset,
            });
        }
        let nz = frictions.len();

        let mut isolators = Vec::new();
        for spec in &robot.isolators {
            let element = format!("isolator \"{}\"", spec.name);
            let parent = self.resolve_link(&spec.parent, &element)?;
            let child = self.resolve_link(&spec.child, &element)?;
            if parent.frame == child.frame {
                return Err(self.robot_error(
                    element,
                    format!(
                        "links \"{}\" and \"{}\" belong to the same rigid body; the isolator would do nothing",
                        spec.parent, spec.child
                    ),
                ));
            }
            let parent_attach = parent.link_in_body * spec.origin;
            // The child attach frame coincides with the parent's at the zero configuration.
            let attach_world = frame_pose_at_zero(&self.bodies, parent.frame) * parent_attach;
            let child_attach =
                frame_pose_at_zero(&self.bodies, child.frame).inverse() * attach_world;
            isolators.push(Isolator {
                name: spec.name.clone(),
                parent: parent.frame,
                child: child.frame,
                parent_attach,
                child_attach,
                stiffness: spec.stiffness,
                damping: spec.damping,
                attach_rotations: [
                    *parent_attach.rotation.to_rotation_matrix().matrix(),
                    *child_attach.rotation.to_rotation_matrix().matrix(),
                ],
                attach_is_identity: [
                    parent_attach.rotation.angle() == 0.0,
                    child_attach.rotation.angle() == 0.0,
                ],
            });
        }

        let actuators = robot
            .actuators
            .iter()
            .map(|a| self.moving_point_axis(a, "actuator"))
            .collect::<Result<Vec<_>, _>>()?;
        let sensors = robot
            .sensors
            .iter()
            .map(|s| self.moving_point_axis(s, "sensor"))
            .collect::<Result<Vec<_>, _>>()?;

        let controller = match &scenario.controller {
            None => None,
            Some(settings) => {
                let find = |list: &[PointAxis], name: &str, key: &str, kind: &str| {
                    list.iter().position(|e| e.name == name).ok_or_else(|| {
                        scenario.error(
                            key,
                            format!(
                                "no {kind} named \"{name}\" in {} (have: {})",
                                robot.file.display(),
                                list.iter()
                                    .map(|e| e.name.as_str())
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                        )
                    })
                };
                let sensor = find(&sensors, &settings.sensor, "controller.sensor", "sensor")?;
                let actuator = find(
                    &actuators,
                    &settings.actuator,
                    "controller.actuator",
                    "actuator",
                )?;
                let (s, a) = (&sensors[sensor], &actuators[actuator]);
                let gains = settings.k > 0.0 || settings.c > 0.0 || settings.k_i > 0.0;
                if gains && s.body == a.body && s.axis.dot(&a.axis) < 0.0 {
                    return Err(scenario.error(
                        "controller",
                        format!(
                            "sensor \"{}\" and actuator \"{}\" act along opposite directions on the same body, so the servo would push away from its reference (positive feedback): flip one axis in {}",
                            s.name,
                            a.name,
                            robot.file.display()
                        ),
                    ));
                }
                let integral_index = (settings.k_i > 0.0).then(|| {
                    let index = self.names.len();
                    self.push_state("controller.integral".into(), StateKind::ErrorIntegral, 1e-4);
                    index
                });
                let several = scenario.compensation.len() > 1;
                let feedforward = (scenario.compensation.iter())
                    .map(|compensation| {
                        self.feedforward(
                            compensation,
                            several,
                            robot,
                            scenario,
                            &frictions,
                            &isolators,
                        )
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                let observer = scenario.observer.map(|settings| {
                    let state_index = self.names.len();
                    self.push_state("dob.state".into(), StateKind::ObserverState, 1.0);
                    Observer {
                        nominal_mass: settings.nominal_mass,
                        cutoff: 2.0 * std::f64::consts::PI * settings.bandwidth,
                        state_index,
                    }
                });
                Some(Controller {
                    sensor,
                    actuator,
                    k: settings.k,
                    c: settings.c,
                    k_i: settings.k_i,
                    integral_index,
                    feedforward,
                    observer,
                })
            }
        };

        let layout = StateLayout {
            names: self.names,
            kinds: self.kinds,
            nominal: self.nominal,
            nq,
            nv,
            nz,
        };
        let mut structure = Structure {
            bodies: self.bodies,
            isolators,
            frictions,
            actuators,
            sensors,
            controller,
            gravity: Vector3::from(scenario.gravity),
            signals: Vec::new(),
            layout,
            mass_blocks: Vec::new(),
        };
        structure.signals = signal_list(&structure);
        let evaluator = check_mass_matrix(&mut structure, &robot.file)?;
        Ok(Model {
            name: robot.name.clone(),
            structure,
            evaluator,
            robot: robot.clone(),
            machine_code: Default::default(),
            notes: std::mem::take(&mut self.notes),
            compensation: scenario.compensation.clone(),
            observer: scenario.observer,
            visuals,
        })
    }

    /// Every link's visuals on the body the link merged into.
    fn visuals(&self) -> Vec<Visual> {
        let mut visuals = Vec::new();
        for link in &self.robot.links {
            let Some(placement) = self.placements.get(link.name.as_str()) else {
                continue;
            };
            visuals.extend(link.visuals.iter().map(|visual| Visual {
                link: link.name.clone(),
                frame: placement.frame,
                origin: placement.link_in_body * visual.origin,
                shape: visual.shape,
            }));
        }
        visuals
    }
}

/// World pose of a body in the zero configuration.
fn body_pose_at_zero(bodies: &[Body], body: usize) -> Isometry3<f64> {
    let own = bodies[body].joint.origin;
    match bodies[body].parent {
        Some(parent) => body_pose_at_zero(bodies, parent) * own,
        None => own,
    }
}

fn frame_pose_at_zero(bodies: &[Body], frame: Frame) -> Isometry3<f64> {
    match frame {
        Frame::World => Isometry3::identity(),
        Frame::Body(b) => body_pose_at_zero(bodies, b),
    }
}

/// Every output signal the model can write, in a fixed order.
fn signal_list(model: &Structure) -> Vec<SignalInfo> {
    let mut signals = Vec::new();
    let mut push = |name: String, unit: &'static str| signals.push(SignalInfo { name, unit });
    for sensor in &model.sensors {
        push(format!("{}.position", sensor.name), "m");
        push(format!("{}.velocity", sensor.name), "m/s");
    }
    if let Some(controller) = &model.controller {
        push("controller.reference".into(), "m");
        push("controller.error".into(), "m");
        if !controller.feedforward.is_empty() {
            push("compensation.force".into(), "N");
        }
        if controller.feedforward.len() > 1 {
            for feedforward in &controller.feedforward {
                let element = feedforward.element.as_deref().unwrap_or("model");
                push(format!("compensation.{element}.force"), "N");
            }
        }
        if controller.observer.is_some() {
            push("dob.estimate".into(), "N");
        }
    }
    for actuator in &model.actuators {
        push(format!("{}.force", actuator.name), "N");
    }
    for body in &model.bodies {
        let name = &body.joint.name;
        match body.joint.motion {
            JointMotion::Prismatic { .. } => {
                push(format!("{name}.q"), "m");
                push(format!("{name}.v"), "m/s");
            }
            JointMotion::Revolute { .. } => {
                push(format!("{name}.q"), "rad");
                push(format!("{name}.v"), "rad/s");
            }
            JointMotion::Floating => {
                for axis in ["x", "y", "z"] {
                    push(format!("{name}.{axis}"), "m");
                }
                for angle in ["roll", "pitch", "yaw"] {
                    push(format!("{name}.{angle}"), "rad");
                }
                for axis in ["vx", "vy", "vz"] {
                    push(format!("{name}.{axis}"), "m/s");
                }
                for axis in ["wx", "wy", "wz"] {
                    push(format!("{name}.{axis}"), "rad/s");
                }
            }
        }
    }
    for friction in &model.frictions {
        push(format!("{}.force", friction.name), "N");
        push(format!("{}.slip_velocity", friction.name), "m/s");
        push(format!("{}.z", friction.name), "m");
    }
    for isolator in &model.isolators {
        for axis in ["dx", "dy", "dz"] {
            push(format!("{}.{axis}", isolator.name), "m");
        }
        for axis in ["rx", "ry", "rz"] {
            push(format!("{}.{axis}", isolator.name), "rad");
        }
    }
    signals
}

/// Groups bodies by the subtree they hang in, numbers each block's dofs, and
/// inverts the blocks that never change.
fn mass_blocks(model: &mut Structure, mass: &nalgebra::DMatrix<f64>) -> Vec<MassBlock> {
    let mut blocks: Vec<MassBlock> = Vec::new();
    for index in 0..model.bodies.len() {
        let block = match model.bodies[index].parent {
            None => {
                blocks.push(MassBlock {
                    dofs: Vec::new(),
                    bodies: Vec::new(),
                    constant_inverse: None,
                    free_body: None,
                });
                blocks.len() - 1
            }
            Some(parent) => model.bodies[parent].block,
        };
        let body = &mut model.bodies[index];
        body.block = block;
        let v0 = body.joint.v_offset;
        blocks[block].dofs.extend(v0..v0 + body.joint.motion.nv());
        blocks[block].bodies.push(index);
    }
    for block in &mut blocks {
        block.dofs.sort_unstable();
        if let [body] = block.bodies[..]
            && matches!(model.bodies[body].joint.motion, JointMotion::Floating)
            && model.bodies[body].mass > 0.0
        {
            let b = &model.bodies[body];
            block.free_body = b.inertia.try_inverse().map(|inverse_inertia| {
                let mass_properties = crate::elements::RigidBody {
                    inverse_mass: 1.0 / b.mass,
                    com: b.com,
                    inertia: b.inertia,
                    inverse_inertia,
                };
                (body, mass_properties)
            });
        }
        let rotates = block
            .bodies
            .iter()
            .any(|&b| model.bodies[b].joint.motion.rotates());
        if !rotates {
            let k = block.dofs.len();
            let sub = nalgebra::DMatrix::from_fn(k, k, |r, c| mass[(block.dofs[r], block.dofs[c])]);
            block.constant_inverse = sub
                .try_inverse()
                .map(|inverse| (0..k * k).map(|i| inverse[(i / k, i % k)]).collect());
        }
    }
    for body in &mut model.bodies {
        let dofs = &blocks[body.block].dofs;
        body.chain_local = body
            .chain
            .iter()
            .map(|d| dofs.iter().position(|x| x == d).unwrap_or(0))
            .collect();
    }
    blocks
}

/// The mass matrix must be positive definite at the zero configuration (every
/// degree of freedom carries mass or inertia); then the model's evaluator is
/// chosen ([`Evaluator::choose`], the one place that decides it).
fn check_mass_matrix(model: &mut Structure, file: &Path) -> Result<Evaluator, LoadError> {
    let x = model.zero_state();
    let mass = dynamics::mass_matrix(model, &x);
    let Some(factor) = mass.clone().cholesky() else {
        let weak = (0..mass.nrows())
            .min_by(|&a, &b| mass[(a, a)].total_cmp(&mass[(b, b)]))
            .unwrap_or(0);
        let body = model
            .bodies
            .iter()
            .find(|b| (b.joint.v_offset..b.joint.v_offset + b.joint.motion.nv()).contains(&weak))
            .map(|b| b.name.clone())
            .unwrap_or_default();
        return Err(LoadError::robot(
            file,
            format!("link \"{body}\""),
            "the mass matrix is singular: a degree of freedom has no mass or inertia (check the <inertia> of this link)",
        ));
    };
    model.mass_blocks = mass_blocks(model, &mass);
    Ok(Evaluator::choose(model, &factor.inverse()))
}
