//! A record fit's section: the records against the fitted stage with the
//! residuals, the parameter table with intervals, what the records could not
//! determine (with the singular values that show it), the per-record
//! residual statistics and the fitted parameters' correlation matrix as a
//! picture. One function for the one-mass fit, one for a stage's.

use fistage_ident::covariance::FitCovariance;
use fistage_ident::record::{Record, RecordFit, RecordReport};
use fistage_ident::report::ParamReport;
use fistage_ident::stage::{StageFit, StageReport};
use serde_json::{Value, json};

use crate::block::number;
use crate::{Block, Section, plot};

/// The section of a one-mass fit of `record`.
pub fn record_section(record: &Record, fit: &RecordFit, report: &RecordReport) -> Section {
    let mut blocks = vec![Block::facts(
        "fit",
        vec![
            ["program".into(), crate::page::generator()],
            ["record".into(), report.source.clone()],
            ["model".into(), report.model.clone()],
            [
                "samples".into(),
                format!(
                    "{} over {} s, {} segments",
                    report.samples,
                    number(report.duration),
                    report.segments
                ),
            ],
            ["iterations".into(), report.iterations.to_string()],
            ["intervals".into(), report.interval_method.clone()],
            [
                "residuals".into(),
                format!(
                    "rms {} m, largest {} m, R^2 {}",
                    number(report.residuals.rms),
                    number(report.residuals.max_abs),
                    number(report.residuals.r_squared)
                ),
            ],
        ],
    )];
    for missing in &report.not_identifiable {
        blocks.push(Block::warning(format!(
            "not determined by this record: {}: {}",
            missing.parameter, missing.reason
        )));
    }
    blocks.extend(report.warnings.iter().map(|w| Block::warning(w.clone())));
    let params = [
        ("f_c", &report.f_c),
        ("f_s", &report.f_s),
        ("v_s", &report.v_s),
        ("sigma0", &report.sigma0),
        ("sigma1", &report.sigma1),
        ("sigma2", &report.sigma2),
        ("mass", &report.mass),
    ];
    blocks.push(parameter_table(
        params
            .iter()
            .filter(|(name, _)| report.mass_fitted || *name != "mass")
            .map(|(name, p)| param_row(name, p))
            .collect(),
    ));
    blocks.extend(data_against_fit(
        &report.source,
        &record.time,
        &record.position,
        &fit.simulated,
        &record.force,
    ));
    if let Some(covariance) = &report.covariance {
        blocks.push(correlation(covariance));
    }
    Section {
        heading: format!("identify record: {}", report.source),
        source: report.source.clone(),
        blocks,
    }
}

/// The table of a curve or one-mass fit's parameters, one row each.
fn parameter_table(rows: Vec<Vec<String>>) -> Block {
    Block::Table {
        title: "parameters".into(),
        columns: [
            "parameter",
            "unit",
            "value",
            "std error",
            "95% low",
            "95% high",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    }
}

fn param_row(name: &str, p: &ParamReport) -> Vec<String> {
    let show = |v: Option<f64>| v.map_or_else(|| "-".into(), number);
    vec![
        name.to_string(),
        p.unit.clone(),
        number(p.value),
        show(p.std_error),
        show(p.ci95.map(|c| c[0])),
        show(p.ci95.map(|c| c[1])),
    ]
}

/// The section of a stage fit to `records`.
pub fn stage_section(records: &[Record], fit: &StageFit, report: &StageReport) -> Section {
    let mut blocks = vec![Block::facts(
        "fit",
        vec![
            ["program".into(), crate::page::generator()],
            ["scenario".into(), report.scenario.clone()],
            ["drive".into(), report.drive.clone()],
            [
                "records".into(),
                records
                    .iter()
                    .map(|r| r.source.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            ],
            [
                "iterations".into(),
                format!(
                    "{} ({}), {} right-hand-side evaluations",
                    report.iterations,
                    if report.converged {
                        "converged"
                    } else {
                        "NOT converged"
                    },
                    report.rhs_evaluations
                ),
            ],
        ],
    )];
    if !report.undetermined.is_empty() {
        blocks.push(Block::warning(format!(
            "not determined by these records (left at the scenario's values): {}",
            report.undetermined.join(", ")
        )));
    }
    if !report.determined_only_together.is_empty() {
        blocks.push(Block::warning(format!(
            "determined only together: {}",
            report.determined_only_together.join("; ")
        )));
    }
    if let Some(note) = &report.tie_note {
        blocks.push(Block::note(note.clone()));
    }
    blocks.push(stage_parameters(report));
    blocks.push(residual_table(report));
    blocks.push(singular_values(report));
    if let Some(covariance) = &report.covariance {
        blocks.push(correlation(covariance));
    }
    for ((record, residuals), simulated) in records.iter().zip(&fit.records).zip(&fit.simulated) {
        for (sensor, readings) in residuals.sensors.iter().zip(simulated) {
            let measured = (record.sensors.iter())
                .find(|s| s.column == sensor.column)
                .map_or(record.position.as_slice(), |s| s.values.as_slice());
            blocks.extend(data_against_fit(
                &format!("{}, {}", residuals.source, sensor.sensor),
                &record.time,
                measured,
                readings,
                &record.force,
            ));
        }
    }
    Section {
        heading: format!("identify stage: {}", report.scenario),
        source: report.scenario.clone(),
        blocks,
    }
}

fn stage_parameters(report: &StageReport) -> Block {
    let show = |v: Option<f64>| v.map_or_else(|| "-".into(), number);
    Block::Table {
        title: "parameters".into(),
        columns: [
            "parameter",
            "path",
            "unit",
            "scenario",
            "start",
            "value",
            "std error",
            "95% low",
            "95% high",
            "",
        ]
        .map(String::from)
        .to_vec(),
        rows: report
            .parameters
            .iter()
            .map(|p| {
                vec![
                    p.name.clone(),
                    p.path.clone(),
                    p.unit.clone(),
                    number(p.nominal),
                    number(p.start),
                    number(p.value),
                    show(p.std_error),
                    show(p.ci95.map(|c| c[0])),
                    show(p.ci95.map(|c| c[1])),
                    if p.fitted { "" } else { "NOT DETERMINED" }.into(),
                ]
            })
            .collect(),
    }
}

fn residual_table(report: &StageReport) -> Block {
    Block::Table {
        title: "residuals per record and sensor".into(),
        columns: [
            "record",
            "sensor",
            "column",
            "rms [m]",
            "largest [m]",
            "noise [m]",
            "rms / noise",
        ]
        .map(String::from)
        .to_vec(),
        rows: report
            .records
            .iter()
            .flat_map(|r| {
                r.sensors.iter().map(move |s| {
                    vec![
                        r.source.clone(),
                        s.sensor.clone(),
                        s.column.clone(),
                        number(s.rms),
                        number(s.max_abs),
                        number(s.noise),
                        number(s.rms / s.noise),
                    ]
                })
            })
            .collect(),
    }
}

/// The singular values of the scaled sensitivities, before and after the
/// fit: a value far below the others is a direction the records cannot see.
fn singular_values(report: &StageReport) -> Block {
    let trace = |name: &str, values: &[f64]| {
        json!({
            "type": "bar", "name": name,
            "x": (1..=values.len()).map(|k| format!("{k}")).collect::<Vec<_>>(),
            "y": plot::values(values),
        })
    };
    let mut traces = vec![trace(
        &format!("before the fit ({})", report.identifiability_before.basis),
        &report.identifiability_before.singular_values,
    )];
    if let Some(after) = &report.identifiability_after {
        traces.push(trace(
            &format!("after the fit ({})", after.basis),
            &after.singular_values,
        ));
    }
    let mut block = plot::figure(
        "singular values of the scaled sensitivities",
        traces,
        "direction",
        "singular value",
    );
    if let Block::Plot { layout, .. } = &mut block {
        layout["yaxis"]["type"] = json!("log");
        layout["hovermode"] = json!("closest");
    }
    block
}

/// The fitted parameters' correlation matrix as a picture.
pub fn correlation(covariance: &FitCovariance) -> Block {
    let n = covariance.parameters.len();
    let c = &covariance.matrix;
    let z: Vec<Vec<Value>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    let scale = (c[i][i] * c[j][j]).sqrt();
                    if scale > 0.0 {
                        plot::value(c[i][j] / scale)
                    } else {
                        Value::Null
                    }
                })
                .collect()
        })
        .collect();
    Block::Plot {
        title: format!(
            "correlation of the fitted parameters ({})",
            covariance.method
        ),
        traces: vec![json!({
            "type": "heatmap", "x": covariance.parameters, "y": covariance.parameters, "z": z,
            "zmin": -1, "zmax": 1, "colorscale": "RdBu", "reversescale": true,
            "texttemplate": "%{z:.2f}",
            "hovertemplate": "%{y} with %{x}: %{z:.3f}<extra></extra>",
        })],
        layout: json!({ "yaxis": { "autorange": "reversed", "automargin": true }, "xaxis": { "automargin": true }, "hovermode": "closest" }),
        height: (160 + 40 * n).min(800) as u32,
    }
}

/// The record against the fit, and the residual with the force beside it.
fn data_against_fit(
    name: &str,
    time: &[f64],
    measured: &[f64],
    simulated: &[f64],
    force: &[f64],
) -> Vec<Block> {
    let residual: Vec<f64> = simulated.iter().zip(measured).map(|(s, m)| s - m).collect();
    let mut second = plot::figure(
        &format!("{name}: residual (fit minus record) and force"),
        vec![plot::line("residual [m]", time, &residual), {
            let mut force = plot::line("force [N]", time, force);
            force["yaxis"] = json!("y2");
            force
        }],
        "time [s]",
        "residual [m]",
    );
    if let Block::Plot { layout, .. } = &mut second {
        layout["yaxis2"] =
            json!({ "title": { "text": "force [N]" }, "overlaying": "y", "side": "right" });
    }
    vec![
        plot::figure(
            &format!("{name}: record and fit"),
            vec![
                plot::line("record", time, measured),
                plot::line("fit", time, simulated),
            ],
            "time [s]",
            "position [m]",
        ),
        second,
    ]
}

/// The section of a curve fit (`identify stribeck` or `identify frf`): its
/// report's parameters with intervals, what the data could not determine,
/// and `plots` (the data against the fit).
pub fn curve_section(heading: &str, report: &impl serde::Serialize, plots: Vec<Block>) -> Section {
    let json = serde_json::to_value(report).unwrap_or(Value::Null);
    let source = json["source"].as_str().unwrap_or_default().to_string();
    let mut blocks = vec![Block::facts(
        "fit",
        vec![
            ["program".into(), crate::page::generator()],
            ["data".into(), source.clone()],
        ],
    )];
    for missing in json["not_identifiable"].as_array().into_iter().flatten() {
        blocks.push(Block::warning(format!(
            "not determined by these data: {}: {}",
            missing["parameter"].as_str().unwrap_or_default(),
            missing["reason"].as_str().unwrap_or_default()
        )));
    }
    for warning in json["warnings"].as_array().into_iter().flatten() {
        blocks.push(Block::warning(
            warning.as_str().unwrap_or_default().to_string(),
        ));
    }
    let show = |v: &Value| v.as_f64().map_or_else(|| "-".into(), number);
    let rows = json
        .as_object()
        .into_iter()
        .flatten()
        .filter(|(_, v)| v.get("value").is_some() && v.get("unit").is_some())
        .map(|(name, p)| {
            vec![
                name.clone(),
                p["unit"].as_str().unwrap_or_default().to_string(),
                show(&p["value"]),
                show(&p["std_error"]),
                show(&p["ci95"][0]),
                show(&p["ci95"][1]),
            ]
        })
        .collect();
    blocks.push(parameter_table(rows));
    blocks.extend(plots);
    Section {
        heading: format!("{heading}: {source}"),
        source,
        blocks,
    }
}
