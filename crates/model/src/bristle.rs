//! How an evaluation treats the bristle states: explicitly (the state's `z`
//! is the `z` of the law), or as the implicit stage of an
//! implicit-explicit integrator, where the state's entry holds the explicit
//! part `c` of the stage and the law solves `z = c + step z'(v, z)` exactly
//! ([`crate::LugreOf::implicit_stage`]). Every evaluation path reads the
//! bristle law through [`BristleStage::law`], so the two treatments cannot
//! drift apart.

use crate::elements::FrictionContact;
use crate::scalar::Scalar;

/// The bristle treatment of one evaluation, kept in the workspace.
#[derive(Debug, Clone)]
pub struct BristleStage<S: Scalar = f64> {
    /// The implicit coefficient of the stage times the step, s; 0: explicit.
    step: f64,
    /// The solved bristle state of each contact (implicit stages only).
    solved: Vec<S>,
}

impl<S: Scalar> BristleStage<S> {
    /// Explicit treatment for `contacts` contacts.
    pub(crate) fn explicit(contacts: usize) -> Self {
        Self {
            step: 0.0,
            solved: vec![S::zero(); contacts],
        }
    }

    /// Friction force and bristle rate of contact `k` at slip velocity
    /// `slip`, where `z` is the state's bristle entry.
    #[inline]
    pub(crate) fn law(&mut self, k: usize, contact: &FrictionContact, slip: S, z: S) -> (S, S) {
        if self.step == 0.0 {
            contact.lugre.force_and_z_rate_of(slip, z)
        } else {
            let (force, rate, solved) = crate::LugreOf::constant(&contact.lugre).implicit_stage(
                slip,
                z,
                S::constant(self.step),
            );
            self.solved[k] = solved;
            (force, rate)
        }
    }

    /// Sets the stage's implicit step (0: explicit).
    pub(crate) fn set_step(&mut self, step: f64) {
        self.step = step;
    }

    /// The solved bristle states of the last implicit evaluation, by contact.
    pub(crate) fn solved(&self) -> &[S] {
        &self.solved
    }
}
