//! Least squares on nalgebra's factorisations: Householder QR of the
//! column-scaled matrix with a rank test, and the unscaled covariance
//! `(A^T A)^-1` from its triangular factor. The problems here have at most a
//! few hundred rows and a handful of columns.

use nalgebra::{DMatrix, DVector, DVectorView, Dyn, QR};

/// A slice seen as a column vector (no copy), for products with a matrix.
pub(crate) fn column(x: &[f64]) -> DVectorView<'_, f64> {
    DVectorView::from_slice(x, x.len())
}

/// The entries of a matrix row by row (the layout of the fits' public covariances).
pub(crate) fn row_major(m: &DMatrix<f64>) -> Vec<f64> {
    m.transpose().as_slice().to_vec()
}

/// Relative size of the smallest diagonal entry of the scaled R below which A
/// counts as rank deficient.
const RANK_TOLERANCE: f64 = 1e-12;

/// The QR factorisation of `A D^-1`, D the column norms of A.
struct ScaledQr {
    qr: QR<f64, Dyn, Dyn>,
    r: DMatrix<f64>,
    scale: Vec<f64>,
}

impl ScaledQr {
    /// `None` if A has fewer rows than columns, a zero or non-finite column, or
    /// is numerically rank deficient.
    fn new(a: &DMatrix<f64>) -> Option<Self> {
        if a.nrows() < a.ncols() {
            return None;
        }
        let scale: Vec<f64> = a.column_iter().map(|c| c.norm()).collect();
        if scale.iter().any(|&s| !(s > 0.0 && s.is_finite())) {
            return None;
        }
        let mut scaled = a.clone();
        for (mut c, s) in scaled.column_iter_mut().zip(&scale) {
            c /= *s;
        }
        let qr = scaled.qr();
        let r = qr.r();
        let diag_max = r.diagonal().amax();
        if r.diagonal()
            .iter()
            .any(|d| d.abs() <= RANK_TOLERANCE * diag_max)
        {
            return None;
        }
        Some(Self { qr, r, scale })
    }
}

/// Solves `min ||A x - b||`; `None` if A has fewer rows than columns, a zero
/// column, or is numerically rank deficient.
pub(crate) fn least_squares(a: &DMatrix<f64>, b: &[f64]) -> Option<Vec<f64>> {
    if b.len() != a.nrows() {
        return None;
    }
    let f = ScaledQr::new(a)?;
    let mut rhs = DVector::from_column_slice(b);
    f.qr.q_tr_mul(&mut rhs);
    let y = f.r.solve_upper_triangular(&rhs.rows(0, a.ncols()))?;
    Some(y.iter().zip(&f.scale).map(|(y, s)| y / s).collect())
}

/// `(A^T A)^-1 = D^-1 R^-1 R^-T D^-1`; `None` where [`least_squares`] fails.
pub(crate) fn inverse_normal(a: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let f = ScaledQr::new(a)?;
    let n = a.ncols();
    // With B = D^-1 R^-1 (the rows of R^-1 scaled), the inverse is B B^T.
    let mut b = f.r.solve_upper_triangular(&DMatrix::identity(n, n))?;
    for (mut row, s) in b.row_iter_mut().zip(&f.scale) {
        row /= *s;
    }
    Some(&b * b.transpose())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn least_squares_matches_normal_equations() {
        // y = 2 + 3 t fitted at t = 0..4 with a perturbation.
        let t = [0.0, 1.0, 2.0, 3.0, 4.0];
        let mut a = DMatrix::zeros(5, 2);
        let mut b = vec![0.0; 5];
        for (i, &ti) in t.iter().enumerate() {
            a[(i, 0)] = 1.0;
            a[(i, 1)] = ti * 1e-3;
            b[i] = 2.0 + 3.0 * ti + if i % 2 == 0 { 0.1 } else { -0.1 };
        }
        let ls = least_squares(&a, &b).unwrap();
        let inverse_normal = inverse_normal(&a).unwrap();
        // Normal equations by hand.
        let (s0, s1, s2) = (5.0, 10.0e-3, 30.0e-6);
        let det = s0 * s2 - s1 * s1;
        let inv = [s2 / det, -s1 / det, -s1 / det, s0 / det];
        for (k, expected) in inv.iter().enumerate() {
            assert!((inverse_normal[(k / 2, k % 2)] - expected).abs() < 1e-9 * expected.abs());
        }
        let atb = a.tr_mul(&column(&b));
        let x0 = inv[0] * atb[0] + inv[1] * atb[1];
        let x1 = inv[2] * atb[0] + inv[3] * atb[1];
        assert!((ls[0] - x0).abs() < 1e-10);
        assert!((ls[1] - x1).abs() < 1e-6);
        let normal = DMatrix::from_row_slice(2, 2, &[s0, s1, s1, s2]);
        let spd = normal.cholesky().unwrap().inverse();
        for k in 0..4 {
            assert!((spd[(k / 2, k % 2)] - inv[k]).abs() < 1e-9 * inv[k].abs());
        }
    }

    #[test]
    fn rank_deficiency_is_reported() {
        let mut a = DMatrix::zeros(3, 2);
        for r in 0..3 {
            a[(r, 0)] = 1.0 + r as f64;
            a[(r, 1)] = 2.0 + 2.0 * r as f64;
        }
        assert!(least_squares(&a, &[1.0, 2.0, 3.0]).is_none());
    }
}
