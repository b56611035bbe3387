//! Small dense linear algebra: Householder least squares with column scaling and
//! the unscaled covariance `(A^T A)^-1`. The problems here have at most a few
//! hundred rows and a handful of columns.

/// A dense row-major matrix.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Mat {
    pub rows: usize,
    pub cols: usize,
    data: Vec<f64>,
}

impl Mat {
    pub fn zeros(rows: usize, cols: usize) -> Self {
        Self {
            rows,
            cols,
            data: vec![0.0; rows * cols],
        }
    }

    #[inline]
    pub fn get(&self, r: usize, c: usize) -> f64 {
        self.data[r * self.cols + c]
    }

    #[inline]
    pub fn set(&mut self, r: usize, c: usize, value: f64) {
        self.data[r * self.cols + c] = value;
    }

    pub fn column(&self, c: usize) -> Vec<f64> {
        (0..self.rows).map(|r| self.get(r, c)).collect()
    }

    /// The matrix made of the listed columns.
    pub fn select_columns(&self, columns: &[usize]) -> Mat {
        let mut out = Mat::zeros(self.rows, columns.len());
        for r in 0..self.rows {
            for (k, &c) in columns.iter().enumerate() {
                out.set(r, k, self.get(r, c));
            }
        }
        out
    }

    /// `A x`.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        (0..self.rows)
            .map(|r| (0..self.cols).map(|c| self.get(r, c) * x[c]).sum())
            .collect()
    }

    /// `A^T y`.
    pub fn tr_mul_vec(&self, y: &[f64]) -> Vec<f64> {
        (0..self.cols)
            .map(|c| (0..self.rows).map(|r| self.get(r, c) * y[r]).sum())
            .collect()
    }

    /// Euclidean norm of each column.
    pub fn column_norms(&self) -> Vec<f64> {
        (0..self.cols)
            .map(|c| {
                (0..self.rows)
                    .map(|r| self.get(r, c).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect()
    }
}

/// A least-squares solution with the unscaled covariance.
#[derive(Debug, Clone)]
pub(crate) struct LeastSquares {
    /// Minimiser of `||A x - b||`.
    pub x: Vec<f64>,
    /// `(A^T A)^-1`, row-major, `cols x cols`.
    pub inverse_normal: Vec<f64>,
}

/// Relative size of the smallest pivot of the scaled R below which A counts as
/// rank deficient.
const RANK_TOLERANCE: f64 = 1e-12;

/// Solves `min ||A x - b||` by Householder QR of the column-scaled matrix.
/// `None` if A has fewer rows than columns, a zero column, or is numerically
/// rank deficient.
pub(crate) fn least_squares(a: &Mat, b: &[f64]) -> Option<LeastSquares> {
    let (m, n) = (a.rows, a.cols);
    if m < n || b.len() != m {
        return None;
    }
    let scale = a.column_norms();
    if scale.iter().any(|&s| !(s > 0.0 && s.is_finite())) {
        return None;
    }
    // Column-major working copy of the scaled matrix and the right-hand side.
    let mut q: Vec<Vec<f64>> = (0..n)
        .map(|c| (0..m).map(|r| a.get(r, c) / scale[c]).collect())
        .collect();
    let mut rhs = b.to_vec();
    for k in 0..n {
        householder_step(&mut q, &mut rhs, k)?;
    }
    let diag_max = (0..n).map(|k| q[k][k].abs()).fold(0.0, f64::max);
    if (0..n).any(|k| q[k][k].abs() <= RANK_TOLERANCE * diag_max) {
        return None;
    }
    let r = |row: usize, col: usize| q[col][row];
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|j| r(i, j) * x[j]).sum();
        x[i] = (rhs[i] - s) / r(i, i);
    }
    let r_inv = upper_triangular_inverse(n, r);
    let mut inverse_normal = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            let s: f64 = (i.max(j)..n)
                .map(|k| r_inv[i * n + k] * r_inv[j * n + k])
                .sum();
            inverse_normal[i * n + j] = s / (scale[i] * scale[j]);
        }
    }
    for (xi, s) in x.iter_mut().zip(&scale) {
        *xi /= s;
    }
    Some(LeastSquares { x, inverse_normal })
}

/// Reflects column k (rows k..) onto a multiple of e_k and applies the
/// reflection to the later columns and the right-hand side.
fn householder_step(q: &mut [Vec<f64>], rhs: &mut [f64], k: usize) -> Option<()> {
    let m = rhs.len();
    let norm = q[k][k..].iter().map(|v| v * v).sum::<f64>().sqrt();
    if norm == 0.0 {
        return None;
    }
    let alpha = if q[k][k] > 0.0 { -norm } else { norm };
    let mut v: Vec<f64> = q[k][k..].to_vec();
    v[0] -= alpha;
    let v_norm2: f64 = v.iter().map(|x| x * x).sum();
    if v_norm2 == 0.0 {
        return Some(());
    }
    let reflect = |col: &mut [f64]| {
        let dot: f64 = v.iter().zip(&col[k..m]).map(|(a, b)| a * b).sum();
        let f = 2.0 * dot / v_norm2;
        for (c, vi) in col[k..m].iter_mut().zip(&v) {
            *c -= f * vi;
        }
    };
    for col in q.iter_mut().skip(k + 1) {
        reflect(col);
    }
    reflect(rhs);
    q[k][k] = alpha;
    for value in q[k][k + 1..].iter_mut() {
        *value = 0.0;
    }
    Some(())
}

/// Inverse of the upper-triangular n x n matrix given by `r(row, col)`, row-major.
fn upper_triangular_inverse(n: usize, r: impl Fn(usize, usize) -> f64) -> Vec<f64> {
    let mut inv = vec![0.0; n * n];
    for j in 0..n {
        inv[j * n + j] = 1.0 / r(j, j);
        for i in (0..j).rev() {
            let s: f64 = (i + 1..=j).map(|k| r(i, k) * inv[k * n + j]).sum();
            inv[i * n + j] = -s / r(i, i);
        }
    }
    inv
}

/// Inverse of a small symmetric positive definite matrix by Cholesky; `None` if
/// it is not positive definite.
pub(crate) fn spd_inverse(n: usize, a: &[f64]) -> Option<Vec<f64>> {
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = (0..j).map(|k| l[i * n + k] * l[j * n + k]).sum();
            if i == j {
                let d = a[i * n + i] - s;
                if d.is_nan() || d <= 0.0 {
                    return None;
                }
                l[i * n + i] = d.sqrt();
            } else {
                l[i * n + j] = (a[i * n + j] - s) / l[j * n + j];
            }
        }
    }
    // inv = L^-T L^-1, with L^-1 lower triangular.
    let mut l_inv = vec![0.0; n * n];
    for j in 0..n {
        l_inv[j * n + j] = 1.0 / l[j * n + j];
        for i in j + 1..n {
            let s: f64 = (j..i).map(|k| l[i * n + k] * l_inv[k * n + j]).sum();
            l_inv[i * n + j] = -s / l[i * n + i];
        }
    }
    let mut inv = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            inv[i * n + j] = (i.max(j)..n)
                .map(|k| l_inv[k * n + i] * l_inv[k * n + j])
                .sum();
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn least_squares_matches_normal_equations() {
        // y = 2 + 3 t fitted at t = 0..4 with a perturbation.
        let t = [0.0, 1.0, 2.0, 3.0, 4.0];
        let mut a = Mat::zeros(5, 2);
        let mut b = vec![0.0; 5];
        for (i, &ti) in t.iter().enumerate() {
            a.set(i, 0, 1.0);
            a.set(i, 1, ti * 1e-3);
            b[i] = 2.0 + 3.0 * ti + if i % 2 == 0 { 0.1 } else { -0.1 };
        }
        let ls = least_squares(&a, &b).unwrap();
        // Normal equations by hand.
        let (s0, s1, s2) = (5.0, 10.0e-3, 30.0e-6);
        let det = s0 * s2 - s1 * s1;
        let inv = [s2 / det, -s1 / det, -s1 / det, s0 / det];
        for (k, expected) in inv.iter().enumerate() {
            assert!((ls.inverse_normal[k] - expected).abs() < 1e-9 * expected.abs());
        }
        let atb = a.tr_mul_vec(&b);
        let x0 = inv[0] * atb[0] + inv[1] * atb[1];
        let x1 = inv[2] * atb[0] + inv[3] * atb[1];
        assert!((ls.x[0] - x0).abs() < 1e-10);
        assert!((ls.x[1] - x1).abs() < 1e-6);
        let spd = spd_inverse(2, &[s0, s1, s1, s2]).unwrap();
        for k in 0..4 {
            assert!((spd[k] - inv[k]).abs() < 1e-9 * inv[k].abs());
        }
    }

    #[test]
    fn rank_deficiency_is_reported() {
        let mut a = Mat::zeros(3, 2);
        for r in 0..3 {
            a.set(r, 0, 1.0 + r as f64);
            a.set(r, 1, 2.0 + 2.0 * r as f64);
        }
        assert!(least_squares(&a, &[1.0, 2.0, 3.0]).is_none());
    }
}
