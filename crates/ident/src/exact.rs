//! Exact solvers for the small robust regressions of [`crate::qp`]: Huber's
//! loss and the L1 loss of `y ~ A x` with `x_j >= 0` on some columns, for a
//! handful of columns (the Stribeck fit has three) and any number of rows.
//!
//! Both problems are convex and piecewise simple (piecewise quadratic, piecewise
//! linear), so their optimum is reached in finitely many exact steps:
//!
//! * **Huber.** The nonnegative orthant has `2^k` faces (k bounded columns).
//!   On each face, Newton's method with an exact line search (the derivative
//!   along the step is piecewise linear, its root is found by walking the
//!   breakpoints) stops when a full Newton step keeps every residual in its
//!   zone (quadratic, or linear on either side): the point is then the exact
//!   stationary point of the quadratic that the loss is on that zone pattern,
//!   found by one linear solve. The faces are visited with the fewest bounds
//!   held first; the first face point that is feasible and whose gradient is
//!   nonnegative on the held columns satisfies the KKT conditions and is the
//!   global optimum.
//! * **L1.** A vertex method (the simplex method of the linear program, written
//!   as in Barrodale and Roberts' L1 algorithm): a vertex is fixed by `p` active
//!   conditions, zero residuals or held bounds. Its dual multipliers follow
//!   from one `p x p` solve; if some condition violates dual feasibility
//!   (a zero residual's multiplier outside `[-1, 1]`, a bound's of the wrong
//!   sign), it is released and the loss is minimised exactly along the edge (a
//!   weighted median of the residuals' breakpoints, stopping at a bound), which
//!   makes another condition active (at a degenerate vertex, where more
//!   residuals are zero than conditions, the step may have length zero and
//!   only exchange conditions). It starts at the vertex of the rows with the
//!   smallest least-squares residuals (one or two exchanges from the optimum,
//!   typically), or at `x = 0` (every column held) if that vertex violates a
//!   bound.
//!   Rows that repeat another, or mirror it (`(-a_i, -y_i)`, as a curve
//!   measured symmetrically gives), are merged into one weighted row first:
//!   they would make every vertex on them degenerate.
//!
//! Each solver *certifies* its answer by the KKT conditions of the convex
//! program, with tolerances at rounding level, and returns `None` when it
//! cannot (a singular zone pattern, a degenerate vertex, an iteration limit):
//! the caller then solves the program with the interior-point solver. A
//! certified answer is the global optimum of the same program, to rounding.

use nalgebra::DMatrix;

use crate::linalg::{column, least_squares};

/// Largest number of columns handled (the faces grow as `2^k`).
const MAX_COLUMNS: usize = 8;

/// Newton iterations per face.
const NEWTON_ITERATIONS: usize = 60;

/// Vertex changes of the L1 method, per column.
const PIVOTS_PER_COLUMN: usize = 40;

/// The Huber regression `min sum huber(a_i x - y_i, delta)` with `x_j >= 0`
/// where `bounded[j]`; `None` if the optimum could not be certified.
pub(crate) fn huber(a: &DMatrix<f64>, y: &[f64], bounded: &[bool], delta: f64) -> Option<Vec<f64>> {
    let p = a.ncols();
    if p == 0 || p > MAX_COLUMNS || !(delta > 0.0 && delta.is_finite()) {
        return None;
    }
    let bounded_columns: Vec<usize> = (0..p).filter(|&j| bounded[j]).collect();
    let mut faces: Vec<u32> = (0..1u32 << bounded_columns.len()).collect();
    faces.sort_by_key(|mask| mask.count_ones());
    for mask in faces {
        let held = |j: usize| {
            bounded_columns
                .iter()
                .position(|&b| b == j)
                .is_some_and(|k| mask & (1 << k) != 0)
        };
        let free: Vec<usize> = (0..p).filter(|&j| !held(j)).collect();
        let sub = a.select_columns(&free);
        let Some(x_free) = huber_unconstrained(&sub, y, delta) else {
            continue;
        };
        if free
            .iter()
            .zip(&x_free)
            .any(|(&j, &value)| bounded[j] && value < 0.0)
        {
            continue;
        }
        let mut x = vec![0.0; p];
        for (&j, &value) in free.iter().zip(&x_free) {
            x[j] = value;
        }
        let r = residuals(a, y, &x);
        let psi: Vec<f64> = r.iter().map(|v| v.clamp(-delta, delta)).collect();
        let g = a.tr_mul(&column(&psi));
        let certified = (0..p).filter(|&j| held(j)).all(|j| {
            let scale: f64 = a.column(j).iter().map(|v| v.abs()).sum::<f64>() * delta;
            g[j] >= -1e-10 * scale
        });
        if certified {
            return Some(x);
        }
    }
    None
}

/// `A x - y`.
fn residuals(a: &DMatrix<f64>, y: &[f64], x: &[f64]) -> Vec<f64> {
    (a * column(x)).iter().zip(y).map(|(f, y)| f - y).collect()
}

/// The zone of a residual: -1 or 1 on the linear parts, 0 on the quadratic part.
fn zone(r: f64, delta: f64) -> i8 {
    if r > delta {
        1
    } else if r < -delta {
        -1
    } else {
        0
    }
}

/// The unconstrained Huber regression; `None` if Newton's method does not end
/// on a nonsingular zone pattern.
fn huber_unconstrained(a: &DMatrix<f64>, y: &[f64], delta: f64) -> Option<Vec<f64>> {
    let (m, p) = a.shape();
    if p == 0 {
        return Some(Vec::new());
    }
    let mut x = least_squares(a, y).unwrap_or_else(|| vec![0.0; p]);
    let mut hessian = DMatrix::zeros(p, p);
    let mut gradient = vec![0.0; p];
    for _ in 0..NEWTON_ITERATIONS {
        let r = residuals(a, y, &x);
        hessian.fill(0.0);
        gradient.fill(0.0);
        for (i, &ri) in r.iter().enumerate() {
            let psi = ri.clamp(-delta, delta);
            let quadratic = ri.abs() <= delta;
            for j in 0..p {
                let aij = a[(i, j)];
                gradient[j] += psi * aij;
                if quadratic {
                    for k in 0..=j {
                        hessian[(j, k)] += aij * a[(i, k)];
                    }
                }
            }
        }
        hessian.fill_upper_triangle_with_lower_triangle();
        let rhs: Vec<f64> = gradient.iter().map(|g| -g).collect();
        let (direction, exact) = match solve_dense(&hessian, &rhs) {
            Some(d) => (d, true),
            None => {
                // Singular pattern (too few residuals in the quadratic zone):
                // a regularised step still descends; the end must be exact.
                let mu = 1e-8 * hessian.trace().max(1e-300) + 1e-12;
                let mut regularised = hessian.clone();
                for j in 0..p {
                    regularised[(j, j)] += mu;
                }
                (solve_dense(&regularised, &rhs)?, false)
            }
        };
        let c = a * column(&direction);
        let slope: f64 = gradient.iter().zip(&direction).map(|(g, d)| g * d).sum();
        if exact && (0..m).all(|i| zone(r[i] + c[i], delta) == zone(r[i], delta)) {
            for (xj, dj) in x.iter_mut().zip(&direction) {
                *xj += dj;
            }
            return Some(x);
        }
        if slope.is_nan() || slope >= 0.0 {
            return None;
        }
        let t = huber_line_search(&r, c.as_slice(), delta, slope)?;
        for (xj, dj) in x.iter_mut().zip(&direction) {
            *xj += t * dj;
        }
    }
    None
}

/// The step t > 0 that minimises `sum huber(r_i + t c_i)`, whose derivative
/// `slope0 + ...` is continuous, piecewise linear and nondecreasing in t.
fn huber_line_search(r: &[f64], c: &[f64], delta: f64, slope0: f64) -> Option<f64> {
    // Each residual is quadratic on an interval of t (maybe empty); the
    // derivative's own slope is the sum of c_i^2 over the residuals inside.
    let mut events: Vec<(f64, f64)> = Vec::with_capacity(2 * r.len());
    let mut curvature = 0.0;
    for (&ri, &ci) in r.iter().zip(c) {
        if ci == 0.0 {
            continue;
        }
        let (t1, t2) = ((-delta - ri) / ci, (delta - ri) / ci);
        let (enter, leave) = (t1.min(t2), t1.max(t2));
        let weight = ci * ci;
        if leave <= 0.0 {
            continue;
        }
        if enter <= 0.0 {
            curvature += weight;
        } else {
            events.push((enter, weight));
        }
        events.push((leave, -weight));
    }
    events.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut t, mut value) = (0.0, slope0);
    for &(at, change) in &events {
        let next = value + curvature * (at - t);
        if next >= 0.0 && curvature > 0.0 {
            return Some(t - value / curvature);
        }
        t = at;
        value = next;
        curvature += change;
    }
    (curvature > 0.0).then(|| t - value / curvature)
}

/// Solves the square system by LU with partial pivoting; `None` if a pivot is
/// at most 1e-13 times the largest entry (singular to working precision).
fn solve_dense(matrix: &DMatrix<f64>, rhs: &[f64]) -> Option<Vec<f64>> {
    let largest = matrix.amax();
    if !(largest > 0.0 && largest.is_finite()) {
        return None;
    }
    let lu = matrix.clone().lu();
    if lu.u().diagonal().iter().any(|d| d.abs() <= 1e-13 * largest) {
        return None;
    }
    let x = lu.solve(&column(rhs))?;
    x.iter()
        .all(|v| v.is_finite())
        .then(|| x.as_slice().to_vec())
}

/// A condition that fixes a vertex of the L1 problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Active {
    /// Residual i is zero.
    Row(usize),
    /// Column j is held at zero (a bound, or a temporary fixing of an
    /// unbounded column at the start).
    Column(usize),
}

/// The L1 regression `min sum |a_i x - y_i|` with `x_j >= 0` where
/// `bounded[j]`; `None` if the optimum could not be certified.
pub(crate) fn l1(a: &DMatrix<f64>, y: &[f64], bounded: &[bool]) -> Option<Vec<f64>> {
    let (m, p) = a.shape();
    if p == 0 || p > MAX_COLUMNS || m < p {
        return None;
    }
    let (a, y, weight) = merge_mirrored_rows(a, y);
    weighted_l1(&a, &y, &weight, bounded)
}

/// Rows that repeat another exactly, or exactly with both signs flipped (a
/// curve measured, or symmetrised, as `f(-v) = -f(v)`), contribute
/// `|a x - y|` twice: they are merged into one row of weight 2 (or more).
/// Otherwise every vertex on such a row would be degenerate.
fn merge_mirrored_rows(a: &DMatrix<f64>, y: &[f64]) -> (DMatrix<f64>, Vec<f64>, Vec<f64>) {
    let (m, p) = a.shape();
    let width = p + 1;
    // Sign-normalised rows (a_i, y_i): the first nonzero entry positive.
    let mut keys = vec![0.0; m * width];
    for i in 0..m {
        let row = &mut keys[i * width..(i + 1) * width];
        for (j, value) in row.iter_mut().take(p).enumerate() {
            *value = a[(i, j)];
        }
        row[p] = y[i];
        let sign = row.iter().find(|v| **v != 0.0).map_or(1.0, |v| v.signum());
        row.iter_mut().for_each(|v| *v = *v * sign + 0.0);
    }
    let key = |i: usize| &keys[i * width..(i + 1) * width];
    let compare = |i: &usize, k: &usize| {
        key(*i)
            .iter()
            .zip(key(*k))
            .map(|(u, v)| u.total_cmp(v))
            .find(|o| o.is_ne())
            .unwrap_or(std::cmp::Ordering::Equal)
    };
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(compare);
    let mut kept: Vec<usize> = Vec::with_capacity(m);
    let mut weight: Vec<f64> = Vec::with_capacity(m);
    for (n, &i) in order.iter().enumerate() {
        if n > 0 && compare(&order[n - 1], &i).is_eq() {
            *weight.last_mut().expect("a row was kept") += 1.0;
        } else {
            kept.push(i);
            weight.push(1.0);
        }
    }
    if kept.len() == m {
        return (a.clone(), y.to_vec(), vec![1.0; m]);
    }
    let y = kept.iter().map(|&i| y[i]).collect();
    (a.select_rows(&kept), y, weight)
}

/// A feasible starting vertex near the optimum: the `p` rows (independent)
/// with the smallest residuals of the weighted least-squares fit, if the
/// point they fix satisfies the bounds; otherwise `x = 0`, every column held.
fn start_vertex(
    a: &DMatrix<f64>,
    y: &[f64],
    weight: &[f64],
    bounded: &[bool],
) -> (Vec<Active>, Vec<f64>) {
    let p = a.ncols();
    let origin = ((0..p).map(Active::Column).collect(), vec![0.0; p]);
    let mut scaled = a.clone();
    for (mut row, w) in scaled.row_iter_mut().zip(weight) {
        row *= *w;
    }
    let rhs: Vec<f64> = y.iter().zip(weight).map(|(y, w)| y * w).collect();
    let Some(ls) = least_squares(&scaled, &rhs) else {
        return origin;
    };
    let r = residuals(a, y, &ls);
    let mut order: Vec<usize> = (0..a.nrows()).collect();
    order.sort_by(|&i, &k| r[i].abs().total_cmp(&r[k].abs()));
    let mut active = Vec::with_capacity(p);
    for &i in &order {
        active.push(Active::Row(i));
        let independent = solve_dense(&gram(a, &active), &vec![1.0; active.len()]).is_some();
        if !independent {
            active.pop();
        }
        if active.len() == p {
            break;
        }
    }
    if active.len() < p {
        return origin;
    }
    match vertex(a, y, &active) {
        Some(x) if (0..p).all(|j| !bounded[j] || x[j] >= 0.0) => (active, x),
        _ => origin,
    }
}

/// The Gram matrix of the rows of the active conditions (all rows here).
fn gram(a: &DMatrix<f64>, active: &[Active]) -> DMatrix<f64> {
    let rows: Vec<usize> = active
        .iter()
        .map(|condition| match *condition {
            Active::Row(i) => i,
            Active::Column(_) => unreachable!("only rows are tested for independence"),
        })
        .collect();
    let b = a.select_rows(&rows);
    &b * b.transpose()
}

/// `min sum w_i |a_i x - y_i|` with `x_j >= 0` where `bounded[j]`.
fn weighted_l1(a: &DMatrix<f64>, y: &[f64], weight: &[f64], bounded: &[bool]) -> Option<Vec<f64>> {
    let (m, p) = a.shape();
    if m < p {
        return None;
    }
    let (mut active, mut x) = start_vertex(a, y, weight, bounded);
    for _ in 0..PIVOTS_PER_COLUMN * p {
        let r = residuals(a, y, &x);
        let on_row = |i: usize| active.contains(&Active::Row(i));
        // q = sum over the other rows of w_i sign(r_i) a_i.
        let mut q = vec![0.0; p];
        for (i, &ri) in r.iter().enumerate() {
            if !on_row(i) && ri != 0.0 {
                for (j, qj) in q.iter_mut().enumerate() {
                    *qj += weight[i] * ri.signum() * a[(i, j)];
                }
            }
        }
        // Multipliers mu: C^T mu = -q, C the rows of the active conditions.
        let c = condition_matrix(a, &active);
        let minus_q: Vec<f64> = q.iter().map(|v| -v).collect();
        let mu = solve_dense(&c.transpose(), &minus_q)?;
        let scale = 1.0 + q.iter().map(|v| v.abs()).fold(0.0, f64::max);
        // The most violated dual condition, with the direction that releases it.
        let mut worst: Option<(usize, f64, f64)> = None;
        for (k, condition) in active.iter().enumerate() {
            let (violation, sigma) = match *condition {
                Active::Row(i) => ((mu[k].abs() - weight[i]) / weight[i], mu[k].signum()),
                Active::Column(j) if bounded[j] => (mu[k] / scale, 1.0),
                Active::Column(_) => (mu[k].abs() / scale, mu[k].signum()),
            };
            if violation > 1e-11 && worst.is_none_or(|(_, v, _)| violation > v) {
                worst = Some((k, violation, sigma));
            }
        }
        let Some((leaving, _, sigma)) = worst else {
            return Some(x);
        };
        let mut unit = vec![0.0; p];
        unit[leaving] = sigma;
        let direction = solve_dense(&c, &unit)?;
        let edge = Edge {
            r: &r,
            weight,
            x: &x,
            direction: &direction,
        };
        let entering = edge.search(a, bounded, &active, leaving)?;
        active[leaving] = entering;
        x = vertex(a, y, &active)?;
    }
    None
}

/// Rows of the active conditions: `a_i` for a zero residual, `e_j` for a held column.
fn condition_matrix(a: &DMatrix<f64>, active: &[Active]) -> DMatrix<f64> {
    let p = a.ncols();
    let mut c = DMatrix::zeros(p, p);
    for (k, condition) in active.iter().enumerate() {
        match *condition {
            Active::Row(i) => c.row_mut(k).copy_from(&a.row(i)),
            Active::Column(j) => c[(k, j)] = 1.0,
        }
    }
    c
}

/// The point where all active conditions hold.
fn vertex(a: &DMatrix<f64>, y: &[f64], active: &[Active]) -> Option<Vec<f64>> {
    let rhs: Vec<f64> = active
        .iter()
        .map(|condition| match *condition {
            Active::Row(i) => y[i],
            Active::Column(_) => 0.0,
        })
        .collect();
    solve_dense(&condition_matrix(a, active), &rhs)
}

/// An edge of the L1 problem: from `x` (residuals `r`) along `direction`.
struct Edge<'a> {
    r: &'a [f64],
    weight: &'a [f64],
    x: &'a [f64],
    direction: &'a [f64],
}

impl Edge<'_> {
    /// Minimises `sum w_i |r_i + t c_i|` over `t >= 0` (c = A d) within the
    /// bounds; returns the condition that becomes active there. `None` if the
    /// edge does not descend (rounding at a degenerate vertex) or the loss is
    /// unbounded along it.
    fn search(
        &self,
        a: &DMatrix<f64>,
        bounded: &[bool],
        active: &[Active],
        leaving: usize,
    ) -> Option<Active> {
        let c = a * column(self.direction);
        // The first bound the edge runs into.
        let mut limit: Option<(f64, usize)> = None;
        for (j, (&xj, &dj)) in self.x.iter().zip(self.direction).enumerate() {
            if bounded[j] && dj < 0.0 && !active.contains(&Active::Column(j)) {
                let t = (xj.max(0.0) / -dj).max(0.0);
                if limit.is_none_or(|(tl, _)| t < tl) {
                    limit = Some((t, j));
                }
            }
        }
        // Residual i changes sign at t_i = -r_i / c_i, where the slope grows by 2 w_i |c_i|.
        let mut slope = 0.0;
        let mut breaks: Vec<(f64, f64, usize)> = Vec::new();
        for (i, (&ri, &ci)) in self.r.iter().zip(&c).enumerate() {
            let w = self.weight[i];
            if let Some(k) = active.iter().position(|&x| x == Active::Row(i)) {
                // The other active rows stay at zero; the released one leaves zero.
                if k == leaving {
                    slope += w * ci.abs();
                }
                continue;
            }
            if ci == 0.0 {
                continue;
            }
            let t = -ri / ci;
            if t >= 0.0 || ri == 0.0 {
                slope -= w * ci.abs();
                breaks.push((t.max(0.0), 2.0 * w * ci.abs(), i));
            } else {
                slope += w * ci.abs();
            }
        }
        // Ties (a degenerate vertex: more zero residuals than conditions) are
        // taken in row order, and may give a step of length zero that only
        // exchanges conditions.
        breaks.sort_by(|u, v| u.0.total_cmp(&v.0).then(u.2.cmp(&v.2)));
        let size: f64 = c.iter().zip(self.weight).map(|(v, w)| w * v.abs()).sum();
        if slope >= -1e-12 * size {
            return None;
        }
        for &(t, change, i) in &breaks {
            if let Some((tl, j)) = limit
                && tl <= t
            {
                return Some(Active::Column(j));
            }
            slope += change;
            if slope >= 0.0 {
                return Some(Active::Row(i));
            }
        }
        limit.map(|(_, j)| Active::Column(j))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn design(rows: &[[f64; 2]]) -> DMatrix<f64> {
        DMatrix::from_fn(rows.len(), 2, |i, j| rows[i][j])
    }

    #[test]
    fn l1_is_a_median_and_huber_a_mean_for_one_column() {
        let a = design(&[[1.0, 0.0]; 5]).select_columns(&[0]);
        let y = [1.0, 2.0, 3.0, 10.0, 50.0];
        let x = l1(&a, &y, &[false]).unwrap();
        assert_eq!(x, vec![3.0]);
        // Huber with a wide threshold is least squares: the mean.
        let x = huber(&a, &y, &[false], 1e3).unwrap();
        assert!((x[0] - 13.2).abs() < 1e-12, "{x:?}");
        // With a narrow one, the M-estimate: sum psi(r) = 0.
        let x = huber(&a, &y, &[false], 1.0).unwrap()[0];
        let psi: f64 = y.iter().map(|v| (x - v).clamp(-1.0, 1.0)).sum();
        assert!(psi.abs() < 1e-12, "{x} {psi}");
    }

    #[test]
    fn bounds_are_respected_and_certified() {
        // y = -1 + 2 t: the intercept wants to be negative.
        let rows: Vec<[f64; 2]> = (0..9).map(|i| [1.0, i as f64 / 8.0]).collect();
        let a = design(&rows);
        let y: Vec<f64> = rows.iter().map(|r| -1.0 + 2.0 * r[1]).collect();
        let x = l1(&a, &y, &[true, true]).unwrap();
        assert_eq!(x[0], 0.0);
        assert!(x[1] > 0.0);
        let x = huber(&a, &y, &[true, true], 0.1).unwrap();
        assert_eq!(x[0], 0.0);
        // Unbounded, both recover the line exactly.
        let x = l1(&a, &y, &[false, false]).unwrap();
        assert!(
            (x[0] + 1.0).abs() < 1e-14 && (x[1] - 2.0).abs() < 1e-14,
            "{x:?}"
        );
        let x = huber(&a, &y, &[false, false], 0.1).unwrap();
        assert!(
            (x[0] + 1.0).abs() < 1e-14 && (x[1] - 2.0).abs() < 1e-14,
            "{x:?}"
        );
    }

    #[test]
    fn line_search_finds_the_root_of_the_piecewise_linear_derivative() {
        // One residual r = -3 + t with delta = 1: derivative -1 until t = 2,
        // then t - 3, zero at t = 3.
        let t = huber_line_search(&[-3.0], &[1.0], 1.0, -1.0).unwrap();
        assert!((t - 3.0).abs() < 1e-15, "{t}");
    }
}
