//! A fit's joint uncertainty as `fit.json` carries it: the covariance of the
//! fitted parameters (SI units, and in the fit's own logarithmic space), the
//! jackknife's replicates, and each parameter's path in the stage's
//! parameter table, so that a tolerance analysis can draw the fitted stage
//! (`[robust] from_fit = "fit.json"`).

use serde::{Deserialize, Serialize};

/// The joint covariance of a fit's free parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitCovariance {
    /// The fitted parameters, by name (`f_c`, `sigma0`, ...).
    pub parameters: Vec<String>,
    /// Each parameter's path in the stage's parameter table
    /// (`overrides.<element>.f_c`), or null where it has none (the moving
    /// mass of the one-mass plant, which several links may make).
    pub paths: Vec<Option<String>>,
    /// The fitted values, SI units.
    pub values: Vec<f64>,
    /// `Cov(theta)`, SI units, row by row (first order from `log_matrix`).
    pub matrix: Vec<Vec<f64>>,
    /// `Cov(ln theta)`, the space the fit works in, row by row.
    pub log_matrix: Vec<Vec<f64>>,
    /// How the covariance was found.
    pub method: String,
    /// Degrees of freedom of the intervals it gives.
    pub degrees_of_freedom: usize,
}

impl FitCovariance {
    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.parameters.len()
    }

    /// Whether it covers no parameter.
    pub fn is_empty(&self) -> bool {
        self.parameters.is_empty()
    }

    /// Whether every list has one entry per parameter, the matrices are
    /// square, finite and symmetric, and the values finite; else what is wrong.
    pub fn check(&self) -> Result<(), String> {
        let p = self.len();
        if p == 0 {
            return Err("covariance.parameters is empty".into());
        }
        for (key, n) in [("paths", self.paths.len()), ("values", self.values.len())] {
            if n != p {
                return Err(format!(
                    "covariance.{key} has {n} entries for {p} parameters"
                ));
            }
        }
        if let Some(k) = self.values.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "covariance.values[{k}] ({}) is not a finite number",
                self.parameters[k]
            ));
        }
        for (key, matrix) in [("matrix", &self.matrix), ("log_matrix", &self.log_matrix)] {
            if matrix.len() != p || matrix.iter().any(|row| row.len() != p) {
                return Err(format!("covariance.{key} is not {p} x {p}"));
            }
            for i in 0..p {
                for j in 0..p {
                    let (a, b) = (matrix[i][j], matrix[j][i]);
                    if !a.is_finite() {
                        return Err(format!("covariance.{key}[{i}][{j}] is not a finite number"));
                    }
                    if (a - b).abs() > 1e-9 * (matrix[i][i].abs() * matrix[j][j].abs()).sqrt() {
                        return Err(format!(
                            "covariance.{key} is not symmetric at [{i}][{j}] ({a} against {b})"
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}
