//! Parameter sweeps: a grid over one or two scalar parameters of a scenario,
//! and at every point the linear verdict (eigenvalues at the slipping
//! equilibrium), the simulated verdict (persistent oscillation of the sensor
//! signal from rest), the oscillation amplitude, and bistability (a stable
//! equilibrium beside a limit cycle). Points run in parallel; any subset of
//! the grid (a shard, or the points a killed run did not finish) can be
//! computed on its own, and results are exact functions of the point, so
//! shards merge into the same table as a single run.
//!
//! ```toml
//! [sweep]
//! analysis = "both"                 # linear | simulation | both
//! duration = 3.0                    # s per simulated point (default: the scenario's)
//! oscillation_threshold = 1e-9      # m, steady peak-to-peak above which a run oscillates
//! [[sweep.axis]]
//! parameter = "controller.k"        # controller.k, controller.c, controller.k_i,
//! from = 1e4                        # platform.velocity, alpha, beta,
//! to = 1e6                          # overrides.<element>.<key>
//! points = 40
//! spacing = "log"                   # lin | log
//! ```
//!
//! `alpha` scales every isolator's stiffness and damping along its compliant
//! (x) axis, `beta` the mass (and inertia) of every link that carries a
//! friction contact: the paper's kappa_1 = alpha kappa_1, eta_1 = alpha eta_1
//! and rho = beta rho (Fig. 9). Both scale the robot file's values.
//!
//! `spread.<key>` (a LuGre parameter: `f_c`, `sigma0`, ...) mismatches the
//! friction contacts: contact i of n (file order) gets its value times
//! `1 + s w_i` with weights w running evenly from +1 to -1 (for the four-bearing
//! stage fl, fr, rl, rr: +1, +1/3, -1/3, -1, so the left and the front bearings
//! sit above the mean). `spread.friction` spreads f_c, f_s and sigma0 together
//! (keeping f_s >= f_c).

use fistage_model::studies::AxisTable;
use fistage_model::{LoadError, Loaded, Parameter, RobotSpec, Scenario};

use crate::assess::{Assessment, in_parallel};
use crate::study::{Provenance, Study, StudyError};

pub use fistage_model::studies::Spacing;

/// One sweep axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Parameter path.
    pub parameter: String,
    /// First value.
    pub from: f64,
    /// Last value.
    pub to: f64,
    /// Number of values (>= 1).
    pub points: usize,
    /// Spacing.
    pub spacing: Spacing,
    /// Explicit values instead of a spacing (`values = [...]` in the file;
    /// `from`, `to` and `points` then follow from it).
    pub list: Option<Vec<f64>>,
}

impl Axis {
    /// The axis an `[[sweep.axis]]` entry (number `k`) gives: `from`, `to`
    /// and `points`, or its `values` (a non-empty list of distinct finite
    /// numbers, with none of the others); else (key, why).
    fn from_table(k: usize, table: &AxisTable) -> Result<Self, (String, String)> {
        let key = format!("sweep.axis[{k}]");
        let Some(values) = &table.values else {
            let missing = |name: &str| (key.clone(), format!("needs {name} (or values)"));
            return Ok(Self {
                parameter: table.parameter.clone(),
                from: table.from.ok_or_else(|| missing("from"))?,
                to: table.to.ok_or_else(|| missing("to"))?,
                points: table.points.ok_or_else(|| missing("points"))?,
                spacing: table.spacing.unwrap_or(Spacing::Lin),
                list: None,
            });
        };
        let key = format!("{key}.values");
        let given = [
            ("from", table.from.is_some()),
            ("to", table.to.is_some()),
            ("points", table.points.is_some()),
            ("spacing", table.spacing.is_some()),
        ];
        if let Some((other, _)) = given.iter().find(|(_, present)| *present) {
            return Err((key, format!("gives the values; leave out {other}")));
        }
        if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
            return Err((key, "must be a non-empty list of finite numbers".into()));
        }
        let mut sorted = values.clone();
        sorted.sort_by(f64::total_cmp);
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            return Err((key, "holds a value twice".into()));
        }
        Ok(Self {
            parameter: table.parameter.clone(),
            from: values[0],
            to: values[values.len() - 1],
            points: values.len(),
            spacing: Spacing::Lin,
            list: Some(values.clone()),
        })
    }

    /// The axis values, first to last.
    pub fn values(&self) -> Vec<f64> {
        if let Some(list) = &self.list {
            return list.clone();
        }
        let n = self.points;
        if n == 1 {
            return vec![self.from];
        }
        (0..n)
            .map(|i| {
                let t = i as f64 / (n - 1) as f64;
                match self.spacing {
                    Spacing::Lin => self.from + (self.to - self.from) * t,
                    Spacing::Log => (self.from.ln() + (self.to.ln() - self.from.ln()) * t).exp(),
                }
            })
            .collect()
    }
}

pub use crate::assess::Analyses;

/// A checked `[sweep]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepSpec {
    /// One or two axes; the first varies fastest in the grid order.
    pub axes: Vec<Axis>,
    /// Analyses to run.
    pub analysis: Analyses,
    /// Simulated time per point, s (default: the scenario's duration).
    pub duration: Option<f64>,
    /// Steady peak-to-peak of the sensor above which a run oscillates, m.
    pub oscillation_threshold: f64,
}

/// Parameter paths every model accepts, besides `overrides.<element>.<key>`.
pub const PARAMETERS: [&str; 7] = fistage_model::parameter::GLOBAL_PATHS;

/// Grid points a sweep may have (checked before anything is allocated): a
/// million simulated points is already days of work.
pub const MAX_GRID_POINTS: usize = 1_000_000;

impl SweepSpec {
    /// Reads the scenario's `[sweep]` table.
    pub fn from_scenario(scenario: &Scenario) -> Result<Self, LoadError> {
        let table = scenario
            .sweep
            .as_ref()
            .ok_or_else(|| scenario.error("sweep", "the scenario has no [sweep] table"))?;
        let axes = (table.axes.iter().enumerate())
            .map(|(k, axis)| Axis::from_table(k, axis))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|(key, m)| scenario.error(key, m))?;
        let spec = SweepSpec {
            axes,
            analysis: table.analysis,
            duration: table.duration,
            oscillation_threshold: table.oscillation_threshold,
        };
        if spec.axes.is_empty() || spec.axes.len() > 2 {
            return Err(scenario.error(
                "sweep.axis",
                format!("needs one or two axes, got {}", spec.axes.len()),
            ));
        }
        for (k, axis) in spec.axes.iter().enumerate() {
            let key = format!("sweep.axis[{k}]");
            if axis.points == 0 {
                return Err(scenario.error(&key, "points must be >= 1"));
            }
            if !axis.from.is_finite() || !axis.to.is_finite() {
                return Err(scenario.error(&key, "from and to must be finite"));
            }
            if axis.spacing == Spacing::Log && (axis.from <= 0.0 || axis.to <= 0.0) {
                return Err(scenario.error(&key, "log spacing needs from > 0 and to > 0"));
            }
            if spec.axes[..k].iter().any(|a| a.parameter == axis.parameter) {
                return Err(scenario.error(
                    format!("{key}.parameter"),
                    format!("\"{}\" is swept twice", axis.parameter),
                ));
            }
        }
        let points = spec
            .axes
            .iter()
            .try_fold(1usize, |n, axis| n.checked_mul(axis.points))
            .filter(|&n| n <= MAX_GRID_POINTS);
        if points.is_none() {
            let sizes: Vec<String> = spec.axes.iter().map(|a| a.points.to_string()).collect();
            return Err(scenario.error(
                "sweep.axis",
                format!(
                    "a grid of {} points; at most {MAX_GRID_POINTS} (split the study into several sweeps)",
                    sizes.join(" x ")
                ),
            ));
        }
        spec.assessment().check(scenario, "sweep")?;
        Ok(spec)
    }

    /// Resolves every axis against the study and checks every grid value
    /// against its parameter's rule, so that no point fails for a reason the
    /// whole grid shares (an axis that names nothing, a negative gain).
    pub fn check_against(&self, scenario: &Scenario, robot: &RobotSpec) -> Result<(), LoadError> {
        for (k, axis) in self.axes.iter().enumerate() {
            let parameter = Parameter::resolve(&axis.parameter, scenario, robot)?;
            for value in axis.values() {
                parameter.check(value).map_err(|message| {
                    scenario.error(
                        format!("sweep.axis[{k}] ({})", axis.parameter),
                        format!("from and to: {message}"),
                    )
                })?;
            }
        }
        Ok(())
    }

    /// What is computed at each point.
    pub fn assessment(&self) -> Assessment {
        Assessment {
            analysis: self.analysis,
            duration: self.duration,
            oscillation_threshold: self.oscillation_threshold,
        }
    }

    /// Number of grid points.
    pub fn len(&self) -> usize {
        self.axes.iter().map(|a| a.points).product()
    }

    /// Whether the grid is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Parameter values of grid point `index` (first axis fastest).
    pub fn point(&self, index: usize) -> Vec<f64> {
        let mut rest = index;
        self.axes
            .iter()
            .map(|axis| {
                let value = axis.values()[rest % axis.points];
                rest /= axis.points;
                value
            })
            .collect()
    }
}

/// What one grid point gave.
#[derive(Debug, Clone, PartialEq)]
pub struct PointResult {
    /// Grid index.
    pub index: usize,
    /// Parameter values, one per axis.
    pub parameters: Vec<f64>,
    /// Slipping equilibrium linearly stable.
    pub stable_linear: Option<bool>,
    /// No persistent oscillation in simulation from rest.
    pub stable_sim: Option<bool>,
    /// Steady peak-to-peak of the sensor signal, m.
    pub amplitude: Option<f64>,
    /// Largest real part of the non-neutral eigenvalues, 1/s.
    pub max_real_eig: Option<f64>,
    /// Stable equilibrium beside a limit cycle (linear stable, simulation oscillates).
    pub bistable: Option<bool>,
}

pub use crate::assess::apply_parameter;

/// The study at one grid point: the scenario with the point's parameters,
/// assembled from the robot file as written.
pub fn variant(
    base: &Loaded,
    robot_file: &RobotSpec,
    spec: &SweepSpec,
    index: usize,
) -> Result<Loaded, LoadError> {
    let values = spec.point(index);
    let assignments: Vec<(&str, f64)> = spec
        .axes
        .iter()
        .zip(values)
        .map(|(axis, value)| (axis.parameter.as_str(), value))
        .collect();
    crate::assess::study_with(base, robot_file, &assignments)
}

/// Evaluates one grid point.
pub fn evaluate_point(
    base: &Loaded,
    robot_file: &RobotSpec,
    spec: &SweepSpec,
    index: usize,
) -> PointResult {
    let parameters = spec.point(index);
    let outcome = variant(base, robot_file, spec, index)
        .map(|loaded| spec.assessment().assess(&loaded))
        .unwrap_or_default();
    PointResult {
        index,
        parameters,
        stable_linear: outcome.stable_linear,
        stable_sim: outcome.stable_sim,
        amplitude: outcome.amplitude,
        max_real_eig: outcome.max_real_eig,
        bistable: outcome.bistable,
    }
}

/// Evaluates the given grid points on `threads` threads; `done` is called with
/// each finished point (from worker threads, in completion order).
pub fn run_points(
    base: &Loaded,
    robot_file: &RobotSpec,
    spec: &SweepSpec,
    indices: &[usize],
    threads: usize,
    done: &(dyn Fn(&PointResult, usize) + Sync),
) -> Vec<PointResult> {
    let mut results = in_parallel(
        indices,
        threads,
        &|index| evaluate_point(base, robot_file, spec, index),
        done,
    );
    results.sort_by_key(|r| r.index);
    results
}

fn bool_cell(value: Option<bool>) -> String {
    value.map_or(String::new(), |b| b.to_string())
}

fn number_cell(value: Option<f64>) -> String {
    value.map_or(String::new(), |v| format!("{v:e}"))
}

/// The CSV header: one column per axis, then the verdicts.
pub fn header(spec: &SweepSpec) -> String {
    let mut columns: Vec<String> = spec.axes.iter().map(|a| a.parameter.clone()).collect();
    columns.extend(
        [
            "stable_linear",
            "stable_sim",
            "amplitude",
            "max_real_eig",
            "bistable",
        ]
        .map(String::from),
    );
    columns.join(",")
}

/// One CSV row (numbers in shortest round-trip form, so rows are exact).
pub fn row(result: &PointResult) -> String {
    let mut cells: Vec<String> = result.parameters.iter().map(|v| format!("{v:e}")).collect();
    cells.push(bool_cell(result.stable_linear));
    cells.push(bool_cell(result.stable_sim));
    cells.push(number_cell(result.amplitude));
    cells.push(number_cell(result.max_real_eig));
    cells.push(bool_cell(result.bistable));
    cells.join(",")
}

/// The grid point a line written by [`row`] holds, if it is a point of
/// this grid (a caller that must not take damaged lines also checks that
/// [`row`] writes the result back as the same line).
pub fn parse_row(line: &str, spec: &SweepSpec) -> Option<PointResult> {
    let n_axes = spec.axes.len();
    let cells: Vec<&str> = line.split(',').collect();
    if cells.len() != n_axes + 5 {
        return None;
    }
    let mut index = 0;
    let mut stride = 1;
    for (axis, cell) in spec.axes.iter().zip(&cells) {
        let values = axis.values();
        let i = values.iter().position(|v| format!("{v:e}") == *cell)?;
        index += i * stride;
        stride *= values.len();
    }
    let flag = |s: &str| s.parse::<bool>().ok();
    let number = |s: &str| s.parse::<f64>().ok();
    Some(PointResult {
        index,
        parameters: spec.point(index),
        stable_linear: flag(cells[n_axes]),
        stable_sim: flag(cells[n_axes + 1]),
        amplitude: number(cells[n_axes + 2]),
        max_real_eig: number(cells[n_axes + 3]),
        bistable: flag(cells[n_axes + 4]),
    })
}

/// A sweep as a [`Study`] of grid points (journal, shards, resume, merge).
pub struct SweepStudy<'a> {
    /// The scenario, loaded.
    pub loaded: &'a Loaded,
    /// Its robot file as read (what the axes write into).
    pub robot_file: &'a RobotSpec,
    /// The grid and its analysis.
    pub spec: &'a SweepSpec,
}

impl SweepStudy<'_> {
    /// What decides the points' numbers, as shard `shard`: the program's
    /// and the Python package's sweeps of one scenario agree on it, so their
    /// shards merge.
    /// `scenario_text`, when given, stands for the scenario file's content
    /// (a scenario made in Python).
    pub fn provenance(
        &self,
        scenario_text: Option<&[u8]>,
        shard: Option<(usize, usize)>,
    ) -> Result<Provenance, StudyError> {
        let spec = self.spec;
        Provenance::of_study(
            "sweep",
            (&self.loaded.scenario.file, scenario_text),
            &self.loaded.scenario.robot,
            &format!("{:?}", spec.axes),
            &format!(
                "{:?}, duration {:?}, oscillation threshold {:?}",
                spec.analysis, spec.duration, spec.oscillation_threshold
            ),
            shard,
        )
    }

    /// `points.json`: an object per point, a key per axis and verdict.
    pub fn points_json(&self, results: &[PointResult]) -> String {
        let json: Vec<serde_json::Value> = results
            .iter()
            .map(|r| {
                let mut object = serde_json::Map::new();
                for (axis, value) in self.spec.axes.iter().zip(&r.parameters) {
                    object.insert(axis.parameter.clone(), serde_json::json!(value));
                }
                object.insert("stable_linear".into(), serde_json::json!(r.stable_linear));
                object.insert("stable_sim".into(), serde_json::json!(r.stable_sim));
                object.insert("amplitude".into(), serde_json::json!(r.amplitude));
                object.insert("max_real_eig".into(), serde_json::json!(r.max_real_eig));
                object.insert("bistable".into(), serde_json::json!(r.bistable));
                serde_json::Value::Object(object)
            })
            .collect();
        serde_json::to_string_pretty(&json).unwrap_or_default() + "\n"
    }
}

impl Study for SweepStudy<'_> {
    type Row = PointResult;
    const TABLE: &'static str = "points.csv";
    const ITEMS: &'static str = "points";
    fn len(&self) -> usize {
        self.spec.len()
    }
    fn header(&self) -> String {
        header(self.spec)
    }
    fn row(&self, row: &PointResult) -> String {
        self::row(row)
    }
    fn index(row: &PointResult) -> usize {
        row.index
    }
    fn parse_row(&self, line: &str) -> Option<PointResult> {
        parse_row(line, self.spec)
    }
    fn compute(
        &self,
        indices: &[usize],
        threads: usize,
        done: &(dyn Fn(&PointResult, usize) + Sync),
    ) -> Vec<PointResult> {
        run_points(
            self.loaded,
            self.robot_file,
            self.spec,
            indices,
            threads,
            done,
        )
    }
}
