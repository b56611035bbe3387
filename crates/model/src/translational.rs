//! Fast path for models in which no joint rotates a body (every joint prismatic):
//! all kinematics are then exactly linear in the joint coordinates, so contact
//! velocities, isolator deflections, sensor readings and actuator directions are
//! constant Jacobian rows, gravity is a constant generalized force, and the mass
//! matrix is constant. The rows are taken from the general kinematics of
//! [`crate::dynamics`] at build time, and the linear part of the motion (gravity
//! and the bushings through `M^-1`) is folded into one affine map of the state;
//! the element laws (LuGre, bushing, servo) are the same functions both paths
//! call. A test checks that both paths give the same state derivative.

use crate::bristle::BristleStage;
use crate::elements::{Inputs, Structure};
use crate::laws::bushing_force;
use crate::rooted::RootedScratch;
use crate::rows::{DYNAMIC, DenseRows, RowTable, SparseRows, dot};
use crate::scalar::Scalar;
use crate::values::InputValues;

/// Constant Jacobian rows of a translational model (row-major, `nv` per row).
///
/// The bushings are linear in their deflection and rate, and gravity and the
/// mass matrix are constant, so everything but the friction and the servo is
/// one affine map of the state: `M^-1 (g + J^T f_bushing(J q + d, J v))` is
/// kept as a constant part and one matrix over the positions and one over the
/// velocities, read off [`bushing_force`] at build time.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TranslationalMap {
    nv: usize,
    /// `M^-1` times gravity and the bushings' forces at zero coordinates.
    constant_accelerations: Vec<f64>,
    /// Accelerations per unit joint coordinate through the bushings (row `i`:
    /// acceleration of coordinate `i`).
    position_accelerations: Vec<f64>,
    /// Accelerations per unit joint rate through the bushings.
    velocity_accelerations: Vec<f64>,
    friction_rows: Vec<f64>,
    /// `M^-1 J_k^T` for each friction row `J_k` (row-major, `nv` per contact):
    /// the accelerations a unit friction force causes.
    friction_accelerations: Vec<f64>,
    sensor_rows: Vec<f64>,
    sensor_offsets: Vec<f64>,
    /// `M^-1 J_a^T` for each actuator direction `J_a`.
    actuator_accelerations: Vec<f64>,
    /// The same rows as non-zero entries, for models beyond the dense sizes.
    sparse: Option<Box<Tables<SparseRows>>>,
}

/// The map's row tables, dense or sparse.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Tables<R> {
    position_accelerations: R,
    velocity_accelerations: R,
    friction_rows: R,
    friction_accelerations: R,
    sensor_rows: R,
    actuator_accelerations: R,
}

/// Degrees of freedom up to which the rows stay dense with a compile-time
/// length; beyond, they are kept sparse.
const DENSE_UP_TO: usize = 8;

/// Row-major `nv`-column rows read off the general kinematics.
struct KinematicRows {
    friction: Vec<f64>,
    isolator: Vec<f64>,
    sensor: Vec<f64>,
    actuator: Vec<f64>,
    gravity: Vec<f64>,
}

impl KinematicRows {
    /// Velocities are linear in the joint rates, so unit joint rates give the
    /// Jacobian columns.
    fn read(model: &Structure, ws: &mut crate::dynamics::Workspace) -> Self {
        let (nv, nq) = (model.layout.nv, model.layout.nq);
        let zero = model.zero_state();
        let inputs = Inputs::default();
        let mut rows = Self {
            friction: vec![0.0; model.frictions.len() * nv],
            isolator: vec![0.0; 3 * model.isolators.len() * nv],
            sensor: vec![0.0; model.sensors.len() * nv],
            actuator: vec![0.0; model.actuators.len() * nv],
            gravity: vec![0.0; nv],
        };
        for j in 0..nv {
            let mut x = zero.clone();
            x[nq + j] = 1.0;
            model.evaluate(&x, &inputs, ws);
            for (k, slip) in ws.elements.slip_velocity.iter().enumerate() {
                rows.friction[k * nv + j] = *slip;
            }
            for (k, rate) in ws.elements.isolator_rate.iter().enumerate() {
                for (axis, r) in rate.iter().take(3).enumerate() {
                    rows.isolator[(3 * k + axis) * nv + j] = *r;
                }
            }
            for (k, v) in ws.elements.sensor_velocity.iter().enumerate() {
                rows.sensor[k * nv + j] = *v;
            }
            for (k, actuator) in model.actuators.iter().enumerate() {
                rows.actuator[k * nv + j] = ws
                    .point_velocity(actuator.body, &actuator.point)
                    .dot(&actuator.axis);
            }
            rows.gravity[j] = model
                .bodies
                .iter()
                .enumerate()
                .map(|(b, body)| body.mass * ws.point_velocity(b, &body.com).dot(&model.gravity))
                .sum();
        }
        rows
    }
}

/// `M^-1 J^T` for each row `J` of a row-major table.
fn accelerations_of(mass_inverse: &[f64], rows: &[f64], nv: usize) -> Vec<f64> {
    rows.chunks_exact(nv.max(1))
        .flat_map(|row| (0..nv).map(move |i| dot(&mass_inverse[i * nv..(i + 1) * nv], row)))
        .collect()
}

impl TranslationalMap {
    /// Reads the rows off the general kinematics and folds the bushings,
    /// gravity and the mass matrix into the affine part.
    pub(crate) fn build(model: &Structure, mass_inverse: &nalgebra::DMatrix<f64>) -> Self {
        let nv = model.layout.nv;
        let mut ws = model.workspace_with(RootedScratch::empty());
        model.evaluate(&model.zero_state(), &Inputs::default(), &mut ws);
        let offsets = ws.elements.isolator_deflection.clone();
        let sensor_offsets = ws.elements.sensor_position.clone();
        let rows = KinematicRows::read(model, &mut ws);
        let m_inv: Vec<f64> = (0..nv * nv)
            .map(|k| mass_inverse[(k / nv, k % nv)])
            .collect();
        // Generalized bushing force: J^T f(J q + d, J v), linear in q and v.
        let (mut force, mut stiffness, mut damping) =
            (rows.gravity.clone(), vec![0.0; nv * nv], vec![0.0; nv * nv]);
        for (k, (isolator, offset)) in model.isolators.iter().zip(&offsets).enumerate() {
            for (axis, &offset) in offset.iter().take(3).enumerate() {
                let (k_axis, c_axis) = (isolator.stiffness[axis], isolator.damping[axis]);
                let row = &rows.isolator[(3 * k + axis) * nv..(3 * k + axis + 1) * nv];
                let at_zero = bushing_force(k_axis, c_axis, offset, 0.0);
                let per_deflection = bushing_force(k_axis, c_axis, 1.0, 0.0);
                let per_rate = bushing_force(k_axis, c_axis, 0.0, 1.0);
                for i in 0..nv {
                    force[i] += row[i] * at_zero;
                    for j in 0..nv {
                        stiffness[i * nv + j] += row[i] * per_deflection * row[j];
                        damping[i * nv + j] += row[i] * per_rate * row[j];
                    }
                }
            }
        }
        let times_m_inv = |table: &[f64]| -> Vec<f64> {
            (0..nv * nv)
                .map(|k| {
                    let (i, j) = (k / nv, k % nv);
                    (0..nv).map(|l| m_inv[i * nv + l] * table[l * nv + j]).sum()
                })
                .collect()
        };
        let mut map = Self {
            nv,
            constant_accelerations: (0..nv)
                .map(|i| dot(&m_inv[i * nv..(i + 1) * nv], &force))
                .collect(),
            position_accelerations: times_m_inv(&stiffness),
            velocity_accelerations: times_m_inv(&damping),
            friction_accelerations: accelerations_of(&m_inv, &rows.friction, nv),
            actuator_accelerations: accelerations_of(&m_inv, &rows.actuator, nv),
            friction_rows: rows.friction,
            sensor_rows: rows.sensor,
            sensor_offsets,
            sparse: None,
        };
        if nv > DENSE_UP_TO {
            let sparse = |table: &[f64]| SparseRows::from_dense(table, nv);
            map.sparse = Some(Box::new(Tables {
                position_accelerations: sparse(&map.position_accelerations),
                velocity_accelerations: sparse(&map.velocity_accelerations),
                friction_rows: sparse(&map.friction_rows),
                friction_accelerations: sparse(&map.friction_accelerations),
                sensor_rows: sparse(&map.sensor_rows),
                actuator_accelerations: sparse(&map.actuator_accelerations),
            }));
        }
        map
    }

    /// The dense tables with rows of `N` entries.
    #[inline(always)]
    fn dense<const N: usize>(&self) -> Tables<DenseRows<'_, N>> {
        let nv = self.nv;
        let rows = |table| DenseRows::<N> { table, nv };
        Tables {
            position_accelerations: rows(&self.position_accelerations),
            velocity_accelerations: rows(&self.velocity_accelerations),
            friction_rows: rows(&self.friction_rows),
            friction_accelerations: rows(&self.friction_accelerations),
            sensor_rows: rows(&self.sensor_rows),
            actuator_accelerations: rows(&self.actuator_accelerations),
        }
    }

    /// The state derivative. Models with up to [`DENSE_UP_TO`] degrees of
    /// freedom take dense rows whose length is a compile-time constant (fully
    /// unrolled products), larger ones their rows' non-zero entries; the
    /// arithmetic is the same but for the products with zero.
    pub(crate) fn rhs<S: Scalar>(
        &self,
        model: &Structure,
        x: &[S],
        inputs: &InputValues<S>,
        dx: &mut [S],
        bristles: &mut BristleStage<S>,
    ) {
        let out = (dx, bristles);
        match (&self.sparse, self.nv) {
            (Some(sparse), _) => {
                let tables = Tables {
                    position_accelerations: &sparse.position_accelerations,
                    velocity_accelerations: &sparse.velocity_accelerations,
                    friction_rows: &sparse.friction_rows,
                    friction_accelerations: &sparse.friction_accelerations,
                    sensor_rows: &sparse.sensor_rows,
                    actuator_accelerations: &sparse.actuator_accelerations,
                };
                self.rhs_with(&tables, model, x, inputs, out)
            }
            (None, 1) => self.rhs_with(&self.dense::<1>(), model, x, inputs, out),
            (None, 2) => self.rhs_with(&self.dense::<2>(), model, x, inputs, out),
            (None, 3) => self.rhs_with(&self.dense::<3>(), model, x, inputs, out),
            (None, 4) => self.rhs_with(&self.dense::<4>(), model, x, inputs, out),
            (None, 5) => self.rhs_with(&self.dense::<5>(), model, x, inputs, out),
            (None, 6) => self.rhs_with(&self.dense::<6>(), model, x, inputs, out),
            (None, 7) => self.rhs_with(&self.dense::<7>(), model, x, inputs, out),
            (None, 8) => self.rhs_with(&self.dense::<8>(), model, x, inputs, out),
            (None, _) => self.rhs_with(&self.dense::<DYNAMIC>(), model, x, inputs, out),
        }
    }

    /// The slip velocity of every friction contact (contact order) at state
    /// `x`: one row product each.
    #[inline]
    pub(crate) fn slip_velocities(
        &self,
        nq: usize,
        x: &[f64],
        platform_velocity: f64,
        out: &mut [f64],
    ) {
        let v = &x[nq..nq + self.nv];
        for (slip, row) in out.iter_mut().zip(self.friction_rows.chunks_exact(self.nv)) {
            *slip = dot(row, v) - platform_velocity;
        }
    }

    /// [`Self::rhs`] through one kind of row tables.
    #[inline(always)]
    fn rhs_with<R: RowTable, S: Scalar>(
        &self,
        tables: &Tables<R>,
        model: &Structure,
        x: &[S],
        inputs: &InputValues<S>,
        (dx, bristles): (&mut [S], &mut BristleStage<S>),
    ) {
        let nv = tables.position_accelerations.columns();
        let nq = model.layout.nq;
        let (q, v) = (&x[..nq], &x[nq..nq + nv]);
        let (q, v) = (&q[..nv], &v[..nv]);
        dx[..nq].copy_from_slice(v);
        for i in 0..nv {
            dx[nq + i] = S::constant(self.constant_accelerations[i])
                + tables.position_accelerations.dot(i, q)
                + tables.velocity_accelerations.dot(i, v);
        }
        let command = match &model.controller {
            Some(controller) => {
                let (sensor, rows) = (controller.sensor, &tables.sensor_rows);
                let (f, values) = controller.law_at_stage(
                    S::constant(self.sensor_offsets[sensor]) + rows.dot(sensor, q),
                    rows.dot(sensor, v),
                    x,
                    inputs,
                    bristles,
                );
                controller.write_rates(&values, dx);
                f
            }
            None => S::zero(),
        };
        if let Some(a) = model.servo_actuator() {
            tables.actuator_accelerations.axpy(
                a,
                command + inputs.servo_force,
                &mut dx[nq..nq + nv],
            );
        }
        // Friction last, straight into the accelerations through the
        // precomputed columns of M^-1 J^T: it waits on an exponential, so
        // everything else is summed by the time it is ready.
        for (k, friction) in model.frictions.iter().enumerate() {
            let slip = tables.friction_rows.dot(k, v) - inputs.platform_velocity;
            let (f, z_rate) = bristles.law(k, friction, slip, x[friction.z_index]);
            tables
                .friction_accelerations
                .axpy(k, -f, &mut dx[nq..nq + nv]);
            dx[friction.z_index] = z_rate;
        }
    }
}
