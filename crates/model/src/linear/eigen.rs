//! Eigenvalues and eigenvectors of a real non-symmetric matrix, for every
//! part of the toolkit that reads a Jacobian's spectrum (the default engine's
//! choice of method, the rapier engine's step, modal and stability analysis).
//! The matrix is first balanced (a diagonal similarity D^-1 A D with powers of
//! two that evens out row and column norms, as LAPACK's gebal does: the
//! Jacobians here mix bristle deflections of micrometres with accelerations of
//! thousands of m/s^2); eigenvalues come from nalgebra's Schur decomposition
//! with an iteration cap (never an endless loop: unbalanced and uncapped, the
//! Schur iteration does not finish on the full-state Jacobian of the
//! four-bearing stage under the Fig. 5b conditions), eigenvectors from complex
//! inverse iteration (shifted slightly off each eigenvalue, deflating against
//! vectors already found for the same eigenvalue so that repeated eigenvalues
//! get independent vectors), mapped back through D. The singular value
//! decomposition used to name a singular balance or to solve least squares
//! goes through [`svd`] for the same reason: nalgebra's own loops forever on
//! a matrix with a NaN entry.

use nalgebra::{Complex, DMatrix, DVector};

/// An eigenvalue with its unit eigenvector.
#[derive(Debug, Clone, PartialEq)]
pub struct EigenPair {
    /// Eigenvalue.
    pub value: Complex<f64>,
    /// Eigenvector, unit 2-norm.
    pub vector: DVector<Complex<f64>>,
    /// Residual `|A v - lambda v| / (|A| + |lambda|)`.
    pub residual: f64,
}

/// Osborne's balancing: returns D (powers of two) such that D^-1 A D has
/// comparable row and column norms.
fn balance(matrix: &DMatrix<f64>) -> Vec<f64> {
    let n = matrix.nrows();
    let mut scale = vec![1.0_f64; n];
    let mut a = matrix.clone();
    for _ in 0..100 {
        let mut changed = false;
        for i in 0..n {
            let column: f64 = (0..n).filter(|&r| r != i).map(|r| a[(r, i)].abs()).sum();
            let row: f64 = (0..n).filter(|&c| c != i).map(|c| a[(i, c)].abs()).sum();
            if column == 0.0 || row == 0.0 {
                continue;
            }
            let mut factor = 1.0_f64;
            let (mut c, mut r) = (column, row);
            while c < r / 2.0 {
                c *= 2.0;
                r /= 2.0;
                factor *= 2.0;
            }
            while c >= r * 2.0 {
                c /= 2.0;
                r *= 2.0;
                factor /= 2.0;
            }
            if (c + r) < 0.95 * (column + row) {
                changed = true;
                scale[i] *= factor;
                for k in 0..n {
                    a[(i, k)] /= factor;
                    a[(k, i)] *= factor;
                }
            }
        }
        if !changed {
            break;
        }
    }
    scale
}

/// The eigenvalues of a square matrix, balanced first; `None` when the Schur
/// iteration does not converge even at a loose tolerance.
pub fn eigenvalues(matrix: &DMatrix<f64>) -> Option<Vec<Complex<f64>>> {
    let scale = balance(matrix);
    schur_eigenvalues(&balanced(matrix, &scale))
}

/// The largest eigenvalue modulus of a square matrix; `None` when the
/// eigenvalues cannot be computed (see [`eigenvalues`]).
pub fn spectral_radius(matrix: &DMatrix<f64>) -> Option<f64> {
    let values = eigenvalues(matrix)?;
    let radius = values.iter().map(|l| l.norm()).fold(0.0, f64::max);
    radius.is_finite().then_some(radius)
}

/// Iterations of the Schur and singular value iterations before they give up
/// (each converges in a few per eigenvalue or singular value when it does).
const MAX_ITERATIONS: usize = 20_000;

/// The singular value decomposition of a matrix, `None` for a matrix with a
/// non-finite entry or when the iteration does not converge.
pub fn svd(
    matrix: DMatrix<f64>,
    compute_u: bool,
    compute_v: bool,
) -> Option<nalgebra::linalg::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>> {
    if matrix.iter().any(|v| !v.is_finite()) {
        return None;
    }
    matrix.try_svd(compute_u, compute_v, f64::EPSILON, MAX_ITERATIONS)
}

/// D^-1 A D for the balancing scale D.
fn balanced(matrix: &DMatrix<f64>, scale: &[f64]) -> DMatrix<f64> {
    let n = matrix.nrows();
    DMatrix::from_fn(n, n, |r, c| matrix[(r, c)] * scale[c] / scale[r])
}

/// Eigenvalues by the Schur form, with an iteration cap and a graded
/// convergence tolerance if the tightest one is not reached.
fn schur_eigenvalues(matrix: &DMatrix<f64>) -> Option<Vec<Complex<f64>>> {
    if matrix.iter().any(|v| !v.is_finite()) {
        return None;
    }
    [f64::EPSILON, 1e-14, 1e-13, 1e-12, 1e-10]
        .into_iter()
        .find_map(|epsilon| {
            nalgebra::linalg::Schur::try_new(matrix.clone(), epsilon, MAX_ITERATIONS)
        })
        .map(|schur| schur.complex_eigenvalues().iter().copied().collect())
}

/// All eigenpairs of a square real matrix, sorted by |lambda|, then by imaginary
/// part. Eigenvalues are NaN if the Schur iteration fails even at a loose tolerance.
pub fn eigen_decomposition(original: &DMatrix<f64>) -> Vec<EigenPair> {
    let n = original.nrows();
    let scale = balance(original);
    let matrix = balanced(original, &scale);
    let mut values =
        schur_eigenvalues(&matrix).unwrap_or_else(|| vec![Complex::new(f64::NAN, f64::NAN); n]);
    values.sort_by(|a, b| a.norm().total_cmp(&b.norm()).then(a.im.total_cmp(&b.im)));
    let complex: DMatrix<Complex<f64>> = matrix.map(|v| Complex::new(v, 0.0));
    let balance_scale = scale_vector(&scale);
    let scale = matrix.norm().max(f64::MIN_POSITIVE);
    let mut pairs: Vec<EigenPair> = Vec::with_capacity(n);
    let mut balanced: Vec<DVector<Complex<f64>>> = Vec::with_capacity(n);
    for value in values {
        let same: Vec<DVector<Complex<f64>>> = pairs
            .iter()
            .zip(&balanced)
            .filter(|(p, _)| (p.value - value).norm() <= 1e-8 * (scale + value.norm()))
            .map(|(_, v)| v.clone())
            .collect();
        let vector = inverse_iteration(&complex, value, scale, &same);
        let residual = (&complex * &vector - &vector * value).norm() / (scale + value.norm());
        // Back to the original coordinates: v = D v_balanced, unit norm.
        let mut original_vector = DVector::from_fn(n, |i, _| vector[i] * balance_scale[i]);
        let norm = original_vector.norm();
        if norm > 0.0 {
            original_vector /= Complex::new(norm, 0.0);
        }
        balanced.push(vector);
        pairs.push(EigenPair {
            value,
            vector: original_vector,
            residual,
        });
    }
    pairs
}

fn scale_vector(scale: &[f64]) -> Vec<Complex<f64>> {
    scale.iter().map(|s| Complex::new(*s, 0.0)).collect()
}

fn inverse_iteration(
    matrix: &DMatrix<Complex<f64>>,
    value: Complex<f64>,
    scale: f64,
    deflate: &[DVector<Complex<f64>>],
) -> DVector<Complex<f64>> {
    let n = matrix.nrows();
    let shift = value + Complex::new(1e-10 * scale, 1e-10 * scale);
    let shifted = matrix - DMatrix::<Complex<f64>>::identity(n, n) * shift;
    let lu = shifted.lu();
    // A start vector with no special structure.
    let mut vector = DVector::from_fn(n, |i, _| {
        Complex::new(1.0 + 0.37 * i as f64, 0.11 * (i % 3) as f64)
    });
    for _ in 0..4 {
        for previous in deflate {
            let projection = previous.dotc(&vector);
            vector -= previous * projection;
        }
        let Some(next) = lu.solve(&vector) else {
            break;
        };
        let norm = next.norm();
        if !norm.is_finite() || norm == 0.0 {
            break;
        }
        vector = next / Complex::new(norm, 0.0);
    }
    vector
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A NaN entry sends nalgebra's own singular value iteration into an
    /// endless loop; these return `None` instead, and the same matrix
    /// without it decomposes.
    #[test]
    fn a_matrix_with_a_nan_entry_has_no_spectrum_and_no_svd() {
        let mut a = DMatrix::from_fn(4, 4, |i, j| (i * 4 + j) as f64 + 1.0);
        let singular = svd(a.clone(), false, true).expect("a finite matrix decomposes");
        // Rank 2: two singular values at round-off.
        let mut values: Vec<f64> = singular.singular_values.iter().copied().collect();
        values.sort_by(f64::total_cmp);
        assert!(values[1] < 1e-12 * values[3], "{values:?}");
        a[(1, 2)] = f64::NAN;
        assert!(svd(a.clone(), false, true).is_none());
        assert!(eigenvalues(&a).is_none());
        assert!(spectral_radius(&a).is_none());
    }

    #[test]
    fn eigenpairs_of_a_damped_oscillator_and_a_repeated_root() {
        // x'' + 2 zeta w x' + w^2 x = 0 twice (a repeated pair) and a real root -3.
        let (w, zeta) = (5.0, 0.1);
        let mut a = DMatrix::zeros(5, 5);
        for block in [0, 2] {
            a[(block, block + 1)] = 1.0;
            a[(block + 1, block)] = -w * w;
            a[(block + 1, block + 1)] = -2.0 * zeta * w;
        }
        a[(4, 4)] = -3.0;
        let pairs = eigen_decomposition(&a);
        assert_eq!(pairs.len(), 5);
        assert!((pairs[0].value.re + 3.0).abs() < 1e-12);
        for pair in &pairs[1..] {
            assert!((pair.value.norm() - w).abs() < 1e-9);
            assert!((-pair.value.re / pair.value.norm() - zeta).abs() < 1e-9);
        }
        for pair in &pairs {
            assert!(pair.residual < 1e-10, "residual {}", pair.residual);
        }
        // The two copies of a repeated eigenvalue get orthogonal vectors.
        assert!((pairs[1].value - pairs[2].value).norm() < 1e-9);
        let overlap = pairs[1].vector.dotc(&pairs[2].vector).norm();
        assert!(overlap < 1e-6, "overlap {overlap}");
    }
}
