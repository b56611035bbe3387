//! The figures of a run: stacked time responses (sensor and reference, joint
//! positions, friction forces, actuator force) and a phase portrait of the
//! sensor (velocity against position).

use std::path::Path;

use fistage_model::{JointMotion, Loaded};
use fistage_sim::{RunOutput, SignalTable};

use super::svg_and_png;
use super::units::{length_unit, scaled};
use crate::{Figure, Panel, PlotError, Series, XyPlot, write_figure, write_xy};

/// Draws `response` and, where the stage has a sensor, `phase` into `dir`;
/// returns the file names.
pub fn write(loaded: &Loaded, output: &RunOutput, dir: &Path) -> Result<Vec<String>, PlotError> {
    let response = response_figure(loaded, &output.signals);
    let mut written = svg_and_png(dir, "response", |path| write_figure(&response, path))?;
    if let Some(portrait) = phase_portrait(loaded, &output.signals) {
        written.extend(svg_and_png(dir, "phase", |path| write_xy(&portrait, path))?);
    }
    Ok(written)
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
    let title = super::title(loaded);
    Figure::new(title, "time [s]", panels.into_iter().flatten().collect())
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
