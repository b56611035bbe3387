//! `fistage sweep SCENARIO [--out DIR] [--shard i/n] [--merge DIR ...]`: run the
//! scenario's `[sweep]` grid in parallel with a progress bar, write
//! `points.csv` (a column per axis, then `stable_linear`, `stable_sim`,
//! `amplitude`, `max_real_eig`, `bistable`), `points.json`, and a stability
//! map. Journal, resume, shards and merge follow `fistage_analysis::study`.

use std::path::{Path, PathBuf};

use anyhow::Context;
use fistage_analysis::study::write_table;
use fistage_analysis::sweep::{Analyses, PointResult, Spacing, SweepSpec, SweepStudy};
use fistage_model::RobotSpec;
use fistage_plot::{ColourScale, Heatmap, Series, XyPlot, write_heatmap, write_xy};

use crate::study::{self, StudyArgs};

/// Arguments of `fistage sweep`.
#[derive(clap::Args)]
pub struct SweepArgs {
    /// Scenario file with a [sweep] table.
    pub scenario: PathBuf,
    /// Output folder (default: out/<scenario>-sweep).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Shards, merging, threads, resume.
    #[command(flatten)]
    pub study: StudyArgs,
}

/// Runs the command.
pub fn run(args: &SweepArgs) -> anyhow::Result<()> {
    let loaded = fistage_model::load(&args.scenario)?;
    let spec = SweepSpec::from_scenario(&loaded.scenario)?;
    let robot_file = RobotSpec::from_file(&loaded.scenario.robot)?;
    spec.check_against(&loaded.scenario, &robot_file)?;
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| fistage_model::output::default_folder(&args.scenario, "sweep"));
    let grid = SweepStudy {
        loaded: &loaded,
        robot_file: &robot_file,
        spec: &spec,
    };
    let provenance = grid.provenance(None, args.study.shard()?)?;
    let (folder, results) = study::gather(&grid, &args.study, &out_dir, &provenance)?;
    write_table(&grid, &results, &folder)?;
    let json_path = folder.path().join("points.json");
    std::fs::write(&json_path, grid.points_json(&results))
        .with_context(|| format!("cannot write {}", json_path.display()))?;
    let pictures = draw(
        &crate::figures::figure_title(&loaded),
        &spec,
        &results,
        folder.path(),
    )?;
    folder.commit()?;
    let missing = spec.len() - results.len();
    println!(
        "{} of {} points in {}/points.csv{}{}",
        results.len(),
        spec.len(),
        out_dir.display(),
        if missing > 0 {
            format!(" ({missing} not computed here)")
        } else {
            String::new()
        },
        if pictures.is_empty() {
            String::new()
        } else {
            format!(", map in {}", pictures.join(", "))
        }
    );
    summarize(&results);
    Ok(())
}

/// 0 stable, 1 oscillating (or linearly unstable), 2 bistable; NaN not computed.
fn category(result: &PointResult) -> f64 {
    if result.bistable == Some(true) {
        2.0
    } else if let Some(stable) = result.stable_sim.or(result.stable_linear) {
        if stable { 0.0 } else { 1.0 }
    } else {
        f64::NAN
    }
}

fn draw(
    title: &str,
    spec: &SweepSpec,
    results: &[PointResult],
    out_dir: &Path,
) -> anyhow::Result<Vec<String>> {
    let mut written = Vec::new();
    match spec.axes.as_slice() {
        [x_axis, y_axis] => {
            let (xs, ys) = (x_axis.values(), y_axis.values());
            let mut values = vec![f64::NAN; xs.len() * ys.len()];
            let mut linear = vec![None; xs.len() * ys.len()];
            for result in results {
                values[result.index] = category(result);
                linear[result.index] = result.stable_linear;
            }
            let (mut bx, mut by) = (Vec::new(), Vec::new());
            let mid = |a: f64, b: f64, log: bool| if log { (a * b).sqrt() } else { 0.5 * (a + b) };
            for row in 0..ys.len() {
                for col in 0..xs.len() {
                    let here = linear[row * xs.len() + col];
                    if col + 1 < xs.len()
                        && here.is_some()
                        && linear[row * xs.len() + col + 1].is_some_and(|v| Some(v) != here)
                    {
                        bx.push(mid(xs[col], xs[col + 1], x_axis.spacing == Spacing::Log));
                        by.push(ys[row]);
                    }
                    if row + 1 < ys.len()
                        && here.is_some()
                        && linear[(row + 1) * xs.len() + col].is_some_and(|v| Some(v) != here)
                    {
                        bx.push(xs[col]);
                        by.push(mid(ys[row], ys[row + 1], y_axis.spacing == Spacing::Log));
                    }
                }
            }
            let mut map = Heatmap::new(
                if title.is_empty() {
                    "stability map".to_string()
                } else {
                    title.to_string()
                },
                x_axis.parameter.clone(),
                y_axis.parameter.clone(),
                xs,
                ys,
                values,
                ColourScale::Categorical {
                    labels: if matches!(spec.analysis, Analyses::Linear) {
                        vec!["stable".into(), "unstable".into(), "bistable".into()]
                    } else {
                        vec!["stable".into(), "oscillating".into(), "bistable".into()]
                    },
                },
            );
            map.x_log = x_axis.spacing == Spacing::Log;
            map.y_log = y_axis.spacing == Spacing::Log;
            map.value_label = "verdict".into();
            if !bx.is_empty() {
                map.overlay
                    .push(Series::markers("linear stability boundary", bx, by));
            }
            for extension in ["svg", "png"] {
                let name = format!("map.{extension}");
                write_heatmap(&map, &out_dir.join(&name))
                    .with_context(|| format!("cannot draw {name}"))?;
                written.push(name);
            }
        }
        [axis] => {
            let xs: Vec<f64> = results.iter().map(|r| r.parameters[0]).collect();
            let mut series = Vec::new();
            let amplitude: Vec<f64> = results
                .iter()
                .map(|r| r.amplitude.unwrap_or(f64::NAN))
                .collect();
            if amplitude.iter().any(|v| v.is_finite()) {
                series.push(Series::line_and_markers(
                    "steady peak-to-peak [m]",
                    xs.clone(),
                    amplitude,
                ));
            }
            let eig: Vec<f64> = results
                .iter()
                .map(|r| r.max_real_eig.unwrap_or(f64::NAN))
                .collect();
            if eig.iter().any(|v| v.is_finite()) {
                series.push(Series::line_and_markers("max Re(lambda) [1/s]", xs, eig));
            }
            let mut plot = XyPlot::new(title.to_string(), axis.parameter.clone(), "value", series);
            plot.x_log = axis.spacing == Spacing::Log;
            for extension in ["svg", "png"] {
                let name = format!("sweep.{extension}");
                write_xy(&plot, &out_dir.join(&name))
                    .with_context(|| format!("cannot draw {name}"))?;
                written.push(name);
            }
        }
        _ => {}
    }
    Ok(written)
}

fn summarize(results: &[PointResult]) {
    let count = |f: &dyn Fn(&PointResult) -> bool| results.iter().filter(|r| f(r)).count();
    println!(
        "linear: {} stable, {} unstable, {} undetermined; simulation: {} stable, {} oscillating; {} bistable",
        count(&|r| r.stable_linear == Some(true)),
        count(&|r| r.stable_linear == Some(false)),
        // Analysed (a largest real part exists) without a verdict the numerics back.
        count(&|r| r.stable_linear.is_none() && r.max_real_eig.is_some()),
        count(&|r| r.stable_sim == Some(true)),
        count(&|r| r.stable_sim == Some(false)),
        count(&|r| r.bistable == Some(true)),
    );
}
