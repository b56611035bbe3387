//! The distributions a toleranced parameter is drawn from, each as its
//! quantile function (inverse CDF) of a uniform number u in (0, 1), so that
//! any sampling design of the unit cube (scrambled Sobol, random, Latin
//! hypercube) carries over to the parameters. A relative distribution is
//! written around the nominal value of the robot and scenario.
//!
//! | `distribution` | relative (`relative = true`, the default) | absolute |
//! |---|---|---|
//! | `uniform` | nominal (1 + half_width (2u - 1)) | low + (high - low) u |
//! | `normal` | nominal (1 + sd z) | mean + sd z |
//! | `lognormal` | nominal exp(sd z) (sd of ln X) | median exp(sd z) |
//! | `truncnormal` | nominal (1 + e), e ~ N(0, sd) within [low, high] | N(mean, sd) within [low, high] |
//!
//! with z = Phi^-1(u). Each distribution also knows the values it can
//! actually give (every design draws u within [2^-54, 1 - 2^-54], so |z| stays
//! below 8.3), so a draw the parameter's rule refuses (a negative stiffness
//! from a wide normal) is found when the study is read, not at sample 3 817,
//! while a normal 5% spread of a positive parameter is accepted.

use fistage_model::rule::Rule;
use statrs::distribution::{ContinuousCDF, Normal};

/// A distribution of one parameter's value, resolved against its nominal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Distribution {
    /// Uniform on [low, high].
    Uniform {
        /// Lower end.
        low: f64,
        /// Upper end.
        high: f64,
    },
    /// Normal.
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation (> 0).
        sd: f64,
    },
    /// Normal restricted to [low, high].
    TruncNormal {
        /// Mean of the untruncated normal.
        mean: f64,
        /// Its standard deviation (> 0).
        sd: f64,
        /// Lower end.
        low: f64,
        /// Upper end.
        high: f64,
    },
    /// ln X normal: X = median exp(sd z).
    LogNormal {
        /// Median.
        median: f64,
        /// Standard deviation of ln X (> 0).
        sd: f64,
    },
}

/// The values a distribution can give: from `low` to `high`, `low` itself
/// excluded when `low_open`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Support {
    /// Lower end (may be -inf).
    pub low: f64,
    /// Upper end (may be +inf).
    pub high: f64,
    /// Whether `low` itself is never drawn.
    pub low_open: bool,
}

/// The smallest u any design draws (and 1 - u the largest).
pub const SMALLEST_U: f64 = 1.0 / (1u64 << 54) as f64;

/// The largest |z| a draw can reach.
fn z_reach() -> f64 {
    -standard_normal().inverse_cdf(SMALLEST_U)
}

fn standard_normal() -> Normal {
    // Mean 0 and standard deviation 1 are valid arguments.
    Normal::standard()
}

impl Distribution {
    /// The value at quantile `u` in (0, 1).
    pub fn quantile(&self, u: f64) -> f64 {
        let z = |u: f64| standard_normal().inverse_cdf(u);
        match *self {
            Self::Uniform { low, high } => low + (high - low) * u,
            Self::Normal { mean, sd } => mean + sd * z(u),
            Self::LogNormal { median, sd } => median * (sd * z(u)).exp(),
            Self::TruncNormal {
                mean,
                sd,
                low,
                high,
            } => {
                let phi = standard_normal();
                let (a, b) = (phi.cdf((low - mean) / sd), phi.cdf((high - mean) / sd));
                (mean + sd * z(a + u * (b - a))).clamp(low, high)
            }
        }
    }

    /// The values it can give (with u in [SMALLEST_U, 1 - SMALLEST_U]).
    pub fn support(&self) -> Support {
        let closed = |low, high| Support {
            low,
            high,
            low_open: false,
        };
        match *self {
            Self::Uniform { low, high } => closed(low, high),
            Self::Normal { mean, sd } => closed(mean - sd * z_reach(), mean + sd * z_reach()),
            Self::TruncNormal { low, high, .. } => closed(low, high),
            Self::LogNormal { median, .. } if median < 0.0 => Support {
                low: f64::NEG_INFINITY,
                high: 0.0,
                low_open: false,
            },
            Self::LogNormal { .. } => Support {
                low: 0.0,
                high: f64::INFINITY,
                low_open: true,
            },
        }
    }

    /// Whether every value it can give passes `rule` (`Err` says why not).
    pub fn check_support(&self, rule: Rule) -> Result<(), String> {
        let Support {
            low,
            high,
            low_open,
        } = self.support();
        let fits = match rule {
            Rule::Finite => true,
            Rule::NonNegative => low >= 0.0,
            Rule::Positive => low > 0.0 || (low == 0.0 && low_open),
            Rule::Spread => low > -1.0 && high < 1.0,
            Rule::RelativeChange => low > -1.0 || (low == -1.0 && low_open),
        };
        if fits {
            return Ok(());
        }
        let ends = |v: f64| {
            if v.is_infinite() {
                format!("{}inf", if v < 0.0 { "-" } else { "" })
            } else {
                format!("{v:.4e}")
            }
        };
        Err(format!(
            "can draw values from {} to {}, but the parameter must be {} (a narrower spread, or truncnormal with low and high, or lognormal)",
            ends(low),
            ends(high),
            rule.requirement()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each quantile function is the inverse of its CDF: the mean of many
    /// evenly spread quantiles is the distribution's mean, and the median is
    /// at u = 1/2.
    #[test]
    fn quantiles_have_the_right_moments() {
        let n = 200_000;
        let mean_of = |d: Distribution| {
            (0..n)
                .map(|i| d.quantile((i as f64 + 0.5) / n as f64))
                .sum::<f64>()
                / n as f64
        };
        let uniform = Distribution::Uniform {
            low: 2.0,
            high: 6.0,
        };
        assert!((mean_of(uniform) - 4.0).abs() < 1e-9);
        let normal = Distribution::Normal { mean: 5.0, sd: 0.5 };
        assert!((mean_of(normal) - 5.0).abs() < 1e-6);
        assert!((normal.quantile(0.841_344_746_068_543) - 5.5).abs() < 1e-9);
        let lognormal = Distribution::LogNormal {
            median: 2.0,
            sd: 0.3,
        };
        // E[X] = median exp(sd^2 / 2).
        assert!((mean_of(lognormal) - 2.0 * (0.045f64).exp()).abs() < 1e-4);
        assert!((lognormal.quantile(0.5) - 2.0).abs() < 1e-12);
        // Symmetric truncation keeps the mean; every value stays inside.
        let truncated = Distribution::TruncNormal {
            mean: 1.0,
            sd: 1.0,
            low: 0.5,
            high: 1.5,
        };
        assert!((mean_of(truncated) - 1.0).abs() < 1e-6);
        for u in [1e-12, 0.3, 1.0 - 1e-12] {
            let v = truncated.quantile(u);
            assert!((0.5..=1.5).contains(&v), "{v}");
        }
    }

    #[test]
    fn a_support_the_rule_refuses_is_named() {
        // A 5% normal spread of a positive value never reaches zero (8.3 sd
        // away); a 20% one can.
        let narrow = Distribution::Normal {
            mean: 1.0,
            sd: 0.05,
        };
        assert!(narrow.check_support(Rule::Positive).is_ok());
        let wide = Distribution::Normal { mean: 1.0, sd: 0.2 };
        assert!(wide.check_support(Rule::Finite).is_ok());
        let message = wide.check_support(Rule::Positive).unwrap_err();
        assert!(
            message.contains("-6.5") && message.contains("> 0"),
            "{message}"
        );
        assert!((z_reach() - 8.29).abs() < 0.01, "{}", z_reach());
        let lognormal = Distribution::LogNormal {
            median: 1.0,
            sd: 2.0,
        };
        assert!(lognormal.check_support(Rule::Positive).is_ok());
        let uniform = Distribution::Uniform {
            low: -0.2,
            high: 0.5,
        };
        assert!(uniform.check_support(Rule::Spread).is_ok());
        assert!(uniform.check_support(Rule::NonNegative).is_err());
    }
}
