//! A stability sweep's section: over two axes the map of verdicts and of the
//! largest real part, with every point's values on hover; over one axis the
//! largest real part and the amplitude along it.

use fistage_analysis::sweep::{Analyses, PointResult, Spacing, SweepSpec};
use fistage_model::Loaded;
use serde_json::{Value, json};

use crate::sections::run::name_of;
use crate::{Block, Section, plot};

/// The section of the sweep `results` of `spec`.
pub fn section(loaded: &Loaded, spec: &SweepSpec, results: &[PointResult]) -> Section {
    let mut blocks = vec![Block::facts(
        "sweep",
        vec![
            ["program".into(), crate::page::generator()],
            [
                "scenario".into(),
                loaded.scenario.file.display().to_string(),
            ],
            [
                "points".into(),
                format!("{} computed of {}", results.len(), spec.len()),
            ],
            [
                "axes".into(),
                spec.axes
                    .iter()
                    .map(|a| a.parameter.clone())
                    .collect::<Vec<_>>()
                    .join(" x "),
            ],
        ],
    )];
    match spec.axes.as_slice() {
        [x, y] => {
            let (xs, ys) = (x.values(), y.values());
            let verdicts = grid(results, xs.len() * ys.len(), |r| category(r, spec));
            let eig = grid(results, xs.len() * ys.len(), |r| r.max_real_eig);
            let amplitude = grid(results, xs.len() * ys.len(), |r| r.amplitude);
            let labels = if matches!(spec.analysis, Analyses::Linear) {
                ["stable", "unstable", "bistable"]
            } else {
                ["stable", "oscillating", "bistable"]
            };
            blocks.push(heatmap(
                "verdicts",
                (x, &xs),
                (y, &ys),
                &verdicts,
                [&eig, &amplitude],
                Some(labels),
            ));
            if eig.iter().any(Option::is_some) {
                blocks.push(heatmap(
                    "largest real part of the eigenvalues [1/s]",
                    (x, &xs),
                    (y, &ys),
                    &eig,
                    [&eig, &amplitude],
                    None,
                ));
            }
        }
        [x] => blocks.push(curves(x, results)),
        _ => {}
    }
    Section {
        heading: format!("sweep: {}", name_of(loaded)),
        source: loaded.scenario.file.display().to_string(),
        blocks,
    }
}

/// Stable 0, unstable or oscillating 1, bistable 2.
fn category(r: &PointResult, spec: &SweepSpec) -> Option<f64> {
    if r.bistable == Some(true) {
        return Some(2.0);
    }
    let stable = match spec.analysis {
        Analyses::Linear => r.stable_linear,
        _ => r.stable_sim.or(r.stable_linear),
    }?;
    Some(if stable { 0.0 } else { 1.0 })
}

fn grid(
    results: &[PointResult],
    cells: usize,
    value: impl Fn(&PointResult) -> Option<f64>,
) -> Vec<Option<f64>> {
    let mut out = vec![None; cells];
    for r in results {
        if let Some(cell) = out.get_mut(r.index) {
            *cell = value(r);
        }
    }
    out
}

fn axis_layout(axis: &fistage_analysis::sweep::Axis) -> Value {
    json!({
        "title": { "text": axis.parameter },
        "type": if axis.spacing == Spacing::Log { "log" } else { "linear" },
        "exponentformat": "SI",
    })
}

fn rows(values: &[Option<f64>], width: usize) -> Vec<Vec<Value>> {
    values
        .chunks(width)
        .map(|row| {
            row.iter()
                .map(|v| v.map_or(Value::Null, plot::value))
                .collect()
        })
        .collect()
}

fn heatmap(
    title: &str,
    (x, xs): (&fistage_analysis::sweep::Axis, &[f64]),
    (y, ys): (&fistage_analysis::sweep::Axis, &[f64]),
    values: &[Option<f64>],
    [eig, amplitude]: [&[Option<f64>]; 2],
    labels: Option<[&str; 3]>,
) -> Block {
    let hover: Vec<Vec<Value>> = eig
        .iter()
        .zip(amplitude)
        .collect::<Vec<_>>()
        .chunks(xs.len())
        .map(|row| {
            row.iter()
                .map(|(e, a)| {
                    let show = |v: &Option<f64>| v.map_or("-".into(), crate::number);
                    json!([show(e), show(a)])
                })
                .collect()
        })
        .collect();
    let mut trace = json!({
        "type": "heatmap", "x": plot::values(xs), "y": plot::values(ys),
        "z": rows(values, xs.len()), "customdata": hover,
        "hovertemplate": format!("{} %{{x}}<br>{} %{{y}}<br>largest real part %{{customdata[0]}} 1/s<br>amplitude %{{customdata[1]}} m<extra></extra>", x.parameter, y.parameter),
    });
    match labels {
        Some(names) => {
            trace["zmin"] = json!(0);
            trace["zmax"] = json!(2);
            trace["colorscale"] = json!([
                [0.0, "#91bfdb"],
                [0.33, "#91bfdb"],
                [0.33, "#fc8d59"],
                [0.67, "#fc8d59"],
                [0.67, "#ffffbf"],
                [1.0, "#ffffbf"]
            ]);
            trace["colorbar"] = json!({ "tickvals": [0.33, 1.0, 1.67], "ticktext": names });
        }
        None => {
            trace["colorscale"] = json!("RdBu");
            trace["reversescale"] = json!(true);
            trace["zmid"] = json!(0);
        }
    }
    Block::Plot {
        title: title.to_string(),
        traces: vec![trace],
        layout: json!({ "xaxis": axis_layout(x), "yaxis": axis_layout(y), "hovermode": "closest" }),
        height: 520,
    }
}

fn curves(x: &fistage_analysis::sweep::Axis, results: &[PointResult]) -> Block {
    let mut sorted: Vec<&PointResult> = results.iter().collect();
    sorted.sort_by(|a, b| a.parameters[0].total_cmp(&b.parameters[0]));
    let line = |name: &str, axis: &str, value: &dyn Fn(&PointResult) -> Option<f64>| {
        json!({
            "type": "scatter", "mode": "lines+markers", "name": name, "yaxis": axis,
            "x": sorted.iter().map(|r| plot::value(r.parameters[0])).collect::<Vec<_>>(),
            "y": sorted.iter().map(|r| value(r).map_or(Value::Null, plot::value)).collect::<Vec<_>>(),
        })
    };
    Block::Plot {
        title: format!("along {}", x.parameter),
        traces: vec![
            line("largest real part [1/s]", "y", &|r| r.max_real_eig),
            line("amplitude [m]", "y2", &|r| r.amplitude),
        ],
        layout: json!({
            "xaxis": axis_layout(x),
            "yaxis": { "title": { "text": "largest real part [1/s]" } },
            "yaxis2": { "title": { "text": "amplitude [m]" }, "overlaying": "y", "side": "right", "exponentformat": "SI" },
            "legend": { "orientation": "h", "y": -0.2 },
        }),
        height: 420,
    }
}
