//! The Dahl friction model: a pre-motion (pre-sliding) model in which the
//! friction force `F` itself is the state,
//!
//! ```text
//! F' = sigma v |1 - F / f_c sgn(v)|^n sgn(1 - F / f_c sgn(v))
//! ```
//!
//! with `sigma` the rest stiffness (the slope of force against displacement at
//! a reversal, the `k_f` of paper Eq. 1), `f_c` the Coulomb level it saturates
//! to and `n` the shape exponent (1 in Dahl's own model). fistage uses it as a
//! compensator's model of friction (paper Section 2.2), not as a contact law.

use std::cmp::Ordering;

use crate::rule::Rule;
use crate::scalar::Scalar;

/// The three Dahl parameters, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DahlParams {
    /// Rest stiffness sigma, N/m.
    pub sigma: f64,
    /// Coulomb level f_c, N.
    pub f_c: f64,
    /// Shape exponent n, 1.
    pub exponent: f64,
}

/// One Dahl parameter: its file name, unit, rule and field.
#[derive(Debug, Clone, Copy)]
pub struct DahlKey {
    /// Name in files and parameter paths.
    pub name: &'static str,
    /// SI unit, as FMI unit names write it.
    pub unit: &'static str,
    /// The rule the value must meet.
    pub rule: Rule,
    /// What the parameter is, in a few words.
    pub description: &'static str,
    slot: fn(&mut DahlParams) -> &mut f64,
}

impl DahlKey {
    /// The value of this parameter in `params`.
    pub fn get(&self, params: &DahlParams) -> f64 {
        let mut copy = *params;
        *(self.slot)(&mut copy)
    }

    /// Sets this parameter in `params` (no check: see [`DahlParams::validate`]).
    pub fn set(&self, params: &mut DahlParams, value: f64) {
        *(self.slot)(params) = value;
    }
}

impl DahlParams {
    /// The parameters in file order.
    pub const KEYS: [DahlKey; 3] = [
        DahlKey {
            name: "sigma",
            unit: "N/m",
            rule: Rule::Positive,
            description: "rest stiffness",
            slot: |p| &mut p.sigma,
        },
        DahlKey {
            name: "f_c",
            unit: "N",
            rule: Rule::Positive,
            description: "Coulomb friction level",
            slot: |p| &mut p.f_c,
        },
        DahlKey {
            name: "exponent",
            unit: "1",
            rule: Rule::Positive,
            description: "shape exponent",
            slot: |p| &mut p.exponent,
        },
    ];

    /// The key named `name`.
    pub fn key(name: &str) -> Option<&'static DahlKey> {
        Self::KEYS.iter().find(|k| k.name == name)
    }

    /// The first parameter that breaks its rule, with the rule's message.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        for key in &Self::KEYS {
            key.rule
                .check(key.get(self))
                .map_err(|e| (key.name, e.to_string()))?;
        }
        Ok(())
    }

    /// The force rate `F'` at velocity `v` and force `force`.
    #[inline]
    pub fn force_rate_of<S: Scalar>(&self, v: S, force: S) -> S {
        // The sign of the motion, written without a branch so that compiled
        // code follows a reversal (at v = -0 it is -1: the rate is a zero of
        // one sign or the other either way).
        let direction = S::one().copysign(v);
        let gap = S::one() - force * S::constant(1.0 / self.f_c) * direction;
        let shape = if self.exponent == 1.0 {
            gap
        } else if gap.compare_value(0.0) == Some(Ordering::Equal) {
            S::zero()
        } else {
            gap.abs().powf(S::constant(self.exponent)) * gap.signum()
        };
        S::constant(self.sigma) * v * shape
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With n = 1 the law integrates in closed form: after a displacement d
    /// from rest in one direction, F = f_c (1 - exp(-sigma d / f_c)).
    #[test]
    fn unit_exponent_saturates_exponentially() {
        let dahl = DahlParams {
            sigma: 2e6,
            f_c: 5.0,
            exponent: 1.0,
        };
        let (v, dt) = (1e-3, 1e-9);
        let mut force = 0.0_f64;
        let steps = 5000;
        for _ in 0..steps {
            // Midpoint rule.
            let half = force + 0.5 * dt * dahl.force_rate_of(v, force);
            force += dt * dahl.force_rate_of(v, half);
        }
        let d = v * dt * steps as f64;
        let exact = dahl.f_c * (1.0 - (-dahl.sigma * d / dahl.f_c).exp());
        assert!((force - exact).abs() < 1e-9, "{force} vs {exact}");
        // A reversal from saturation starts at slope sigma (1 + F / f_c):
        // twice the rest stiffness.
        let saturated = dahl.f_c * (1.0 - 1e-12);
        let slope = dahl.force_rate_of(-v, saturated) / -v;
        assert!((slope / dahl.sigma - 2.0).abs() < 1e-9, "{slope}");
    }
}
