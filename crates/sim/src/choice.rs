//! Which integration method the default engine (`auto`) takes for a model,
//! decided once from the model's linearisation and the run's tolerance
//! before a run: the explicit Dormand-Prince 5(4), the classical
//! fourth-order method ([`fistage_ode::ClassicalRungeKutta`]), or the implicit-explicit
//! `ARK5(4)8L[2]SA` with the bristle states implicit ([`fistage_ode::ImexRungeKutta`]).
//!
//! The explicit step is bounded by the spectral radius of the Jacobian; the
//! implicit-explicit one by that of its explicit part, the Jacobian with the
//! bristle rows removed. Both are read at the slipping equilibrium (the stage
//! at rest, the counter-surfaces sliding at the scenario's platform velocity
//! less its traverse velocity), where the bristle relaxation is fastest. The
//! implicit-explicit method takes 8 evaluations a step against 6, and more
//! arithmetic per stage, so it is chosen only where it lifts the bound by
//! at least [`REQUIRED_GAIN`]; a model without LuGre contacts, or with no
//! slipping equilibrium to read, stays explicit.
//!
//! Of the explicit methods, the classical fourth-order one takes four
//! evaluations a step against Dormand-Prince's six, and where lightly damped
//! stiff modes set the step both take about the same steps; its fourth order
//! loses where the smooth motion's accuracy sets the step. Measured on the shipped
//! stages (BENCHMARKS.md), it takes fewer evaluations at rtol 1e-6 on every
//! stage the explicit method serves (0.55 to 0.65 of Dormand-Prince's on the
//! six-degree-of-freedom stages) and more from 1e-7 on, so the explicit
//! choice is the classical method from [`LOOSE_RTOL`] up.

use fistage_model::eigen::spectral_radius;
use fistage_model::{EquilibriumKind, Inputs, Model};
use fistage_ode::MethodKind;

/// How much the implicit treatment of the bristles must raise the bound on
/// the explicit step before it pays (measured on the paper's Fig. 5b stage
/// and the four-bearing traverse: see BENCHMARKS.md).
pub const REQUIRED_GAIN: f64 = 4.0;

/// The tolerance from which the explicit choice is the classical
/// fourth-order method instead of Dormand-Prince 5(4).
pub const LOOSE_RTOL: f64 = 5e-7;

/// The method and what it was chosen from.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodChoice {
    /// The method.
    pub method: MethodKind,
    /// Spectral radius of the Jacobian at the slipping equilibrium, 1/s (if found).
    pub full_radius: Option<f64>,
    /// Spectral radius of its explicit part (bristle rows removed), 1/s.
    pub explicit_radius: Option<f64>,
    /// Why, in words.
    pub reason: String,
}

/// The cheapest sound method for `model` integrated to `rtol` when the
/// counter-surfaces slide at `slipping` (its platform velocity), starting
/// the equilibrium search at `start`.
pub fn choose_method(model: &Model, slipping: &Inputs, start: &[f64], rtol: f64) -> MethodChoice {
    let choice = choose_split(model, slipping, start);
    if choice.method != MethodKind::DormandPrince || rtol < LOOSE_RTOL {
        return choice;
    }
    MethodChoice {
        method: MethodKind::Classical,
        reason: format!(
            "{}; at rtol {rtol:e} (from {LOOSE_RTOL:e}) the classical fourth-order method",
            choice.reason
        ),
        ..choice
    }
}

/// Implicit bristles or an explicit method (Dormand-Prince standing for
/// both explicit methods), read off the linearisation.
fn choose_split(model: &Model, slipping: &Inputs, start: &[f64]) -> MethodChoice {
    let explicit = |reason: String| MethodChoice {
        method: MethodKind::DormandPrince,
        full_radius: None,
        explicit_radius: None,
        reason,
    };
    let bristles = model.bristle_states();
    if bristles.is_empty() {
        return explicit("no LuGre contact: nothing to treat implicitly".into());
    }
    if slipping.platform_velocity == 0.0 {
        return explicit("the counter-surfaces do not slide: no bristle relaxation to read".into());
    }
    let equilibrium = match model.equilibrium(EquilibriumKind::Slipping, slipping, start) {
        Ok(x) => x,
        Err(e) => return explicit(format!("{e}; explicit by default")),
    };
    let mut jacobian = model.jacobian(&equilibrium, slipping);
    let Some(full) = spectral_radius(&jacobian) else {
        return explicit(
            "the Jacobian's eigenvalues at the slipping equilibrium did not converge; explicit by default"
                .into(),
        );
    };
    for &row in &bristles {
        jacobian.row_mut(row).fill(0.0);
    }
    let Some(explicit_part) = spectral_radius(&jacobian) else {
        return explicit(
            "the eigenvalues without the bristle rows did not converge; explicit by default".into(),
        );
    };
    let gain = full / explicit_part.max(f64::MIN_POSITIVE);
    let (method, verdict) = if gain >= REQUIRED_GAIN {
        (
            MethodKind::Imex,
            "the bristle relaxation bounds the explicit step",
        )
    } else {
        (
            MethodKind::DormandPrince,
            "the bristles do not bound the explicit step",
        )
    };
    MethodChoice {
        method,
        full_radius: Some(full),
        explicit_radius: Some(explicit_part),
        reason: format!(
            "{verdict}: spectral radius {full:.3e} 1/s, {explicit_part:.3e} 1/s without the bristle rows ({gain:.1}x; implicit bristles pay from {REQUIRED_GAIN}x)"
        ),
    }
}
