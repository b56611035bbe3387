//! Linearisation: the exact Jacobian `df/dx` (and `df/du`) by forward-mode dual
//! numbers through the same generic code that is simulated, and tangent
//! coordinates for floating joints.
//!
//! A floating joint's attitude is a unit quaternion (4 numbers, 3 degrees of
//! freedom). Around a state x the tangent coordinates replace each quaternion
//! by a small rotation vector `dtheta` in the joint frame, with
//! `Q(dtheta) = exp(dtheta / 2) * Q`. [`Tangent::expand`] maps tangent
//! perturbations to state perturbations and [`Tangent::project`] maps state
//! rates back, so that `project * J * expand` is the Jacobian of a minimal
//! state, fit for eigenvalues.

use nalgebra::{DMatrix, Matrix3, UnitQuaternion, Vector3};

use crate::dynamics::quaternion_at;
use crate::elements::{Inputs, JointMotion, StateKind};
use crate::model::Model;
use crate::scalar::Dual64;

/// Minimal (tangent) coordinates around a state.
#[derive(Debug, Clone)]
pub struct Tangent {
    /// Names: floating joints contribute `<joint>.rx`, `.ry`, `.rz` in place of
    /// the quaternion; everything else keeps its state name.
    pub names: Vec<String>,
    /// Kinds (`Angle` for the rotation-vector entries).
    pub kinds: Vec<StateKind>,
    /// Number of position coordinates (= number of velocity coordinates).
    pub n_positions: usize,
    /// n_states x n_tangent: state perturbation from a tangent perturbation.
    pub expand: DMatrix<f64>,
    /// n_tangent x n_states: tangent rate from a state rate.
    pub project: DMatrix<f64>,
}

impl Model {
    /// `df/dx` at (x, u), exact to round-off: dual numbers through the
    /// evaluation the simulation uses ([`Model::rhs_of`]).
    pub fn jacobian(&self, x: &[f64], inputs: &Inputs) -> DMatrix<f64> {
        let n = self.n_states();
        let u = inputs.values::<Dual64>();
        let mut ws = self.workspace_of::<Dual64>();
        let mut xd: Vec<Dual64> = x.iter().map(|v| Dual64::from_re(*v)).collect();
        let mut dx = vec![Dual64::from_re(0.0); n];
        let mut jacobian = DMatrix::zeros(n, n);
        for col in 0..n {
            xd[col].eps = 1.0;
            self.rhs_of(&xd, &u, &mut dx, &mut ws);
            for row in 0..n {
                jacobian[(row, col)] = dx[row].eps;
            }
            xd[col].eps = 0.0;
        }
        jacobian
    }

    /// `df/du` at (x, u): one column per input in the order of [`Inputs::NAMES`].
    pub fn input_jacobian(&self, x: &[f64], inputs: &Inputs) -> DMatrix<f64> {
        let n = self.n_states();
        let xd: Vec<Dual64> = x.iter().map(|v| Dual64::from_re(*v)).collect();
        let mut ws = self.workspace_of::<Dual64>();
        let mut dx = vec![Dual64::from_re(0.0); n];
        let mut jacobian = DMatrix::zeros(n, Inputs::NAMES.len());
        for col in 0..Inputs::NAMES.len() {
            let mut u = inputs.values::<Dual64>();
            let seeded = match col {
                0 => &mut u.reference_position,
                1 => &mut u.reference_velocity,
                2 => &mut u.servo_force,
                _ => &mut u.platform_velocity,
            };
            seeded.eps = 1.0;
            self.rhs_of(&xd, &u, &mut dx, &mut ws);
            for row in 0..n {
                jacobian[(row, col)] = dx[row].eps;
            }
        }
        jacobian
    }

    /// Directional derivative of every output (see [`Model::signals`]) at
    /// state x along the input direction `direction` (one entry per input, in
    /// the order of [`Inputs::NAMES`]), the state held fixed. Exact to round-off.
    pub fn output_input_derivative(
        &self,
        x: &[f64],
        inputs: &Inputs,
        direction: &[f64; 4],
    ) -> Vec<f64> {
        self.directional_derivative(x, inputs, None, direction).1
    }

    /// Directional derivatives at (x, u) along a state direction (none: the
    /// state held fixed) and an input direction (in the order of
    /// [`Inputs::NAMES`]): of the state rates `f(x, u)` and of every output.
    /// One dual-number pass; exact to round-off.
    pub fn directional_derivative(
        &self,
        x: &[f64],
        inputs: &Inputs,
        state_direction: Option<&[f64]>,
        input_direction: &[f64; 4],
    ) -> (Vec<f64>, Vec<f64>) {
        let xd: Vec<Dual64> = match state_direction {
            Some(dir) => x
                .iter()
                .zip(dir)
                .map(|(v, d)| Dual64::new(*v, *d))
                .collect(),
            None => x.iter().map(|v| Dual64::from_re(*v)).collect(),
        };
        let mut u = inputs.values::<Dual64>();
        u.reference_position.eps = input_direction[0];
        u.reference_velocity.eps = input_direction[1];
        u.servo_force.eps = input_direction[2];
        u.platform_velocity.eps = input_direction[3];
        let mut ws = self.workspace_of::<Dual64>();
        let mut rates = vec![Dual64::from_re(0.0); self.n_states()];
        self.rhs_of(&xd, &u, &mut rates, &mut ws);
        let mut out = vec![Dual64::from_re(0.0); self.structure.signals.len()];
        self.outputs_of(&xd, &u, &mut out, &mut ws);
        (
            rates.iter().map(|d| d.eps).collect(),
            out.iter().map(|d| d.eps).collect(),
        )
    }

    /// Tangent coordinates around state x.
    pub fn tangent(&self, x: &[f64]) -> Tangent {
        let n = self.n_states();
        let floating: Vec<usize> = self
            .structure
            .bodies
            .iter()
            .filter(|b| matches!(b.joint.motion, JointMotion::Floating))
            .map(|b| b.joint.q_offset)
            .collect();
        let n_tangent = n - floating.len();
        let mut expand = DMatrix::zeros(n, n_tangent);
        let mut project = DMatrix::zeros(n_tangent, n);
        let mut names = Vec::with_capacity(n_tangent);
        let mut kinds = Vec::with_capacity(n_tangent);
        let (mut state, mut reduced) = (0, 0);
        while state < n {
            if let Some(&q0) = floating.iter().find(|&&q0| q0 + 3 == state) {
                let joint = self
                    .structure
                    .bodies
                    .iter()
                    .find(|b| b.joint.q_offset == q0)
                    .map(|b| b.joint.name.clone())
                    .unwrap_or_default();
                let q = quaternion_at(x, state);
                let (w, v) = (q.w, Vector3::new(q.i, q.j, q.k));
                let skew = v.cross_matrix();
                // dQ = 1/2 (0, dtheta) * Q; dtheta = 2 vec(dQ * Q^-1).
                let lower: Matrix3<f64> = (Matrix3::identity() * w - skew) * 0.5;
                let back: Matrix3<f64> = (Matrix3::identity() * w + skew) * 2.0;
                for k in 0..3 {
                    expand[(state, reduced + k)] = -0.5 * v[k];
                    project[(reduced + k, state)] = -2.0 * v[k];
                    for r in 0..3 {
                        expand[(state + 1 + r, reduced + k)] = lower[(r, k)];
                        project[(reduced + k, state + 1 + r)] = back[(k, r)];
                    }
                }
                for axis in ["rx", "ry", "rz"] {
                    names.push(format!("{joint}.{axis}"));
                    kinds.push(StateKind::Angle);
                }
                state += 4;
                reduced += 3;
            } else {
                expand[(state, reduced)] = 1.0;
                project[(reduced, state)] = 1.0;
                names.push(self.structure.layout.names[state].clone());
                kinds.push(self.structure.layout.kinds[state]);
                state += 1;
                reduced += 1;
            }
        }
        Tangent {
            names,
            kinds,
            n_positions: self.structure.layout.nv,
            expand,
            project,
        }
    }

    /// Jacobian in tangent coordinates at (x, u): `project * df/dx * expand`.
    pub fn tangent_jacobian(&self, x: &[f64], inputs: &Inputs) -> (DMatrix<f64>, Tangent) {
        let tangent = self.tangent(x);
        let jacobian = &tangent.project * self.jacobian(x, inputs) * &tangent.expand;
        (jacobian, tangent)
    }

    /// Moves state x by a tangent perturbation (quaternions by rotation, renormalised).
    pub fn retract(&self, x: &[f64], step: &[f64]) -> Vec<f64> {
        let tangent = self.tangent(x);
        let mut moved = x.to_vec();
        let linear = &tangent.expand * nalgebra::DVector::from_column_slice(step);
        for (i, value) in moved.iter_mut().enumerate() {
            if self.structure.layout.kinds[i] != StateKind::Quaternion {
                *value += linear[i];
            }
        }
        let mut reduced = 0;
        let mut state = 0;
        while state < moved.len() {
            if self.structure.layout.kinds[state] == StateKind::Quaternion {
                let rotation = UnitQuaternion::from_scaled_axis(Vector3::new(
                    step[reduced],
                    step[reduced + 1],
                    step[reduced + 2],
                ));
                let q = rotation * quaternion_at(x, state);
                moved[state..state + 4].copy_from_slice(&[q.w, q.i, q.j, q.k]);
                state += 4;
                reduced += 3;
            } else {
                state += 1;
                reduced += 1;
            }
        }
        moved
    }
}
