//! Confidence intervals, residual statistics and the distributions they need.
//!
//! Least-squares fits use the linearised covariance at the optimum,
//! `Cov = s^2 (J^T J)^-1` with `s^2 = SSR / (n - p)`, and Student-t intervals
//! with `n - p` degrees of freedom. Robust (Huber, L1) fits use Huber's
//! covariance for M-estimators,
//! `Cov = K^2 [sum psi^2 / (n - p)] / [mean psi']^2 (J^T J)^-1`,
//! `K = 1 + (p / n) var(psi') / mean(psi')^2`, with `psi` the Huber score.
//!
//! The distribution functions (Student t, F, chi-squared) are statrs's, behind
//! the few named helpers the fits use.

use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, Continuous, ContinuousCDF, FisherSnedecor, StudentsT};

use nalgebra::DMatrix;

use crate::linalg::inverse_normal;

/// A fitted parameter with its standard error and 95% confidence interval, SI units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// The estimate.
    pub value: f64,
    /// Standard error; `None` when the data do not determine it (singular Jacobian).
    pub std_error: Option<f64>,
    /// 95% confidence interval `[lo, hi]`, clipped to the parameter's bounds;
    /// `None` when the standard error is unknown.
    pub ci95: Option<[f64; 2]>,
}

impl Estimate {
    /// An estimate with a symmetric interval `value +- t * std_error`, clipped below at `lower`.
    pub fn new(value: f64, std_error: Option<f64>, t_quantile: f64, lower: f64) -> Self {
        let ci95 = std_error.map(|se| {
            let half = t_quantile * se;
            [(value - half).max(lower), (value + half).max(lower)]
        });
        Self {
            value,
            std_error,
            ci95,
        }
    }

    /// A value known exactly (an input, not a fitted parameter).
    pub fn exact(value: f64) -> Self {
        Self {
            value,
            std_error: Some(0.0),
            ci95: Some([value, value]),
        }
    }

    /// Whether `truth` lies inside the 95% interval.
    pub fn covers(&self, truth: f64) -> bool {
        self.ci95.is_some_and(|[lo, hi]| lo <= truth && truth <= hi)
    }

    /// Half the width of the 95% interval, if known.
    pub fn half_width(&self) -> Option<f64> {
        self.ci95.map(|[lo, hi]| 0.5 * (hi - lo))
    }
}

/// How well a fit reproduces its data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResidualStats {
    /// Number of data points.
    pub n: usize,
    /// Degrees of freedom of the residual, `n - p`.
    pub dof: usize,
    /// Root mean square of the residuals, in the unit of the fitted quantity.
    pub rms: f64,
    /// Largest absolute residual.
    pub max_abs: f64,
    /// Coefficient of determination `1 - SSR / SST`.
    pub r_squared: f64,
    /// Robust residual scale, 1.4826 times the median absolute residual.
    pub robust_scale: f64,
    /// Lines of the data file whose residual exceeds 5 robust scales.
    pub suspected_outliers: Vec<u64>,
}

/// Residuals further than this many robust scales are reported as outliers.
const OUTLIER_SCALES: f64 = 5.0;

impl ResidualStats {
    /// Statistics of `residuals` (model minus data) of `observed` data.
    pub(crate) fn new(residuals: &[f64], observed: &[f64], lines: &[u64], n_params: usize) -> Self {
        let n = residuals.len();
        let ssr: f64 = residuals.iter().map(|r| r * r).sum();
        let mean = observed.iter().sum::<f64>() / n.max(1) as f64;
        let sst: f64 = observed.iter().map(|y| (y - mean).powi(2)).sum();
        let robust_scale = mad_scale(residuals);
        let suspected_outliers = residuals
            .iter()
            .zip(lines)
            .filter(|(r, _)| robust_scale > 0.0 && r.abs() > OUTLIER_SCALES * robust_scale)
            .map(|(_, &line)| line)
            .collect();
        Self {
            n,
            dof: n.saturating_sub(n_params),
            rms: (ssr / n.max(1) as f64).sqrt(),
            max_abs: residuals.iter().map(|r| r.abs()).fold(0.0, f64::max),
            r_squared: if sst > 0.0 { 1.0 - ssr / sst } else { f64::NAN },
            robust_scale,
            suspected_outliers,
        }
    }
}

/// 1.4826 times the median absolute value: the standard deviation of Gaussian
/// residuals, unaffected by a minority of outliers.
pub fn mad_scale(residuals: &[f64]) -> f64 {
    if residuals.is_empty() {
        return 0.0;
    }
    let mut abs: Vec<f64> = residuals.iter().map(|r| r.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let mid = abs.len() / 2;
    let median = if abs.len() % 2 == 1 {
        abs[mid]
    } else {
        0.5 * (abs[mid - 1] + abs[mid])
    };
    1.482_602_218_505_602 * median
}

/// Covariance `s^2 (J^T J)^-1` of a least-squares fit; `None` if J is singular.
pub(crate) fn least_squares_covariance(
    jacobian: &DMatrix<f64>,
    residuals: &[f64],
) -> Option<DMatrix<f64>> {
    let dof = jacobian
        .nrows()
        .checked_sub(jacobian.ncols())
        .filter(|&d| d > 0)?;
    let s2 = residuals.iter().map(|r| r * r).sum::<f64>() / dof as f64;
    Some(inverse_normal(jacobian)? * s2)
}

/// Huber's covariance of an M-estimate with Huber score at threshold `delta`.
pub(crate) fn huber_covariance(
    jacobian: &DMatrix<f64>,
    residuals: &[f64],
    delta: f64,
) -> Option<DMatrix<f64>> {
    let (n, p) = jacobian.shape();
    let dof = n.checked_sub(p).filter(|&d| d > 0)?;
    let psi2: f64 = residuals
        .iter()
        .map(|r| r.clamp(-delta, delta).powi(2))
        .sum();
    let inside = residuals.iter().filter(|r| r.abs() < delta).count() as f64;
    let m = inside / n as f64;
    if m <= 0.0 {
        return None;
    }
    let k = 1.0 + (p as f64 / n as f64) * (1.0 - m) / m;
    let factor = k * k * (psi2 / dof as f64) / (m * m);
    Some(inverse_normal(jacobian)? * factor)
}

/// Standard errors from a covariance matrix (`None` for a non-positive variance).
pub(crate) fn standard_errors(p: usize, covariance: Option<&DMatrix<f64>>) -> Vec<Option<f64>> {
    (0..p)
        .map(|i| {
            covariance
                .map(|c| c[(i, i)])
                .filter(|v| *v >= 0.0 && v.is_finite())
                .map(f64::sqrt)
        })
        .collect()
}

/// The two-sided 95% Student-t quantile `t_{0.975}(dof)`.
pub fn t95(dof: f64) -> f64 {
    student_t_quantile(0.975, dof)
}

/// CDF of Student's t distribution with `dof` degrees of freedom (NaN unless `dof > 0`).
pub fn student_t_cdf(t: f64, dof: f64) -> f64 {
    StudentsT::new(0.0, 1.0, dof).map_or(f64::NAN, |d| d.cdf(t))
}

/// Quantile of Student's t distribution: the t with `student_t_cdf(t, dof) = p`
/// (NaN unless `0 < p < 1` and `dof > 0`).
///
/// statrs inverts the incomplete beta function, which loses accuracy as `dof`
/// grows (7% at 1e7 degrees of freedom); a few Newton steps on its CDF, which
/// stays accurate (1e-13 for the degrees of freedom of the fits here, 1e-8 at
/// 1e7), bring the quantile back to the accuracy of the CDF.
pub fn student_t_quantile(p: f64, dof: f64) -> f64 {
    if !(p > 0.0 && p < 1.0) {
        return f64::NAN;
    }
    let Ok(t) = StudentsT::new(0.0, 1.0, dof) else {
        return f64::NAN;
    };
    let mut x = t.inverse_cdf(p);
    for _ in 0..QUANTILE_NEWTON_STEPS {
        let step = (t.cdf(x) - p) / t.pdf(x);
        if !step.is_finite() {
            break;
        }
        x -= step;
        if step.abs() <= 1e-15 * (1.0 + x.abs()) {
            break;
        }
    }
    x
}

/// Newton steps that polish statrs's Student-t quantile.
const QUANTILE_NEWTON_STEPS: usize = 20;

/// Survival function P(F > f) of the F distribution with (d1, d2) degrees of freedom.
pub fn f_distribution_sf(f: f64, d1: f64, d2: f64) -> f64 {
    FisherSnedecor::new(d1, d2).map_or(f64::NAN, |d| d.sf(f))
}

/// Survival function P(X > x) of the chi-squared distribution with k degrees of freedom.
pub fn chi_squared_sf(x: f64, k: f64) -> f64 {
    ChiSquared::new(k).map_or(f64::NAN, |d| d.sf(x))
}

#[cfg(test)]
mod tests {
    use super::*;
    use statrs::function::gamma::ln_gamma;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1e-300)
    }

    #[test]
    fn log_gamma_known_values() {
        assert!(close(
            ln_gamma(0.5),
            std::f64::consts::PI.sqrt().ln(),
            1e-13
        ));
        assert!(close(ln_gamma(10.0), 362_880f64.ln(), 1e-13));
        assert!(ln_gamma(1.0).abs() < 1e-14 && ln_gamma(2.0).abs() < 1e-14);
    }

    /// Reference quantiles from standard statistical tables.
    #[test]
    fn student_t_quantiles() {
        for (dof, t) in [
            (1.0, 12.706_204_736_174_7),
            (2.0, 4.302_652_729_749_464),
            (5.0, 2.570_581_835_636_314),
            (10.0, 2.228_138_851_986_274),
            (30.0, 2.042_272_456_301_238),
        ] {
            let q = t95(dof);
            assert!(close(q, t, 1e-9), "dof {dof}: {q} vs {t}");
        }
        assert!(close(
            student_t_cdf(-2.228_138_851_986_274, 10.0),
            0.025,
            1e-9
        ));
        // Large dof tends to the normal quantile 1.959964.
        assert!(close(t95(1e7), 1.959_963_984_540_054, 1e-6));
    }

    #[test]
    fn f_and_chi_squared_critical_values() {
        // 5% critical values: F(4, 60) = 2.525215, F(4, 72) ~ 2.498919; chi2(4) = 9.487729.
        assert!(close(f_distribution_sf(2.525_215_2, 4.0, 60.0), 0.05, 1e-5));
        assert!(close(
            chi_squared_sf(9.487_729_036_781_154, 4.0),
            0.05,
            1e-10
        ));
        assert!(close(chi_squared_sf(2.0, 2.0), (-1.0f64).exp(), 1e-12));
        assert!(close(
            chi_squared_sf(50.0, 4.0),
            26.0 * (-25.0f64).exp(),
            1e-10
        ));
        // F(1, d) = t(d)^2.
        let t = 2.228_138_851_986_274;
        assert!(close(f_distribution_sf(t * t, 1.0, 10.0), 0.05, 1e-9));
    }

    #[test]
    fn mad_of_known_residuals() {
        let r = [1.0, -2.0, 3.0, -4.0, 100.0];
        assert!(close(mad_scale(&r), 1.482_602_218_505_602 * 3.0, 1e-15));
    }
}
