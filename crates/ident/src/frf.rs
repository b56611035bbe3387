//! Fitting the pre-motion FRF (paper Eq. 33) from servo force to table displacement:
//!
//! ```text
//! G(s) = 1 / (M s^2 + (sigma1 + sigma2) s + sigma0),   M = m_t + m_b
//! ```
//!
//! **Method (no initial guess).** With `D(jw) = sigma0 - M w^2 + j w c`,
//! `c = sigma1 + sigma2`, complex data give the *relative* equation error
//! `e_k = G_k D(j w_k) - 1`, which is linear in `(sigma0, c, M)`: a bounded
//! least-squares problem (all three >= 0) solved by Clarabel. Unlike fitting
//! `1 / G_k` directly, whose noise grows like `M w^2` above resonance, `e_k` is
//! the relative error of G, so every frequency counts alike. That estimate
//! starts Levenberg-Marquardt on the output error in logarithmic form,
//! `ln G_k - ln G(j w_k) = ln|G_k D| + j arg(G_k D)`, i.e. the magnitude error in
//! nepers and the (wrapped) phase error in radians: the maximum-likelihood
//! criterion for noise on magnitude (dB) and phase (degrees). The parameters are
//! iterated as logarithms, which keeps them positive. A second pass weights the
//! magnitude and phase residuals by their own estimated standard deviations.
//!
//! Magnitude-only data use `1 / |G|^2 = sigma0^2 + (c^2 - 2 sigma0 M) w^2 + M^2 w^4`,
//! linear in its three coefficients (relative weighting again), for the start,
//! and the log-magnitude error for the refinement.
//!
//! The mass is known (`MassOption::Known`, the paper's 1.5 kg) or fitted.
//! `sigma1 = (sigma1 + sigma2) - sigma2` needs sigma2 from the Stribeck fit.
//! A user-supplied start only adds a candidate to the data-derived ones; the
//! candidate with the smallest final error wins.

use fistage_model::LugreParams;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::Complex;
use crate::error::{IdentError, Result};
use crate::linalg::row_major;
use crate::lm::levenberg_marquardt;
use crate::qp::{RegressionLoss, regression};
use crate::stribeck::line_span;
use crate::uncertainty::{Estimate, least_squares_covariance, mad_scale, standard_errors, t95};

/// A measured frequency response from servo force to table displacement, SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfData {
    /// Where the data came from (file name), for messages.
    pub source: String,
    /// Name of the frequency column as written in the file.
    pub frequency_column: String,
    /// Name(s) of the response column(s) as written in the file.
    pub response_column: String,
    /// Angular frequencies, rad/s.
    pub omega: Vec<f64>,
    /// G(j w), m/N (phase 0 when `has_phase` is false).
    pub response: Vec<Complex>,
    /// Whether the phase was measured (complex or magnitude-and-phase data).
    pub has_phase: bool,
    /// Physical line of each point in the file (header = line 1).
    pub lines: Vec<u64>,
}

impl FrfData {
    /// Complex data not read from a file (points on lines 2, 3, ...).
    pub fn new_complex(source: impl Into<String>, omega: Vec<f64>, response: Vec<Complex>) -> Self {
        Self::in_memory(source.into(), omega, response, true)
    }

    /// Magnitude-only data not read from a file (points on lines 2, 3, ...).
    pub fn new_magnitude(source: impl Into<String>, omega: Vec<f64>, magnitude: &[f64]) -> Self {
        let response = magnitude.iter().map(|&m| Complex::new(m, 0.0)).collect();
        Self::in_memory(source.into(), omega, response, false)
    }

    fn in_memory(source: String, omega: Vec<f64>, response: Vec<Complex>, has_phase: bool) -> Self {
        let lines = (0..omega.len() as u64).map(|i| i + 2).collect();
        Self {
            source,
            frequency_column: "frequency".to_string(),
            response_column: "response".to_string(),
            omega,
            response,
            has_phase,
            lines,
        }
    }

    /// Number of frequencies.
    pub fn len(&self) -> usize {
        self.omega.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.omega.is_empty()
    }

    /// The same data without the phase.
    pub fn magnitude_only(&self) -> FrfData {
        FrfData {
            response: self
                .response
                .iter()
                .map(|g| Complex::new(g.norm(), 0.0))
                .collect(),
            has_phase: false,
            ..self.clone()
        }
    }

    /// Checks positive finite frequencies, nonzero finite responses and at least
    /// `n_params + 1` points.
    pub fn check(&self, n_params: usize) -> Result<()> {
        if self.response.len() != self.len() || self.lines.len() != self.len() {
            return Err(IdentError::InvalidOption(format!(
                "{}: {} frequencies but {} responses",
                self.source,
                self.len(),
                self.response.len()
            )));
        }
        for i in 0..self.len() {
            self.check_point(i)?;
        }
        let needed = n_params + 1;
        if self.len() < needed {
            return Err(IdentError::InsufficientData {
                file: self.source.clone(),
                column: self.frequency_column.clone(),
                message: format!(
                    "{} data rows ({}), but fitting {n_params} parameters needs at least {needed} \
                     (one more than the parameters, for the confidence intervals)",
                    self.len(),
                    line_span(&self.lines)
                ),
            });
        }
        Ok(())
    }

    fn check_point(&self, i: usize) -> Result<()> {
        let cell = |column: &str, message: String| IdentError::BadCell {
            file: self.source.clone(),
            line: self.lines[i],
            row: i + 1,
            column: column.to_string(),
            message,
        };
        let w = self.omega[i];
        if !(w > 0.0 && w.is_finite()) {
            return Err(cell(
                &self.frequency_column,
                format!(
                    "frequency must be > 0, got {} rad/s",
                    fistage_model::rule::show(w)
                ),
            ));
        }
        let g = self.response[i];
        if !(g.re.is_finite() && g.im.is_finite()) || g.norm() == 0.0 {
            return Err(cell(
                &self.response_column,
                format!(
                    "response must be finite and nonzero, got {} + {}j m/N",
                    fistage_model::rule::show(g.re),
                    fistage_model::rule::show(g.im)
                ),
            ));
        }
        Ok(())
    }
}

/// How the mass `M = m_t + m_b` enters the fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MassOption {
    /// Known mass, kg.
    Known(f64),
    /// Fitted with sigma0 and sigma1 + sigma2.
    Fit,
}

/// sigma2 from a Stribeck fit, to split sigma1 off the FRF damping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sigma2Input {
    /// sigma2, N s/m.
    pub value: f64,
    /// Its 95% interval, if known (its uncertainty then widens sigma1's).
    pub ci95: Option<[f64; 2]>,
}

/// A starting point for the FRF fit (optional; it adds a candidate).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrfStart {
    /// sigma0, N/m.
    pub sigma0: f64,
    /// sigma1 + sigma2, N s/m.
    pub damping: f64,
    /// M, kg (ignored when the mass is known).
    pub mass: f64,
}

/// Options of an FRF fit. `Default` fits the mass, uses the phase when present.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfOptions {
    /// Known or fitted mass.
    pub mass: MassOption,
    /// sigma2 from the Stribeck fit.
    pub sigma2: Option<Sigma2Input>,
    /// Use the phase when the data have it.
    pub use_phase: bool,
    /// An extra starting candidate.
    pub start: Option<FrfStart>,
}

impl Default for FrfOptions {
    fn default() -> Self {
        Self {
            mass: MassOption::Fit,
            sigma2: None,
            use_phase: true,
            start: None,
        }
    }
}

impl FrfOptions {
    /// Options with a known mass, kg.
    pub fn with_mass(mass: f64) -> Self {
        Self {
            mass: MassOption::Known(mass),
            ..Self::default()
        }
    }

    fn check(&self) -> Result<()> {
        let positive = |name: &str, x: f64| {
            if x > 0.0 && x.is_finite() {
                Ok(())
            } else {
                Err(IdentError::InvalidOption(format!(
                    "{name} must be a positive number, got {}",
                    fistage_model::rule::show(x)
                )))
            }
        };
        if let MassOption::Known(m) = self.mass {
            positive("mass", m)?;
        }
        if let Some(s) = self.sigma2 {
            if !(s.value >= 0.0 && s.value.is_finite()) {
                return Err(IdentError::InvalidOption(format!(
                    "sigma2 must be a number >= 0, got {}",
                    fistage_model::rule::show(s.value)
                )));
            }
            if let Some([lo, hi]) = s.ci95
                && !(lo <= s.value && s.value <= hi && lo.is_finite() && hi.is_finite())
            {
                return Err(IdentError::InvalidOption(format!(
                    "the sigma2 interval [{lo}, {hi}] must contain sigma2 = {}",
                    s.value
                )));
            }
        }
        if let Some(start) = self.start {
            positive("start sigma0", start.sigma0)?;
            positive("start damping", start.damping)?;
            positive("start mass", start.mass)?;
        }
        Ok(())
    }
}

/// Residual statistics of an FRF fit (data minus model).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrfResiduals {
    /// Number of frequencies.
    pub n: usize,
    /// Residual components (2 per frequency with phase, 1 without) minus parameters.
    pub dof: usize,
    /// RMS magnitude error, dB.
    pub rms_magnitude_db: f64,
    /// Largest magnitude error, dB.
    pub max_magnitude_db: f64,
    /// RMS phase error, degrees (fits with phase).
    pub rms_phase_deg: Option<f64>,
    /// Largest phase error, degrees (fits with phase).
    pub max_phase_deg: Option<f64>,
    /// RMS of |G_meas - G_model| / |G_model| (fits with phase).
    pub rms_relative: Option<f64>,
    /// `1 - SSR / SST` of the magnitude in dB.
    pub r_squared_db: f64,
    /// Lines whose magnitude or phase error exceeds 5 robust scales.
    pub suspected_outliers: Vec<u64>,
}

/// A fitted FRF.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrfFit {
    /// Bristle stiffness sigma0, N/m.
    pub sigma0: Estimate,
    /// Pre-motion damping sigma1 + sigma2, N s/m.
    pub damping: Estimate,
    /// Mass M = m_t + m_b, kg (an exact interval when it was given).
    pub mass: Estimate,
    /// Whether the mass was fitted.
    pub mass_fitted: bool,
    /// sigma1 = damping - sigma2, N s/m, when sigma2 was given.
    pub sigma1: Option<Estimate>,
    /// sigma2 as given, N s/m.
    pub sigma2: Option<Estimate>,
    /// Covariance of (sigma0, damping[, mass]), row-major; `None` if singular.
    pub covariance: Option<Vec<f64>>,
    /// Whether the phase was used.
    pub used_phase: bool,
    /// Residual statistics.
    pub residuals: FrfResiduals,
    /// Weights applied to the magnitude (per neper) and phase (per radian) errors.
    pub weights: [f64; 2],
    /// Levenberg-Marquardt iterations, all candidates and passes.
    pub iterations: usize,
}

impl FrfFit {
    /// The fitted G(j omega), m/N.
    pub fn response(&self, omega: f64) -> Complex {
        model_denominator(
            omega,
            self.sigma0.value,
            self.damping.value,
            self.mass.value,
        )
        .inv()
    }

    /// LuGre parameters with sigma0 and, when sigma2 was given, sigma1 replaced.
    pub fn apply_to(&self, base: LugreParams) -> LugreParams {
        LugreParams {
            sigma0: self.sigma0.value,
            sigma1: self.sigma1.map_or(base.sigma1, |s| s.value),
            ..base
        }
    }
}

/// `sigma0 - M w^2 + j w c`.
fn model_denominator(omega: f64, sigma0: f64, damping: f64, mass: f64) -> Complex {
    Complex::new(sigma0 - mass * omega * omega, omega * damping)
}

/// Fits sigma0, sigma1 + sigma2 (and M) to an FRF.
pub fn fit_frf(data: &FrfData, options: &FrfOptions) -> Result<FrfFit> {
    options.check()?;
    let n_params = match options.mass {
        MassOption::Known(_) => 2,
        MassOption::Fit => 3,
    };
    data.check(n_params)?;
    let use_phase = data.has_phase && options.use_phase;
    if use_phase {
        check_phase_convention(data)?;
    }
    let problem = Problem {
        omega: &data.omega,
        response: &data.response,
        use_phase,
        known_mass: match options.mass {
            MassOption::Known(m) => Some(m),
            MassOption::Fit => None,
        },
    };
    let mut candidates = vec![
        problem.linear_estimate(&data.source)?,
        problem.heuristic_start(),
    ];
    if let Some(s) = options.start {
        candidates.push([s.sigma0, s.damping, problem.known_mass.unwrap_or(s.mass)]);
    }
    let mut weights = [1.0, 1.0];
    let mut iterations = 0;
    let mut best: Option<(f64, Vec<f64>)> = None;
    for candidate in &candidates {
        let (q, ssr, its) = problem.refine(&problem.to_log(candidate), weights);
        iterations += its;
        if best.as_ref().is_none_or(|(b, _)| ssr < *b) {
            best = Some((ssr, q));
        }
    }
    let Some((_, mut q)) = best else {
        return Err(IdentError::Solver {
            file: data.source.clone(),
            message: "no starting point".to_string(),
        });
    };
    if problem.use_phase
        && let Some(w) = problem.balanced_weights(&q)
    {
        weights = w;
        let (refined, _, its) = problem.refine(&q, weights);
        iterations += its;
        q = refined;
    }
    if !problem
        .natural(&q)
        .iter()
        .all(|v| v.is_finite() && *v > 0.0)
    {
        return Err(IdentError::Solver {
            file: data.source.clone(),
            message: "the FRF fit did not converge to finite parameters".to_string(),
        });
    }
    Ok(problem.build_fit(data, &q, weights, options.sigma2, iterations))
}

/// A mass-spring-damper lags: its phase lies between 0 and -180 degrees, so
/// `sin(arg G) < 0` at every frequency (clearly so near resonance, within the
/// noise far from it). Data whose phase leads on balance were exported with
/// the opposite sign convention.
fn check_phase_convention(data: &FrfData) -> Result<()> {
    let balance: f64 = data.response.iter().map(|g| g.im / g.norm()).sum();
    if balance > 0.0 {
        let leading = data.response.iter().filter(|g| g.im > 0.0).count();
        return Err(IdentError::InsufficientData {
            file: data.source.clone(),
            column: data.response_column.clone(),
            message: format!(
                "the phase leads (is positive) at {leading} of {} frequencies, but the stage's \
                 response lags (0 to -180 degrees): negate the phase if the analyser uses the \
                 opposite sign convention, or fit the magnitude only (--magnitude-only)",
                data.len()
            ),
        });
    }
    Ok(())
}

/// The data and the fixed settings of one FRF fit.
struct Problem<'a> {
    omega: &'a [f64],
    response: &'a [Complex],
    use_phase: bool,
    known_mass: Option<f64>,
}

impl Problem<'_> {
    fn n_params(&self) -> usize {
        if self.known_mass.is_some() { 2 } else { 3 }
    }

    /// (sigma0, damping, mass) from the log parameters.
    fn natural(&self, q: &[f64]) -> [f64; 3] {
        let mass = self.known_mass.unwrap_or_else(|| q[2].exp());
        [q[0].exp(), q[1].exp(), mass]
    }

    fn to_log(&self, p: &[f64; 3]) -> Vec<f64> {
        let mut q = vec![p[0].ln(), p[1].ln()];
        if self.known_mass.is_none() {
            q.push(p[2].ln());
        }
        q
    }

    /// Bounded linear estimate from the relative equation error (complex data)
    /// or from the polynomial in w^2 of 1/|G|^2 (magnitude data), made usable
    /// as a start where a parameter came out at its bound.
    fn linear_estimate(&self, source: &str) -> Result<[f64; 3]> {
        let solver_error = |message: String| IdentError::Solver {
            file: source.to_string(),
            message,
        };
        let estimate = if self.use_phase {
            self.complex_linear_estimate().map_err(solver_error)?
        } else {
            self.magnitude_linear_estimate().map_err(solver_error)?
        };
        let fallback = self.heuristic_start();
        let mut out = [0.0; 3];
        for k in 0..3 {
            out[k] = if estimate[k] > 0.0 && estimate[k].is_finite() {
                estimate[k]
            } else {
                fallback[k]
            };
        }
        Ok(out)
    }

    fn complex_linear_estimate(&self) -> std::result::Result<[f64; 3], String> {
        let n = self.omega.len();
        let cols = self.n_params();
        let mut a = DMatrix::zeros(2 * n, cols);
        let mut y = vec![0.0; 2 * n];
        for (k, (&w, &g)) in self.omega.iter().zip(self.response).enumerate() {
            // G (sigma0 + j w c - M w^2) = 1, split into real and imaginary rows.
            let (re, im) = (2 * k, 2 * k + 1);
            a[(re, 0)] = g.re;
            a[(re, 1)] = -g.im * w;
            a[(im, 0)] = g.im;
            a[(im, 1)] = g.re * w;
            y[re] = 1.0;
            match self.known_mass {
                Some(m) => {
                    y[re] += g.re * m * w * w;
                    y[im] += g.im * m * w * w;
                }
                None => {
                    a[(re, 2)] = -g.re * w * w;
                    a[(im, 2)] = -g.im * w * w;
                }
            }
        }
        let x = regression(&a, &y, &vec![true; cols], RegressionLoss::L2)?;
        Ok([x[0], x[1], self.known_mass.unwrap_or_else(|| x[2])])
    }

    fn magnitude_linear_estimate(&self) -> std::result::Result<[f64; 3], String> {
        // (alpha + beta w^2 + gamma w^4) |G|^2 = 1 with alpha = sigma0^2,
        // beta = c^2 - 2 sigma0 M, gamma = M^2.
        let cols = self.n_params();
        let mut a = DMatrix::zeros(self.omega.len(), cols);
        let mut y = vec![1.0; self.omega.len()];
        for (k, (&w, &g)) in self.omega.iter().zip(self.response).enumerate() {
            let g2 = g.norm_sqr();
            a[(k, 0)] = g2;
            a[(k, 1)] = g2 * w * w;
            match self.known_mass {
                Some(m) => y[k] -= m * m * w.powi(4) * g2,
                None => a[(k, 2)] = g2 * w.powi(4),
            }
        }
        let nonnegative = [true, false, true];
        let x = regression(&a, &y, &nonnegative[..cols], RegressionLoss::L2)?;
        let sigma0 = x[0].sqrt();
        let mass = self.known_mass.unwrap_or_else(|| x[2].sqrt());
        let c2 = x[1] + 2.0 * sigma0 * mass;
        Ok([sigma0, if c2 > 0.0 { c2.sqrt() } else { 0.0 }, mass])
    }

    /// A start read off the data: static compliance at the lowest frequency,
    /// mass line at the highest, damping from the peak.
    fn heuristic_start(&self) -> [f64; 3] {
        let index_of = |better: fn(f64, f64) -> bool, values: &[f64]| {
            (0..values.len()).fold(0, |best, k| {
                if better(values[k], values[best]) {
                    k
                } else {
                    best
                }
            })
        };
        let magnitudes: Vec<f64> = self.response.iter().map(|g| g.norm()).collect();
        let low = index_of(|a, b| a < b, self.omega);
        let high = index_of(|a, b| a > b, self.omega);
        let peak = index_of(|a, b| a > b, &magnitudes);
        let sigma0 = 1.0 / self.response[low].norm();
        let w_high = self.omega[high];
        let mass = self
            .known_mass
            .unwrap_or_else(|| 1.0 / (self.response[high].norm() * w_high * w_high));
        let damping = 1.0 / (self.response[peak].norm() * self.omega[peak]);
        [sigma0, damping, mass]
    }

    /// Levenberg-Marquardt on the weighted log error from `q0`; returns the log
    /// parameters, the sum of squares and the iterations.
    fn refine(&self, q0: &[f64], weights: [f64; 2]) -> (Vec<f64>, f64, usize) {
        let outcome = levenberg_marquardt(
            q0,
            |q, r| self.residuals(q, weights, r),
            |q, j| self.jacobian(q, weights, j),
            200,
        );
        (outcome.params, outcome.ssr, outcome.iterations)
    }

    /// Weighted `ln|G_k D_k|` (and `arg(G_k D_k)`), i.e. data minus model in log form.
    fn residuals(&self, q: &[f64], weights: [f64; 2], r: &mut Vec<f64>) {
        let [sigma0, damping, mass] = self.natural(q);
        r.clear();
        for (&w, &g) in self.omega.iter().zip(self.response) {
            let p = g * model_denominator(w, sigma0, damping, mass);
            r.push(weights[0] * p.norm().ln());
            if self.use_phase {
                r.push(weights[1] * p.arg());
            }
        }
    }

    fn jacobian(&self, q: &[f64], weights: [f64; 2], j: &mut DMatrix<f64>) {
        let [sigma0, damping, mass] = self.natural(q);
        let rows_per_point = if self.use_phase { 2 } else { 1 };
        for (k, &w) in self.omega.iter().enumerate() {
            let d = model_denominator(w, sigma0, damping, mass);
            let partials = [
                Complex::new(sigma0, 0.0),
                Complex::new(0.0, w * damping),
                Complex::new(-mass * w * w, 0.0),
            ];
            for (col, dd) in partials.iter().take(self.n_params()).enumerate() {
                let ratio = *dd / d;
                j[(rows_per_point * k, col)] = weights[0] * ratio.re;
                if self.use_phase {
                    j[(rows_per_point * k + 1, col)] = weights[1] * ratio.im;
                }
            }
        }
    }

    /// Weights 1/sd for magnitude and phase errors (geometric mean 1), from the
    /// unweighted residuals at `q`; `None` when the residuals are negligible.
    fn balanced_weights(&self, q: &[f64]) -> Option<[f64; 2]> {
        let mut r = Vec::new();
        self.residuals(q, [1.0, 1.0], &mut r);
        let n = self.omega.len() as f64;
        let var_mag = r.iter().step_by(2).map(|x| x * x).sum::<f64>() / n;
        let var_phase = r.iter().skip(1).step_by(2).map(|x| x * x).sum::<f64>() / n;
        if !(var_mag > 1e-24 && var_phase > 1e-24) {
            return None;
        }
        let (sd_mag, sd_phase) = (var_mag.sqrt(), var_phase.sqrt());
        let mean = (sd_mag * sd_phase).sqrt();
        Some([mean / sd_mag, mean / sd_phase])
    }

    fn build_fit(
        &self,
        data: &FrfData,
        q: &[f64],
        weights: [f64; 2],
        sigma2: Option<Sigma2Input>,
        iterations: usize,
    ) -> FrfFit {
        let p = self.n_params();
        let natural = self.natural(q);
        let mut r = Vec::new();
        self.residuals(q, weights, &mut r);
        let mut j = DMatrix::zeros(r.len(), p);
        self.jacobian(q, weights, &mut j);
        // From d/d(ln x) to d/dx.
        for (mut col, value) in j.column_iter_mut().zip(&natural) {
            col /= *value;
        }
        let covariance = least_squares_covariance(&j, &r);
        let errors = standard_errors(p, covariance.as_ref());
        let dof = r.len() - p;
        let t = t95(dof as f64);
        let sigma0 = Estimate::new(natural[0], errors[0], t, 0.0);
        let damping = Estimate::new(natural[1], errors[1], t, 0.0);
        let mass = match self.known_mass {
            Some(m) => Estimate::exact(m),
            None => Estimate::new(natural[2], errors[2], t, 0.0),
        };
        let sigma2_estimate = sigma2.map(sigma2_as_estimate);
        let sigma1 = sigma2_estimate.map(|s2| subtract(&damping, &s2));
        FrfFit {
            sigma0,
            damping,
            mass,
            mass_fitted: self.known_mass.is_none(),
            sigma1,
            sigma2: sigma2_estimate,
            covariance: covariance.as_ref().map(row_major),
            used_phase: self.use_phase,
            residuals: self.residual_stats(data, q, dof),
            weights,
            iterations,
        }
    }

    fn residual_stats(&self, data: &FrfData, q: &[f64], dof: usize) -> FrfResiduals {
        let [sigma0, damping, mass] = self.natural(q);
        let db_per_neper = 20.0 / std::f64::consts::LN_10;
        let mut mag_db = Vec::with_capacity(self.omega.len());
        let mut phase_deg = Vec::with_capacity(self.omega.len());
        let mut relative = Vec::with_capacity(self.omega.len());
        for (&w, &g) in self.omega.iter().zip(self.response) {
            let d = model_denominator(w, sigma0, damping, mass);
            let p = g * d;
            mag_db.push(db_per_neper * p.norm().ln());
            phase_deg.push(p.arg().to_degrees());
            relative.push((p - Complex::new(1.0, 0.0)).norm());
        }
        let rms = |x: &[f64]| (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt();
        let max_abs = |x: &[f64]| x.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let measured_db: Vec<f64> = self
            .response
            .iter()
            .map(|g| db_per_neper * g.norm().ln())
            .collect();
        let mean_db = measured_db.iter().sum::<f64>() / measured_db.len() as f64;
        let sst: f64 = measured_db.iter().map(|v| (v - mean_db).powi(2)).sum();
        let ssr: f64 = mag_db.iter().map(|v| v * v).sum();
        let mut suspected = outlier_lines(&mag_db, &data.lines);
        if self.use_phase {
            suspected.extend(outlier_lines(&phase_deg, &data.lines));
            suspected.sort_unstable();
            suspected.dedup();
        }
        FrfResiduals {
            n: self.omega.len(),
            dof,
            rms_magnitude_db: rms(&mag_db),
            max_magnitude_db: max_abs(&mag_db),
            rms_phase_deg: self.use_phase.then(|| rms(&phase_deg)),
            max_phase_deg: self.use_phase.then(|| max_abs(&phase_deg)),
            rms_relative: self.use_phase.then(|| rms(&relative)),
            r_squared_db: if sst > 0.0 { 1.0 - ssr / sst } else { f64::NAN },
            suspected_outliers: suspected,
        }
    }
}

fn outlier_lines(residuals: &[f64], lines: &[u64]) -> Vec<u64> {
    let scale = mad_scale(residuals);
    residuals
        .iter()
        .zip(lines)
        .filter(|(r, _)| scale > 0.0 && r.abs() > 5.0 * scale)
        .map(|(_, &l)| l)
        .collect()
}

/// sigma2 as an estimate: its interval as given (standard error = half-width / 1.96).
fn sigma2_as_estimate(s: Sigma2Input) -> Estimate {
    match s.ci95 {
        Some([lo, hi]) => {
            let half = 0.5 * (hi - lo);
            Estimate {
                value: s.value,
                std_error: Some(half / 1.959_963_984_540_054),
                ci95: Some([lo, hi]),
            }
        }
        None => Estimate::exact(s.value),
    }
}

/// `a - b` for independent estimates: half-widths added in quadrature.
fn subtract(a: &Estimate, b: &Estimate) -> Estimate {
    let value = a.value - b.value;
    let std_error = match (a.std_error, b.std_error) {
        (Some(x), Some(y)) => Some(x.hypot(y)),
        _ => None,
    };
    let ci95 = match (a.half_width(), b.half_width()) {
        (Some(x), Some(y)) => {
            let half = x.hypot(y);
            Some([value - half, value + half])
        }
        _ => None,
    };
    Estimate {
        value,
        std_error,
        ci95,
    }
}
