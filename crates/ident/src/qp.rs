//! Sign-constrained linear regression as convex programs for Clarabel.
//!
//! All three losses fit `y ~ A x` with `x_j >= 0` for the constrained columns:
//!
//! * L2: the QP `min 1/2 x' (A'A) x - (A'y)' x`, then polished on the active set
//!   found by the interior-point solver (an exact least-squares solve on the free
//!   columns, kept when it satisfies the KKT conditions), so that exact data give
//!   exact parameters.
//! * Huber with threshold delta: `huber(r) = min_u 1/2 u^2 + delta |r - u|`, i.e.
//!   the QP over `(x, u, t)`: `min 1/2 |u|^2 + delta sum t` with
//!   `-t <= A x - y - u <= t`.
//! * L1: the LP over `(x, t)`: `min sum t` with `-t <= A x - y <= t`.
//!
//! Columns and data are scaled to unit norm before solving; a column that is
//! numerically zero (e.g. a Stribeck term far below the data's velocities) is
//! held at zero.
//!
//! The robust programs are first given to the exact solvers of
//! [`crate::exact`] (a finite active-set Newton method for Huber, a vertex
//! method for L1), which certify their answer by the KKT conditions; Clarabel
//! solves them only when that fails. Both give the optimum of the same convex
//! program; the exact solvers do it in microseconds and to rounding accuracy.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT,
};

use std::cell::Cell;

use crate::exact;
use nalgebra::DMatrix;

use crate::linalg::{column, least_squares};

/// How the robust programs are solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Method {
    /// The exact solvers, Clarabel where they cannot certify the optimum.
    Exact,
    /// Clarabel only, with its default tolerances (the method before the
    /// exact solvers; kept for comparisons).
    #[cfg_attr(not(test), allow(dead_code))]
    Clarabel,
    /// Clarabel only, with tolerances tightened to 1e-12 (a reference for tests).
    #[cfg_attr(not(test), allow(dead_code))]
    ClarabelTight,
}

thread_local! {
    /// Robust programs that the exact solvers handed to Clarabel on this thread.
    static CLARABEL_FALLBACKS: Cell<usize> = const { Cell::new(0) };
}

/// How many robust programs fell back to Clarabel so far on this thread.
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) fn clarabel_fallbacks() -> usize {
    CLARABEL_FALLBACKS.with(Cell::get)
}

/// The loss of a regression, with its threshold resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum RegressionLoss {
    /// Sum of squares.
    L2,
    /// Huber loss with this threshold (in the units of y).
    Huber(f64),
    /// Sum of absolute values.
    L1,
}

impl RegressionLoss {
    /// The loss of the residual vector.
    pub fn value(self, residuals: &[f64]) -> f64 {
        match self {
            Self::L2 => residuals.iter().map(|r| r * r).sum(),
            Self::Huber(delta) => residuals.iter().map(|&r| huber(r, delta)).sum(),
            Self::L1 => residuals.iter().map(|r| r.abs()).sum(),
        }
    }
}

/// `r^2 / 2` inside the threshold, `delta (|r| - delta / 2)` outside.
pub(crate) fn huber(r: f64, delta: f64) -> f64 {
    let a = r.abs();
    if a <= delta {
        0.5 * a * a
    } else {
        delta * (a - 0.5 * delta)
    }
}

/// Columns whose norm is below this fraction of the largest are held at zero.
const NEGLIGIBLE_COLUMN: f64 = 1e-12;

/// Fits `y ~ A x` with `x_j >= 0` where `nonnegative[j]`. Returns x, or the
/// solver's complaint.
pub(crate) fn regression(
    a: &DMatrix<f64>,
    y: &[f64],
    nonnegative: &[bool],
    loss: RegressionLoss,
) -> Result<Vec<f64>, String> {
    regression_with(a, y, nonnegative, loss, Method::Exact)
}

/// [`regression`] with a choice of solver for the robust programs.
pub(crate) fn regression_with(
    a: &DMatrix<f64>,
    y: &[f64],
    nonnegative: &[bool],
    loss: RegressionLoss,
    method: Method,
) -> Result<Vec<f64>, String> {
    let norms: Vec<f64> = a.column_iter().map(|c| c.norm()).collect();
    let largest = norms.iter().copied().fold(0.0, f64::max);
    let active: Vec<usize> = (0..a.ncols())
        .filter(|&c| norms[c] > NEGLIGIBLE_COLUMN * largest && norms[c].is_finite())
        .collect();
    let mut x = vec![0.0; a.ncols()];
    let y_scale = y.iter().map(|v| v * v).sum::<f64>().sqrt();
    if active.is_empty() || y_scale == 0.0 {
        return Ok(x);
    }
    let mut scaled = a.select_columns(&active);
    for (mut col, &c) in scaled.column_iter_mut().zip(&active) {
        col /= norms[c];
    }
    let y_scaled: Vec<f64> = y.iter().map(|v| v / y_scale).collect();
    let bounded: Vec<bool> = active.iter().map(|&c| nonnegative[c]).collect();
    let tight = method == Method::ClarabelTight;
    let exact_first = method == Method::Exact;
    let fallback = |found: Option<Vec<f64>>| {
        if found.is_none() && exact_first {
            CLARABEL_FALLBACKS.with(|n| n.set(n.get() + 1));
        }
        found
    };
    let solution = match loss {
        RegressionLoss::L2 => solve_l2(&scaled, &y_scaled, &bounded)?,
        RegressionLoss::Huber(delta) => {
            let delta = delta / y_scale;
            let found = exact_first
                .then(|| exact::huber(&scaled, &y_scaled, &bounded, delta))
                .flatten();
            match fallback(found) {
                Some(x) => x,
                None => solve_huber(&scaled, &y_scaled, &bounded, delta, tight)?,
            }
        }
        RegressionLoss::L1 => {
            let found = exact_first
                .then(|| exact::l1(&scaled, &y_scaled, &bounded))
                .flatten();
            match fallback(found) {
                Some(x) => x,
                None => solve_l1(&scaled, &y_scaled, &bounded, tight)?,
            }
        }
    };
    for (k, &c) in active.iter().enumerate() {
        let value = solution[k] * y_scale / norms[c];
        x[c] = if nonnegative[c] {
            value.max(0.0)
        } else {
            value
        };
    }
    Ok(x)
}

/// Builder of `A x + s = b`, `s >= 0` rows in triplet form.
struct Constraints {
    rows: Vec<usize>,
    cols: Vec<usize>,
    values: Vec<f64>,
    b: Vec<f64>,
}

impl Constraints {
    fn new() -> Self {
        Self {
            rows: Vec::new(),
            cols: Vec::new(),
            values: Vec::new(),
            b: Vec::new(),
        }
    }

    /// Adds the row `sum coef_k x_{col_k} <= rhs`.
    fn add_le(&mut self, terms: impl IntoIterator<Item = (usize, f64)>, rhs: f64) {
        let row = self.b.len();
        for (col, coef) in terms {
            if coef != 0.0 {
                self.rows.push(row);
                self.cols.push(col);
                self.values.push(coef);
            }
        }
        self.b.push(rhs);
    }

    /// Adds `x_j >= 0` for the bounded variables.
    fn add_nonnegative(&mut self, bounded: &[bool]) {
        for (j, _) in bounded.iter().enumerate().filter(|(_, b)| **b) {
            self.add_le([(j, -1.0)], 0.0);
        }
    }

    fn matrix(&self, n: usize) -> CscMatrix<f64> {
        CscMatrix::new_from_triplets(
            self.b.len(),
            n,
            self.rows.clone(),
            self.cols.clone(),
            self.values.clone(),
        )
    }
}

/// Runs Clarabel on `min 1/2 x'Px + q'x` with the nonnegative-cone constraints
/// (to tolerances of 1e-12 if `tight`, Clarabel's defaults otherwise).
fn solve(
    p: &CscMatrix<f64>,
    q: &[f64],
    constraints: &Constraints,
    tight: bool,
) -> Result<Vec<f64>, String> {
    let n = q.len();
    let a = constraints.matrix(n);
    let cones: Vec<SupportedConeT<f64>> = if constraints.b.is_empty() {
        Vec::new()
    } else {
        vec![NonnegativeConeT(constraints.b.len())]
    };
    let mut settings = DefaultSettings {
        verbose: false,
        presolve_enable: false,
        ..DefaultSettings::default()
    };
    if tight {
        settings.tol_gap_abs = 1e-12;
        settings.tol_gap_rel = 1e-12;
        settings.tol_feas = 1e-12;
        settings.tol_ktratio = 1e-10;
        settings.max_iter = 400;
    }
    let mut solver = DefaultSolver::new(p, q, &a, &constraints.b, &cones, settings)
        .map_err(|e| format!("problem setup: {e}"))?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => Ok(solver.solution.x.clone()),
        status => Err(format!("Clarabel stopped with status {status:?}")),
    }
}

/// Upper triangle of a dense symmetric matrix given by `entry(i, j)`.
fn upper_triangle(n: usize, entry: impl Fn(usize, usize) -> f64) -> CscMatrix<f64> {
    let (mut rows, mut cols, mut values) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..n {
        for i in 0..=j {
            let v = entry(i, j);
            if v != 0.0 {
                rows.push(i);
                cols.push(j);
                values.push(v);
            }
        }
    }
    CscMatrix::new_from_triplets(n, n, rows, cols, values)
}

fn solve_l2(a: &DMatrix<f64>, y: &[f64], bounded: &[bool]) -> Result<Vec<f64>, String> {
    let n = a.ncols();
    let gram = a.tr_mul(a);
    let p = upper_triangle(n, |i, j| gram[(i, j)]);
    let q: Vec<f64> = a.tr_mul(&column(y)).iter().map(|v| -v).collect();
    let mut constraints = Constraints::new();
    constraints.add_nonnegative(bounded);
    let x = solve(&p, &q, &constraints, false)?;
    Ok(polish_l2(a, y, bounded, &x).unwrap_or(x))
}

/// Exact least squares on the free set suggested by the interior-point solution,
/// kept only if it is feasible and satisfies the KKT sign conditions.
fn polish_l2(a: &DMatrix<f64>, y: &[f64], bounded: &[bool], x: &[f64]) -> Option<Vec<f64>> {
    let largest = x.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let at_bound = |j: usize| bounded[j] && x[j] <= 1e-6 * largest.max(1e-12);
    let free: Vec<usize> = (0..a.ncols()).filter(|&j| !at_bound(j)).collect();
    let mut polished = vec![0.0; a.ncols()];
    if !free.is_empty() {
        let sub = a.select_columns(&free);
        let ls = least_squares(&sub, y)?;
        for (k, &j) in free.iter().enumerate() {
            if bounded[j] && ls[k] < 0.0 {
                return None;
            }
            polished[j] = ls[k];
        }
    }
    // Gradient of 1/2 |A x - y|^2 must be >= 0 on the bound variables.
    let residual = a * column(&polished) - column(y);
    let gradient = a.tr_mul(&residual);
    let tolerance = 1e-8 * (1.0 + y.iter().map(|v| v.abs()).fold(0.0, f64::max));
    if (0..a.ncols()).any(|j| at_bound(j) && gradient[j] < -tolerance) {
        return None;
    }
    Some(polished)
}

fn solve_huber(
    a: &DMatrix<f64>,
    y: &[f64],
    bounded: &[bool],
    delta: f64,
    tight: bool,
) -> Result<Vec<f64>, String> {
    let (m, p) = a.shape();
    // Variables: x (p), u (m), t (m).
    let n = p + 2 * m;
    let u = |i: usize| p + i;
    let t = |i: usize| p + m + i;
    let pmat = upper_triangle(n, |i, j| {
        if i == j && i >= p && i < p + m {
            1.0
        } else {
            0.0
        }
    });
    let mut q = vec![0.0; n];
    for i in 0..m {
        q[t(i)] = delta;
    }
    let mut constraints = Constraints::new();
    for (i, &yi) in y.iter().enumerate() {
        let row = (0..p).map(|j| (j, a[(i, j)]));
        constraints.add_le(row.chain([(u(i), -1.0), (t(i), -1.0)]), yi);
        let row = (0..p).map(|j| (j, -a[(i, j)]));
        constraints.add_le(row.chain([(u(i), 1.0), (t(i), -1.0)]), -yi);
    }
    constraints.add_nonnegative(bounded);
    let x = solve(&pmat, &q, &constraints, tight)?;
    Ok(x[..p].to_vec())
}

fn solve_l1(
    a: &DMatrix<f64>,
    y: &[f64],
    bounded: &[bool],
    tight: bool,
) -> Result<Vec<f64>, String> {
    let (m, p) = a.shape();
    // Variables: x (p), t (m).
    let n = p + m;
    let t = |i: usize| p + i;
    let pmat = CscMatrix::new_from_triplets(n, n, Vec::new(), Vec::new(), Vec::new());
    let mut q = vec![0.0; n];
    for i in 0..m {
        q[t(i)] = 1.0;
    }
    let mut constraints = Constraints::new();
    for (i, &yi) in y.iter().enumerate() {
        let row = (0..p).map(|j| (j, a[(i, j)]));
        constraints.add_le(row.chain([(t(i), -1.0)]), yi);
        let row = (0..p).map(|j| (j, -a[(i, j)]));
        constraints.add_le(row.chain([(t(i), -1.0)]), -yi);
    }
    constraints.add_nonnegative(bounded);
    let x = solve(&pmat, &q, &constraints, tight)?;
    Ok(x[..p].to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line_data(outlier: f64) -> (DMatrix<f64>, Vec<f64>) {
        let n = 21;
        let mut a = DMatrix::zeros(n, 2);
        let mut y = vec![0.0; n];
        for (i, yi) in y.iter_mut().enumerate() {
            let t = i as f64 / 10.0;
            a[(i, 0)] = 1.0;
            a[(i, 1)] = t;
            *yi = 1.0 + 2.0 * t + 0.01 * ((i * 7) % 5) as f64 - 0.02;
        }
        y[5] += outlier;
        (a, y)
    }

    #[test]
    fn l2_is_exact_on_exact_data() {
        let mut a = DMatrix::zeros(4, 2);
        let mut y = vec![0.0; 4];
        for (i, yi) in y.iter_mut().enumerate() {
            a[(i, 0)] = 1.0;
            a[(i, 1)] = i as f64;
            *yi = 0.5 + 3.0 * i as f64;
        }
        let x = regression(&a, &y, &[true, true], RegressionLoss::L2).unwrap();
        assert!(
            (x[0] - 0.5).abs() < 1e-14 && (x[1] - 3.0).abs() < 1e-14,
            "{x:?}"
        );
    }

    #[test]
    fn bounds_hold_and_polish_keeps_them() {
        // The unconstrained intercept would be negative.
        let mut a = DMatrix::zeros(3, 2);
        let y = vec![-0.5, 1.0, 2.5];
        for i in 0..3 {
            a[(i, 0)] = 1.0;
            a[(i, 1)] = i as f64;
        }
        let x = regression(&a, &y, &[true, false], RegressionLoss::L2).unwrap();
        assert_eq!(x[0], 0.0);
        // With x0 = 0 the slope is <t, y> / <t, t> = (1 + 5) / 5.
        assert!((x[1] - 1.2).abs() < 1e-12, "{x:?}");
    }

    #[test]
    fn robust_losses_resist_an_outlier() {
        let (a, y) = line_data(50.0);
        let l2 = regression(&a, &y, &[false, false], RegressionLoss::L2).unwrap();
        let hub = regression(&a, &y, &[false, false], RegressionLoss::Huber(0.05)).unwrap();
        let l1 = regression(&a, &y, &[false, false], RegressionLoss::L1).unwrap();
        assert!((l2[1] - 2.0).abs() > 0.5);
        assert!((hub[1] - 2.0).abs() < 0.02, "{hub:?}");
        assert!((l1[1] - 2.0).abs() < 0.02, "{l1:?}");
    }
}
