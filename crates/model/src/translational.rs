//! Fast path for models in which no joint rotates a body (every joint prismatic):
//! all kinematics are then exactly linear in the joint coordinates, so contact
//! velocities, isolator deflections, sensor readings and actuator directions are
//! constant Jacobian rows, gravity is a constant generalized force, and the mass
//! matrix is constant. The rows are taken from the general kinematics of
//! [`crate::dynamics`] at build time; the element laws (LuGre, bushing, servo)
//! are the same functions both paths call. A test checks that both paths give
//! the same state derivative.

use crate::dynamics::{Workspace, bushing_force, servo_force};
use crate::model::{Inputs, Model};

/// Constant Jacobian rows of a translational model (row-major, `nv` per row).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TranslationalMap {
    nv: usize,
    mass_inverse: Vec<f64>,
    gravity: Vec<f64>,
    friction_rows: Vec<f64>,
    /// Translational bushing axes with stiffness or damping: (stiffness, damping,
    /// deflection offset, row start in `isolator_rows`).
    isolator_axes: Vec<(f64, f64, f64, usize)>,
    isolator_rows: Vec<f64>,
    sensor_rows: Vec<f64>,
    sensor_offsets: Vec<f64>,
    actuator_rows: Vec<f64>,
}

impl TranslationalMap {
    /// Reads the rows off the general kinematics: velocities are linear in the
    /// joint rates, so unit joint rates give the Jacobian columns.
    pub(crate) fn build(model: &Model, mass_inverse: &nalgebra::DMatrix<f64>) -> Self {
        let nv = model.layout.nv;
        let nq = model.layout.nq;
        let mut ws = model.workspace();
        let zero = model.zero_state();
        let inputs = Inputs::default();
        let (nf, ni, ns, na) = (
            model.frictions.len(),
            model.isolators.len(),
            model.sensors.len(),
            model.actuators.len(),
        );
        let mut map = Self {
            nv,
            mass_inverse: (0..nv * nv)
                .map(|k| mass_inverse[(k / nv, k % nv)])
                .collect(),
            gravity: vec![0.0; nv],
            friction_rows: vec![0.0; nf * nv],
            isolator_axes: Vec::new(),
            isolator_rows: vec![0.0; 3 * ni * nv],
            sensor_rows: vec![0.0; ns * nv],
            sensor_offsets: Vec::new(),
            actuator_rows: vec![0.0; na * nv],
        };
        model.evaluate(&zero, &inputs, &mut ws);
        for (k, isolator) in model.isolators.iter().enumerate() {
            for axis in 0..3 {
                let (stiffness, damping) = (isolator.stiffness[axis], isolator.damping[axis]);
                if stiffness != 0.0 || damping != 0.0 {
                    let offset = ws.elements.isolator_deflection[k][axis];
                    map.isolator_axes
                        .push((stiffness, damping, offset, (3 * k + axis) * nv));
                }
            }
        }
        map.sensor_offsets = ws.elements.sensor_position.clone();
        for j in 0..nv {
            let mut x = zero.clone();
            x[nq + j] = 1.0;
            model.evaluate(&x, &inputs, &mut ws);
            for k in 0..nf {
                map.friction_rows[k * nv + j] = ws.elements.slip_velocity[k];
            }
            for k in 0..ni {
                for axis in 0..3 {
                    map.isolator_rows[(3 * k + axis) * nv + j] = ws.elements.isolator_rate[k][axis];
                }
            }
            for k in 0..ns {
                map.sensor_rows[k * nv + j] = ws.elements.sensor_velocity[k];
            }
            for (k, actuator) in model.actuators.iter().enumerate() {
                map.actuator_rows[k * nv + j] = ws
                    .point_velocity(actuator.body, &actuator.point)
                    .dot(&actuator.axis);
            }
            map.gravity[j] = model
                .bodies
                .iter()
                .enumerate()
                .map(|(b, body)| body.mass * ws.point_velocity(b, &body.com).dot(&model.gravity))
                .sum();
        }
        map
    }

    /// The state derivative; `ws` only supplies scratch space for the
    /// generalized forces and the element values.
    pub(crate) fn rhs(
        &self,
        model: &Model,
        x: &[f64],
        inputs: &Inputs,
        dx: &mut [f64],
        ws: &mut Workspace,
    ) {
        let nv = self.nv;
        let nq = model.layout.nq;
        let (q, v) = (&x[..nq], &x[nq..nq + nv]);
        dx[..nq].copy_from_slice(v);
        let force = &mut ws.generalized;
        force.copy_from_slice(&self.gravity);
        for (k, friction) in model.frictions.iter().enumerate() {
            let row = &self.friction_rows[k * nv..(k + 1) * nv];
            let slip = dot(row, v) - inputs.platform_velocity;
            let (f, z_rate) = friction.lugre.force_and_z_rate(slip, x[friction.z_index]);
            axpy(-f, row, force);
            dx[friction.z_index] = z_rate;
        }
        for &(stiffness, damping, offset, start) in &self.isolator_axes {
            let row = &self.isolator_rows[start..start + nv];
            let f = bushing_force(stiffness, damping, offset + dot(row, q), dot(row, v));
            axpy(f, row, force);
        }
        let elements = &mut ws.elements;
        elements.reference = inputs.reference;
        for k in 0..model.sensors.len() {
            let row = &self.sensor_rows[k * nv..(k + 1) * nv];
            elements.sensor_position[k] = self.sensor_offsets[k] + dot(row, q);
            elements.sensor_velocity[k] = dot(row, v);
        }
        servo_force(model, x, &inputs.values(), elements);
        for k in 0..model.actuators.len() {
            let row = &self.actuator_rows[k * nv..(k + 1) * nv];
            axpy(elements.actuator_force[k], row, force);
        }
        for row in 0..nv {
            dx[nq + row] = dot(&self.mass_inverse[row * nv..(row + 1) * nv], force);
        }
        if let Some(index) = model.controller.as_ref().and_then(|c| c.integral_index) {
            dx[index] = elements.tracking_error;
        }
    }
}

/// `a . b` over `a`'s length, summed in order (index loops over pre-sliced
/// operands compile to fewer instructions than iterator chains for the
/// handful of entries these rows have).
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let b = &b[..a.len()];
    let mut sum = 0.0;
    for i in 0..a.len() {
        sum += a[i] * b[i];
    }
    sum
}

/// `y += alpha x` over `x`'s length.
#[inline(always)]
fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    let y = &mut y[..x.len()];
    for i in 0..x.len() {
        y[i] += alpha * x[i];
    }
}
