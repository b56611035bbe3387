//! A run's section: provenance, the summary statistics over the steady-state
//! window, and every output signal against time, one plot per unit.

use fistage_model::Loaded;
use fistage_sim::RunOutput;

use crate::block::number;
use crate::{Block, Section, plot};

/// The section of a run of `loaded`.
pub fn section(loaded: &Loaded, output: &RunOutput) -> Section {
    let mut blocks = vec![provenance(loaded, output), summary(loaded, output)];
    blocks.extend(signal_plots(output));
    Section {
        heading: format!("run: {}", name_of(loaded)),
        source: loaded.scenario.file.display().to_string(),
        blocks,
    }
}

/// The scenario's file stem.
pub(crate) fn name_of(loaded: &Loaded) -> String {
    loaded
        .scenario
        .file
        .file_stem()
        .map_or_else(|| "scenario".into(), |s| s.to_string_lossy().into_owned())
}

fn provenance(loaded: &Loaded, output: &RunOutput) -> Block {
    let scenario = &loaded.scenario;
    let stats = &output.trajectory.stats;
    let mut rows = vec![
        ["program".into(), crate::page::generator()],
        ["scenario".into(), scenario.file.display().to_string()],
    ];
    if !scenario.title.is_empty() {
        rows.push(["title".into(), scenario.title.clone()]);
    }
    rows.extend([
        ["robot".into(), scenario.robot.display().to_string()],
        [
            "duration".into(),
            format!("{} s", number(scenario.duration)),
        ],
        [
            "steady-state window".into(),
            format!(
                "{} s to {} s",
                number(scenario.window[0]),
                number(scenario.window[1])
            ),
        ],
        ["engine".into(), stats.engine.to_string()],
        [
            "relative tolerance".into(),
            format!("{:e}", scenario.solver.rtol),
        ],
        [
            "steps".into(),
            format!(
                "{} ({} rejected, {} right-hand-side evaluations)",
                stats.counts.steps, stats.counts.rejected, stats.counts.rhs_evaluations
            ),
        ],
        ["wall time".into(), format!("{:.3} s", stats.wall_time_s)],
    ]);
    Block::facts("provenance", rows)
}

fn summary(loaded: &Loaded, output: &RunOutput) -> Block {
    let window = loaded.scenario.window;
    Block::Table {
        title: format!(
            "summary over the steady-state window ({} s to {} s)",
            number(window[0]),
            number(window[1])
        ),
        columns: [
            "signal",
            "unit",
            "mean",
            "peak-to-peak",
            "rms",
            "min",
            "max",
        ]
        .map(String::from)
        .to_vec(),
        rows: output
            .summary
            .iter()
            .map(|s| {
                vec![
                    s.name.clone(),
                    s.unit.clone(),
                    number(s.stats.mean),
                    number(s.stats.peak_to_peak),
                    number(s.stats.rms),
                    number(s.stats.min),
                    number(s.stats.max),
                ]
            })
            .collect(),
    }
}

/// One plot per unit, in the order the units first appear.
fn signal_plots(output: &RunOutput) -> Vec<Block> {
    let table = &output.signals;
    let mut units: Vec<&str> = Vec::new();
    for unit in &table.units {
        if !units.contains(&unit.as_str()) {
            units.push(unit);
        }
    }
    units
        .into_iter()
        .map(|unit| {
            let traces = table
                .names
                .iter()
                .zip(&table.units)
                .zip(&table.columns)
                .filter(|((_, u), _)| u.as_str() == unit)
                .map(|((name, _), column)| plot::line(name, &table.times, column))
                .collect();
            plot::figure(
                &format!("signals in {unit}"),
                traces,
                "time [s]",
                &format!("[{unit}]"),
            )
        })
        .collect()
}
