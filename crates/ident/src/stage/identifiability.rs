//! What records can and cannot tell about a stage's parameters, from the
//! fit's own sensitivities: before the fit from the information matrix of
//! the readings (white measurement noise of the size the records show),
//! after it from the jackknife's covariance (which also holds what
//! correlated errors, such as an unmeasured force, cost).
//!
//! Both work in the logarithms of the parameters, so a standard deviation
//! is a relative spread. A parameter, or a combination of parameters, is
//! undetermined when its 95% interval spans more than a factor of two
//! either way (`1.96 sd(ln theta) > ln 2`): the records cannot tell its
//! value within a factor of two.

use nalgebra::DMatrix;
use serde::Serialize;

/// The largest standard deviation of a logarithm that counts as
/// determined: a 95% interval within a factor of two either way.
pub const DETERMINED_LOG_SD: f64 = std::f64::consts::LN_2 / 1.959_963_984_540_054;

/// One direction in the logarithms of the parameters.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Direction {
    /// Standard deviation of the combination, in its logarithm (infinite:
    /// the records do not see it at all).
    pub sd_log: f64,
    /// Whether it is determined ([`DETERMINED_LOG_SD`]).
    pub determined: bool,
    /// The combination `sum w_j ln theta_j`: (path, weight) for the weights
    /// of at least a tenth of the largest, largest first, the largest
    /// scaled to 1.
    pub combination: Vec<(String, f64)>,
    /// The combination written out, e.g. `ln f_c(friction_fl) - ln f_c(friction_fr)`.
    pub text: String,
    /// The unit vector of the direction, one entry per parameter.
    #[serde(skip)]
    pub vector: Vec<f64>,
}

/// One parameter's verdict.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterVerdict {
    /// Its path.
    pub path: String,
    /// Standard deviation of its logarithm (its relative spread).
    pub sd_log: f64,
    /// Whether it is determined.
    pub determined: bool,
}

/// What the records determine.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Identifiability {
    /// `sensitivities` (before the fit) or `jackknife` (after it).
    pub basis: String,
    /// Singular values of the scaled sensitivities (`1 / sd` of each
    /// direction), largest first.
    pub singular_values: Vec<f64>,
    /// Every direction, best determined first.
    pub directions: Vec<Direction>,
    /// Every parameter.
    pub parameters: Vec<ParameterVerdict>,
}

impl Identifiability {
    /// From the sensitivities: `jacobian` rows of `paths.len()` entries, each
    /// already divided by its reading's noise level.
    pub(crate) fn from_sensitivities(paths: &[String], jacobian: &[f64]) -> Self {
        let p = paths.len();
        let mut information = DMatrix::<f64>::zeros(p, p);
        for row in jacobian.chunks_exact(p) {
            for i in 0..p {
                for j in 0..p {
                    information[(i, j)] += row[i] * row[j];
                }
            }
        }
        let eigen = information.symmetric_eigen();
        let largest = eigen.eigenvalues.iter().fold(0.0f64, |m, &v| m.max(v));
        let pairs: Vec<(f64, Vec<f64>)> = (0..p)
            .map(|i| {
                let value = eigen.eigenvalues[i];
                // Below round-off of the largest, a direction is not seen.
                let sd = if value > 1e-13 * largest && value > 0.0 {
                    1.0 / value.sqrt()
                } else {
                    f64::INFINITY
                };
                (sd, eigen.eigenvectors.column(i).iter().copied().collect())
            })
            .collect();
        Self::from_directions("sensitivities", paths, pairs)
    }

    /// From a covariance of the logarithms.
    pub(crate) fn from_covariance(paths: &[String], covariance: &DMatrix<f64>) -> Self {
        let p = paths.len();
        let eigen = covariance.clone().symmetric_eigen();
        let pairs: Vec<(f64, Vec<f64>)> = (0..p)
            .map(|i| {
                let sd = eigen.eigenvalues[i].max(0.0).sqrt();
                (sd, eigen.eigenvectors.column(i).iter().copied().collect())
            })
            .collect();
        Self::from_directions("jackknife", paths, pairs)
    }

    fn from_directions(basis: &str, paths: &[String], mut pairs: Vec<(f64, Vec<f64>)>) -> Self {
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let parameters = paths
            .iter()
            .enumerate()
            .map(|(j, path)| {
                // A direction the records do not see counts as seen at
                // round-off of the best one, so a parameter with only a
                // round-off share in it is not made undetermined by it.
                let floor = pairs
                    .iter()
                    .map(|(sd, _)| *sd)
                    .fold(f64::INFINITY, f64::min)
                    * 1e8;
                let variance: f64 = (pairs.iter())
                    .map(|(sd, v)| (sd.min(floor) * v[j]).powi(2))
                    .sum();
                let sd_log = if variance.is_finite() {
                    variance.sqrt()
                } else {
                    f64::INFINITY
                };
                ParameterVerdict {
                    path: path.clone(),
                    sd_log,
                    determined: sd_log <= DETERMINED_LOG_SD,
                }
            })
            .collect();
        let directions = pairs
            .iter()
            .map(|(sd, vector)| direction(paths, *sd, vector))
            .collect();
        Self {
            basis: basis.to_string(),
            singular_values: pairs.iter().map(|(sd, _)| 1.0 / sd).collect(),
            directions,
            parameters,
        }
    }

    /// The parameters it calls undetermined.
    pub fn undetermined(&self) -> Vec<String> {
        (self.parameters.iter())
            .filter(|p| !p.determined)
            .map(|p| p.path.clone())
            .collect()
    }

    /// Determined combinations of the parameters none of which is
    /// determined alone (e.g. the sum of four bearings' f_c when only the
    /// table is measured), as text: the well-determined directions of the
    /// undetermined parameters' information once the determined ones are
    /// accounted for (its Schur complement).
    pub fn determined_only_together(&self) -> Vec<String> {
        let p = self.parameters.len();
        let mut information = DMatrix::<f64>::zeros(p, p);
        for (d, sigma) in self.directions.iter().zip(&self.singular_values) {
            let v = nalgebra::DVector::from_column_slice(&d.vector);
            information += (v.clone() * v.transpose()) * sigma.powi(2);
        }
        let (u, k): (Vec<usize>, Vec<usize>) =
            (0..p).partition(|&j| !self.parameters[j].determined);
        if u.len() < 2 {
            return Vec::new();
        }
        let block = |rows: &[usize], cols: &[usize]| {
            DMatrix::from_fn(rows.len(), cols.len(), |i, j| {
                information[(rows[i], cols[j])]
            })
        };
        let mut schur = block(&u, &u);
        if !k.is_empty()
            && let Some(inverse) = block(&k, &k).try_inverse()
        {
            schur -= block(&u, &k) * inverse * block(&k, &u);
        }
        let paths: Vec<String> = u.iter().map(|&j| self.parameters[j].path.clone()).collect();
        let eigen = schur.symmetric_eigen();
        (0..u.len())
            .filter(|&i| eigen.eigenvalues[i] > 0.0)
            .map(|i| {
                let sd = 1.0 / eigen.eigenvalues[i].sqrt();
                let v: Vec<f64> = eigen.eigenvectors.column(i).iter().copied().collect();
                direction(&paths, sd, &v)
            })
            .filter(|d| d.determined && d.combination.len() > 1)
            .map(|d| d.text)
            .collect()
    }
}

/// A direction as a named combination.
fn direction(paths: &[String], sd: f64, vector: &[f64]) -> Direction {
    let largest = vector.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let sign = vector
        .iter()
        .copied()
        .find(|v| v.abs() == largest)
        .map_or(1.0, f64::signum);
    let mut combination: Vec<(String, f64)> = paths
        .iter()
        .zip(vector)
        .map(|(p, &w)| (p.clone(), sign * w / largest.max(f64::MIN_POSITIVE)))
        .filter(|(_, w)| w.abs() >= 0.1)
        .collect();
    // Largest first; weights equal to round-off keep the paths' order.
    let rounded = |w: f64| (w.abs() * 1e6).round();
    combination.sort_by(|a, b| rounded(b.1).total_cmp(&rounded(a.1)));
    let mut text = String::new();
    for (k, (path, w)) in combination.iter().enumerate() {
        let name = short(path);
        let magnitude = w.abs();
        let op = match (k, *w < 0.0) {
            (0, false) => String::new(),
            (0, true) => "-".into(),
            (_, false) => " + ".into(),
            (_, true) => " - ".into(),
        };
        if (magnitude - 1.0).abs() < 0.005 {
            text += &format!("{op}ln {name}");
        } else {
            text += &format!("{op}{magnitude:.2} ln {name}");
        }
    }
    Direction {
        sd_log: sd,
        determined: sd <= DETERMINED_LOG_SD,
        combination,
        text,
        vector: vector.to_vec(),
    }
}

/// `f_c(friction_fl)` for `overrides.friction_fl.f_c`; other paths as they are.
pub fn short(path: &str) -> String {
    match path
        .strip_prefix("overrides.")
        .and_then(|rest| rest.rsplit_once('.'))
    {
        Some((element, key)) => format!("{key}({element})"),
        None => path.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two parameters that always move the reading together are determined
    /// only as their sum; a third, seen alone, is determined.
    #[test]
    fn a_sum_seen_together_is_named_and_its_parts_are_not() {
        let paths: Vec<String> = ["overrides.a.f_c", "overrides.b.f_c", "overrides.c.k_x"]
            .map(String::from)
            .to_vec();
        let mut jacobian = Vec::new();
        for k in 0..200 {
            let t = k as f64 / 200.0;
            jacobian.extend([10.0 * t, 10.0 * t, 5.0 * (7.0 * t).sin()]);
        }
        let found = Identifiability::from_sensitivities(&paths, &jacobian);
        assert_eq!(
            found.undetermined(),
            vec!["overrides.a.f_c".to_string(), "overrides.b.f_c".into()]
        );
        assert!(found.parameters[2].determined);
        let together = found.determined_only_together();
        assert_eq!(
            together,
            vec!["ln f_c(a) + ln f_c(b)".to_string()],
            "{found:?}"
        );
        assert!(
            found
                .directions
                .last()
                .is_some_and(|d| d.sd_log.is_infinite())
        );
        assert_eq!(
            found.directions.last().map(|d| d.text.as_str()),
            Some("ln f_c(a) - ln f_c(b)")
        );
    }
}
