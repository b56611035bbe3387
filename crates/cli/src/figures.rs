//! The figures `fistage run` draws: stacked time responses (sensor and
//! reference, joint positions, friction forces, actuator force) and a phase
//! portrait of the sensor (velocity against position), each as SVG and PNG.

use std::path::Path;

use anyhow::Context;
use fistage_model::{JointMotion, Loaded};
use fistage_plot::{Figure, Panel, Series, XyPlot, write_figure, write_xy};
use fistage_sim::{RunOutput, SignalTable};

/// A length unit chosen so that plotted numbers stay readable.
struct LengthUnit {
    name: &'static str,
    scale: f64,
}

fn length_unit(values: &[&[f64]]) -> LengthUnit {
    let largest = values
        .iter()
        .flat_map(|v| v.iter())
        .filter(|v| v.is_finite())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    if largest >= 1e-2 {
        LengthUnit {
            name: "mm",
            scale: 1e3,
        }
    } else if largest >= 1e-5 {
        LengthUnit {
            name: "µm",
            scale: 1e6,
        }
    } else {
        LengthUnit {
            name: "nm",
            scale: 1e9,
        }
    }
}

fn scaled(values: &[f64], scale: f64) -> Vec<f64> {
    values.iter().map(|v| v * scale).collect()
}

/// Signals of the table whose names end in `suffix` and whose unit is `unit`.
fn signals_with<'a>(table: &'a SignalTable, suffix: &str, unit: &str) -> Vec<(&'a str, &'a [f64])> {
    table
        .names
        .iter()
        .zip(&table.units)
        .zip(&table.columns)
        .filter(|((name, u), _)| name.ends_with(suffix) && u.as_str() == unit)
        .map(|((name, _), column)| (name.as_str(), column.as_slice()))
        .collect()
}

/// The `<element>.force` signals of the named elements.
fn forces_of<'a, 'n>(
    table: &'a SignalTable,
    elements: impl Iterator<Item = &'n str>,
) -> Vec<(&'a str, &'a [f64])> {
    let wanted: Vec<String> = elements.map(|e| format!("{e}.force")).collect();
    signals_with(table, ".force", "N")
        .into_iter()
        .filter(|(name, _)| wanted.iter().any(|w| w == name))
        .collect()
}

fn length_panel(label: &str, table: &SignalTable, named: &[(&str, &[f64])]) -> Option<Panel> {
    if named.is_empty() {
        return None;
    }
    let unit = length_unit(&named.iter().map(|(_, v)| *v).collect::<Vec<_>>());
    let series = named
        .iter()
        .map(|(name, values)| Series::line(*name, table.times.clone(), scaled(values, unit.scale)))
        .collect();
    Some(Panel::new(format!("{label} [{}]", unit.name), series))
}

fn force_panel(label: &str, table: &SignalTable, named: &[(&str, &[f64])]) -> Option<Panel> {
    if named.is_empty() {
        return None;
    }
    let series = named
        .iter()
        .map(|(name, values)| Series::line(*name, table.times.clone(), values.to_vec()))
        .collect();
    Some(Panel::new(format!("{label} [N]"), series))
}

fn response_figure(loaded: &Loaded, table: &SignalTable) -> Figure {
    let mut sensor_signals = signals_with(table, ".position", "m");
    let reference = table.column("controller.reference");
    let moving = reference.is_some_and(|r| r.iter().any(|v| *v != r[0]));
    let mut sensor_label = "sensor";
    if moving {
        // A moving reference dwarfs the error: show the tracking error instead.
        if let Some(error) = table.column("controller.error") {
            sensor_signals = vec![("controller.error", error)];
            sensor_label = "tracking error";
        }
    } else if let Some(reference) = reference {
        sensor_signals.push(("reference", reference));
    }
    let joints: Vec<_> = loaded
        .model
        .bodies()
        .iter()
        .flat_map(|body| {
            let name = &body.joint.name;
            match body.joint.motion {
                JointMotion::Prismatic { .. } => vec![format!("{name}.q")],
                JointMotion::Floating => ["x", "y", "z"]
                    .iter()
                    .map(|a| format!("{name}.{a}"))
                    .collect(),
                JointMotion::Revolute { .. } => Vec::new(),
            }
        })
        .filter_map(|name| {
            let index = table.names.iter().position(|n| *n == name)?;
            Some((table.names[index].as_str(), table.columns[index].as_slice()))
        })
        .collect();
    let panels = [
        length_panel(sensor_label, table, &sensor_signals),
        length_panel("joint position", table, &joints),
        force_panel(
            "friction force",
            table,
            &forces_of(
                table,
                loaded.model.frictions().iter().map(|f| f.name.as_str()),
            ),
        ),
        force_panel(
            "actuator force",
            table,
            &forces_of(
                table,
                loaded.model.actuators().iter().map(|a| a.name.as_str()),
            ),
        ),
    ];
    let title = figure_title(loaded);
    Figure::new(title, "time [s]", panels.into_iter().flatten().collect())
}

/// The scenario's title, shortened to fit a figure's width.
pub fn figure_title(loaded: &Loaded) -> String {
    const LONGEST: usize = 70;
    let title = if loaded.scenario.title.is_empty() {
        loaded.scenario.file.display().to_string()
    } else {
        loaded.scenario.title.clone()
    };
    if title.chars().count() <= LONGEST {
        return title;
    }
    let cut: String = title.chars().take(LONGEST - 3).collect();
    format!("{}...", cut.trim_end())
}

/// Velocity against position of the first sensor: the whole run, and the
/// steady-state window drawn over it.
fn phase_portrait(loaded: &Loaded, table: &SignalTable) -> Option<XyPlot> {
    let sensor = loaded.model.sensors().first()?;
    let position = table.column(&format!("{}.position", sensor.name))?;
    let velocity = table.column(&format!("{}.velocity", sensor.name))?;
    let unit = length_unit(&[position]);
    let velocity_unit = length_unit(&[velocity]);
    let x = scaled(position, unit.scale);
    let v = scaled(velocity, velocity_unit.scale);
    let window = loaded.scenario.window;
    let (steady_x, steady_v): (Vec<f64>, Vec<f64>) = table
        .times
        .iter()
        .zip(x.iter().zip(&v))
        .filter(|(t, _)| **t >= window[0] && **t <= window[1])
        .map(|(_, (a, b))| (*a, *b))
        .unzip();
    Some(XyPlot::new(
        format!("Phase portrait of {}", sensor.name),
        format!("{}.position [{}]", sensor.name, unit.name),
        format!("{}.velocity [{}/s]", sensor.name, velocity_unit.name),
        vec![
            Series::line("whole run", x, v),
            Series::line(
                format!("steady state ({} s to {} s)", window[0], window[1]),
                steady_x,
                steady_v,
            ),
        ],
    ))
}

/// Writes the run's figures into `out_dir`; returns their file names.
pub fn run_figures(
    loaded: &Loaded,
    output: &RunOutput,
    out_dir: &Path,
) -> anyhow::Result<Vec<String>> {
    let mut written = Vec::new();
    let response = response_figure(loaded, &output.signals);
    for extension in ["svg", "png"] {
        let name = format!("response.{extension}");
        write_figure(&response, &out_dir.join(&name))
            .with_context(|| format!("cannot draw {name}"))?;
        written.push(name);
    }
    if let Some(portrait) = phase_portrait(loaded, &output.signals) {
        for extension in ["svg", "png"] {
            let name = format!("phase.{extension}");
            write_xy(&portrait, &out_dir.join(&name))
                .with_context(|| format!("cannot draw {name}"))?;
            written.push(name);
        }
    }
    Ok(written)
}
