//! The `[sweep]` and `[robust]` tables as a scenario file writes them: their
//! keys, the kinds of their values and their defaults. They are read with
//! the rest of the scenario ([`crate::load`]), so an unknown key in any table
//! is refused in one place, by every command; what they mean (grids,
//! distributions, verdicts) is the analysis crate's.

use serde::{Deserialize, Serialize};

/// Which analyses a study runs at each point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Analyses {
    /// Eigenvalues at the slipping equilibrium.
    Linear,
    /// Simulation from rest.
    Simulation,
    /// Both, and bistability.
    Both,
}

impl Analyses {
    /// Whether the eigenvalues are computed.
    pub fn linear(self) -> bool {
        self != Self::Simulation
    }
    /// Whether the stage is simulated.
    pub fn simulation(self) -> bool {
        self != Self::Linear
    }
}

/// Grid spacing along a sweep axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Spacing {
    /// Evenly spaced values.
    #[serde(alias = "linear")]
    Lin,
    /// Evenly spaced logarithms.
    #[serde(alias = "logarithmic")]
    Log,
}

/// How a tolerance analysis samples the unit cube.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    /// Scrambled Sobol (quasi-Monte Carlo).
    Sobol,
    /// Plain Monte Carlo.
    Random,
    /// Latin hypercube.
    #[serde(alias = "latin_hypercube")]
    Lhs,
}

/// The distribution families of a `[[robust.parameter]]`'s `distribution`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// Uniform between two bounds.
    Uniform,
    /// Normal.
    Normal,
    /// Normal truncated to two bounds.
    #[serde(alias = "truncated_normal")]
    Truncnormal,
    /// Log-normal.
    Lognormal,
}

/// A `[sweep]` table.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepTable {
    /// The `[[sweep.axis]]` entries, in file order.
    #[serde(rename = "axis")]
    pub axes: Vec<AxisTable>,
    /// Analyses to run (default: both).
    #[serde(default = "both")]
    pub analysis: Analyses,
    /// Simulated time per point, s (default: the scenario's duration).
    pub duration: Option<f64>,
    /// Steady peak-to-peak of the sensor above which a run oscillates, m.
    #[serde(default = "default_threshold")]
    pub oscillation_threshold: f64,
}

/// A `[[sweep.axis]]` entry: `from`, `to`, `points` (and `spacing`), or the
/// `values` themselves.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisTable {
    /// Parameter path.
    pub parameter: String,
    /// First value.
    pub from: Option<f64>,
    /// Last value.
    pub to: Option<f64>,
    /// Number of values.
    pub points: Option<usize>,
    /// Spacing (default: linear).
    pub spacing: Option<Spacing>,
    /// The values, instead of a spacing.
    pub values: Option<Vec<f64>>,
}

/// A `[robust]` table.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobustTable {
    /// Stages drawn (default 1000).
    #[serde(default = "default_samples")]
    pub samples: usize,
    /// Seed of the draw.
    #[serde(default)]
    pub seed: u64,
    /// Analyses to run (default: linear).
    #[serde(default = "linear")]
    pub analysis: Analyses,
    /// How the unit cube is sampled (default: Sobol).
    #[serde(default = "sobol")]
    pub sampling: Sampling,
    /// Simulated time per stage, s (default: the scenario's duration).
    pub duration: Option<f64>,
    /// Steady peak-to-peak of the sensor above which a run oscillates, m.
    #[serde(default = "default_threshold")]
    pub oscillation_threshold: f64,
    /// The `[[robust.parameter]]` entries, in file order.
    #[serde(rename = "parameter", default)]
    pub parameters: Vec<ParameterTable>,
    /// A fit's `fit.json` (relative to the scenario file) whose fitted
    /// parameters are drawn jointly, with the fit's covariance.
    pub from_fit: Option<std::path::PathBuf>,
    /// How `from_fit` is drawn (default: normal).
    #[serde(default)]
    pub from_fit_draw: FitDraw,
}

impl Default for RobustTable {
    /// The table with every default and nothing toleranced.
    fn default() -> Self {
        Self {
            samples: default_samples(),
            seed: 0,
            analysis: linear(),
            sampling: sobol(),
            duration: None,
            oscillation_threshold: default_threshold(),
            parameters: Vec::new(),
            from_fit: None,
            from_fit_draw: FitDraw::default(),
        }
    }
}

/// How `[robust] from_fit` draws a fit's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FitDraw {
    /// Multivariate normal about the fitted values with the fit's
    /// covariance (SI units).
    #[default]
    Normal,
    /// The jackknife's replicates themselves, each drawn with equal
    /// probability and spread about the fit by sqrt(blocks - 1) in the
    /// logarithms, so that their covariance is the fit's.
    Replicates,
}

/// A `[[robust.parameter]]` entry: which parameter (`*` within element
/// names matches several) and how it is drawn.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParameterTable {
    /// Parameter path.
    pub parameter: String,
    /// Distribution family.
    pub distribution: Family,
    /// Widths relative to the nominal value (default) or absolute values.
    #[serde(default = "yes")]
    pub relative: bool,
    /// One draw for every parameter the path matches (default: one each).
    #[serde(default)]
    pub shared: bool,
    /// Half width of a uniform distribution.
    pub half_width: Option<f64>,
    /// Lower bound.
    pub low: Option<f64>,
    /// Upper bound.
    pub high: Option<f64>,
    /// Mean.
    pub mean: Option<f64>,
    /// Median of a log-normal distribution.
    pub median: Option<f64>,
    /// Standard deviation.
    pub sd: Option<f64>,
}

fn both() -> Analyses {
    Analyses::Both
}

fn linear() -> Analyses {
    Analyses::Linear
}

fn sobol() -> Sampling {
    Sampling::Sobol
}

fn yes() -> bool {
    true
}

fn default_samples() -> usize {
    1000
}

fn default_threshold() -> f64 {
    1e-9
}
