//! LuGre friction at one contact: parameters, validation, bristle dynamics,
//! friction force and the steady-state (Stribeck) curve.
//!
//! With `v` the sliding velocity of the contact relative to its counter-surface:
//!
//! ```text
//! sigma0 * g(v) = f_c + (f_s - f_c) * exp(-(v / v_s)^2)
//! z'  = v - |v| / g(v) * z
//! f_f = sigma0 * z + sigma1 * z' + sigma2 * v
//! ```
//!
//! The steady state of a contact sliding at constant `v` is
//! `f_ss(v) = [f_c + (f_s - f_c) exp(-(v/v_s)^2)] sgn(v) + sigma2 v` (paper Eq. 30).

use serde::{Deserialize, Serialize};

use crate::rule::Rule;
use crate::scalar::{Scalar, kink_abs};
use thiserror::Error;

/// A LuGre parameter that violates its physical requirement.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{name} must be {requirement}, got {shown}", shown = crate::rule::show(*.value))]
pub struct InvalidLugreParameter {
    /// Parameter name as used in files (`sigma0`, `f_c`, ...).
    pub name: &'static str,
    /// The offending value.
    pub value: f64,
    /// The requirement in words, e.g. `> 0` or `>= f_c (6.5)`.
    pub requirement: String,
}

impl InvalidLugreParameter {
    /// `name` breaking `rule` (a non-finite value breaks "finite").
    pub(crate) fn new(name: &'static str, value: f64, rule: Rule) -> Self {
        let rule = if value.is_finite() {
            rule
        } else {
            Rule::Finite
        };
        Self {
            name,
            value,
            requirement: rule.requirement_for(value),
        }
    }
}

/// The six LuGre parameters of one contact, SI units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LugreParams {
    /// Bristle stiffness sigma0, N/m.
    pub sigma0: f64,
    /// Bristle (micro) damping sigma1, N s/m.
    pub sigma1: f64,
    /// Viscous friction sigma2, N s/m.
    pub sigma2: f64,
    /// Coulomb friction level f_C, N.
    pub f_c: f64,
    /// Static (breakaway) friction level f_S, N.
    pub f_s: f64,
    /// Stribeck velocity v_s, m/s.
    pub v_s: f64,
}

/// One LuGre parameter: its file name, unit, own validity rule and field.
/// [`LugreParams::KEYS`] lists them; a new LuGre parameter is one entry there
/// (and its field), and every reader, override, sweep and FMU variable follows.
#[derive(Debug, Clone, Copy)]
pub struct LugreKey {
    /// Name in files and parameter paths (`sigma0`, `f_c`, ...).
    pub name: &'static str,
    /// SI unit, as FMI unit names write it.
    pub unit: &'static str,
    /// The rule the value must meet on its own (`f_s >= f_c` is checked jointly).
    pub rule: Rule,
    /// What the parameter is, in a few words.
    pub description: &'static str,
    get: fn(&LugreParams) -> f64,
    slot: fn(&mut LugreParams) -> &mut f64,
}

impl LugreKey {
    /// The value of this parameter in `params`.
    pub fn get(&self, params: &LugreParams) -> f64 {
        (self.get)(params)
    }

    /// Sets this parameter in `params` (no check: see [`LugreParams::validate`]).
    pub fn set(&self, params: &mut LugreParams, value: f64) {
        *(self.slot)(params) = value;
    }
}

impl LugreParams {
    /// The parameters in file order, with units and rules.
    pub const KEYS: [LugreKey; 6] = [
        LugreKey {
            name: "sigma0",
            unit: "N/m",
            rule: Rule::Positive,
            description: "bristle stiffness",
            get: |p| p.sigma0,
            slot: |p| &mut p.sigma0,
        },
        LugreKey {
            name: "sigma1",
            unit: "N.s/m",
            rule: Rule::NonNegative,
            description: "bristle damping",
            get: |p| p.sigma1,
            slot: |p| &mut p.sigma1,
        },
        LugreKey {
            name: "sigma2",
            unit: "N.s/m",
            rule: Rule::NonNegative,
            description: "viscous friction",
            get: |p| p.sigma2,
            slot: |p| &mut p.sigma2,
        },
        LugreKey {
            name: "f_c",
            unit: "N",
            rule: Rule::Positive,
            description: "Coulomb friction level",
            get: |p| p.f_c,
            slot: |p| &mut p.f_c,
        },
        LugreKey {
            name: "f_s",
            unit: "N",
            rule: Rule::Positive,
            description: "static (breakaway) friction level",
            get: |p| p.f_s,
            slot: |p| &mut p.f_s,
        },
        LugreKey {
            name: "v_s",
            unit: "m/s",
            rule: Rule::Positive,
            description: "Stribeck velocity",
            get: |p| p.v_s,
            slot: |p| &mut p.v_s,
        },
    ];

    /// Names of the parameters in file order (those of [`Self::KEYS`]).
    pub const NAMES: [&'static str; 6] = {
        let mut names = [""; 6];
        let mut i = 0;
        while i < names.len() {
            names[i] = Self::KEYS[i].name;
            i += 1;
        }
        names
    };

    /// The key named `name`.
    pub fn key(name: &str) -> Option<&'static LugreKey> {
        Self::KEYS.iter().find(|k| k.name == name)
    }

    /// The identified bearing of the source paper, Table 1.
    pub const fn paper_table1() -> Self {
        Self {
            sigma0: 2.2e6,
            sigma1: 237.0,
            sigma2: 14.2,
            f_c: 5.1,
            f_s: 6.5,
            v_s: 16.7e-3,
        }
    }

    /// Checks every key's rule (sigma0 > 0, f_c > 0, v_s > 0, sigma1 >= 0,
    /// sigma2 >= 0, all finite) and f_s >= f_c.
    pub fn validate(&self) -> Result<(), InvalidLugreParameter> {
        self.validate_each()?;
        if self.f_s < self.f_c {
            return Err(InvalidLugreParameter {
                name: "f_s",
                value: self.f_s,
                requirement: format!(">= f_c ({})", self.f_c),
            });
        }
        Ok(())
    }

    /// Checks each key's own rule (finite; sigma0, f_c, f_s, v_s > 0;
    /// sigma1, sigma2 >= 0), not the ordering `f_s >= f_c`: what makes the
    /// law defined, `g(v) >= min(f_c, f_s) > 0`. A compensator's model is
    /// held to this (its errors may cross the ordering); an element to
    /// [`LugreParams::validate`].
    pub fn validate_each(&self) -> Result<(), InvalidLugreParameter> {
        for key in &Self::KEYS {
            let value = key.get(self);
            if !value.is_finite() {
                return Err(InvalidLugreParameter::new(key.name, value, Rule::Finite));
            }
        }
        for key in &Self::KEYS {
            let value = key.get(self);
            if !key.rule.admits(value) {
                return Err(InvalidLugreParameter::new(key.name, value, key.rule));
            }
        }
        Ok(())
    }

    /// The parameters in the order of [`Self::KEYS`].
    pub fn values(&self) -> [f64; 6] {
        Self::KEYS.map(|k| k.get(self))
    }

    /// Mutable access by file name, for overrides and parameter sweeps.
    pub fn get_mut(&mut self, name: &str) -> Option<&mut f64> {
        Self::key(name).map(|k| (k.slot)(self))
    }

    /// Stribeck level `f_c + (f_s - f_c) exp(-(v/v_s)^2)`, N (always > 0).
    #[inline]
    pub fn stribeck_level(&self, v: f64) -> f64 {
        let r = v / self.v_s;
        self.f_c + (self.f_s - self.f_c) * (-r * r).exp()
    }

    /// `g(v)`, the steady bristle deflection magnitude at velocity v, m.
    #[inline]
    pub fn g(&self, v: f64) -> f64 {
        self.stribeck_level(v) / self.sigma0
    }

    /// Bristle rate `z' = v - |v| / g(v) * z`, m/s.
    #[inline]
    pub fn z_rate(&self, v: f64, z: f64) -> f64 {
        v - v.abs() * self.sigma0 / self.stribeck_level(v) * z
    }

    /// Friction force on the contact (opposing positive `v`) and the bristle rate.
    #[inline]
    pub fn force_and_z_rate(&self, v: f64, z: f64) -> (f64, f64) {
        self.force_and_z_rate_of(v, z)
    }

    /// [`Self::force_and_z_rate`] for any [`Scalar`] (dual numbers differentiate it
    /// with respect to the state).
    #[inline]
    pub fn force_and_z_rate_of<S: Scalar>(&self, v: S, z: S) -> (S, S) {
        LugreOf::constant(self).force_and_z_rate(v, z)
    }

    /// Steady-state friction at constant sliding velocity v (paper Eq. 30), N.
    /// At v = 0 this is 0 (the sgn convention of the paper).
    pub fn steady_state_force(&self, v: f64) -> f64 {
        self.stribeck_level(v) * v.signum_or_zero() + self.sigma2 * v
    }

    /// The bristle deflection of the slipping equilibrium, `sgn(v) g(v)` (paper Eq. 29), m.
    pub fn steady_state_z(&self, v: f64) -> f64 {
        self.g(v) * v.signum_or_zero()
    }
}

/// The LuGre law with parameters of any [`Scalar`]: dual parameters give the
/// derivatives of the force and the bristle rate with respect to a parameter
/// (the record identification's sensitivities). [`LugreParams`] evaluates
/// through it, so the law is written once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LugreOf<S> {
    /// Bristle stiffness sigma0, N/m.
    pub sigma0: S,
    /// Bristle damping sigma1, N s/m.
    pub sigma1: S,
    /// Viscous friction sigma2, N s/m.
    pub sigma2: S,
    /// Coulomb level f_C, N.
    pub f_c: S,
    /// Static level f_S, N.
    pub f_s: S,
    /// Stribeck velocity v_s, m/s.
    pub v_s: S,
}

impl<S: Scalar> LugreOf<S> {
    /// The parameters of `params`, constant.
    pub fn constant(params: &LugreParams) -> Self {
        Self {
            sigma0: S::constant(params.sigma0),
            sigma1: S::constant(params.sigma1),
            sigma2: S::constant(params.sigma2),
            f_c: S::constant(params.f_c),
            f_s: S::constant(params.f_s),
            v_s: S::constant(params.v_s),
        }
    }

    /// Friction force on the contact (opposing positive `v`) and the bristle rate.
    ///
    /// The operations are ordered for a short dependency chain (an
    /// integrator's stages wait on each other): the exponential starts
    /// without a division, and everything that does not need the Stribeck
    /// level is ready before it.
    #[inline]
    pub fn force_and_z_rate(&self, v: S, z: S) -> (S, S) {
        let level = self.level(v);
        let z_dot = v - kink_abs(v) * self.sigma0 * z / level;
        (self.force(v, z, z_dot), z_dot)
    }

    /// The law at an implicit stage of the bristle state: for a given slip
    /// velocity the bristle equation `z' = v - (sigma0 |v| / g(v)) z` is
    /// linear in `z`, so the `z` that solves `z = c + step z'(v, z)` is
    /// exact, `z = (c + step v) / (1 + step sigma0 |v| / g(v))`. Returns the
    /// force and the rate at that `z`, and the `z` itself. With `step` 0 it
    /// is [`Self::force_and_z_rate`] at `z = c`.
    #[inline]
    pub fn implicit_stage(&self, v: S, c: S, step: S) -> (S, S, S) {
        // With r = sigma0 |v| / level: z' = v - r z and z = c + step z' give
        // z' = (v - r c) / (1 + step r), written with one division.
        let pull = kink_abs(v) * self.sigma0;
        let level = self.level(v);
        let z_dot = (v * level - pull * c) / (level + step * pull);
        let z = c + step * z_dot;
        (self.force(v, z, z_dot), z_dot, z)
    }

    /// The Stribeck level sigma0 g(v) = f_C + (f_S - f_C) exp(-(v / v_s)^2), N
    /// (the curve's argument a multiplication, not a division).
    #[inline]
    fn level(&self, v: S) -> S {
        let r = v * (S::one() / self.v_s);
        self.f_c + (self.f_s - self.f_c) * (-(r * r)).exp()
    }

    /// The friction force sigma0 z + sigma1 z' + sigma2 v.
    #[inline]
    fn force(&self, v: S, z: S, z_dot: S) -> S {
        self.sigma0 * z + self.sigma2 * v + self.sigma1 * z_dot
    }
}

/// `sgn` with sgn(0) = 0, as in the paper.
trait SignumOrZero {
    fn signum_or_zero(self) -> Self;
}

impl SignumOrZero for f64 {
    #[inline]
    fn signum_or_zero(self) -> f64 {
        if self > 0.0 {
            1.0
        } else if self < 0.0 {
            -1.0
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn table1_is_valid() {
        LugreParams::paper_table1().validate().unwrap();
    }

    #[test]
    fn validation_names_the_parameter() {
        let mut p = LugreParams::paper_table1();
        p.sigma0 = -3.0;
        let e = p.validate().unwrap_err();
        assert_eq!(e.name, "sigma0");
        assert_eq!(e.to_string(), "sigma0 must be > 0, got -3");
        let mut p = LugreParams::paper_table1();
        p.f_s = 4.0;
        assert_eq!(p.validate().unwrap_err().name, "f_s");
        let mut p = LugreParams::paper_table1();
        p.v_s = 0.0;
        assert_eq!(p.validate().unwrap_err().name, "v_s");
        let mut p = LugreParams::paper_table1();
        p.sigma1 = f64::NAN;
        assert_eq!(p.validate().unwrap_err().name, "sigma1");
    }

    /// At the slipping equilibrium z = sgn(v) g(v) the bristle rate vanishes and
    /// the force is the steady-state force of Eq. 30.
    #[test]
    fn slipping_equilibrium_gives_eq30() {
        let p = LugreParams::paper_table1();
        for &v in &[-0.2, -0.02, -1e-3, 1e-4, 5e-3, 0.0167, 0.05, 1.0] {
            let z = p.steady_state_z(v);
            let (f, z_dot) = p.force_and_z_rate(v, z);
            assert!(
                z_dot.abs() < 1e-15 * v.abs().max(1.0),
                "z' = {z_dot} at v = {v}"
            );
            let by_eq30 = (p.f_c + (p.f_s - p.f_c) * (-(v / p.v_s).powi(2)).exp()) * v.signum()
                + p.sigma2 * v;
            assert_relative_eq!(f, by_eq30, max_relative = 1e-12);
            assert_relative_eq!(f, p.steady_state_force(v), max_relative = 1e-14);
        }
        // At v = v_s the Stribeck term is exactly 1/e of its excess.
        assert_relative_eq!(
            p.stribeck_level(p.v_s),
            5.1 + 1.4 / std::f64::consts::E,
            max_relative = 1e-14
        );
    }
}
