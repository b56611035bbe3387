//! The least-squares algebra every output-error fit shares: the normal
//! equations of weighted residuals, a scaled inverse that says when the
//! information matrix is singular, and the linearised delete-one-block
//! jackknife that gives honest intervals when residuals are correlated.
//!
//! Residuals of a record are correlated (quantisation, unmeasured forces),
//! so the Jacobian-only covariance `s^2 H^-1` comes out far too narrow. The
//! jackknife leaves one block of residuals out at a time: the estimate moves
//! by `d_b = (H - H_b)^-1 g_b`, with `g_b` and `H_b` the block's score and
//! information, and `(G - 1)/G sum_b d_b d_b^T` is the covariance.

use nalgebra::{DMatrix, DVector};

use crate::stribeck::Loss;

/// `H = J^T W J` and `g = J^T W r` of residuals `r` with Jacobian rows of
/// `p` entries (`jacobian[k * p..(k + 1) * p]`) and weights `w`.
pub(crate) fn normal_equations(
    jacobian: &[f64],
    residual: &[f64],
    weight: &dyn Fn(usize) -> f64,
    p: usize,
) -> (DMatrix<f64>, DVector<f64>) {
    let mut h = DMatrix::zeros(p, p);
    let mut g = DVector::zeros(p);
    for (k, &r) in residual.iter().enumerate() {
        let row = &jacobian[k * p..(k + 1) * p];
        let w = weight(k);
        for i in 0..p {
            g[i] += w * row[i] * r;
            for j in 0..=i {
                h[(i, j)] += w * row[i] * row[j];
            }
        }
    }
    for i in 0..p {
        for j in 0..i {
            h[(j, i)] = h[(i, j)];
        }
    }
    (h, g)
}

/// The inverse of a symmetric positive matrix by Jacobi-scaled Cholesky;
/// None when it is singular to working precision.
pub(crate) fn scaled_inverse(h: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let p = h.nrows();
    let d: Vec<f64> = (0..p).map(|i| h[(i, i)].max(0.0).sqrt()).collect();
    if d.iter().any(|&v| v == 0.0 || !v.is_finite()) {
        return None;
    }
    let scaled = DMatrix::from_fn(p, p, |i, j| h[(i, j)] / (d[i] * d[j]));
    let eigen = scaled.clone().symmetric_eigen();
    let (lo, hi) = eigen
        .eigenvalues
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &e| (a.min(e), b.max(e)));
    if lo.is_nan() || lo <= 1e-13 * hi {
        return None;
    }
    let inv = scaled.cholesky()?.inverse();
    Some(DMatrix::from_fn(p, p, |i, j| inv[(i, j)] / (d[i] * d[j])))
}

/// The jackknife's answer.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Jackknife {
    /// `(G - 1)/G sum_b d_b d_b^T`.
    pub covariance: DMatrix<f64>,
    /// `d_b` per block: how far the estimate moves without block `b`.
    pub replicates: Vec<DVector<f64>>,
    /// `H^-1` (the Jacobian-only covariance is `s^2 H^-1`).
    pub inverse: DMatrix<f64>,
}

/// The linearised delete-one-block jackknife over row ranges `blocks`;
/// None when `H` cannot be inverted.
pub(crate) fn block_jackknife(
    h: &DMatrix<f64>,
    jacobian: &[f64],
    residual: &[f64],
    weight: &dyn Fn(usize) -> f64,
    blocks: &[(usize, usize)],
) -> Option<Jackknife> {
    let p = h.nrows();
    let inverse = scaled_inverse(h)?;
    let replicates: Vec<DVector<f64>> = blocks
        .iter()
        .map(|&(a, b)| {
            let mut score = DVector::<f64>::zeros(p);
            let mut info = DMatrix::<f64>::zeros(p, p);
            for k in a..b {
                let w = weight(k);
                let row = &jacobian[k * p..(k + 1) * p];
                for i in 0..p {
                    score[i] += w * residual[k] * row[i];
                    for j in 0..p {
                        info[(i, j)] += w * row[i] * row[j];
                    }
                }
            }
            let without = h - &info;
            without
                .cholesky()
                .map(|c| c.solve(&score))
                .unwrap_or_else(|| &inverse * &score)
        })
        .collect();
    let g = blocks.len() as f64;
    let mut covariance = DMatrix::<f64>::zeros(p, p);
    for delta in &replicates {
        covariance += delta * delta.transpose();
    }
    covariance *= (g - 1.0) / g;
    Some(Jackknife {
        covariance,
        replicates,
        inverse,
    })
}

/// The loss of one residual (half the square for L2).
pub(crate) fn rho(loss: Loss, r: f64, threshold: f64) -> f64 {
    let a = r.abs();
    match loss {
        Loss::Huber if a > threshold => threshold * a - 0.5 * threshold * threshold,
        _ => 0.5 * r * r,
    }
}

/// The IRLS weight of one residual.
pub(crate) fn weight(loss: Loss, r: f64, threshold: f64) -> f64 {
    match loss {
        Loss::Huber if r.abs() > threshold => threshold / r.abs(),
        _ => 1.0,
    }
}
