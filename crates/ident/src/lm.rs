//! Levenberg-Marquardt for small nonlinear least-squares problems, and Brent's
//! derivative-free minimiser for one variable.

use nalgebra::DMatrix;

use crate::linalg::least_squares;

/// Result of a Levenberg-Marquardt run.
#[derive(Debug, Clone)]
pub(crate) struct LmOutcome {
    pub params: Vec<f64>,
    pub ssr: f64,
    pub iterations: usize,
}

/// Minimises `|r(p)|^2` from `start`. `residuals(p, r)` fills r; `jacobian(p, J)`
/// fills dr/dp. Each step solves the damped problem
/// `[J; sqrt(lambda) D] dp = [-r; 0]` (D the column norms of J) by QR.
pub(crate) fn levenberg_marquardt(
    start: &[f64],
    mut residuals: impl FnMut(&[f64], &mut Vec<f64>),
    mut jacobian: impl FnMut(&[f64], &mut DMatrix<f64>),
    max_iterations: usize,
) -> LmOutcome {
    let p_len = start.len();
    let mut params = start.to_vec();
    let mut r = Vec::new();
    residuals(&params, &mut r);
    let mut ssr = sum_of_squares(&r);
    if !ssr.is_finite() {
        return LmOutcome {
            params,
            ssr,
            iterations: 0,
        };
    }
    let m = r.len();
    let mut jac = DMatrix::zeros(m, p_len);
    let mut lambda: f64 = 1e-3;
    let mut trial_r = Vec::new();
    let mut iterations = 0;
    while iterations < max_iterations && ssr > 0.0 {
        iterations += 1;
        jacobian(&params, &mut jac);
        let mut augmented = DMatrix::zeros(m + p_len, p_len);
        augmented.rows_mut(0, m).copy_from(&jac);
        for (j, c) in jac.column_iter().enumerate() {
            augmented[(m + j, j)] = lambda.sqrt() * c.norm().max(1e-300);
        }
        let mut rhs: Vec<f64> = r.iter().map(|v| -v).collect();
        rhs.resize(m + p_len, 0.0);
        let Some(step) = least_squares(&augmented, &rhs) else {
            lambda *= 10.0;
            if lambda > 1e16 {
                break;
            }
            continue;
        };
        let trial: Vec<f64> = params.iter().zip(&step).map(|(p, d)| p + d).collect();
        residuals(&trial, &mut trial_r);
        let trial_ssr = sum_of_squares(&trial_r);
        if trial_ssr.is_finite() && trial_ssr < ssr {
            let decrease = ssr - trial_ssr;
            let step_size = step.iter().map(|d| d * d).sum::<f64>().sqrt();
            let size = params.iter().map(|p| p * p).sum::<f64>().sqrt();
            params = trial;
            std::mem::swap(&mut r, &mut trial_r);
            ssr = trial_ssr;
            lambda = (lambda / 3.0).max(1e-15);
            if step_size <= 1e-14 * (1.0 + size) || decrease <= 1e-15 * ssr {
                break;
            }
        } else {
            lambda *= 4.0;
            if lambda > 1e16 {
                break;
            }
        }
    }
    LmOutcome {
        params,
        ssr,
        iterations,
    }
}

fn sum_of_squares(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// Result of a one-dimensional minimisation.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Minimum {
    pub x: f64,
    pub value: f64,
}

/// Brent's method on `[a, b]`: golden-section steps with parabolic interpolation
/// where it is safe, until the bracket is narrower than about `4 tol`
/// (absolute). The function may fail; the first failure is returned.
pub(crate) fn brent_minimize<E>(
    mut f: impl FnMut(f64) -> Result<f64, E>,
    a: f64,
    b: f64,
    tol: f64,
    max_iterations: usize,
) -> Result<Minimum, E> {
    const GOLDEN: f64 = 0.381_966_011_250_105_1;
    let (mut lo, mut hi) = (a.min(b), a.max(b));
    let mut x = lo + GOLDEN * (hi - lo);
    let mut fx = f(x)?;
    let (mut w, mut fw, mut v, mut fv) = (x, fx, x, fx);
    let (mut step, mut previous_step) = (0.0f64, 0.0f64);
    for _ in 0..max_iterations {
        let mid = 0.5 * (lo + hi);
        let tol2 = 2.0 * tol;
        if (x - mid).abs() <= tol2 - 0.5 * (hi - lo) {
            break;
        }
        let golden_step = |x: f64| if x >= mid { lo - x } else { hi - x };
        let mut use_golden = true;
        if previous_step.abs() > tol {
            // Parabola through (v, fv), (w, fw), (x, fx).
            let r = (x - w) * (fx - fv);
            let q0 = (x - v) * (fx - fw);
            let mut p = (x - v) * q0 - (x - w) * r;
            let mut q = 2.0 * (q0 - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            let older = previous_step;
            previous_step = step;
            if p.abs() < (0.5 * q * older).abs() && p > q * (lo - x) && p < q * (hi - x) {
                step = p / q;
                let u = x + step;
                if u - lo < tol2 || hi - u < tol2 {
                    step = tol.copysign(mid - x);
                }
                use_golden = false;
            }
        }
        if use_golden {
            previous_step = golden_step(x);
            step = GOLDEN * previous_step;
        }
        let u = if step.abs() >= tol {
            x + step
        } else {
            x + tol.copysign(step)
        };
        let fu = f(u)?;
        if fu <= fx {
            if u >= x {
                lo = x;
            } else {
                hi = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                lo = u;
            } else {
                hi = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    Ok(Minimum { x, value: fx })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brent_finds_smooth_and_kinked_minima() {
        let m = brent_minimize(
            |x| Ok::<_, ()>((x - 0.3).powi(2) + 1.0),
            -2.0,
            3.0,
            1e-10,
            200,
        )
        .unwrap();
        assert!((m.x - 0.3).abs() < 1e-8, "{m:?}");
        let m = brent_minimize(|x| Ok::<_, ()>((x - 1.7).abs()), 0.0, 5.0, 1e-10, 200).unwrap();
        assert!((m.x - 1.7).abs() < 1e-8, "{m:?}");
    }

    #[test]
    fn lm_fits_an_exponential() {
        // y = 2 exp(-1.5 t), started far away.
        let t: Vec<f64> = (0..20).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 * (-1.5 * t).exp()).collect();
        let out = levenberg_marquardt(
            &[0.5, 0.1],
            |p, r| {
                r.clear();
                r.extend(t.iter().zip(&y).map(|(t, y)| p[0] * (-p[1] * t).exp() - y));
            },
            |p, j| {
                for (i, t) in t.iter().enumerate() {
                    j[(i, 0)] = (-p[1] * t).exp();
                    j[(i, 1)] = -p[0] * t * (-p[1] * t).exp();
                }
            },
            200,
        );
        assert!((out.params[0] - 2.0).abs() < 1e-10 && (out.params[1] - 1.5).abs() < 1e-10);
    }
}
