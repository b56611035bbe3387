//! Fast path for models in which no joint rotates a body (every joint prismatic):
//! all kinematics are then exactly linear in the joint coordinates, so contact
//! velocities, isolator deflections, sensor readings and actuator directions are
//! constant Jacobian rows, gravity is a constant generalized force, and the mass
//! matrix is constant. The rows are taken from the general kinematics of
//! [`crate::dynamics`] at build time; the element laws (LuGre, bushing, servo)
//! are the same functions both paths call. A test checks that both paths give
//! the same state derivative.

use crate::bristle::BristleStage;
use crate::elements::{Inputs, Structure};
use crate::laws::bushing_force;
use crate::rooted::RootedScratch;
use crate::scalar::Scalar;
use crate::values::InputValues;

/// Constant Jacobian rows of a translational model (row-major, `nv` per row).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TranslationalMap {
    nv: usize,
    mass_inverse: Vec<f64>,
    gravity: Vec<f64>,
    friction_rows: Vec<f64>,
    /// `M^-1 J_k^T` for each friction row `J_k` (row-major, `nv` per contact):
    /// the accelerations a unit friction force causes.
    friction_accelerations: Vec<f64>,
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
    pub(crate) fn build(model: &Structure, mass_inverse: &nalgebra::DMatrix<f64>) -> Self {
        let nv = model.layout.nv;
        let nq = model.layout.nq;
        let mut ws = model.workspace_with(RootedScratch::empty());
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
            friction_accelerations: vec![0.0; nf * nv],
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
        for k in 0..nf {
            for i in 0..nv {
                map.friction_accelerations[k * nv + i] = dot(
                    &map.mass_inverse[i * nv..(i + 1) * nv],
                    &map.friction_rows[k * nv..(k + 1) * nv],
                );
            }
        }
        map
    }

    /// The state derivative; `ws` only supplies scratch space for the
    /// generalized forces. Models with up to four
    /// degrees of freedom take a path whose row length is a compile-time
    /// constant (fully unrolled products); the arithmetic is the same.
    pub(crate) fn rhs<S: Scalar>(
        &self,
        model: &Structure,
        x: &[S],
        inputs: &InputValues<S>,
        dx: &mut [S],
        generalized: &mut [S],
        bristles: &mut BristleStage<S>,
    ) {
        match self.nv {
            1 => self.rhs_sized::<1, S>(model, x, inputs, dx, generalized, bristles),
            2 => self.rhs_sized::<2, S>(model, x, inputs, dx, generalized, bristles),
            3 => self.rhs_sized::<3, S>(model, x, inputs, dx, generalized, bristles),
            4 => self.rhs_sized::<4, S>(model, x, inputs, dx, generalized, bristles),
            _ => self.rhs_sized::<DYNAMIC, S>(model, x, inputs, dx, generalized, bristles),
        }
    }

    /// [`Self::rhs`] with rows of `N` entries (`N` = [`DYNAMIC`]: `nv`).
    #[inline(always)]
    fn rhs_sized<const N: usize, S: Scalar>(
        &self,
        model: &Structure,
        x: &[S],
        inputs: &InputValues<S>,
        dx: &mut [S],
        generalized: &mut [S],
        bristles: &mut BristleStage<S>,
    ) {
        let nv = row_length::<N>(self.nv);
        let nq = model.layout.nq;
        let (q, v) = (&x[..nq], &x[nq..nq + nv]);
        let (q, v) = (&q[..nv], &v[..nv]);
        dx[..nq].copy_from_slice(v);
        let force = &mut generalized[..nv];
        for (f, g) in force.iter_mut().zip(&self.gravity[..nv]) {
            *f = S::constant(*g);
        }
        for &(stiffness, damping, offset, start) in &self.isolator_axes {
            let row = &self.isolator_rows[start..start + nv];
            let deflection = S::constant(offset) + dot(row, q);
            let f = bushing_force(stiffness, damping, deflection, dot(row, v));
            axpy(f, row, force);
        }
        let command = match &model.controller {
            Some(controller) => {
                let sensor = row::<N>(&self.sensor_rows, nv, controller.sensor);
                let (f, values) = controller.law(
                    S::constant(self.sensor_offsets[controller.sensor]) + dot(sensor, q),
                    dot(sensor, v),
                    x,
                    inputs,
                );
                controller.write_rates(&values, dx);
                f
            }
            None => S::zero(),
        };
        if let Some(a) = model.servo_actuator() {
            let actuator = row::<N>(&self.actuator_rows, nv, a);
            axpy(command + inputs.servo_force, actuator, force);
        }
        for i in 0..nv {
            dx[nq + i] = dot(row::<N>(&self.mass_inverse, nv, i), force);
        }
        // Friction last, straight into the accelerations through the
        // precomputed columns of M^-1 J^T: it waits on an exponential, so
        // everything else is summed by the time it is ready.
        for (k, friction) in model.frictions.iter().enumerate() {
            let slip = dot(row::<N>(&self.friction_rows, nv, k), v) - inputs.platform_velocity;
            let (f, z_rate) = bristles.law(k, friction, slip, x[friction.z_index]);
            let column = row::<N>(&self.friction_accelerations, nv, k);
            axpy(-f, column, &mut dx[nq..nq + nv]);
            dx[friction.z_index] = z_rate;
        }
    }
}

/// Row length marker for "known only at run time".
const DYNAMIC: usize = 0;

/// The row length: `N`, or `nv` when `N` is [`DYNAMIC`]. With a constant
/// `N` every slice below has a length the compiler knows.
#[inline(always)]
fn row_length<const N: usize>(nv: usize) -> usize {
    if N == DYNAMIC { nv } else { N }
}

/// Row `k` of a row-major table with rows of `nv` (= `N` unless dynamic) entries.
#[inline(always)]
fn row<const N: usize>(table: &[f64], nv: usize, k: usize) -> &[f64] {
    let nv = row_length::<N>(nv);
    &table[k * nv..(k + 1) * nv]
}

/// `a . b` over `a`'s length, summed in order (index loops over pre-sliced
/// operands compile to fewer instructions than iterator chains for the
/// handful of entries these rows have).
#[inline(always)]
fn dot<S: Scalar>(a: &[f64], b: &[S]) -> S {
    let b = &b[..a.len()];
    // -0.0 is the exact additive identity (+0.0 is not, for -0.0), so the
    // compiler drops the first addition.
    let mut sum = S::constant(-0.0);
    for i in 0..a.len() {
        sum += b[i] * S::constant(a[i]);
    }
    sum
}

/// `y += alpha x` over `x`'s length.
#[inline(always)]
fn axpy<S: Scalar>(alpha: S, x: &[f64], y: &mut [S]) {
    let y = &mut y[..x.len()];
    for i in 0..x.len() {
        y[i] += alpha * S::constant(x[i]);
    }
}
