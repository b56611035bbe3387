//! The model seen body by body, for engines that integrate the rigid bodies
//! themselves (the rapier engine): the world motion of every body at a state,
//! the inverse map from body motions back to joint coordinates, and the
//! wrenches the force elements (isolators, LuGre contacts, servo) apply to each
//! body, computed by the same code the native right-hand side uses.

use nalgebra::{Rotation3, UnitQuaternion};

use crate::dynamics::Workspace;
use crate::elements::{BodyMotion, BodyWrench, Inputs, JointMotion};
use crate::model::Model;

impl Model {
    /// World motion of every body at state x, in body order.
    pub fn body_motions(&self, x: &[f64], ws: &mut Workspace) -> Vec<BodyMotion> {
        self.evaluate(x, &Inputs::default(), ws);
        (0..self.structure.bodies.len())
            .map(|i| BodyMotion {
                rotation: ws.rotation_of(i),
                origin: ws.origin_of(i),
                omega: ws.omega_of(i),
                velocity: ws.velocity_of(i),
            })
            .collect()
    }

    /// Writes the joint positions and rates that put every body at `motions`
    /// into `x` (bristle and integrator entries are left as they are). For
    /// floating joints the quaternion sign nearest the one already in `x` is
    /// kept, and revolute angles stay nearest the previous angle, so the
    /// coordinates are continuous along a trajectory.
    pub fn set_joint_state(&self, motions: &[BodyMotion], x: &mut [f64]) {
        let nq = self.structure.layout.nq;
        let rest = BodyMotion::identity();
        for (i, body) in self.structure.bodies.iter().enumerate() {
            let parent = body.parent.map_or(&rest, |p| &motions[p]);
            let motion = &motions[i];
            let joint = &body.joint;
            let joint_rotation = parent.rotation * joint.origin_rotation;
            let joint_origin = parent.origin + parent.rotation * joint.origin.translation.vector;
            let carried = parent.velocity + parent.omega.cross(&(motion.origin - parent.origin));
            let relative_velocity = motion.velocity - carried;
            let relative_omega = motion.omega - parent.omega;
            let (q0, v0) = (joint.q_offset, nq + joint.v_offset);
            match joint.motion {
                JointMotion::Prismatic { axis } => {
                    let s = joint_rotation * axis;
                    x[q0] = (motion.origin - joint_origin).dot(&s);
                    x[v0] = relative_velocity.dot(&s);
                }
                JointMotion::Revolute { axis } => {
                    let s = joint_rotation * axis;
                    let relative = Rotation3::from_matrix_unchecked(
                        joint_rotation.transpose() * motion.rotation,
                    );
                    let angle = relative.scaled_axis().dot(&axis);
                    let turns = ((x[q0] - angle) / std::f64::consts::TAU).round();
                    x[q0] = angle + turns * std::f64::consts::TAU;
                    x[v0] = relative_omega.dot(&s);
                }
                JointMotion::Floating => {
                    let to_joint = joint_rotation.transpose();
                    let offset = to_joint * (motion.origin - joint_origin);
                    let attitude = UnitQuaternion::from_rotation_matrix(
                        &Rotation3::from_matrix_unchecked(to_joint * motion.rotation),
                    );
                    let previous = [x[q0 + 3], x[q0 + 4], x[q0 + 5], x[q0 + 6]];
                    let mut q = [attitude.w, attitude.i, attitude.j, attitude.k];
                    let agreement: f64 = q.iter().zip(&previous).map(|(a, b)| a * b).sum();
                    if agreement < 0.0 {
                        q.iter_mut().for_each(|c| *c = -*c);
                    }
                    x[q0..q0 + 3].copy_from_slice(offset.as_slice());
                    x[q0 + 3..q0 + 7].copy_from_slice(&q);
                    let linear = to_joint * relative_velocity;
                    let angular = to_joint * relative_omega;
                    x[v0..v0 + 3].copy_from_slice(linear.as_slice());
                    x[v0 + 3..v0 + 6].copy_from_slice(angular.as_slice());
                }
            }
        }
    }

    /// The wrench every force element applies to each body at (x, u), without
    /// gravity, written into `wrenches` (one per body). Also leaves the
    /// element values (friction forces, bristle rates, tracking error) in
    /// `ws.elements`, as [`Model::evaluate`] does.
    pub fn element_wrenches(
        &self,
        x: &[f64],
        inputs: &Inputs,
        ws: &mut Workspace,
        wrenches: &mut [BodyWrench],
    ) {
        self.evaluate(x, inputs, ws);
        for (i, wrench) in wrenches.iter_mut().enumerate() {
            *wrench = ws.wrench_of(i);
        }
    }

    /// Rates of the states that are not body motion (bristle deflections and
    /// the servo's own states) after [`Model::element_wrenches`]: pairs
    /// of (state index, rate).
    pub fn internal_rates(&self, ws: &Workspace) -> Vec<(usize, f64)> {
        let mut rates: Vec<(usize, f64)> = self
            .structure
            .frictions
            .iter()
            .zip(&ws.elements.z_rate)
            .map(|(friction, rate)| (friction.z_index, *rate))
            .collect();
        if let Some(controller) = &self.structure.controller {
            rates.extend(controller.state_rates(&ws.elements.servo));
        }
        rates
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::load;
    use nalgebra::Vector3;
    use std::path::Path;

    fn loaded(scenario: &str) -> crate::Loaded {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        load(&root.join(scenario)).expect("shipped scenario loads")
    }

    /// A state with every joint displaced and moving, quaternions normalised.
    fn busy_state(model: &Model) -> Vec<f64> {
        let mut x: Vec<f64> = (0..model.n_states())
            .map(|i| 1e-3 * ((i as f64) * 1.7).sin())
            .collect();
        for body in &model.structure.bodies {
            if let JointMotion::Floating = body.joint.motion {
                let q0 = body.joint.q_offset + 3;
                let q = UnitQuaternion::from_euler_angles(0.02, -0.03, 0.4);
                x[q0..q0 + 4].copy_from_slice(&[q.w, q.i, q.j, q.k]);
            }
        }
        x
    }

    #[test]
    fn joint_state_inverts_body_motions() {
        for scenario in [
            "scenarios/coupling/drive_offset_traverse.toml",
            "scenarios/paper/fig05b_fi.toml",
        ] {
            let model = loaded(scenario).model;
            let x = busy_state(&model);
            let mut ws = model.workspace();
            let motions = model.body_motions(&x, &mut ws);
            let mut back = x.clone();
            let n = model.structure.layout.nq + model.structure.layout.nv;
            back[..n].iter_mut().for_each(|v| *v = 0.0);
            // Keep the quaternion hemisphere hint of the original state.
            for body in &model.structure.bodies {
                if let JointMotion::Floating = body.joint.motion {
                    let q0 = body.joint.q_offset + 3;
                    back[q0] = 1.0;
                }
            }
            model.set_joint_state(&motions, &mut back);
            for (i, (a, b)) in x.iter().zip(&back).enumerate() {
                assert!(
                    (a - b).abs() < 1e-14,
                    "{scenario}: {} {a} vs {b}",
                    model.structure.layout.names[i]
                );
            }
        }
    }

    /// The wrenches plus gravity, through the mass matrix, give the same
    /// accelerations as the right-hand side (for a model whose joints do not
    /// rotate, where accelerations are M^-1 (J^T wrenches)).
    #[test]
    fn element_wrenches_drive_the_same_accelerations() {
        let loaded = loaded("scenarios/paper/fig05b_fi.toml");
        let model = &loaded.model;
        let x = busy_state(model);
        let inputs = Inputs {
            platform_velocity: 0.02,
            ..Inputs::default()
        };
        let mut ws = model.workspace();
        let mut wrenches = vec![
            BodyWrench {
                force: Vector3::zeros(),
                moment: Vector3::zeros(),
            };
            model.structure.bodies.len()
        ];
        model.element_wrenches(&x, &inputs, &mut ws, &mut wrenches);
        let mut dx = vec![0.0; model.n_states()];
        model.rhs(&x, &inputs, &mut dx, &mut model.workspace());
        let nq = model.structure.layout.nq;
        for (i, body) in model.structure.bodies.iter().enumerate() {
            if let JointMotion::Prismatic { axis } = body.joint.motion {
                // One prismatic body per joint to the world: m a = F . axis + m g . axis.
                let acceleration = dx[nq + body.joint.v_offset];
                let force =
                    wrenches[i].force.dot(&axis) + body.mass * model.structure.gravity.dot(&axis);
                assert!(
                    (body.mass * acceleration - force).abs() < 1e-9 * force.abs().max(1.0),
                    "{}: m a = {} vs F = {force}",
                    body.name,
                    body.mass * acceleration
                );
            }
        }
        for (index, rate) in model.internal_rates(&ws) {
            assert_eq!(dx[index], rate);
        }
    }
}
