//! A tolerance analysis's section: the probabilities with their intervals,
//! the histograms of the largest real part and of the amplitude, the
//! sensitivity ranking, and each drawn parameter against the largest real
//! part, sample by sample.

use fistage_analysis::robust::{Probability, Quantiles, RobustSpec, SampleResult, Summary};
use fistage_model::Loaded;
use serde_json::{Value, json};

use crate::block::number;
use crate::sections::run::name_of;
use crate::{Block, Section, plot};

/// Samples drawn as points at most (a histogram takes them all).
const MAX_POINTS: usize = 5000;
/// Parameters drawn against the largest real part at most (the most sensitive).
const MAX_SCATTERS: usize = 6;

/// The section of the population `results` of `spec`.
pub fn section(
    loaded: &Loaded,
    spec: &RobustSpec,
    results: &[SampleResult],
    summary: &Summary,
) -> Section {
    let mut blocks = vec![facts(loaded, summary), quantiles(summary)];
    let eig: Vec<f64> = results
        .iter()
        .filter_map(|r| r.outcome.max_real_eig)
        .collect();
    if !eig.is_empty() {
        blocks.push(histogram(
            "largest real part of the eigenvalues (zero: the stability limit)",
            &eig,
            "largest real part [1/s]",
            true,
        ));
    }
    let amplitude: Vec<f64> = results.iter().filter_map(|r| r.outcome.amplitude).collect();
    if !amplitude.is_empty() {
        blocks.push(histogram(
            "steady peak-to-peak tracking error (simulated)",
            &amplitude,
            "amplitude [m]",
            false,
        ));
    }
    if !summary.sensitivity.is_empty() {
        blocks.push(sensitivity(summary));
    }
    // The drawn values of the parameters that matter most, against the verdict.
    let columns = spec.columns();
    blocks.extend(
        summary
            .sensitivity
            .iter()
            .take(MAX_SCATTERS)
            .filter_map(|s| columns.iter().position(|t| t.path == s.parameter))
            .filter_map(|c| scatter(&columns[c].path, c, results)),
    );
    Section {
        heading: format!("robust: {}", name_of(loaded)),
        source: loaded.scenario.file.display().to_string(),
        blocks,
    }
}

fn probability(p: &Option<Probability>) -> String {
    p.as_ref().map_or_else(
        || "not computed".into(),
        |p| {
            format!(
                "{} (95% interval {} to {}, n = {})",
                number(p.estimate),
                number(p.ci95[0]),
                number(p.ci95[1]),
                p.n
            )
        },
    )
}

fn facts(loaded: &Loaded, summary: &Summary) -> Block {
    Block::facts(
        "population",
        vec![
            ["program".into(), crate::page::generator()],
            [
                "scenario".into(),
                loaded.scenario.file.display().to_string(),
            ],
            ["robot".into(), loaded.scenario.robot.display().to_string()],
            [
                "samples".into(),
                format!(
                    "{} computed of {} ({:?} design, seed {})",
                    summary.computed, summary.samples, summary.sampling, summary.seed
                ),
            ],
            [
                "P(linearly unstable)".into(),
                probability(&summary.p_unstable_linear),
            ],
            ["P(oscillating)".into(), probability(&summary.p_oscillating)],
            [
                "without a verdict".into(),
                format!(
                    "{} linear, {} simulated; {} stages refused by the model",
                    summary.undetermined_linear, summary.undetermined_simulated, summary.refused
                ),
            ],
        ],
    )
}

fn quantiles(summary: &Summary) -> Block {
    let row = |name: &str, unit: &str, q: &Option<Quantiles>| {
        q.as_ref().map(|q| {
            vec![
                name.to_string(),
                unit.to_string(),
                number(q.p05),
                number(q.p50),
                number(q.p95),
                number(q.max),
            ]
        })
    };
    Block::Table {
        title: "quantiles".into(),
        columns: ["quantity", "unit", "5%", "median", "95%", "largest"]
            .map(String::from)
            .to_vec(),
        rows: [
            row("largest real part", "1/s", &summary.max_real_eig_quantiles),
            row("amplitude", "m", &summary.amplitude_quantiles),
            row("yaw amplitude", "rad", &summary.yaw_amplitude_quantiles),
        ]
        .into_iter()
        .flatten()
        .collect(),
    }
}

fn histogram(title: &str, values: &[f64], x_title: &str, zero_line: bool) -> Block {
    let mut block = plot::figure(
        title,
        vec![json!({
            "type": "histogram", "x": plot::values(values), "nbinsx": 60,
            "marker": { "color": "#4575b4" }, "name": "samples",
        })],
        x_title,
        "samples",
    );
    if let Block::Plot { layout, .. } = &mut block {
        layout["hovermode"] = json!("closest");
        layout["bargap"] = json!(0.02);
        if zero_line {
            layout["shapes"] = json!([{
                "type": "line", "xref": "x", "yref": "paper", "x0": 0, "x1": 0, "y0": 0, "y1": 1,
                "line": { "color": "#d73027", "width": 2, "dash": "dash" },
            }]);
        }
    }
    block
}

fn sensitivity(summary: &Summary) -> Block {
    let ranked: Vec<_> = summary.sensitivity.iter().rev().collect();
    let mut block = plot::figure(
        &format!("which tolerance matters ({})", summary.sensitivity_method),
        vec![json!({
            "type": "bar", "orientation": "h",
            "x": ranked.iter().map(|s| plot::value(s.index)).collect::<Vec<Value>>(),
            "y": ranked.iter().map(|s| s.parameter.clone()).collect::<Vec<String>>(),
            "marker": { "color": "#4575b4" }, "name": "index",
        })],
        "sensitivity index",
        "",
    );
    if let Block::Plot { layout, height, .. } = &mut block {
        layout["hovermode"] = json!("closest");
        layout["yaxis"]["automargin"] = json!(true);
        *height = (120 + 28 * ranked.len()).min(900) as u32;
    }
    block
}

/// One parameter's drawn values against the largest real part, stable and
/// unstable samples told apart.
fn scatter(entry: &str, column: usize, results: &[SampleResult]) -> Option<Block> {
    let points: Vec<(f64, f64)> = results
        .iter()
        .filter_map(|r| Some((*r.values.get(column)?, r.outcome.max_real_eig?)))
        .take(MAX_POINTS)
        .collect();
    if points.is_empty() {
        return None;
    }
    let trace = |name: &str, colour: &str, keep: &dyn Fn(f64) -> bool| {
        let kept: Vec<&(f64, f64)> = points.iter().filter(|p| keep(p.1)).collect();
        json!({
            "type": "scatter", "mode": "markers", "name": name,
            "x": kept.iter().map(|p| plot::value(p.0)).collect::<Vec<_>>(),
            "y": kept.iter().map(|p| plot::value(p.1)).collect::<Vec<_>>(),
            "marker": { "color": colour, "size": 4, "opacity": 0.6 },
        })
    };
    let mut block = plot::figure(
        &format!("{entry} against the largest real part"),
        vec![
            trace("stable", "#4575b4", &|v| v <= 0.0),
            trace("unstable", "#d73027", &|v| v > 0.0),
        ],
        entry,
        "largest real part [1/s]",
    );
    if let Block::Plot { layout, .. } = &mut block {
        layout["hovermode"] = json!("closest");
    }
    Some(block)
}
