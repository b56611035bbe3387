//! First estimates from the record itself, so that no guess is asked of the
//! user:
//!
//! 1. velocity and acceleration from the encoder by Savitzky-Golay
//!    differentiation over about a millisecond, and the friction force
//!    `F = f - M a` the stage felt;
//! 2. from steady sliding (one sign of velocity, well above the encoder's
//!    velocity noise, for a few milliseconds), the Stribeck curve
//!    `F = sgn(v) (f_c + (f_s - f_c) exp(-(v/v_s)^2)) + sigma2 v` (and the
//!    mass `M a` with it when the mass is free): linear least squares for
//!    each v_s, v_s by a one-dimensional search;
//! 3. from the presliding stretches (|F| well below f_c, the contact a
//!    spring and damper on its rest point), `F = sigma0 (x - x_rest) +
//!    (sigma1 + sigma2) v` by least squares, one rest point per stretch.
//!
//! The full nonlinear fit then starts here ([`super::fit`]).

use fistage_model::LugreParams;
use fistage_model::eigen::svd;
use nalgebra::{DMatrix, DVector};

use super::data::Record;
use super::plant::{RecordParam, Theta};
use crate::error::{IdentError, Result};
use crate::lm::brent_minimize;

/// The first estimates and how they were found.
#[derive(Debug, Clone, PartialEq)]
pub struct StartEstimate {
    /// The parameters.
    pub theta: Theta,
    /// Sliding samples used for the Stribeck curve.
    pub sliding_samples: usize,
    /// Presliding samples used for sigma0 and the damping.
    pub presliding_samples: usize,
    /// What could not be estimated from the record and was set by a rule
    /// instead, for the report.
    pub notes: Vec<String>,
    /// The parameters set by a rule (a floor, a default ratio) rather than
    /// estimated: the fit does not hold them near their start.
    pub ruled: Vec<RecordParam>,
}

/// Derivatives of the encoder signal.
pub(crate) struct Derivatives {
    /// Velocity, m/s (NaN outside the window).
    pub velocity: Vec<f64>,
    /// Acceleration, m/s^2 (NaN outside the window).
    pub acceleration: Vec<f64>,
    /// The force averaged over the window, N.
    pub force: Vec<f64>,
    /// Velocity below which motion is not told from encoder noise, m/s.
    pub velocity_noise: f64,
    /// The encoder's step (its quantisation), m.
    pub quantum: f64,
}

/// Savitzky-Golay (quadratic) derivatives over a window of about 1 ms.
pub(crate) fn derivatives(record: &Record) -> Derivatives {
    let n = record.len();
    let dt = record.sample_interval();
    let w = ((0.5e-3 / dt).round() as usize).clamp(2, (n / 4).max(2));
    let wf = w as f64;
    let sum_i2: f64 = (1..=w).map(|i| 2.0 * (i * i) as f64).sum();
    let mean_i2 = wf * (wf + 1.0) / 3.0;
    let sum_c2: f64 = (-(w as i64)..=w as i64)
        .map(|i| ((i * i) as f64 - mean_i2).powi(2))
        .sum();
    let mut velocity = vec![f64::NAN; n];
    let mut acceleration = vec![f64::NAN; n];
    let mut force = vec![f64::NAN; n];
    let x = &record.position;
    for k in w..n.saturating_sub(w) {
        let (mut s1, mut s2, mut sf) = (0.0, 0.0, 0.0);
        for i in -(w as i64)..=w as i64 {
            let xi = x[(k as i64 + i) as usize] - x[k];
            s1 += i as f64 * xi;
            s2 += ((i * i) as f64 - mean_i2) * xi;
        }
        for f in &record.force[k - w..k + w] {
            sf += f;
        }
        velocity[k] = s1 / (sum_i2 * dt);
        acceleration[k] = 2.0 * s2 / (sum_c2 * dt * dt);
        force[k] = sf / (2 * w) as f64;
    }
    let quantum = encoder_quantum(x).unwrap_or(1e-9);
    Derivatives {
        velocity,
        acceleration,
        force,
        velocity_noise: 20.0 * quantum / (wf * dt),
        quantum,
    }
}

/// The smallest step between distinct encoder readings (the quantisation),
/// from the differences of neighbouring samples.
fn encoder_quantum(x: &[f64]) -> Option<f64> {
    let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-12);
    x.windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|&d| d > 1e-12 * scale)
        .fold(None, |m: Option<f64>, d| Some(m.map_or(d, |m| m.min(d))))
}

/// First estimates of all seven parameters; `mass` when it is known.
pub fn estimate_start(record: &Record, mass: Option<f64>) -> Result<StartEstimate> {
    let d = derivatives(record);
    let dt = record.sample_interval();
    let sliding = steady_sliding(&d, (3e-3 / dt).round() as usize);
    if sliding.len() < 20 {
        return Err(IdentError::InsufficientData {
            file: record.source.clone(),
            column: record.columns[2].clone(),
            message: format!(
                "{} samples of steady sliding (|v| above {:.2e} m/s for 3 ms); f_c, f_s, v_s and \
                 sigma2 cannot be determined: the record needs motion beyond breakaway",
                sliding.len(),
                d.velocity_noise
            ),
        });
    }
    // Pass 1: the faster half of the sliding samples, far above any Stribeck
    // velocity, give f_c, sigma2 and the mass; pass 2: presliding gives
    // sigma0 and so the presliding distance f_c / sigma0; pass 3: samples
    // that have slid several presliding distances since their last reversal
    // give the whole curve.
    let mut speeds: Vec<f64> = sliding.iter().map(|&k| d.velocity[k].abs()).collect();
    let mid = speeds.len() / 2;
    speeds.select_nth_unstable_by(mid, f64::total_cmp);
    let median_speed = speeds[mid];
    let fast: Vec<usize> = sliding
        .iter()
        .copied()
        .filter(|&k| d.velocity[k].abs() >= median_speed)
        .collect();
    let coarse = curve_at(&d, &thin(&fast), 1e-300, mass).1;
    let min_stretch = (20e-3 / dt) as usize;
    let mut notes = Vec::new();
    let mut ruled = Vec::new();
    let presliding = presliding_samples(&d, coarse.f_c, coarse.mass, min_stretch);
    let presliding_fit = fit_presliding(record, &d, &presliding, coarse.mass);
    let travel = displacement_since_reversal(&d, &record.position);
    let reach = presliding_fit.map_or(0.0, |(sigma0, _)| 3.0 * coarse.f_c / sigma0);
    let slid: Vec<usize> = sliding
        .iter()
        .copied()
        .filter(|&k| travel[k] >= reach)
        .collect();
    let stribeck = fit_curve(
        &d,
        &thin(if slid.len() >= 20 { &slid } else { &sliding }),
        mass,
    );
    let presliding = presliding_samples(&d, stribeck.f_c, stribeck.mass, min_stretch);
    let (sigma0, damping) = match fit_presliding(record, &d, &presliding, stribeck.mass) {
        Some(fit) => fit,
        None => {
            notes.push(
                "no presliding stretch to estimate sigma0 and the damping from; started from \
                 sigma0 = f_c / 2 um and a damping ratio of 0.1"
                    .to_string(),
            );
            ruled.push(RecordParam::Sigma0);
            (stribeck.f_c / 2e-6, f64::NAN)
        }
    };
    let critical = 2.0 * (sigma0 * stribeck.mass).sqrt();
    let sigma1 = if damping.is_finite() && damping > stribeck.sigma2 + 0.02 * critical {
        damping - stribeck.sigma2
    } else {
        if damping.is_finite() {
            notes.push(format!(
                "the presliding damping {damping:.3e} N s/m does not exceed sigma2; sigma1 \
                 started from a damping ratio of 0.1"
            ));
        }
        ruled.push(RecordParam::Sigma1);
        0.1 * critical
    };
    let sigma2_floor = 1e-6 * critical;
    if stribeck.sigma2 <= sigma2_floor {
        ruled.push(RecordParam::Sigma2);
    }
    let lugre = LugreParams {
        sigma0,
        sigma1,
        sigma2: stribeck.sigma2.max(sigma2_floor),
        f_c: stribeck.f_c,
        f_s: stribeck.f_s,
        v_s: stribeck.v_s,
    };
    Ok(StartEstimate {
        theta: Theta::new(&lugre, stribeck.mass),
        sliding_samples: sliding.len(),
        presliding_samples: presliding.len(),
        notes,
        ruled,
    })
}

/// At most 10 000 of `samples`, evenly spread.
fn thin(samples: &[usize]) -> Vec<usize> {
    let step = samples.len().div_ceil(10_000).max(1);
    samples.iter().copied().step_by(step).collect()
}

/// |x_k - x_r| with r the last sample before k where the velocity changed sign.
fn displacement_since_reversal(d: &Derivatives, position: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; position.len()];
    let mut origin = position.first().copied().unwrap_or(0.0);
    let mut sign = 0.0;
    for (k, &v) in d.velocity.iter().enumerate() {
        if v.is_finite() && v != 0.0 && v.signum() != sign {
            sign = v.signum();
            origin = position[k];
        }
        out[k] = (position[k] - origin).abs();
    }
    out
}

/// Samples that have slid with one sign of velocity, above the noise, for
/// the last `hold` samples.
fn steady_sliding(d: &Derivatives, hold: usize) -> Vec<usize> {
    let mut out = Vec::new();
    let mut run = 0usize;
    let mut sign = 0.0;
    for (k, &v) in d.velocity.iter().enumerate() {
        let s = if v.abs() > d.velocity_noise {
            v.signum()
        } else {
            0.0
        };
        run = if s != 0.0 && s == sign { run + 1 } else { 0 };
        sign = s;
        if run >= hold && d.acceleration[k].is_finite() {
            out.push(k);
        }
    }
    out
}

/// The Stribeck curve and mass from sliding samples.
#[derive(Debug, Clone, Copy)]
struct Curve {
    f_c: f64,
    f_s: f64,
    v_s: f64,
    sigma2: f64,
    mass: f64,
}

/// Robust least squares of `f = M a + sgn(v) (f_c + df exp(-(v/v_s)^2)) +
/// sigma2 v` at fixed v_s. Some samples that pass for steady sliding are
/// not (presliding in a fast small chirp, relaxation after a stop), so the
/// fit is trimmed: samples further than 2.5 robust scales from the fit are
/// dropped and the rest refitted, five times. Coefficients that come out
/// negative are set to zero and the rest refitted. Returns the trimmed
/// mean square and the curve.
fn curve_at(d: &Derivatives, samples: &[usize], v_s: f64, mass: Option<f64>) -> (f64, Curve) {
    let row = |k: usize| {
        let (v, acc) = (d.velocity[k], d.acceleration[k]);
        let full = [acc, v.signum(), v.signum() * (-(v / v_s).powi(2)).exp(), v];
        (full, d.force[k] - mass.map_or(0.0, |m| m * acc))
    };
    let mut keep = vec![true; samples.len()];
    let mut coef = [mass.unwrap_or(0.0), 0.0, 0.0, 0.0];
    let mut mean_square = f64::INFINITY;
    for _ in 0..5 {
        coef = constrained_solve(samples, &keep, &row, mass.is_none(), coef[0]);
        let residuals: Vec<f64> = samples
            .iter()
            .map(|&k| {
                let (a, b) = row(k);
                (0..4).map(|c| a[c] * coef[c]).sum::<f64>() - b
            })
            .collect();
        let kept: Vec<f64> = residuals
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(r, _)| *r)
            .collect();
        let scale = crate::uncertainty::mad_scale(&kept).max(1e-300);
        mean_square = kept.iter().map(|r| r * r).sum::<f64>() / kept.len().max(1) as f64;
        for (flag, r) in keep.iter_mut().zip(&residuals) {
            *flag = r.abs() <= 2.5 * scale;
        }
    }
    let f_c = coef[1].max(1e-12);
    (
        mean_square,
        Curve {
            f_c,
            f_s: f_c + coef[2],
            v_s,
            sigma2: coef[3],
            mass: coef[0],
        },
    )
}

/// Normal-equation least squares over the kept samples with the mass column
/// when `free_mass`; a negative mass, df or sigma2 is set to zero and the
/// rest refitted.
fn constrained_solve(
    samples: &[usize],
    keep: &[bool],
    row: &dyn Fn(usize) -> ([f64; 4], f64),
    free_mass: bool,
    mass: f64,
) -> [f64; 4] {
    let mut active = [free_mass, true, true, true];
    loop {
        let columns: Vec<usize> = (0..4).filter(|&c| active[c]).collect();
        let p = columns.len();
        let mut h = DMatrix::<f64>::zeros(p, p);
        let mut g = DVector::<f64>::zeros(p);
        for (&k, _) in samples.iter().zip(keep).filter(|(_, k)| **k) {
            let (a, b) = row(k);
            for (i, &ci) in columns.iter().enumerate() {
                g[i] += a[ci] * b;
                for (j, &cj) in columns.iter().enumerate() {
                    h[(i, j)] += a[ci] * a[cj];
                }
            }
        }
        let solution = svd(h, true, true)
            .and_then(|svd| svd.solve(&g, 1e-13).ok())
            .unwrap_or_else(|| DVector::zeros(p));
        let mut coef = [if free_mass { 0.0 } else { mass }, 0.0, 0.0, 0.0];
        for (j, &c) in columns.iter().enumerate() {
            coef[c] = solution[j];
        }
        match (0..4).find(|&c| active[c] && c != 1 && coef[c] < 0.0) {
            Some(c) => active[c] = false,
            None => return coef,
        }
    }
}

/// The best curve over v_s (log-spaced scan, then Brent on the bracket).
fn fit_curve(d: &Derivatives, samples: &[usize], mass: Option<f64>) -> Curve {
    let speeds = samples.iter().map(|&k| d.velocity[k].abs());
    let v_max = speeds.clone().fold(0.0, f64::max);
    let v_min = speeds.fold(f64::INFINITY, f64::min).max(1e-9);
    let (lo, hi) = ((0.3 * v_min).ln(), (2.0 * v_max).ln());
    let cost = |ln_v: f64| curve_at(d, samples, ln_v.exp(), mass).0;
    let grid = 30;
    let points: Vec<(f64, f64)> = (0..=grid)
        .map(|i| {
            let x = lo + (hi - lo) * i as f64 / grid as f64;
            (x, cost(x))
        })
        .collect();
    let best = (0..points.len())
        .min_by(|&a, &b| points[a].1.total_cmp(&points[b].1))
        .unwrap_or(0);
    let a = points[best.saturating_sub(1)].0;
    let b = points[(best + 1).min(grid)].0;
    let ln_v = brent_minimize(|x| Ok::<f64, ()>(cost(x)), a, b, 1e-4, 60)
        .map(|m| m.x)
        .unwrap_or(points[best].0);
    let mut curve = curve_at(d, samples, ln_v.exp(), mass).1;
    if !(curve.mass.is_finite() && curve.mass > 0.0) {
        curve.mass = mass.unwrap_or(1.0);
    }
    curve
}

/// Stretches of at least `min_len` samples with the friction force below
/// 0.8 f_c throughout, and of those the samples below 0.4 f_c: the contact
/// is then nearly the linear spring of presliding.
fn presliding_samples(d: &Derivatives, f_c: f64, mass: f64, min_len: usize) -> Vec<Vec<usize>> {
    let friction = |k: usize| d.force[k] - mass * d.acceleration[k];
    let mut stretches = Vec::new();
    let mut current: Vec<usize> = Vec::new();
    let mut length = 0;
    for k in 0..d.velocity.len() {
        let f = friction(k);
        if f.is_finite() && f.abs() < 0.8 * f_c {
            length += 1;
            if f.abs() < 0.4 * f_c {
                current.push(k);
            }
        } else {
            if length >= min_len && current.len() >= 10 {
                stretches.push(std::mem::take(&mut current));
            }
            current.clear();
            length = 0;
        }
    }
    if length >= min_len && current.len() >= 10 {
        stretches.push(current);
    }
    stretches
}

/// `F - mean = sigma0 (x - mean) + c (v - mean)` over the stretches that
/// move more than a few encoder steps. Returns (sigma0, c).
fn fit_presliding(
    record: &Record,
    d: &Derivatives,
    stretches: &[Vec<usize>],
    mass: f64,
) -> Option<(f64, f64)> {
    let mut rows: Vec<[f64; 3]> = Vec::new();
    for stretch in stretches {
        let xs: Vec<f64> = stretch.iter().map(|&k| record.position[k]).collect();
        let (lo, hi) = xs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        if hi - lo < 10.0 * d.quantum {
            continue;
        }
        let len = stretch.len() as f64;
        let mean = |f: &dyn Fn(usize) -> f64| stretch.iter().map(|&k| f(k)).sum::<f64>() / len;
        let friction = |k: usize| d.force[k] - mass * d.acceleration[k];
        let (mf, mx, mv) = (
            mean(&friction),
            mean(&|k| record.position[k]),
            mean(&|k| d.velocity[k]),
        );
        for &k in stretch {
            rows.push([
                friction(k) - mf,
                record.position[k] - mx,
                d.velocity[k] - mv,
            ]);
        }
    }
    if rows.len() < 10 {
        return None;
    }
    let a = DMatrix::from_fn(rows.len(), 2, |i, j| rows[i][j + 1]);
    let b = DVector::from_iterator(rows.len(), rows.iter().map(|r| r[0]));
    let solution = svd(a, true, true)?.solve(&b, 1e-12).ok()?;
    let (sigma0, c) = (solution[0], solution[1]);
    (sigma0.is_finite() && sigma0 > 0.0).then_some((sigma0, c))
}
