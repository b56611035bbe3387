//! Tracking compared: several scenarios (cases) run over one grid of
//! parameters, each point simulated and reduced to its tracking metrics
//! (RMS error, the peak error around each velocity reversal, each
//! staircase step's settling time), and each case set against an optional
//! baseline scenario: the paper's Fig. 3 studies (feedforward compensation
//! with and without friction isolator against the uncompensated stage, over
//! the circle's velocity and the model error; settling with a disturbance
//! observer over the step size).
//!
//! The grid is the `[sweep]` axes of the first case. Every case takes every
//! axis; the baseline takes the axes it has (an uncompensated baseline has no
//! `compensation.error.*`) and is run once per value of those. A case's
//! point is compared with the baseline's point of the same values.
//!
//! Per case and value of the first axis, [`Comparison::curves`] gives the
//! chosen metric's mean over the second axis with its standard deviation
//! (with one axis: each run's own spread over its events), and the relative
//! reduction against the baseline, `100 (1 - m / m_baseline)` percent, with
//! its mean and standard deviation over the second axis.

use fistage_model::{LoadError, Loaded, Parameter, RobotSpec};

use crate::assess::{in_parallel, study_with};
use crate::study::Study;
use crate::sweep::Axis;

/// One scenario of a comparison.
#[derive(Debug, Clone)]
pub struct Case {
    /// Its name in tables and legends (the file's stem).
    pub name: String,
    /// The scenario, loaded.
    pub loaded: Loaded,
    /// Its robot file as written (every point starts from it).
    pub robot_file: RobotSpec,
    /// The grid axes it takes, by index.
    pub axes: Vec<usize>,
}

impl Case {
    /// A case over `grid`. A case must take every axis (the error names the
    /// first it cannot); a baseline takes those it can.
    pub fn new(
        name: String,
        loaded: Loaded,
        robot_file: RobotSpec,
        grid: &[Axis],
        baseline: bool,
    ) -> Result<Self, LoadError> {
        let mut axes = Vec::new();
        for (k, axis) in grid.iter().enumerate() {
            match Parameter::resolve(&axis.parameter, &loaded.scenario, &robot_file) {
                Ok(_) => axes.push(k),
                Err(_) if baseline => {}
                Err(e) => return Err(e),
            }
        }
        Ok(Self {
            name,
            loaded,
            robot_file,
            axes,
        })
    }
}

/// Which tracking metric the curves show.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Metric {
    /// Mean peak |error| around the velocity reversals, m.
    PeakError,
    /// Mean settling time of the staircase steps, s.
    SettlingTime,
    /// RMS error over the statistics window, m.
    RmsError,
}

impl Metric {
    /// Its name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::PeakError => "peak_error",
            Self::SettlingTime => "settling_time",
            Self::RmsError => "rms_error",
        }
    }

    /// Its unit.
    pub fn unit(self) -> &'static str {
        match self {
            Self::PeakError | Self::RmsError => "m",
            Self::SettlingTime => "s",
        }
    }

    /// The metric named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        [Self::PeakError, Self::SettlingTime, Self::RmsError]
            .into_iter()
            .find(|m| m.name() == name)
    }

    /// The metric a reference calls for: settling for a staircase, the
    /// reversal peak otherwise.
    pub fn for_reference(reference: &fistage_model::Reference) -> Self {
        match reference {
            fistage_model::Reference::Staircase { .. } => Self::SettlingTime,
            _ => Self::PeakError,
        }
    }

    fn of(self, metrics: &Metrics) -> Option<(f64, Option<f64>)> {
        match self {
            Self::PeakError => metrics.peak_error.map(|m| (m, metrics.peak_error_std)),
            Self::SettlingTime => metrics
                .settling_time
                .filter(|_| metrics.unsettled == Some(0))
                .map(|m| (m, metrics.settling_time_std)),
            Self::RmsError => Some((metrics.rms_error, None)),
        }
    }
}

/// The tracking metrics of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metrics {
    /// RMS error over the statistics window, m.
    pub rms_error: f64,
    /// Mean peak |error| around the reversals, m.
    pub peak_error: Option<f64>,
    /// Its standard deviation over the reversals, m.
    pub peak_error_std: Option<f64>,
    /// Mean settling time of the steps that settled, s.
    pub settling_time: Option<f64>,
    /// Its standard deviation over the steps, s.
    pub settling_time_std: Option<f64>,
    /// Steps that never settled.
    pub unsettled: Option<usize>,
}

/// One point of one case.
#[derive(Debug, Clone, PartialEq)]
pub struct CompareRow {
    /// Item index in the whole comparison.
    pub index: usize,
    /// The case, by index.
    pub case: usize,
    /// The value of every grid axis the case takes (`None` where it takes none).
    pub values: Vec<Option<f64>>,
    /// The metrics, `None` when the run failed.
    pub metrics: Option<Metrics>,
    /// Why the run failed.
    pub failure: Option<String>,
}

/// A curve of one case: per value of the first axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// The case, by index.
    pub case: usize,
    /// First-axis values (one point, 0, without axes).
    pub x: Vec<f64>,
    /// Mean metric.
    pub mean: Vec<f64>,
    /// Its spread (standard deviation), see the module guide.
    pub std: Vec<f64>,
    /// Mean reduction against the baseline, percent (empty without one; NaN
    /// for the baseline itself and where the baseline's metric is 0 or missing).
    pub reduction_mean: Vec<f64>,
    /// Its standard deviation over the second axis, percent (NaN for a
    /// case without one).
    pub reduction_std: Vec<f64>,
    /// Points behind each value that gave the metric.
    pub points: Vec<usize>,
    /// Points behind each value that did not (failed runs, unsettled steps,
    /// no reversal in the run): a value with any has no mean (NaN), so that
    /// no mean stands for fewer points than the grid has.
    pub missing: Vec<usize>,
}

/// Cases over one grid, the first one the baseline when there is one.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// The grid axes (one or two, or none for single runs).
    pub axes: Vec<Axis>,
    /// The cases, the baseline first when `has_baseline`.
    pub cases: Vec<Case>,
    /// Whether `cases[0]` is the baseline.
    pub has_baseline: bool,
    /// The metric the curves show.
    pub metric: Metric,
}

impl Comparison {
    /// Points of a case.
    fn points_of(&self, case: &Case) -> usize {
        case.axes.iter().map(|&k| self.axes[k].points).product()
    }

    /// Items of the whole comparison.
    pub fn len(&self) -> usize {
        self.cases.iter().map(|c| self.points_of(c)).sum()
    }

    /// Whether there is nothing to compute.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The curves as `curves.csv`: one row per case and x, empty where a value is missing.
    pub fn curves_csv(&self, curves: &[Curve]) -> String {
        let metric = self.metric.name();
        let mut text = format!(
            "case,{},{metric}_mean,{metric}_std,reduction_percent_mean,reduction_percent_std,points,missing\n",
            self.x_label()
        );
        let number = |v: f64| {
            if v.is_finite() {
                format!("{v:e}")
            } else {
                String::new()
            }
        };
        for curve in curves {
            let name = &self.cases[curve.case].name;
            for i in 0..curve.x.len() {
                let reduction = |v: &[f64]| v.get(i).copied().unwrap_or(f64::NAN);
                text.push_str(&format!(
                    "{name},{},{},{},{},{},{},{}\n",
                    number(curve.x[i]),
                    number(curve.mean[i]),
                    number(curve.std[i]),
                    number(reduction(&curve.reduction_mean)),
                    number(reduction(&curve.reduction_std)),
                    curve.points[i],
                    curve.missing[i]
                ));
            }
        }
        text
    }

    /// The curves as `summary.json`: the metric, its unit, the x, the
    /// baseline and each case's curve (missing values as null).
    pub fn curves_summary(&self, curves: &[Curve]) -> serde_json::Value {
        let finite = |v: &[f64]| -> Vec<Option<f64>> {
            v.iter().map(|x| x.is_finite().then_some(*x)).collect()
        };
        let json: Vec<serde_json::Value> = curves
            .iter()
            .map(|curve| {
                let case = &self.cases[curve.case];
                serde_json::json!({
                    "case": case.name,
                    "title": case.loaded.scenario.title,
                    "x": finite(&curve.x),
                    "mean": finite(&curve.mean),
                    "std": finite(&curve.std),
                    "reduction_percent_mean": finite(&curve.reduction_mean),
                    "reduction_percent_std": finite(&curve.reduction_std),
                    "points": curve.points,
                    "missing": curve.missing,
                })
            })
            .collect();
        serde_json::json!({
            "metric": self.metric.name(),
            "unit": self.metric.unit(),
            "x": self.x_label(),
            "baseline": self.has_baseline.then(|| self.cases[0].name.clone()),
            "curves": json,
        })
    }

    /// The first axis's parameter, or "case" without axes: the curves' x.
    pub fn x_label(&self) -> String {
        self.axes
            .first()
            .map_or("case".into(), |a| a.parameter.clone())
    }

    /// [`Comparison::x_label`] with the parameter's unit, for plots.
    pub fn x_label_with_unit(&self) -> String {
        let case = &self.cases[self.cases.len() - 1];
        let unit = self.axes.first().and_then(|a| {
            Parameter::resolve(&a.parameter, &case.loaded.scenario, &case.robot_file)
                .ok()
                .map(|p| p.unit())
        });
        match unit {
            Some(unit) => format!("{} [{unit}]", self.x_label()),
            None => self.x_label(),
        }
    }

    /// The case and axis values of item `index`.
    pub fn item(&self, mut index: usize) -> (usize, Vec<Option<f64>>) {
        for (c, case) in self.cases.iter().enumerate() {
            let n = self.points_of(case);
            if index < n {
                let mut values = vec![None; self.axes.len()];
                for &k in &case.axes {
                    let axis = &self.axes[k];
                    values[k] = Some(axis.values()[index % axis.points]);
                    index /= axis.points;
                }
                return (c, values);
            }
            index -= n;
        }
        (self.cases.len(), Vec::new())
    }

    /// Simulates item `index`.
    pub fn evaluate(&self, index: usize) -> CompareRow {
        let (case_index, values) = self.item(index);
        let mut row = CompareRow {
            index,
            case: case_index,
            values: values.clone(),
            metrics: None,
            failure: None,
        };
        let Some(case) = self.cases.get(case_index) else {
            row.failure = Some("no such item".into());
            return row;
        };
        let assignments: Vec<(&str, f64)> = (self.axes.iter().zip(&values))
            .filter_map(|(axis, v)| v.map(|v| (axis.parameter.as_str(), v)))
            .collect();
        let outcome = study_with(&case.loaded, &case.robot_file, &assignments)
            .map_err(|e| e.to_string())
            .and_then(|loaded| {
                fistage_sim::run_scenario(&loaded, &mut fistage_sim::no_progress)
                    .map_err(|e| e.to_string())
            });
        match outcome {
            Ok(output) => match output.tracking {
                Some(t) => {
                    row.metrics = Some(Metrics {
                        rms_error: t.rms_error,
                        peak_error: t.reversal_peak_error.mean,
                        peak_error_std: t.reversal_peak_error.std,
                        settling_time: t.settling.as_ref().and_then(|s| s.times.mean),
                        settling_time_std: t.settling.as_ref().and_then(|s| s.times.std),
                        unsettled: t.settling.as_ref().map(|s| s.unsettled),
                    });
                }
                None => row.failure = Some("the scenario has no servo to track with".into()),
            },
            Err(message) => row.failure = Some(message),
        }
        row
    }

    /// Simulates the given items on `threads` threads, in index order.
    pub fn run(
        &self,
        indices: &[usize],
        threads: usize,
        done: &(dyn Fn(&CompareRow, usize) + Sync),
    ) -> Vec<CompareRow> {
        let mut rows = in_parallel(indices, threads, &|i| self.evaluate(i), done);
        rows.sort_by_key(|r| r.index);
        rows
    }

    /// The table's header.
    pub fn header(&self) -> String {
        let mut columns = vec!["case".to_string()];
        columns.extend(self.axes.iter().map(|a| a.parameter.clone()));
        columns.extend(
            [
                "rms_error",
                "peak_error",
                "peak_error_std",
                "settling_time",
                "settling_time_std",
                "unsettled_steps",
            ]
            .map(String::from),
        );
        columns.join(",")
    }

    /// One row (numbers in shortest round-trip form; blank where none).
    pub fn row(&self, row: &CompareRow) -> String {
        let number = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
        let mut cells = vec![self.cases[row.case].name.clone()];
        cells.extend(row.values.iter().map(|v| number(*v)));
        let m = row.metrics;
        cells.push(number(m.map(|m| m.rms_error)));
        cells.push(number(m.and_then(|m| m.peak_error)));
        cells.push(number(m.and_then(|m| m.peak_error_std)));
        cells.push(number(m.and_then(|m| m.settling_time)));
        cells.push(number(m.and_then(|m| m.settling_time_std)));
        cells.push(
            m.and_then(|m| m.unsettled)
                .map_or(String::new(), |u| u.to_string()),
        );
        cells.join(",")
    }

    /// The finished row a line of the table holds, if it is one of this
    /// comparison's. A failed run's row is not one: it is computed again.
    pub fn parse_row(&self, line: &str) -> Option<CompareRow> {
        let n_axes = self.axes.len();
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != 1 + n_axes + 6 {
            return None;
        }
        let case = self.cases.iter().position(|c| c.name == cells[0])?;
        let index = self.index_of(case, &cells[1..=n_axes])?;
        let number = |s: &str| s.parse::<f64>().ok();
        let metric = &cells[1 + n_axes..];
        let rms_error = number(metric[0])?;
        Some(CompareRow {
            index,
            case,
            values: self.item(index).1,
            metrics: Some(Metrics {
                rms_error,
                peak_error: number(metric[1]),
                peak_error_std: number(metric[2]),
                settling_time: number(metric[3]),
                settling_time_std: number(metric[4]),
                unsettled: metric[5].parse().ok(),
            }),
            failure: None,
        })
    }

    /// The item of `case` whose axis cells read `cells`.
    fn index_of(&self, case: usize, cells: &[&str]) -> Option<usize> {
        let offset: usize = self.cases[..case].iter().map(|c| self.points_of(c)).sum();
        let (mut index, mut stride) = (0, 1);
        for (k, axis) in self.axes.iter().enumerate() {
            let takes = self.cases[case].axes.contains(&k);
            if !takes {
                if !cells[k].is_empty() {
                    return None;
                }
                continue;
            }
            let values: Vec<String> = axis.values().iter().map(|v| format!("{v:e}")).collect();
            let i = values.iter().position(|v| v == cells[k])?;
            index += i * stride;
            stride *= axis.points;
        }
        Some(offset + index)
    }

    /// The metric of the baseline's point matching `values` on its axes.
    fn baseline_metric(&self, rows: &[CompareRow], values: &[Option<f64>]) -> Option<f64> {
        if !self.has_baseline {
            return None;
        }
        let base = &self.cases[0];
        rows.iter()
            .filter(|r| r.case == 0)
            .find(|r| base.axes.iter().all(|&k| r.values[k] == values[k]))
            .and_then(|r| r.metrics.as_ref())
            .and_then(|m| self.metric.of(m))
            .map(|(m, _)| m)
    }

    /// The curves of every case, the baseline's first when there is one
    /// (with no reduction: see the module guide).
    pub fn curves(&self, rows: &[CompareRow]) -> Vec<Curve> {
        let first = self.axes.first();
        let xs = first.map_or(vec![0.0], |a| a.values());
        (0..self.cases.len())
            .map(|case| {
                let mut curve = Curve {
                    case,
                    x: Vec::new(),
                    mean: Vec::new(),
                    std: Vec::new(),
                    reduction_mean: Vec::new(),
                    reduction_std: Vec::new(),
                    points: Vec::new(),
                    missing: Vec::new(),
                };
                for &x in &xs {
                    let at: Vec<&CompareRow> = (rows.iter())
                        .filter(|r| r.case == case && first.is_none_or(|_| r.values[0] == Some(x)))
                        .collect();
                    let mut metric = Vec::new();
                    let mut reduction = Vec::new();
                    let mut spread = None;
                    let mut missing = 0;
                    let mut without_baseline = false;
                    for row in &at {
                        match row.metrics.as_ref().and_then(|m| self.metric.of(m)) {
                            Some((m, own)) => {
                                metric.push(m);
                                spread = own;
                                let base = self.baseline_metric(rows, &row.values);
                                // A baseline of 0 leaves no reduction to speak of.
                                match base.filter(|b| *b > 0.0) {
                                    Some(b) => reduction.push(100.0 * (1.0 - m / b)),
                                    None => without_baseline = true,
                                }
                            }
                            None => missing += 1,
                        }
                    }
                    if missing > 0 {
                        metric.clear();
                    }
                    if missing > 0 || without_baseline || (self.has_baseline && case == 0) {
                        reduction.clear();
                    }
                    let (mean, std) = mean_std(&metric);
                    curve.x.push(x);
                    curve.mean.push(mean);
                    let over_second = self.cases[case].axes.len() >= 2;
                    curve.std.push(if over_second || metric.is_empty() {
                        std
                    } else {
                        spread.unwrap_or(0.0)
                    });
                    if self.has_baseline {
                        let (mean, std) = mean_std(&reduction);
                        curve.reduction_mean.push(mean);
                        // One run per value: no spread over a second axis.
                        curve
                            .reduction_std
                            .push(if over_second { std } else { f64::NAN });
                    }
                    curve.points.push(metric.len());
                    curve.missing.push(missing);
                }
                curve
            })
            .collect()
    }
}

/// Mean and population standard deviation (NaN for no values).
fn mean_std(values: &[f64]) -> (f64, f64) {
    if values.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}

impl Study for Comparison {
    type Row = CompareRow;
    const TABLE: &'static str = "points.csv";
    const ITEMS: &'static str = "points";
    fn len(&self) -> usize {
        Comparison::len(self)
    }
    fn header(&self) -> String {
        Comparison::header(self)
    }
    fn row(&self, row: &CompareRow) -> String {
        Comparison::row(self, row)
    }
    fn index(row: &CompareRow) -> usize {
        row.index
    }
    fn parse_row(&self, line: &str) -> Option<CompareRow> {
        Comparison::parse_row(self, line)
    }
    fn compute(
        &self,
        indices: &[usize],
        threads: usize,
        done: &(dyn Fn(&CompareRow, usize) + Sync),
    ) -> Vec<CompareRow> {
        self.run(indices, threads, done)
    }
}
