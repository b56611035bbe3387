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
use crate::rows::{DYNAMIC, DenseRows, PackedRows, RowTable, SparseRows, dot, most_nonzeros};
use crate::scalar::Scalar;
use crate::values::{InputValues, ServoValues};

/// Where an evaluation writes: the state derivative, then the workspace's
/// generalized forces, bristle stage and servo values.
pub(crate) type RhsOut<'a, S> = (
    &'a mut [S],
    &'a mut [S],
    &'a mut BristleStage<S>,
    &'a mut ServoValues<S>,
);

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
    /// The same rows as non-zero entries, where that is cheaper than dense.
    sparse: SparseTables,
}

/// The rows' non-zero entries, when the model's rows are kept that way.
#[derive(Debug, Clone, PartialEq)]
enum SparseTables {
    /// Dense rows only.
    None,
    /// At most two non-zero entries in every row (a rail stage: a contact
    /// touches one body, an isolator joins two, the mass matrix is diagonal).
    Two(Box<Tables<PackedRows<2>>>),
    /// At most three.
    Three(Box<Tables<PackedRows<3>>>),
    /// At most four.
    Four(Box<Tables<PackedRows<4>>>),
    /// Each row's own count, beyond the dense sizes.
    Compressed(Box<Tables<SparseRows>>),
}

/// The map's row tables, dense or sparse.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Tables<R> {
    mass_inverse: R,
    friction_rows: R,
    friction_accelerations: R,
    isolator_rows: R,
    sensor_rows: R,
    actuator_rows: R,
}

impl<R> Tables<R> {
    /// The same tables, borrowed (the form the row operations take).
    fn by_ref(&self) -> Tables<&R> {
        Tables {
            mass_inverse: &self.mass_inverse,
            friction_rows: &self.friction_rows,
            friction_accelerations: &self.friction_accelerations,
            isolator_rows: &self.isolator_rows,
            sensor_rows: &self.sensor_rows,
            actuator_rows: &self.actuator_rows,
        }
    }
}

/// Degrees of freedom up to which the rows stay dense with a compile-time
/// length unless a fixed count of entries per row is cheaper; beyond, they
/// are kept sparse.
const DENSE_UP_TO: usize = 8;

impl<R> Tables<R> {
    /// Each of `map`'s tables through `convert`, or `None` when one refuses.
    fn of(map: &TranslationalMap, convert: impl Fn(&[f64]) -> Option<R>) -> Option<Box<Self>> {
        Some(Box::new(Tables {
            mass_inverse: convert(&map.mass_inverse)?,
            friction_rows: convert(&map.friction_rows)?,
            friction_accelerations: convert(&map.friction_accelerations)?,
            isolator_rows: convert(&map.isolator_rows)?,
            sensor_rows: convert(&map.sensor_rows)?,
            actuator_rows: convert(&map.actuator_rows)?,
        }))
    }
}

impl SparseTables {
    /// The cheapest form of `map`'s rows: a fixed count of entries per row
    /// when every row has at most four non-zeros and that is fewer than the
    /// degrees of freedom, dense rows up to [`DENSE_UP_TO`] degrees of
    /// freedom, each row's own entries beyond.
    fn choose(map: &TranslationalMap) -> Self {
        let nv = map.nv;
        let tables = [
            &map.mass_inverse[..],
            &map.friction_rows,
            &map.friction_accelerations,
            &map.isolator_rows,
            &map.sensor_rows,
            &map.actuator_rows,
        ];
        let most = most_nonzeros(&tables, nv);
        let packed = (most < nv)
            .then(|| match most {
                0..=2 => Tables::of(map, |t| PackedRows::from_dense(t, nv)).map(Self::Two),
                3 => Tables::of(map, |t| PackedRows::from_dense(t, nv)).map(Self::Three),
                4 => Tables::of(map, |t| PackedRows::from_dense(t, nv)).map(Self::Four),
                _ => None,
            })
            .flatten();
        match packed {
            Some(packed) => packed,
            None if nv > DENSE_UP_TO => Tables::of(map, |t| Some(SparseRows::from_dense(t, nv)))
                .map_or(Self::None, Self::Compressed),
            None => Self::None,
        }
    }
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
            sparse: SparseTables::None,
        };
        model.evaluate(&zero, &inputs, &mut ws);
        for (k, isolator) in model.isolators.iter().enumerate() {
            for axis in 0..3 {
                let (stiffness, damping) = (isolator.stiffness[axis], isolator.damping[axis]);
                if stiffness != 0.0 || damping != 0.0 {
                    let offset = ws.elements.isolator_deflection[k][axis];
                    map.isolator_axes
                        .push((stiffness, damping, offset, 3 * k + axis));
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
        map.sparse = SparseTables::choose(&map);
        map
    }

    /// The dense tables with rows of `N` entries.
    #[inline(always)]
    fn dense<const N: usize>(&self) -> Tables<DenseRows<'_, N>> {
        let nv = self.nv;
        let rows = |table| DenseRows::<N> { table, nv };
        Tables {
            mass_inverse: rows(&self.mass_inverse),
            friction_rows: rows(&self.friction_rows),
            friction_accelerations: rows(&self.friction_accelerations),
            isolator_rows: rows(&self.isolator_rows),
            sensor_rows: rows(&self.sensor_rows),
            actuator_rows: rows(&self.actuator_rows),
        }
    }

    /// The state derivative into `out.0`; the rest of `out` is the
    /// workspace's scratch (generalized forces, the bristle stage, the
    /// servo's values). The rows are those [`SparseTables::choose`]
    /// picked: a fixed count of non-zero entries per row, dense rows whose
    /// length is a compile-time constant (fully unrolled products), or each
    /// row's own non-zero entries; the sums are the same but for the products
    /// with zero.
    pub(crate) fn rhs<S: Scalar>(
        &self,
        model: &Structure,
        x: &[S],
        inputs: &InputValues<S>,
        out: RhsOut<'_, S>,
    ) {
        match (&self.sparse, self.nv) {
            (SparseTables::Two(t), _) => self.rhs_with(&t.by_ref(), model, x, inputs, out),
            (SparseTables::Three(t), _) => self.rhs_with(&t.by_ref(), model, x, inputs, out),
            (SparseTables::Four(t), _) => self.rhs_with(&t.by_ref(), model, x, inputs, out),
            (SparseTables::Compressed(t), _) => self.rhs_with(&t.by_ref(), model, x, inputs, out),
            (SparseTables::None, 1) => self.rhs_with(&self.dense::<1>(), model, x, inputs, out),
            (SparseTables::None, 2) => self.rhs_with(&self.dense::<2>(), model, x, inputs, out),
            (SparseTables::None, 3) => self.rhs_with(&self.dense::<3>(), model, x, inputs, out),
            (SparseTables::None, 4) => self.rhs_with(&self.dense::<4>(), model, x, inputs, out),
            (SparseTables::None, 5) => self.rhs_with(&self.dense::<5>(), model, x, inputs, out),
            (SparseTables::None, 6) => self.rhs_with(&self.dense::<6>(), model, x, inputs, out),
            (SparseTables::None, 7) => self.rhs_with(&self.dense::<7>(), model, x, inputs, out),
            (SparseTables::None, 8) => self.rhs_with(&self.dense::<8>(), model, x, inputs, out),
            (SparseTables::None, _) => {
                self.rhs_with(&self.dense::<DYNAMIC>(), model, x, inputs, out)
            }
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
        (dx, generalized, bristles, servo): RhsOut<'_, S>,
    ) {
        let nv = tables.mass_inverse.columns();
        let nq = model.layout.nq;
        let (q, v) = (&x[..nq], &x[nq..nq + nv]);
        let (q, v) = (&q[..nv], &v[..nv]);
        dx[..nq].copy_from_slice(v);
        let force = &mut generalized[..nv];
        for (f, g) in force.iter_mut().zip(&self.gravity[..nv]) {
            *f = S::constant(*g);
        }
        for &(stiffness, damping, offset, row) in &self.isolator_axes {
            let rows = &tables.isolator_rows;
            let deflection = S::constant(offset) + rows.dot(row, q);
            let f = bushing_force(stiffness, damping, deflection, rows.dot(row, v));
            rows.axpy(row, f, force);
        }
        let command = match &model.controller {
            Some(controller) => {
                let (sensor, rows) = (controller.sensor, &tables.sensor_rows);
                // Written in place in the workspace: the servo's values are
                // a few hundred bytes, too many to clear or copy each time.
                let f = controller.law_into(
                    S::constant(self.sensor_offsets[sensor]) + rows.dot(sensor, q),
                    rows.dot(sensor, v),
                    x,
                    inputs,
                    bristles,
                    servo,
                );
                controller.write_rates(servo, dx);
                f
            }
            None => S::zero(),
        };
        if let Some(a) = model.servo_actuator() {
            tables
                .actuator_rows
                .axpy(a, command + inputs.servo_force, force);
        }
        for i in 0..nv {
            dx[nq + i] = tables.mass_inverse.dot(i, force);
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
