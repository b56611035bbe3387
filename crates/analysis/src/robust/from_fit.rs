//! Drawing the identified stage: `[robust] from_fit = "fit.json"` draws the
//! parameters a fit determined jointly, from the fit's own uncertainty, so
//! that a tolerance analysis gives P(unstable) of the stage the records
//! describe.
//!
//! ```toml
//! [robust]
//! from_fit = "fit/fit.json"      # relative to the scenario file
//! from_fit_draw = "normal"       # normal (default) | replicates
//! ```
//!
//! * `normal`: multivariate normal about the fitted values with the fit's
//!   covariance in SI units (`covariance.matrix`), one design dimension per
//!   parameter, `theta = mean + L z` with `L L^T` the covariance (from its
//!   eigen-decomposition, so a singular covariance draws on its subspace)
//!   and `z` the standard normal quantiles of the design's numbers.
//! * `replicates`: one design dimension picks one of the jackknife's `G`
//!   replicates, spread about the fit by `sqrt(G - 1)` in the logarithms, so
//!   their covariance is the fit's and no draw changes sign. Only `G`
//!   distinct stages (28 for a 7 s record): the probability's interval is
//!   that of the draw from them, and a verdict that turns on a finer
//!   difference than one stage in `G` is beyond them.
//!
//! A fitted parameter without a path in the stage's parameter table (the
//! one-mass plant's moving mass) is left out: the marginal of the others is
//! drawn exactly (for `normal`). A parameter the fit could not determine is
//! refused, by name: its covariance says nothing.

use std::path::{Path, PathBuf};

use fistage_ident::{FitCovariance, NotIdentifiable};
use fistage_model::studies::FitDraw;
use fistage_model::{LoadError, Parameter, RobotSpec, Scenario};
use nalgebra::DMatrix;
use serde::Deserialize;

use super::{Distribution, Target};

/// What `from_fit` reads of a `fit.json` (other keys are the fit's own).
#[derive(Deserialize)]
struct FitFile {
    covariance: Option<FitCovariance>,
    #[serde(default)]
    replicates: Vec<Vec<f64>>,
    #[serde(default)]
    not_identifiable: Vec<NotIdentifiable>,
}

/// The fitted parameters of a `from_fit` table, drawn jointly.
#[derive(Debug, Clone, PartialEq)]
pub struct FittedDraw {
    /// The `fit.json` read.
    pub file: PathBuf,
    /// How it is drawn.
    pub draw: FitDraw,
    /// The drawn parameters: path, the scenario's value, and the marginal
    /// normal of the fit (what a reader sees; the draw is joint).
    pub targets: Vec<Target>,
    /// Fitted parameters that have no path here, left out.
    pub left_out: Vec<String>,
    /// The fitted values, SI units.
    mean: Vec<f64>,
    /// `L` with `L L^T` the covariance of the drawn parameters.
    factor: DMatrix<f64>,
    /// Per replicate, `sqrt(G - 1) (ln theta_b - ln theta)`.
    log_spreads: Vec<Vec<f64>>,
}

impl FittedDraw {
    /// Reads `file` (relative to the scenario's folder) and resolves its
    /// parameters against the study; every error names the file and the key.
    pub fn read(
        file: &Path,
        draw: FitDraw,
        scenario: &Scenario,
        robot: &RobotSpec,
    ) -> Result<Self, LoadError> {
        let file = match scenario.file.parent() {
            Some(folder) if file.is_relative() => folder.join(file),
            _ => file.to_path_buf(),
        };
        let refuse =
            |why: String| scenario.error("robust.from_fit", format!("{}: {why}", file.display()));
        let text =
            fistage_model::input::read_text(&file, fistage_model::input::MAX_DESCRIPTION_BYTES)
                .map_err(|e| refuse(e.to_string()))?;
        let fit: FitFile = serde_json::from_str(&text).map_err(|e| refuse(e.to_string()))?;
        let covariance = fit.covariance.ok_or_else(|| {
            refuse("holds no covariance (a fit whose information matrix could not be inverted, or not a fit's fit.json)".into())
        })?;
        covariance.check().map_err(refuse)?;
        let keep: Vec<usize> = (0..covariance.len())
            .filter(|&k| covariance.paths[k].is_some())
            .collect();
        if keep.is_empty() {
            return Err(refuse(
                "no fitted parameter has a path in the parameter table (covariance.paths)".into(),
            ));
        }
        for &k in &keep {
            let name = &covariance.parameters[k];
            if let Some(n) = fit.not_identifiable.iter().find(|n| &n.parameter == name) {
                return Err(refuse(format!(
                    "{name} was not determined by its record ({}): a population cannot be drawn from its interval",
                    n.reason
                )));
            }
        }
        let mut targets = Vec::new();
        for &k in &keep {
            let path = covariance.paths[k].as_deref().unwrap_or_default();
            let parameter = Parameter::resolve(path, scenario, robot)
                .map_err(|e| refuse(format!("covariance.paths[{k}]: {e}")))?;
            targets.push(Target {
                path: parameter.path().to_string(),
                nominal: parameter.read(scenario, robot),
                distribution: Distribution::Normal {
                    mean: covariance.values[k],
                    sd: covariance.matrix[k][k].max(0.0).sqrt(),
                },
            });
        }
        let sub = DMatrix::from_fn(keep.len(), keep.len(), |i, j| {
            covariance.matrix[keep[i]][keep[j]]
        });
        let factor = square_root(&sub).map_err(refuse)?;
        let log_spreads = match draw {
            FitDraw::Normal => Vec::new(),
            FitDraw::Replicates => {
                replicate_spreads(&fit.replicates, &covariance, &keep).map_err(refuse)?
            }
        };
        Ok(Self {
            file,
            draw,
            targets,
            left_out: (0..covariance.len())
                .filter(|k| !keep.contains(k))
                .map(|k| covariance.parameters[k].clone())
                .collect(),
            mean: keep.iter().map(|&k| covariance.values[k]).collect(),
            factor,
            log_spreads,
        })
    }

    /// With `replicates`, the number of distinct stages it can draw (the
    /// fit's blocks): a probability over them is resolved no finer than
    /// one over that, however many samples are drawn.
    pub fn distinct_stages(&self) -> Option<usize> {
        (self.draw == FitDraw::Replicates).then_some(self.log_spreads.len())
    }

    /// Design dimensions it takes: one per parameter, or one for a replicate.
    pub fn dimensions(&self) -> usize {
        match self.draw {
            FitDraw::Normal => self.mean.len(),
            FitDraw::Replicates => 1,
        }
    }

    /// The drawn values, one per target, from the design's numbers `u`
    /// (`dimensions()` of them, each in (0, 1)).
    pub fn values(&self, u: &[f64]) -> Vec<f64> {
        match self.draw {
            FitDraw::Normal => {
                let standard = Distribution::Normal { mean: 0.0, sd: 1.0 };
                let z: Vec<f64> = u.iter().map(|&u| standard.quantile(u)).collect();
                (0..self.mean.len())
                    .map(|i| {
                        self.mean[i]
                            + (0..z.len())
                                .map(|j| self.factor[(i, j)] * z[j])
                                .sum::<f64>()
                    })
                    .collect()
            }
            FitDraw::Replicates => {
                let count = self.log_spreads.len();
                let b = ((u[0] * count as f64) as usize).min(count - 1);
                self.mean
                    .iter()
                    .zip(&self.log_spreads[b])
                    .map(|(m, d)| m * d.exp())
                    .collect()
            }
        }
    }
}

/// `L` with `L L^T = c` for a symmetric positive semidefinite `c` (from its
/// eigen-decomposition); a clearly negative eigenvalue is refused.
fn square_root(c: &DMatrix<f64>) -> Result<DMatrix<f64>, String> {
    let eigen = c.clone().symmetric_eigen();
    let largest = eigen
        .eigenvalues
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    if let Some(low) = eigen
        .eigenvalues
        .iter()
        .find(|&&v| v < -1e-9 * largest.max(f64::MIN_POSITIVE))
    {
        return Err(format!(
            "covariance.matrix is not a covariance: it has the negative eigenvalue {low:e}"
        ));
    }
    let n = c.nrows();
    Ok(DMatrix::from_fn(n, n, |i, j| {
        eigen.eigenvectors[(i, j)] * eigen.eigenvalues[j].max(0.0).sqrt()
    }))
}

/// `sqrt(G - 1) (ln theta_b - ln theta)` of the kept parameters per replicate.
fn replicate_spreads(
    replicates: &[Vec<f64>],
    covariance: &FitCovariance,
    keep: &[usize],
) -> Result<Vec<Vec<f64>>, String> {
    if replicates.len() < 2 {
        return Err(format!(
            "from_fit_draw = \"replicates\" needs the fit's replicates, and it holds {}",
            replicates.len()
        ));
    }
    let inflation = ((replicates.len() - 1) as f64).sqrt();
    replicates
        .iter()
        .enumerate()
        .map(|(b, row)| {
            if row.len() != covariance.len() {
                return Err(format!(
                    "replicates[{b}] has {} values for {} parameters",
                    row.len(),
                    covariance.len()
                ));
            }
            keep.iter()
                .map(|&k| {
                    let (value, fitted) = (row[k], covariance.values[k]);
                    if value > 0.0 && fitted > 0.0 && value.is_finite() {
                        Ok(inflation * (value / fitted).ln())
                    } else {
                        Err(format!(
                            "replicates[{b}][{k}] ({}) and the fitted value must be positive to be spread in logarithms",
                            covariance.parameters[k]
                        ))
                    }
                })
                .collect()
        })
        .collect()
}
