//! How an evaluation treats the bristle states: explicitly (the state's `z`
//! is the `z` of the law), or as the implicit stage of an
//! implicit-explicit integrator, where the state's entry holds the explicit
//! part `c` of the stage and the law solves `z = c + step z'(v, z)` exactly
//! ([`crate::LugreOf::implicit_stage`]). Every evaluation path reads the
//! bristle law through [`BristleStage::law`], and a feedforward
//! compensator's LuGre model through [`BristleStage::compensator_law`], so
//! the two treatments cannot drift apart. A compensator's bristle equation
//! is linear in its state for the reference (or virtual bearing) velocity of
//! the stage, so it is solved the same way; a Dahl model (nonlinear in its
//! state for exponents other than 1) stays explicit.

use crate::elements::FrictionContact;
use crate::elements::FrictionModel;
use crate::scalar::Scalar;

/// The bristle treatment of one evaluation, kept in the workspace.
#[derive(Debug, Clone)]
pub struct BristleStage<S: Scalar = f64> {
    /// The implicit coefficient of the stage times the step, s (`None`:
    /// explicit).
    step: Option<S>,
    /// The solved bristle state of each contact (implicit stages only).
    solved: Vec<S>,
    /// The solved state of each compensator's LuGre model (implicit stages
    /// only; a Dahl model's entry unused).
    compensators: Vec<S>,
}

impl<S: Scalar> BristleStage<S> {
    /// Explicit treatment for `contacts` contacts and `compensators`
    /// compensators.
    pub(crate) fn explicit(contacts: usize, compensators: usize) -> Self {
        Self {
            step: None,
            solved: vec![S::zero(); contacts],
            compensators: vec![S::zero(); compensators],
        }
    }

    /// Friction force and bristle rate of contact `k` at slip velocity
    /// `slip`, where `z` is the state's bristle entry.
    #[inline(always)]
    pub(crate) fn law(&mut self, k: usize, contact: &FrictionContact, slip: S, z: S) -> (S, S) {
        match self.step {
            None => contact.lugre.force_and_z_rate_of(slip, z),
            Some(step) => {
                let (force, rate, solved) =
                    crate::LugreOf::constant(&contact.lugre).implicit_stage(slip, z, step);
                self.solved[k] = solved;
                (force, rate)
            }
        }
    }

    /// Force and state rate of compensator `k`'s friction `model` at
    /// velocity `v`, where `w` is the state's entry (the explicit part of the
    /// stage for a LuGre model at an implicit stage).
    #[inline]
    pub(crate) fn compensator_law(
        &mut self,
        k: usize,
        model: &FrictionModel,
        v: S,
        w: S,
    ) -> (S, S) {
        match (model, self.step) {
            (FrictionModel::Lugre(p), Some(step)) => {
                let (force, rate, solved) = crate::LugreOf::constant(p).implicit_stage(v, w, step);
                self.compensators[k] = solved;
                (force, rate)
            }
            _ => model.force_and_rate(v, w),
        }
    }

    /// Sets the stage's implicit step (`None`: explicit).
    pub(crate) fn set_step(&mut self, step: Option<S>) {
        self.step = step;
    }

    /// The solved bristle states of the last implicit evaluation, by contact.
    pub(crate) fn solved(&self) -> &[S] {
        &self.solved
    }

    /// The solved state of each compensator's model of the last implicit
    /// evaluation, by compensator (meaningful for LuGre models).
    pub(crate) fn solved_compensators(&self) -> &[S] {
        &self.compensators
    }
}
