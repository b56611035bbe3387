//! Tolerance analysis of a population of stages: the parameters that scatter
//! from part to part are drawn from their distributions, and each sample is
//! judged as a sweep point is (the linear verdict at the slipping
//! equilibrium, and with `simulation` the simulated verdict and the steady
//! tracking-error amplitude). The summary gives the probability that a stage
//! is linearly unstable, or oscillates, with a Wilson 95% interval, the
//! quantiles of the largest real part and of the amplitude, and which
//! tolerance matters most (Spearman rank correlation of each drawn parameter
//! with the largest real part and with the amplitude).
//!
//! ```toml
//! [robust]
//! samples = 4000                 # default 1000
//! seed = 7                       # default 0
//! analysis = "linear"            # linear (default) | simulation | both
//! sampling = "sobol"             # sobol (scrambled, default) | random | lhs
//! duration = 2.0                 # s per simulated sample (default: the scenario's)
//! oscillation_threshold = 1e-9   # m, as in [sweep]
//!
//! [[robust.parameter]]
//! parameter = "overrides.bearing_*.f_s"   # any path sweep accepts; '*' matches
//! distribution = "normal"                 # within a name; each match is drawn
//! relative = true                         # independently unless shared = true
//! sd = 0.05
//! ```
//!
//! See [`distribution`] for the distributions and their keys, and
//! [`from_fit`] for drawing an identified stage from its fit (`from_fit =
//! "fit.json"`, alone or with parameter entries). Every sample
//! is a function of (seed, index) alone ([`sampling`]), so shards compute
//! the samples a single run would. The binomial interval is exact in its
//! coverage for plain Monte Carlo (`random`); for the scrambled and
//! stratified designs it is conservative (their variance is no larger for
//! the smooth boundaries of these studies).

pub mod distribution;
pub mod from_fit;
pub mod sampling;
pub mod statistics;
mod study;
pub mod table;
pub mod tune;

use fistage_model::studies::{Family, ParameterTable};
use fistage_model::{LoadError, Loaded, Parameter, RobotSpec, Scenario};
use serde::Serialize;

pub use distribution::Distribution;
pub use from_fit::FittedDraw;
pub use sampling::{Design, Sampling};
pub use statistics::{Probability, quantile, spearman};
pub use study::RobustStudy;

use crate::assess::{Assessment, Outcome, in_parallel, study_with};

/// Samples a study may have (checked before anything is allocated).
pub const MAX_SAMPLES: usize = 1_000_000;

/// One drawn parameter: its path, nominal value and distribution.
#[derive(Debug, Clone, PartialEq)]
pub struct Target {
    /// Parameter path.
    pub path: String,
    /// Value in the robot and scenario.
    pub nominal: f64,
    /// Distribution of its value.
    pub distribution: Distribution,
}

/// One dimension of the design: one uniform number per sample, drawn into
/// one target, or into several (`shared = true`) at the same quantile.
#[derive(Debug, Clone, PartialEq)]
pub struct Dimension {
    /// The `parameter` entry it comes from (a path or a pattern).
    pub entry: String,
    /// What it draws.
    pub targets: Vec<Target>,
}

/// A checked `[robust]` table, resolved against its study.
#[derive(Debug, Clone)]
pub struct RobustSpec {
    /// Samples.
    pub samples: usize,
    /// Seed of the design.
    pub seed: u64,
    /// Design of the unit cube.
    pub sampling: Sampling,
    /// What is computed per sample.
    pub assessment: Assessment,
    /// The design's dimensions.
    pub dimensions: Vec<Dimension>,
    /// The parameters drawn jointly from a fit (`from_fit`), after the
    /// dimensions.
    pub fitted: Option<FittedDraw>,
    design: Design,
}

/// What one sample gave.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleResult {
    /// Sample index.
    pub index: usize,
    /// Drawn values, one per target (in [`RobustSpec::columns`] order).
    pub values: Vec<f64>,
    /// Verdicts and amplitude.
    pub outcome: Outcome,
    /// Why the sample's stage could not be built (values the model refuses
    /// together, such as f_s below f_c), if so.
    pub refused: Option<String>,
}

impl RobustSpec {
    /// Reads the scenario's `[robust]` table and resolves it against the
    /// study (`robot` as written in its file), with `samples` and `seed`
    /// from the command line in place of the table's when given. Every
    /// error names the key.
    pub fn from_scenario(
        scenario: &Scenario,
        robot: &RobotSpec,
        samples: Option<usize>,
        seed: Option<u64>,
    ) -> Result<Self, LoadError> {
        let raw = scenario
            .robust
            .as_ref()
            .ok_or_else(|| scenario.error("robust", "the scenario has no [robust] table"))?;
        let samples = samples.unwrap_or(raw.samples);
        if samples == 0 || samples > MAX_SAMPLES {
            return Err(scenario.error(
                "robust.samples",
                format!("must be from 1 to {MAX_SAMPLES}, got {samples}"),
            ));
        }
        if raw.parameters.is_empty() && raw.from_fit.is_none() {
            return Err(scenario.error(
                "robust.parameter",
                "no [[robust.parameter]] and no from_fit: nothing is toleranced",
            ));
        }
        let assessment = Assessment {
            analysis: raw.analysis,
            duration: raw.duration,
            oscillation_threshold: raw.oscillation_threshold,
        };
        assessment.check(scenario, "robust")?;
        // A distribution is about the study's value: the robot file's after
        // the scenario's own overrides (a drawn value then replaces it).
        let mut overridden = robot.clone();
        fistage_model::assembly::apply_overrides(&mut overridden, scenario)?;
        let mut dimensions: Vec<Dimension> = Vec::new();
        for (k, entry) in raw.parameters.iter().enumerate() {
            let key = format!("robust.parameter[{k}]");
            let targets = resolve_entry(entry, &key, scenario, &overridden)?;
            for target in &targets {
                let taken = dimensions
                    .iter()
                    .flat_map(|d| &d.targets)
                    .any(|t| t.path == target.path);
                if taken {
                    return Err(scenario.error(
                        format!("{key}.parameter"),
                        format!("\"{}\" is toleranced twice", target.path),
                    ));
                }
            }
            if entry.shared {
                dimensions.push(Dimension {
                    entry: entry.parameter.clone(),
                    targets,
                });
            } else {
                dimensions.extend(targets.into_iter().map(|t| Dimension {
                    entry: entry.parameter.clone(),
                    targets: vec![t],
                }));
            }
        }
        let fitted = match &raw.from_fit {
            Some(file) => Some(FittedDraw::read(file, raw.from_fit_draw, scenario, robot)?),
            None => None,
        };
        if let Some(fitted) = &fitted
            && let Some(both) = fitted.targets.iter().find(|t| {
                dimensions
                    .iter()
                    .flat_map(|d| &d.targets)
                    .any(|d| d.path == t.path)
            })
        {
            return Err(scenario.error(
                "robust.from_fit",
                format!(
                    "\"{}\" is drawn from the fit and toleranced by a [[robust.parameter]] too",
                    both.path
                ),
            ));
        }
        let seed = seed.unwrap_or(raw.seed);
        let count = dimensions.len() + fitted.as_ref().map_or(0, FittedDraw::dimensions);
        let design = Design::new(raw.sampling, seed, samples, count)
            .map_err(|why| scenario.error("robust.sampling", why))?;
        Ok(Self {
            samples,
            seed,
            sampling: raw.sampling,
            assessment,
            dimensions,
            fitted,
            design,
        })
    }

    /// The drawn parameters, one column each, in design order.
    pub fn columns(&self) -> Vec<&Target> {
        let fitted = self.fitted.iter().flat_map(|f| &f.targets);
        self.dimensions
            .iter()
            .flat_map(|d| &d.targets)
            .chain(fitted)
            .collect()
    }

    /// The parameter values of sample `index`, one per column.
    pub fn values(&self, index: usize) -> Vec<f64> {
        let u = self.design.point(index);
        let (independent, joint) = u.split_at(self.dimensions.len());
        let mut values: Vec<f64> = self
            .dimensions
            .iter()
            .zip(independent)
            .flat_map(|(d, &u)| d.targets.iter().map(move |t| t.distribution.quantile(u)))
            .collect();
        if let Some(fitted) = &self.fitted {
            values.extend(fitted.values(joint));
        }
        values
    }

    /// Evaluates sample `index` of the study `base` (whose robot file, as
    /// written, is `robot_file`).
    pub fn evaluate(&self, base: &Loaded, robot_file: &RobotSpec, index: usize) -> SampleResult {
        let values = self.values(index);
        let assignments: Vec<(&str, f64)> = self
            .columns()
            .iter()
            .zip(&values)
            .map(|(t, &v)| (t.path.as_str(), v))
            .collect();
        let (outcome, refused) = match study_with(base, robot_file, &assignments) {
            Ok(loaded) => (self.assessment.assess(&loaded), None),
            Err(error) => (Outcome::default(), Some(error.to_string())),
        };
        SampleResult {
            index,
            values,
            outcome,
            refused,
        }
    }

    /// Evaluates the given samples on `threads` threads, in index order;
    /// `done` is called with each as it finishes.
    pub fn run(
        &self,
        base: &Loaded,
        robot_file: &RobotSpec,
        indices: &[usize],
        threads: usize,
        done: &(dyn Fn(&SampleResult, usize) + Sync),
    ) -> Vec<SampleResult> {
        let mut results = in_parallel(
            indices,
            threads,
            &|index| self.evaluate(base, robot_file, index),
            done,
        );
        results.sort_by_key(|r| r.index);
        results
    }
}

/// The targets of one `[[robust.parameter]]` entry, each with its resolved
/// distribution, checked against the parameter's rule.
fn resolve_entry(
    entry: &ParameterTable,
    key: &str,
    scenario: &Scenario,
    robot: &RobotSpec,
) -> Result<Vec<Target>, LoadError> {
    let parameters: Vec<Parameter> = if entry.parameter.contains('*') {
        let found = Parameter::matching(&entry.parameter, scenario, robot);
        if found.is_empty() {
            return Err(scenario.error(
                format!("{key}.parameter"),
                format!("\"{}\" matches no parameter of this study", entry.parameter),
            ));
        }
        found
    } else {
        vec![Parameter::resolve(&entry.parameter, scenario, robot)?]
    };
    parameters
        .iter()
        .map(|parameter| {
            let nominal = parameter.read(scenario, robot);
            let distribution = distribution_of(entry, nominal)
                .map_err(|(field, why)| scenario.error(format!("{key}.{field}"), why))?;
            distribution
                .check_support(parameter.rule())
                .map_err(|why| scenario.error(format!("{key} ({})", parameter.path()), why))?;
            Ok(Target {
                path: parameter.path().to_string(),
                nominal,
                distribution,
            })
        })
        .collect()
}

/// The distribution an entry gives a parameter of this nominal value, or
/// (key, why) for the first key at fault.
fn distribution_of(
    entry: &ParameterTable,
    nominal: f64,
) -> Result<Distribution, (&'static str, String)> {
    let need = |field: &'static str, value: Option<f64>| -> Result<f64, (&'static str, String)> {
        match value {
            Some(v) if v.is_finite() => Ok(v),
            Some(v) => Err((field, format!("must be finite, got {v}"))),
            None => Err((
                field,
                format!("{:?} needs {field}", entry.distribution).to_lowercase(),
            )),
        }
    };
    let positive = |field: &'static str, value: Option<f64>| {
        let v = need(field, value)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err((
                field,
                format!("must be > 0, got {}", fistage_model::rule::show(v)),
            ))
        }
    };
    let ordered = |low: f64, high: f64| {
        if low < high {
            Ok((low, high))
        } else {
            Err((
                "high",
                format!(
                    "must be above low ({}), got {}",
                    fistage_model::rule::show(low),
                    fistage_model::rule::show(high)
                ),
            ))
        }
    };
    if entry.relative && nominal == 0.0 {
        return Err((
            "relative",
            "a relative spread of a parameter whose nominal value is 0 is 0: give relative = false and absolute values".into(),
        ));
    }
    // Relative fractions become absolute values around the nominal.
    let around = |fraction: f64| nominal * (1.0 + fraction);
    let (scale, sorted) = (nominal.abs(), |a: f64, b: f64| (a.min(b), a.max(b)));
    Ok(match (entry.distribution, entry.relative) {
        (Family::Uniform, true) => {
            let w = positive("half_width", entry.half_width)?;
            let (low, high) = sorted(around(-w), around(w));
            Distribution::Uniform { low, high }
        }
        (Family::Uniform, false) => {
            let (low, high) = ordered(need("low", entry.low)?, need("high", entry.high)?)?;
            Distribution::Uniform { low, high }
        }
        (Family::Normal, true) => Distribution::Normal {
            mean: nominal,
            sd: positive("sd", entry.sd)? * scale,
        },
        (Family::Normal, false) => Distribution::Normal {
            mean: need("mean", entry.mean)?,
            sd: positive("sd", entry.sd)?,
        },
        (Family::Lognormal, relative) => Distribution::LogNormal {
            median: if relative {
                nominal
            } else {
                need("median", entry.median)?
            },
            sd: positive("sd", entry.sd)?,
        },
        (Family::Truncnormal, relative) => {
            let sd = positive("sd", entry.sd)?;
            let (low, high) = ordered(need("low", entry.low)?, need("high", entry.high)?)?;
            if relative {
                let (low, high) = sorted(around(low), around(high));
                Distribution::TruncNormal {
                    mean: nominal,
                    sd: sd * scale,
                    low,
                    high,
                }
            } else {
                Distribution::TruncNormal {
                    mean: need("mean", entry.mean)?,
                    sd,
                    low,
                    high,
                }
            }
        }
    })
}

/// Quantiles of a set of values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Quantiles {
    /// 5%.
    pub p05: f64,
    /// Median.
    pub p50: f64,
    /// 95%.
    pub p95: f64,
    /// Largest.
    pub max: f64,
}

impl Quantiles {
    fn of(mut values: Vec<f64>) -> Option<Self> {
        values.sort_by(f64::total_cmp);
        Some(Self {
            p05: quantile(&values, 0.05)?,
            p50: quantile(&values, 0.5)?,
            p95: quantile(&values, 0.95)?,
            max: *values.last()?,
        })
    }
}

/// One parameter's influence.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sensitivity {
    /// Parameter path.
    pub parameter: String,
    /// The ranking measure: |rank correlation| with the largest real part
    /// (or with the amplitude when only simulation ran).
    pub index: f64,
    /// Spearman rank correlation with the largest real part.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rank_correlation_max_real_eig: Option<f64>,
    /// Spearman rank correlation with the amplitude.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rank_correlation_amplitude: Option<f64>,
}

/// What `summary.json` holds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Samples of the study.
    pub samples: usize,
    /// Samples computed (all of them after a merge).
    pub computed: usize,
    /// Design.
    pub sampling: Sampling,
    /// Seed.
    pub seed: u64,
    /// P(largest real part > 0): the estimate over the samples with a linear
    /// verdict; the interval also spans every outcome the undetermined ones
    /// could have had.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub p_unstable_linear: Option<Probability>,
    /// Samples whose linear verdict the numerics could not back.
    pub undetermined_linear: usize,
    /// P(persistent oscillation in simulation) over the simulated samples;
    /// the interval also spans every outcome of those without a verdict.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub p_oscillating: Option<Probability>,
    /// Samples without a simulated verdict: still decaying after the
    /// longest run (neither below the threshold nor persistent), or a
    /// failed run.
    pub undetermined_simulated: usize,
    /// Samples whose stage could not be built (see samples.csv, `refused`).
    pub refused: usize,
    /// Quantiles of the largest real part, 1/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_real_eig_quantiles: Option<Quantiles>,
    /// Quantiles of the steady tracking-error amplitude, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub amplitude_quantiles: Option<Quantiles>,
    /// Quantiles of the steady yaw amplitude (stages with a floating table), rad.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub yaw_amplitude_quantiles: Option<Quantiles>,
    /// How `sensitivity` ranks.
    pub sensitivity_method: &'static str,
    /// Parameters by influence, largest first.
    pub sensitivity: Vec<Sensitivity>,
}

impl Summary {
    /// The summary of these results of `spec`.
    pub fn of(spec: &RobustSpec, results: &[SampleResult]) -> Self {
        // Verdicts of built stages only, so that no count exceeds `built`.
        let built_stages = || results.iter().filter(|r| r.refused.is_none());
        let linear: Vec<bool> = built_stages()
            .filter_map(|r| r.outcome.stable_linear)
            .collect();
        let simulated: Vec<bool> = built_stages()
            .filter_map(|r| r.outcome.stable_sim)
            .collect();
        let analysis = spec.assessment.analysis;
        let count_false = |v: &[bool]| v.iter().filter(|s| !**s).count();
        let built = built_stages().count();
        let eig: Vec<(usize, f64)> = results
            .iter()
            .enumerate()
            .filter_map(|(i, r)| r.outcome.max_real_eig.map(|v| (i, v)))
            .collect();
        let amp: Vec<(usize, f64)> = results
            .iter()
            .enumerate()
            .filter_map(|(i, r)| r.outcome.amplitude.map(|v| (i, v)))
            .collect();
        let correlation = |column: usize, metric: &[(usize, f64)]| {
            let x: Vec<f64> = metric
                .iter()
                .map(|&(i, _)| results[i].values[column])
                .collect();
            let y: Vec<f64> = metric.iter().map(|&(_, v)| v).collect();
            spearman(&x, &y)
        };
        let mut sensitivity: Vec<Sensitivity> = spec
            .columns()
            .iter()
            .enumerate()
            .map(|(column, target)| {
                let eig_rho = correlation(column, &eig);
                let amp_rho = correlation(column, &amp);
                Sensitivity {
                    parameter: target.path.clone(),
                    index: eig_rho.or(amp_rho).map_or(0.0, f64::abs),
                    rank_correlation_max_real_eig: eig_rho,
                    rank_correlation_amplitude: amp_rho,
                }
            })
            .collect();
        sensitivity.sort_by(|a, b| b.index.total_cmp(&a.index));
        Self {
            samples: spec.samples,
            computed: results.len(),
            sampling: spec.sampling,
            seed: spec.seed,
            p_unstable_linear: analysis.linear().then(|| {
                Probability::with_unknown(count_false(&linear), linear.len(), built - linear.len())
            }),
            undetermined_linear: if analysis.linear() {
                built - linear.len()
            } else {
                0
            },
            p_oscillating: analysis.simulation().then(|| {
                Probability::with_unknown(
                    count_false(&simulated),
                    simulated.len(),
                    built - simulated.len(),
                )
            }),
            undetermined_simulated: if analysis.simulation() {
                built - simulated.len()
            } else {
                0
            },
            refused: results.len() - built,
            max_real_eig_quantiles: Quantiles::of(eig.iter().map(|&(_, v)| v).collect()),
            amplitude_quantiles: Quantiles::of(amp.iter().map(|&(_, v)| v).collect()),
            yaw_amplitude_quantiles: Quantiles::of(
                results
                    .iter()
                    .filter_map(|r| r.outcome.yaw_amplitude)
                    .collect(),
            ),
            sensitivity_method: if analysis.linear() {
                "|Spearman rank correlation| of each drawn parameter with the largest real part"
            } else {
                "|Spearman rank correlation| of each drawn parameter with the amplitude"
            },
            sensitivity,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A distribution is about the scenario's value of its key, override
    /// included: the damped four-bearing study sets every isolator's c_x to
    /// 80 N s/m and spreads it +-30%, so every draw lies in [56, 104], not
    /// about the robot file's 0.5.
    #[test]
    fn a_distribution_is_about_the_scenarios_overridden_value() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let scenario = Scenario::from_file(&root.join("scenarios/robust/four_bearing_damped.toml"))
            .expect("scenario");
        let robot = RobotSpec::from_file(&scenario.robot).expect("robot");
        let spec = RobustSpec::from_scenario(&scenario, &robot, Some(64), None).expect("spec");
        let columns = spec.columns();
        let c_x = (columns.iter())
            .position(|t| t.path == "overrides.isolator_fl.c_x")
            .expect("c_x is drawn");
        assert_eq!(columns[c_x].nominal, 80.0);
        for i in 0..64 {
            let value = spec.values(i)[c_x];
            assert!((56.0..=104.0).contains(&value), "draw {i}: {value}");
        }
    }

    #[test]
    fn patterns_match_within_a_name() {
        assert!(Parameter::path_matches(
            "overrides.bearing_*.f_s",
            "overrides.bearing_fl.f_s"
        ));
        assert!(!Parameter::path_matches(
            "overrides.bearing_*.f_s",
            "overrides.bearing_fl.f_c"
        ));
        assert!(!Parameter::path_matches(
            "overrides.*.f_s",
            "overrides.a.b.f_s"
        ));
        assert!(Parameter::path_matches(
            "overrides.*.*",
            "overrides.iso.k_x"
        ));
        assert!(Parameter::path_matches("controller.k", "controller.k"));
        assert!(!Parameter::path_matches("controller.k", "controller.k_i"));
    }
}
