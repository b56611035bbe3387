//! Validity rules of parameters: the one place where "a stiffness must be >= 0"
//! or "a LuGre sigma0 must be > 0" is written. The robot reader, the scenario
//! reader, scenario overrides, sweeps and the FMU all check values with these.

use std::fmt;

/// What a parameter value must satisfy (every rule also requires a finite value).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Rule {
    /// Any finite number.
    Finite,
    /// Finite and `>= 0`.
    NonNegative,
    /// Finite and `> 0`.
    Positive,
    /// A relative spread `s` applied as factors `1 + s w` with `|w| <= 1`: `-1 < s < 1`.
    Spread,
}

/// A value that breaks its rule.
#[derive(Debug, Clone, PartialEq)]
pub struct RuleViolation {
    /// The rule.
    pub rule: Rule,
    /// The offending value.
    pub value: f64,
}

impl fmt::Display for RuleViolation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "must be {}, got {}", self.rule.requirement(), self.value)
    }
}

impl std::error::Error for RuleViolation {}

impl Rule {
    /// The requirement in words, e.g. `> 0`.
    pub fn requirement(self) -> &'static str {
        match self {
            Rule::Finite => "finite",
            Rule::NonNegative => ">= 0",
            Rule::Positive => "> 0",
            Rule::Spread => "between -1 and 1 (exclusive)",
        }
    }

    /// Whether `value` satisfies the rule.
    pub fn admits(self, value: f64) -> bool {
        value.is_finite()
            && match self {
                Rule::Finite => true,
                Rule::NonNegative => value >= 0.0,
                Rule::Positive => value > 0.0,
                Rule::Spread => value.abs() < 1.0,
            }
    }

    /// Checks `value`; a non-finite value fails as "must be finite".
    pub fn check(self, value: f64) -> Result<(), RuleViolation> {
        if !value.is_finite() {
            return Err(RuleViolation {
                rule: Rule::Finite,
                value,
            });
        }
        if self.admits(value) {
            Ok(())
        } else {
            Err(RuleViolation { rule: self, value })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_admit_what_they_say() {
        assert!(Rule::Finite.admits(-1e300));
        assert!(!Rule::Finite.admits(f64::NAN));
        assert!(Rule::NonNegative.admits(0.0));
        assert!(!Rule::NonNegative.admits(-1e-300));
        assert!(!Rule::Positive.admits(0.0));
        assert!(!Rule::Positive.admits(f64::INFINITY));
        assert!(Rule::Spread.admits(-0.99));
        assert!(!Rule::Spread.admits(1.0));
        assert_eq!(
            Rule::NonNegative.check(-3.0).unwrap_err().to_string(),
            "must be >= 0, got -3"
        );
        assert_eq!(
            Rule::Positive.check(f64::NAN).unwrap_err().to_string(),
            "must be finite, got NaN"
        );
    }
}
