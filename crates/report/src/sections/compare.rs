//! A comparison's section: per case the metric against the first axis with
//! its +-1 sigma band, and its reduction against the baseline.

use fistage_analysis::compare::{Comparison, Curve};
use fistage_analysis::sweep::Spacing;
use serde_json::{Value, json};

use crate::{Block, Section, plot};

/// Colours of the cases, in order.
const COLOURS: [&str; 8] = [
    "#4575b4", "#d73027", "#1a9850", "#984ea3", "#ff7f00", "#a65628", "#f781bf", "#666666",
];

/// The section of `comparison`'s `curves`.
pub fn section(comparison: &Comparison, curves: &[Curve]) -> Section {
    let metric = comparison.metric;
    let first = &comparison.cases[0];
    let mut blocks = vec![Block::facts(
        "comparison",
        vec![
            ["program".into(), crate::page::generator()],
            [
                "cases".into(),
                comparison
                    .cases
                    .iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            ],
            [
                "metric".into(),
                format!("{} [{}]", metric.name(), metric.unit()),
            ],
            [
                "axes".into(),
                comparison
                    .axes
                    .iter()
                    .map(|a| a.parameter.as_str())
                    .collect::<Vec<_>>()
                    .join(" x "),
            ],
        ],
    )];
    let spread = if comparison.axes.len() >= 2 {
        format!("mean, band +-1 sigma over {}", comparison.axes[1].parameter)
    } else {
        "mean, band +-1 sigma over the run's events".into()
    };
    blocks.push(banded(
        comparison,
        &format!("{} ({spread})", metric.name().replace('_', " ")),
        &format!("{} [{}]", metric.name(), metric.unit()),
        curves,
        |c| (&c.mean, &c.std),
    ));
    if comparison.has_baseline {
        blocks.push(banded(
            comparison,
            &format!("reduction against {} ({spread})", first.name),
            "reduction [%]",
            curves,
            |c| (&c.reduction_mean, &c.reduction_std),
        ));
    }
    Section {
        heading: format!("compare: {}", first.name),
        source: first.loaded.scenario.file.display().to_string(),
        blocks,
    }
}

fn banded(
    comparison: &Comparison,
    title: &str,
    y_title: &str,
    curves: &[Curve],
    pick: impl Fn(&Curve) -> (&Vec<f64>, &Vec<f64>),
) -> Block {
    let mut traces = Vec::new();
    for (k, curve) in curves.iter().enumerate() {
        let (mean, std) = pick(curve);
        let colour = COLOURS[k % COLOURS.len()];
        let name = &comparison.cases[curve.case].name;
        let edge = |sign: f64| -> Vec<Value> {
            mean.iter()
                .zip(std)
                .map(|(m, s)| plot::value(m + sign * s))
                .collect()
        };
        traces.push(json!({
            "type": "scatter", "mode": "lines", "x": plot::values(&curve.x), "y": edge(-1.0),
            "line": { "width": 0, "color": colour }, "showlegend": false, "hoverinfo": "skip",
            "legendgroup": name,
        }));
        traces.push(json!({
            "type": "scatter", "mode": "lines", "x": plot::values(&curve.x), "y": edge(1.0),
            "fill": "tonexty", "fillcolor": format!("{colour}33"), "line": { "width": 0, "color": colour },
            "showlegend": false, "hoverinfo": "skip", "legendgroup": name,
        }));
        traces.push(json!({
            "type": "scatter", "mode": "lines+markers", "name": name, "legendgroup": name,
            "x": plot::values(&curve.x), "y": plot::values(mean),
            "error_y": { "type": "data", "array": plot::values(std), "visible": false },
            "customdata": plot::values(std),
            "hovertemplate": "%{y:.4g} +- %{customdata:.3g}<extra>%{fullData.name}</extra>",
            "line": { "color": colour },
        }));
    }
    let mut block = plot::figure(title, traces, &comparison.x_label_with_unit(), y_title);
    let log = comparison
        .axes
        .first()
        .is_some_and(|a| a.spacing == Spacing::Log);
    if let (true, Block::Plot { layout, .. }) = (log, &mut block) {
        layout["xaxis"]["type"] = json!("log");
    }
    block
}
