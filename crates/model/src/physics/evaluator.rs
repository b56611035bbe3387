//! The one evaluator of a model's right-hand side. Which way it evaluates is
//! decided once, in [`Evaluator::choose`], when the model is built; the
//! simulation ([`crate::Model::rhs`]) and the linearisation
//! ([`crate::Model::jacobian`], dual numbers) both go through
//! [`Evaluator::rhs`], so equilibria and eigenvalues are those of the very
//! code that is integrated. Every way gives the state derivative of the
//! general recursive dynamics up to round-off (tests hold them to it at
//! random states).

use nalgebra::DMatrix;

use crate::dynamics::{EvaluationPath, InputValues, Workspace};
use crate::elements::Structure;
use crate::rooted::{RootedPlan, RootedScratch};
use crate::scalar::Scalar;
use crate::translational::TranslationalMap;

/// How a model's right-hand side is evaluated.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Evaluator {
    /// No joint rotates a body: constant Jacobian rows and inverse mass matrix.
    ConstantJacobian(TranslationalMap),
    /// Every body jointed straight to the world: free bodies and rail masses.
    RootedBodies(RootedPlan),
    /// Bodies in chains: recursive kinematics and a backward pass.
    General,
}

impl Evaluator {
    /// The cheapest exact evaluation for the model's structure, given the
    /// inverse of its mass matrix at the zero configuration.
    pub(crate) fn choose(model: &Structure, mass_inverse: &DMatrix<f64>) -> Self {
        if model.bodies.iter().all(|b| !b.joint.motion.rotates()) {
            return Self::ConstantJacobian(TranslationalMap::build(model, mass_inverse));
        }
        match RootedPlan::build(model) {
            Some(plan) => Self::RootedBodies(plan),
            None => Self::General,
        }
    }

    /// Which way this is.
    pub(crate) fn path(&self) -> EvaluationPath {
        match self {
            Self::ConstantJacobian(_) => EvaluationPath::ConstantJacobian,
            Self::RootedBodies(_) => EvaluationPath::RootedBodies,
            Self::General => EvaluationPath::General,
        }
    }

    /// The scratch space its evaluation needs in a workspace.
    pub(crate) fn scratch<S: Scalar>(&self) -> RootedScratch<S> {
        match self {
            Self::RootedBodies(plan) => plan.scratch(),
            _ => RootedScratch::empty(),
        }
    }

    /// The slip velocity of every friction contact at state `x`, contact order.
    #[inline]
    pub(crate) fn slip_velocities(
        &self,
        model: &Structure,
        x: &[f64],
        inputs: &InputValues<f64>,
        out: &mut [f64],
        ws: &mut Workspace<f64>,
    ) {
        match self {
            Self::ConstantJacobian(map) => {
                map.slip_velocities(model.layout.nq, x, inputs.platform_velocity, out)
            }
            Self::RootedBodies(plan) => {
                plan.slip_velocities(x, inputs.platform_velocity, out, &mut ws.rooted)
            }
            Self::General => {
                model.evaluate_values(x, inputs, ws);
                for (slip, value) in out.iter_mut().zip(&ws.elements.slip_velocity) {
                    *slip = *value;
                }
            }
        }
    }

    /// The state derivative, in any scalar type.
    #[inline]
    pub(crate) fn rhs<S: Scalar>(
        &self,
        model: &Structure,
        x: &[S],
        inputs: &InputValues<S>,
        dx: &mut [S],
        ws: &mut Workspace<S>,
    ) {
        match self {
            Self::ConstantJacobian(map) => {
                let out = (
                    dx,
                    &mut ws.generalized[..],
                    &mut ws.bristles,
                    &mut ws.elements.servo,
                );
                map.rhs(model, x, inputs, out)
            }
            Self::RootedBodies(plan) => plan.rhs(
                model,
                x,
                inputs,
                dx,
                &mut ws.rooted,
                &mut ws.elements,
                &mut ws.bristles,
            ),
            Self::General => model.rhs_general(x, inputs, dx, ws),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::{Dual64, Inputs, load};

    /// The slip velocities of the fast paths (translational rows, rooted
    /// bodies' motion) equal those of the general kinematics, at states away
    /// from rest and with the platform moving.
    #[test]
    fn slip_velocities_of_the_chosen_path_equal_the_general_ones() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        for scenario in [
            "scenarios/coupling/friction20_traverse.toml",
            "scenarios/bench/axis_4fi_fig05b.toml",
            "scenarios/paper/fig05b_fi.toml",
        ] {
            let loaded = load(&root.join(scenario)).expect("loads");
            let model = &loaded.model;
            let mut x = model.zero_state();
            for (i, v) in x.iter_mut().enumerate() {
                *v += 1e-3 * ((i * 7 % 11) as f64 - 5.0);
            }
            let inputs = Inputs {
                platform_velocity: 0.02,
                ..Inputs::default()
            };
            let mut ws = model.workspace();
            model.evaluate(&x, &inputs, &mut ws);
            let general = ws.elements.slip_velocity.clone();
            let mut fast = vec![f64::NAN; model.frictions().len()];
            model.slip_velocities(&x, &inputs.values(), &mut fast, &mut ws);
            assert!(
                general.iter().any(|v| v.abs() > 1e-3),
                "{scenario}: {general:?}"
            );
            for (k, (a, b)) in fast.iter().zip(&general).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-14 * b.abs().max(1e-3),
                    "{scenario}: contact {k}: {a} against {b}"
                );
            }
        }
    }

    /// The exact Jacobian through the chosen evaluation equals the one
    /// through the general dynamics.
    #[test]
    fn jacobian_of_the_chosen_path_equals_the_general_one() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        for scenario in [
            "scenarios/coupling/friction20_traverse.toml",
            "scenarios/paper/fig05b_fi.toml",
        ] {
            let loaded = load(&root.join(scenario)).expect("loads");
            let model = &loaded.model;
            let n = model.n_states();
            let mut x = model.zero_state();
            for (i, v) in x.iter_mut().enumerate() {
                *v += 1e-6 * ((i * 7 % 11) as f64 - 5.0);
            }
            let inputs = Inputs {
                platform_velocity: 0.02,
                servo_force: 0.3,
                ..Inputs::default()
            };
            let chosen = model.jacobian(&x, &inputs);
            let u = inputs.values::<Dual64>();
            let mut ws = model.workspace_of::<Dual64>();
            let mut xd: Vec<Dual64> = x.iter().map(|v| Dual64::from_re(*v)).collect();
            let mut dx = vec![Dual64::from_re(0.0); n];
            let mut worst: f64 = 0.0;
            for col in 0..n {
                xd[col].eps = 1.0;
                model.rhs_general(&xd, &u, &mut dx, &mut ws);
                for row in 0..n {
                    let scale = chosen[(row, col)].abs().max(dx[row].eps.abs()).max(1.0);
                    worst = worst.max((chosen[(row, col)] - dx[row].eps).abs() / scale);
                    assert!(
                        (chosen[(row, col)] - dx[row].eps).abs() <= 1e-9 * scale,
                        "{scenario}: d{}/d{}: {} vs {}",
                        model.layout().names[row],
                        model.layout().names[col],
                        chosen[(row, col)],
                        dx[row].eps
                    );
                }
                xd[col].eps = 0.0;
            }
        }
    }
}
