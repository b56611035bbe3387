//! Validity rules of parameters: the one place where "a stiffness must be >= 0"
//! or "a LuGre sigma0 must be > 0" is written. The robot reader, the scenario
//! reader, scenario overrides, sweeps and the FMU all check values with these.

use std::fmt;

/// The largest magnitude any parameter may have (SI units): beyond it no
/// stage is described, and the numerics only overflow.
pub const MAX_MAGNITUDE: f64 = 1e18;
/// The smallest value a positive parameter may have (SI units): below it the
/// model's time scales underflow.
pub const MIN_POSITIVE: f64 = 1e-18;

/// What a parameter value must satisfy (every rule also requires a finite
/// value of magnitude at most [`MAX_MAGNITUDE`], and a positive one at least
/// [`MIN_POSITIVE`]).
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
    /// A relative change `e` applied as the factor `1 + e`: `e > -1`.
    RelativeChange,
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
        write!(
            f,
            "must be {}, got {}",
            self.rule.requirement_for(self.value),
            show(self.value)
        )
    }
}

impl std::error::Error for RuleViolation {}

/// A number as a message shows it: plainly, or in exponent form when it is
/// very large or very small.
pub fn show(value: f64) -> String {
    let magnitude = value.abs();
    if value == 0.0 || !value.is_finite() || (1e-4..1e15).contains(&magnitude) {
        value.to_string()
    } else {
        format!("{value:e}")
    }
}

/// A message with every number written out in more than 20 characters (a
/// parser's full-decimal `1e300`) shown as [`show`] shows it.
pub fn readable_numbers(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        let (before, from) = rest.split_at(start);
        out.push_str(before);
        let end = from
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(from.len());
        let (number, after) = from.split_at(end);
        match number.parse::<f64>() {
            Ok(value) if number.len() > 20 => out.push_str(&show(value)),
            _ => out.push_str(number),
        }
        rest = after;
    }
    out.push_str(rest);
    out
}

impl Rule {
    /// The requirement in words, e.g. `> 0`.
    pub fn requirement(self) -> &'static str {
        match self {
            Rule::Finite => "finite",
            Rule::NonNegative => ">= 0",
            Rule::Positive => "> 0",
            Rule::Spread => "between -1 and 1 (exclusive)",
            Rule::RelativeChange => "> -1 (a relative change; the factor 1 + e stays positive)",
        }
    }

    /// The requirement `value` fails (or the rule's, when it passes): the
    /// magnitude bounds are named when they are what is broken.
    pub fn requirement_for(self, value: f64) -> String {
        if value.is_finite() && value.abs() > MAX_MAGNITUDE {
            format!("at most {MAX_MAGNITUDE:e} in magnitude (SI units)")
        } else if self == Rule::Positive && value > 0.0 && value < MIN_POSITIVE {
            format!("at least {MIN_POSITIVE:e} (SI units)")
        } else if !value.is_finite() {
            "finite".into()
        } else {
            self.requirement().into()
        }
    }

    /// Whether `value` satisfies the rule.
    pub fn admits(self, value: f64) -> bool {
        value.is_finite()
            && value.abs() <= MAX_MAGNITUDE
            && match self {
                Rule::Finite => true,
                Rule::NonNegative => value >= 0.0,
                Rule::Positive => value >= MIN_POSITIVE,
                Rule::Spread => value.abs() < 1.0,
                Rule::RelativeChange => value > -1.0,
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

/// The longest name a link, joint or element may have.
const MAX_NAME_LENGTH: usize = 128;
/// Characters that would break a CSV header (`name [unit]`), a parameter
/// path or an FMI name.
const FORBIDDEN_IN_NAMES: &[char] = &[',', ';', '"', '\'', '[', ']', '{', '}', '<', '>', '=', '\\'];

/// Why a name cannot serve as a signal, CSV and FMI name, if it cannot.
pub fn check_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("empty".into());
    }
    if name.chars().count() > MAX_NAME_LENGTH {
        return Err(format!("longer than {MAX_NAME_LENGTH} characters"));
    }
    if name.trim() != name {
        return Err("leading or trailing white space".into());
    }
    if let Some(c) = name
        .chars()
        .find(|c| c.is_control() || FORBIDDEN_IN_NAMES.contains(c))
    {
        return Err(format!("contains {c:?}"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {

    #[test]
    fn numbers_written_out_in_full_are_shown_short() {
        let long = format!("invalid type: floating point `{}`, expected u64", 1e300);
        assert_eq!(
            readable_numbers(&long),
            "invalid type: floating point `1e300`, expected u64"
        );
        let tiny = format!("got {} at line 3", 1e-300);
        assert_eq!(readable_numbers(&tiny), "got 1e-300 at line 3");
        let plain = "line 12: 0.25 is not 3";
        assert_eq!(readable_numbers(plain), plain);
    }

    use super::*;

    #[test]
    fn rules_admit_what_they_say() {
        assert!(Rule::Finite.admits(-1e18));
        assert!(!Rule::Finite.admits(-1e300));
        assert!(!Rule::Positive.admits(1e-300));
        assert!(Rule::NonNegative.admits(1e-300));
        assert_eq!(
            Rule::Positive.check(1e-300).unwrap_err().to_string(),
            "must be at least 1e-18 (SI units), got 1e-300"
        );
        assert_eq!(
            Rule::Finite.check(1e300).unwrap_err().to_string(),
            "must be at most 1e18 in magnitude (SI units), got 1e300"
        );
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
